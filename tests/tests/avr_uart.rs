//! The board as the chip sees it: the firmware behind an emulated USART as strict as the
//! ATmega2560's (two bytes of receive buffer plus the shift register, see
//! `quad_host::emu::Mega2560`), at both line rates.
//!
//! - bytes back to back at the highest baud, garbage mixed in: every valid frame answered, no
//!   byte lost by the chip's buffer;
//! - the longest interrupts-off stretch while receiving, per baud, within one byte time at the
//!   fastest supported baud;
//! - a firmware that keeps interrupts off too long (a test-only binary) loses bytes, and the
//!   emulator counts them and shows them to the firmware (DOR0);
//! - request's last byte → answer's first byte per request type, and poses per second with the
//!   full readback, per baud (the figures of BENCHMARKS.md, printed with `--nocapture`).
//!
//! All times are simulated (16 MHz cycles).

use integration_tests::avr_bench::{self, STANCE_HEIGHT_M};
use kin_core::body::Pose;
use kin_core::RotationOrder;
use quad_host::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, AVR_ANGLE_TOLERANCE_RAD,
};
use quad_host::emu::{build, Mega2560};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::Link;
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, HostToDevice, LinkTimeout, Request, RobotPreset,
    ServoId, MAX_DECODED_LEN, MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use seeded_rng::SplitMix64 as Rng;
use std::process::Command;
use std::time::Duration;

/// CPU cycles per byte on a real 8N1 line at the fastest supported baud (1 Mbaud: 10 bits of
/// 16 cycles): the bound of every interrupts-off stretch while bytes may arrive.
const BYTE_CYCLES_AT_1MBAUD: u64 = 160;

/// A `SetBodyPose`'s last byte → its answer's first byte, beyond the body IK itself (as the
/// firmware runs it: its solver built at boot), at most (cycles; 1 ms at 16 MHz). Measured
/// 0.90 ms at 115,200 baud and 0.98 ms at 1 Mbaud (BENCHMARKS.md), where more of the request's
/// bytes are decoded after its last byte.
const ROUND_TRIP_OVER_IK_CYCLES: u64 = 16_000;

/// Body poses per second with full readback at 1 Mbaud, two requests in flight, at least.
const POSES_PER_S_AT_1MBAUD: f64 = 200.0;

fn elf(bin: &str) -> std::path::PathBuf {
    build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"))
}

fn frame(seq: u16, request: Request) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    encode_frame(&HostToDevice { seq, request }, &mut buf)
        .expect("encodes")
        .to_vec()
}

/// Feeds the device's bytes to `acc` and returns the answers.
fn decode(acc: &mut Accumulator<MAX_DECODED_LEN>, bytes: &[u8]) -> Vec<DeviceToHost> {
    let mut out = Vec::new();
    let mut rest = bytes;
    loop {
        match acc.feed::<DeviceToHost>(rest) {
            Feed::NeedMore => return out,
            Feed::Frame { msg, remaining } => {
                out.push(msg);
                rest = remaining;
            }
            other => panic!("the device sent an unreadable frame: {other:?}"),
        }
    }
}

/// Sends `bytes` (back to back) and collects the answers within `wait`.
fn exchange(link: &mut EmulatorLink, bytes: &[u8], wait: Duration) -> Vec<DeviceToHost> {
    link.send(bytes).expect("send");
    let end = link.now() + wait;
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut answers = Vec::new();
    let mut buf = [0u8; 512];
    while link.now() < end {
        let n = link.recv(&mut buf, end - link.now()).expect("recv");
        answers.extend(decode(&mut acc, &buf[..n]));
    }
    answers
}

fn hello(link: &mut EmulatorLink) {
    let answers = exchange(
        link,
        &frame(
            1,
            Request::Hello {
                version: PROTOCOL_VERSION,
            },
        ),
        Duration::from_millis(20),
    );
    assert!(
        matches!(answers[..], [DeviceToHost::HelloAck { seq: 1, .. }]),
        "{answers:?}"
    );
}

/// Line noise: `len` bytes, a third of them `0x00` (so that it makes many short "frames").
fn noise(rng: &mut Rng, len: usize) -> Vec<u8> {
    (0..len)
        .map(|_| {
            if rng.chance(1.0 / 3.0) {
                0
            } else {
                rng.below(256) as u8
            }
        })
        .collect()
}

#[test]
fn back_to_back_bytes_at_1mbaud_with_garbage_lose_nothing_and_every_valid_frame_is_answered() {
    let mut link = EmulatorLink::boot(&elf(build::FIRMWARE_1MBAUD), EmulatorConfig::new(1_000_000))
        .unwrap_or_else(|e| panic!("{e}"));
    hello(&mut link);
    link.mcu_mut().reset_interrupts_off();
    let mut rng = Rng::new(0x0AB1_E5EE);
    let mut framing_nacks = 0;
    for i in 0..40u16 {
        // Noise and a request, back to back, one request at a time (the link rules).
        let seq = 100 + i;
        let request = match i % 4 {
            0 => Request::GetState,
            1 => Request::GetCalibration {
                servo: ServoId::ALL[usize::from(i) % 12],
            },
            2 => Request::SetLinkTimeout(LinkTimeout::default()),
            _ => Request::SetBodyPose(Pose::rotation(0.01 * f32::from(i % 7), 0.0, 0.0)),
        };
        let len = rng.below(60) as usize;
        let mut wire = noise(&mut rng, len);
        wire.extend(frame(seq, request));
        let answers = exchange(&mut link, &wire, Duration::from_millis(15));
        framing_nacks += answers.iter().filter(|a| a.seq().is_none()).count();
        let answered: Vec<u16> = answers.iter().filter_map(DeviceToHost::seq).collect();
        assert_eq!(answered, [seq], "round {i}: {answers:?}");
    }
    // At most one nack of an unreadable frame per 10 ms (40 rounds of ≤ 15 ms).
    assert!(framing_nacks <= 60, "{framing_nacks} framing nacks");
    assert_eq!(link.rx_overruns(), 0, "bytes lost by the receive buffer");
    let off = link.mcu().interrupts_off();
    assert!(
        off.longest_receiving_cycles <= BYTE_CYCLES_AT_1MBAUD,
        "interrupts off for {} cycles while receiving (pc {:#x})",
        off.longest_receiving_cycles,
        off.longest_receiving_pc
    );
    assert_eq!(link.pulse_stats().errors, 0);
    assert_eq!(link.mcu().resets().count, 0);
}

/// Streams body poses through the client; returns the stream.
fn stream_poses(bin: &str, baud: u32, n: usize) -> PoseStream<EmulatorLink> {
    let mut link =
        EmulatorLink::boot(&elf(bin), EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
    link.mcu_mut().reset_interrupts_off();
    let setup = StreamSetup {
        robot: avr_bench::robot(),
        preset: RobotPreset::Shahriar2023,
        stance_height_m: Some(STANCE_HEIGHT_M),
        order: Some(RotationOrder::Zyx),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    let mut stream = PoseStream::connect(Client::new(link, ClientConfig::emulator()), setup)
        .unwrap_or_else(|e| panic!("{e}"));
    for k in 0..n {
        let t = k as f32 / n as f32 * std::f32::consts::TAU;
        let pose = Pose::rotation(0.15 * t.sin(), 0.1 * t.cos(), 0.05 * (2.0 * t).sin());
        let r = stream.send(&pose).expect("link");
        assert!(matches!(r, PoseResult::Acked { .. }), "pose {k}: {r:?}");
    }
    stream
}

#[test]
fn interrupts_off_while_receiving_stay_within_one_byte_time_at_both_baud_rates() {
    for (bin, baud) in [
        (build::FIRMWARE, 115_200u32),
        (build::FIRMWARE_1MBAUD, 1_000_000),
    ] {
        let mut stream = stream_poses(bin, baud, 30);
        let link = stream.client_mut().link_mut();
        let off = link.mcu().interrupts_off();
        let byte_cycles = 10 * 16_000_000 / u64::from(baud);
        println!(
            "{bin} @ {baud}: longest interrupts-off stretch while receiving {} cycles \
             ({:.2} byte times at this baud, {:.2} at 1 Mbaud); overall {} cycles; \
             receive overruns {}",
            off.longest_receiving_cycles,
            off.longest_receiving_cycles as f64 / byte_cycles as f64,
            off.longest_receiving_cycles as f64 / BYTE_CYCLES_AT_1MBAUD as f64,
            off.longest_cycles,
            link.rx_overruns()
        );
        assert!(
            off.longest_receiving_cycles <= BYTE_CYCLES_AT_1MBAUD,
            "{bin}: {off:?} (pc {:#x})",
            off.longest_receiving_pc
        );
        assert_eq!(link.rx_overruns(), 0, "{bin}");
        assert_eq!(link.pulse_stats().errors, 0, "{bin}");
    }
}

/// The address of the firmware's static whose name contains `name` (avr-nm).
fn static_address(elf: &std::path::Path, name: &str) -> u16 {
    let out = Command::new("avr-nm")
        .arg(elf)
        .output()
        .expect("avr-nm runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.contains(name))
        .unwrap_or_else(|| panic!("no symbol {name}"));
    let addr = u32::from_str_radix(line.split_whitespace().next().expect("address"), 16)
        .expect("hex address");
    // Data addresses carry avr-gcc's 0x800000 offset.
    (addr & 0xFFFF) as u16
}

#[test]
fn a_firmware_that_keeps_interrupts_off_too_long_loses_bytes_and_the_emulator_counts_them() {
    let bad = elf(build::FIRMWARE_1MBAUD_CLI_HOLD);
    // The defect on purpose: the link's own check of the stretches would stop it.
    let config = EmulatorConfig {
        check_interrupts_off: false,
        ..EmulatorConfig::new(1_000_000)
    };
    let mut link = EmulatorLink::boot(&bad, config).unwrap_or_else(|e| panic!("{e}"));
    hello(&mut link);
    link.mcu_mut().reset_interrupts_off();
    let mut wire = Vec::new();
    for seq in 0..8 {
        wire.extend(frame(seq, Request::GetState));
    }
    let _ = exchange(&mut link, &wire, Duration::from_millis(20));
    let off = link.mcu().interrupts_off();
    assert!(
        off.longest_receiving_cycles > BYTE_CYCLES_AT_1MBAUD,
        "the defect is in place: {off:?}"
    );
    let lost = link.rx_overruns();
    assert!(lost > 0, "the emulator counts the lost bytes");
    assert_eq!(link.line_stats().rx_overflow, lost);
    // The firmware saw DOR0 set in its receive interrupt and counted the damage.
    let line_errors = static_address(&bad, "LINE_ERRORS");
    let seen = u16::from_le_bytes([
        link.mcu().data(line_errors),
        link.mcu().data(line_errors + 1),
    ]);
    assert!(seen > 0, "the firmware read DOR0 ({lost} bytes lost)");
    println!(
        "firmware-1mbaud-cli-hold: interrupts off {} cycles while receiving, {lost} bytes \
         lost, {seen} DOR0 seen by the firmware",
        off.longest_receiving_cycles
    );

    // The same traffic through the real firmware loses nothing.
    let mut link = EmulatorLink::boot(&elf(build::FIRMWARE_1MBAUD), EmulatorConfig::new(1_000_000))
        .unwrap_or_else(|e| panic!("{e}"));
    hello(&mut link);
    let answers = exchange(&mut link, &wire, Duration::from_millis(20));
    assert_eq!(answers.len(), 8, "{answers:?}");
    assert_eq!(link.rx_overruns(), 0);
}

/// Cycles from the end of a request's last byte to the first answer byte written to UDR0,
/// one request at a time on a fresh MCU (after `Hello`).
fn round_trip_cycles(bin: &str, requests: &[(&str, Request)]) -> Vec<(String, u64, u64)> {
    let mut mcu = Mega2560::new(&elf(bin)).unwrap_or_else(|e| panic!("{e}"));
    while mcu.uart_baud().is_none() {
        mcu.step().expect("boots");
    }
    // Bytes per 16 MHz cycle as the emulated line counts them (simavr: 11 bits per byte).
    let baud = mcu.uart_baud().expect("configured");
    let byte_cycles = (11.0 * 16e6 / baud).round() as u64;
    // Let the device finish booting (its stance IK) before the first request.
    mcu.run_cycles(16_000 * 30).expect("runs");
    let mut out = Vec::new();
    let hello = frame(
        0,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    );
    let all = std::iter::once(("Hello", hello.clone()))
        .chain(
            requests
                .iter()
                .enumerate()
                .map(|(i, (name, r))| (*name, frame(i as u16 + 1, *r))),
        )
        .collect::<Vec<_>>();
    for (name, bytes) in all {
        // Let the previous answer drain.
        mcu.run_cycles(200 * byte_cycles).expect("runs");
        let _ = mcu.uart_take();
        let start = mcu.cycle();
        mcu.uart_write(&bytes);
        let last_byte_in = start + bytes.len() as u64 * byte_cycles;
        let limit = start + 16_000_000 / 10;
        let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
        let mut first: Option<u64> = None;
        let mut answer = Vec::new();
        while mcu.cycle() < limit && answer.is_empty() {
            mcu.step().expect("runs");
            for (cycle, b) in mcu.uart_take() {
                if b != 0 && first.is_none() {
                    // The frame's leading delimiter was written one byte earlier.
                    first = Some(cycle.saturating_sub(byte_cycles));
                }
                answer.extend(decode(&mut acc, &[b]));
            }
        }
        assert!(!answer.is_empty(), "{bin}: no answer to {name}");
        let first = first.expect("an answer byte");
        out.push((
            name.to_owned(),
            first.saturating_sub(last_byte_in),
            bytes.len() as u64,
        ));
    }
    out
}

#[test]
fn request_to_first_answer_byte_per_request_type_and_poses_per_second() {
    let pose = Pose::rotation(0.1, -0.05, 0.08);
    let requests = [
        ("GetState", Request::GetState),
        ("SetBodyPose", Request::SetBodyPose(pose)),
        (
            "SetFeet",
            Request::SetFeet {
                feet_in_body_m: std::array::from_fn(|i| {
                    let x = if i < 2 { 0.3 } else { -0.3 };
                    let y = if i % 2 == 0 { 0.184 } else { -0.184 };
                    [x, y, -STANCE_HEIGHT_M]
                }),
            },
        ),
        (
            "SetJoints",
            Request::SetJoints {
                angles_rad: [
                    0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
                ],
            },
        ),
        ("SetOutputs", Request::SetOutputs { enabled: true }),
        (
            "SetLinkTimeout",
            Request::SetLinkTimeout(LinkTimeout::default()),
        ),
    ];
    let mut bench = avr_bench::BenchFirmware::boot(&elf(build::BENCH));
    let (ik_cycles, solved) = bench.body(avr_bench::FIRMWARE_BACKEND, &pose);
    assert!(solved.is_some(), "the benchmark solves the pose");
    for (bin, baud) in [
        (build::FIRMWARE, 115_200u32),
        (build::FIRMWARE_1MBAUD, 1_000_000),
    ] {
        for (name, cycles, len) in round_trip_cycles(bin, &requests) {
            println!(
                "{bin} @ {baud}: {name} ({len} B): last request byte -> first answer byte \
                 {cycles} cycles = {:.2} ms",
                cycles as f64 / 16_000.0
            );
            if name == "SetBodyPose" {
                // The body IK itself (the benchmark firmware, same pose) plus 1 ms.
                println!(
                    "  body IK alone {ik_cycles} cycles = {:.2} ms; the rest {:.2} ms",
                    ik_cycles as f64 / 16_000.0,
                    cycles.saturating_sub(ik_cycles) as f64 / 16_000.0
                );
                // The IK + 1 ms: decoding, the pulse mapping, the readback and the answer's
                // serialization take the rest (docs/benchmark-journal.md).
                assert!(
                    cycles <= ik_cycles + ROUND_TRIP_OVER_IK_CYCLES,
                    "{bin}: {cycles} cycles > body IK {ik_cycles} + {ROUND_TRIP_OVER_IK_CYCLES}"
                );
            }
        }
        let mut stream = stream_poses(bin, baud, 60);
        let stats = stream.stats();
        println!(
            "{bin} @ {baud}: {:.1} body poses/s with full readback (one request at a time, \
             simulated time), overruns {}",
            stats.poses_per_s,
            stream.client_mut().link_mut().rx_overruns()
        );
        assert_eq!(stream.client_mut().link_mut().rx_overruns(), 0);
        let (per_s, answered) = pipelined_poses_per_s(bin, baud, 60);
        println!(
            "{bin} @ {baud}: {per_s:.1} body poses/s with full readback, two requests in \
             flight (the device solves the next while the answer is on the wire)"
        );
        assert_eq!(answered, 60);
        if baud == 115_200 {
            // 95 % of the 100 poses/s that request and answer in sequence take on the wire.
            assert!(per_s >= 95.0, "{per_s:.1} poses/s");
        } else {
            assert!(
                per_s >= POSES_PER_S_AT_1MBAUD,
                "{bin}: {per_s:.1} poses/s < {POSES_PER_S_AT_1MBAUD}"
            );
        }
    }
}

/// Body poses per second (simulated) when the host keeps two `SetBodyPose` requests in
/// flight: it sends the next as soon as an answer is complete. Returns the rate and the number
/// of poses acked.
fn pipelined_poses_per_s(bin: &str, baud: u32, n: u16) -> (f64, u16) {
    let mut link =
        EmulatorLink::boot(&elf(bin), EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
    hello(&mut link);
    let pose = |k: u16| {
        let t = f32::from(k) / f32::from(n) * std::f32::consts::TAU;
        Request::SetBodyPose(Pose::rotation(0.15 * t.sin(), 0.1 * t.cos(), 0.0))
    };
    let start = link.now();
    let mut next = 0u16;
    for _ in 0..2 {
        link.send(&frame(10 + next, pose(next))).expect("send");
        next += 1;
    }
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut acked = 0u16;
    let mut buf = [0u8; 256];
    let deadline = start + Duration::from_secs(2);
    while acked < n && link.now() < deadline {
        let got = link
            .recv(&mut buf, Duration::from_millis(50))
            .expect("recv");
        for answer in decode(&mut acc, &buf[..got]) {
            assert!(matches!(answer, DeviceToHost::Ack { .. }), "{answer:?}");
            acked += 1;
            if next < n {
                link.send(&frame(10 + next, pose(next))).expect("send");
                next += 1;
            }
        }
    }
    assert_eq!(link.rx_overruns(), 0);
    let elapsed = (link.now() - start).as_secs_f64();
    (f64::from(acked) / elapsed, acked)
}

/// A random request with plausible fields (some out of range, some unreachable).
fn random_request(rng: &mut Rng) -> Request {
    let angle = |rng: &mut Rng| rng.range(-0.4, 0.4) as f32;
    match rng.below(8) {
        0 => Request::GetState,
        1 => Request::SetBodyPose(Pose {
            roll_rad: angle(rng),
            pitch_rad: angle(rng),
            yaw_rad: angle(rng),
            x_m: rng.range(-0.05, 0.05) as f32,
            y_m: rng.range(-0.05, 0.05) as f32,
            z_m: rng.range(-0.05, 0.05) as f32,
        }),
        2 => Request::SetJoints {
            angles_rad: std::array::from_fn(|i| match i % 3 {
                0 => angle(rng),
                1 => 0.5 + angle(rng),
                _ => -1.0 + angle(rng),
            }),
        },
        3 => Request::SetOutputs {
            enabled: rng.chance(0.7),
        },
        4 => Request::GetCalibration {
            servo: ServoId::ALL[rng.below(12) as usize],
        },
        5 => Request::SetLinkTimeout(LinkTimeout::default()),
        6 => Request::SetBodyPose(Pose {
            yaw_rad: if rng.chance(0.5) { 1e38 } else { f32::NAN },
            ..Pose::default()
        }),
        _ => Request::SetFeet {
            feet_in_body_m: std::array::from_fn(|_| {
                [
                    rng.range(-0.5, 0.5) as f32,
                    rng.range(-0.3, 0.3) as f32,
                    rng.range(-0.6, 0.0) as f32,
                ]
            }),
        },
    }
}

/// The wire frame of arbitrary decoded bytes `body` with a good CRC.
fn frame_with_good_crc(body: &[u8]) -> Vec<u8> {
    let mut data = body.to_vec();
    data.extend_from_slice(&quad_protocol::crc::checksum(body).to_be_bytes());
    let mut out = vec![0];
    let mut run: Vec<u8> = Vec::new();
    for &b in &data {
        if b == 0 {
            out.push(run.len() as u8 + 1);
            out.append(&mut run);
        } else {
            run.push(b);
        }
    }
    out.push(run.len() as u8 + 1);
    out.append(&mut run);
    out.push(0);
    out
}

/// What the device reads in `wire` (the protocol's own decoder).
fn readable(wire: &[u8]) -> Vec<HostToDevice> {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut out = Vec::new();
    let mut rest = wire;
    loop {
        match acc.feed::<HostToDevice>(rest) {
            Feed::NeedMore => return out,
            Feed::Frame { msg, remaining } => {
                out.push(msg);
                rest = remaining;
            }
            other => rest = other.remaining(),
        }
    }
}

#[test]
fn bounded_fuzz_of_the_emulated_firmware_never_drives_a_wrong_pulse() {
    let mut link = EmulatorLink::boot(&elf(build::FIRMWARE_1MBAUD), EmulatorConfig::new(1_000_000))
        .unwrap_or_else(|e| panic!("{e}"));
    hello(&mut link);
    let mut rng = Rng::new(0xF0_2201);
    let mut calibration = [quad_protocol::servo::Calibration::default(); 12];
    for (i, c) in calibration.iter_mut().enumerate() {
        let answers = exchange(
            &mut link,
            &frame(
                2,
                Request::GetCalibration {
                    servo: ServoId::ALL[i],
                },
            ),
            Duration::from_millis(5),
        );
        let [DeviceToHost::Calibration {
            calibration: got, ..
        }] = answers[..]
        else {
            panic!("{answers:?}");
        };
        *c = got;
    }
    // Whether the last SetOutputs the device acked asked for the outputs on.
    let mut enabled_by_ack = false;
    let (mut garbage, mut mutated, mut random_payloads, mut acks) = (0, 0, 0, 0);
    for round in 0..400u16 {
        let seq = 1000 + round;
        let wire = match rng.below(4) {
            0 => {
                garbage += 1;
                let len = 1 + rng.below(40) as usize;
                noise(&mut rng, len)
            }
            1 => {
                mutated += 1;
                let mut f = frame(seq, random_request(&mut rng));
                for _ in 0..1 + rng.below(3) {
                    let i = rng.below(f.len() as u64) as usize;
                    match rng.below(3) {
                        0 => f[i] ^= 1 << rng.below(8),
                        1 => f[i] = rng.below(256) as u8,
                        _ => {
                            f.remove(i);
                        }
                    }
                }
                f
            }
            2 => {
                random_payloads += 1;
                let mut body = vec![(seq & 0x7F) as u8, rng.below(13) as u8];
                for _ in 0..rng.below(50) {
                    body.push(rng.below(256) as u8);
                }
                frame_with_good_crc(&body)
            }
            _ => frame(seq, random_request(&mut rng)),
        };
        let sent = readable(&wire);
        let answers = exchange(&mut link, &wire, Duration::from_millis(12));
        for answer in &answers {
            let Some(seq) = answer.seq() else { continue };
            let request = sent.iter().find(|m| m.seq == seq).map(|m| m.request);
            if let (DeviceToHost::Ack { .. }, Some(Request::SetOutputs { enabled })) =
                (answer, request)
            {
                enabled_by_ack = enabled;
            }
            if let DeviceToHost::Configured {
                setting:
                    quad_protocol::Setting::Calibration {
                        servo,
                        calibration: c,
                    },
                ..
            } = answer
            {
                calibration[servo.index()] = *c;
            }
            let Some(rb) = answer.readback() else {
                continue;
            };
            acks += 1;
            let on = rb.flags.contains(quad_protocol::Flags::OUTPUTS_ENABLED);
            assert!(
                !on || enabled_by_ack,
                "round {round}: outputs on without an acked SetOutputs {{ enabled: true }}"
            );
            assert!(
                rb.angles_rad.iter().all(|a| a.is_finite()),
                "round {round}: {rb:?}"
            );
            if on {
                for (i, (&p, c)) in rb.pulses_half_us.iter().zip(&calibration).enumerate() {
                    assert!(
                        c.min_half_us() <= p && p <= c.max_half_us(),
                        "round {round}: channel {i} pulse {p} beyond its travel"
                    );
                }
            }
        }
    }
    let pins = link.pulse_stats();
    println!(
        "fuzz: {garbage} garbage, {mutated} mutated, {random_payloads} valid-CRC random \
         payloads, {acks} readbacks checked, {} pulses checked, {} overruns",
        pins.checked,
        link.rx_overruns()
    );
    assert_eq!(pins.errors, 0, "{:?}", pins.first_error);
    assert_eq!(link.rx_overruns(), 0);
    assert_eq!(link.mcu().resets().count, 0, "no panic, no watchdog reset");
}

/// Poses streamed as fast as the 1 Mbaud line carries them (one pose repeated, then poses far
/// apart: body roll alternating ±0.25 rad) move the twelve pins by at most the joint-speed
/// limiter's step per servo period: the device never writes a streamed pose past the limiter,
/// whatever the requests' timing against the PWM periods. Also with a pause between poses.
#[test]
fn streamed_poses_never_step_a_pin_beyond_the_limiter() {
    use quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S;
    use quad_protocol::servo::STANDARD_US_PER_RAD;
    for gap_ms in [0u64, 7, 30] {
        let mut mcu = Mega2560::new(&elf(build::FIRMWARE_1MBAUD)).unwrap_or_else(|e| panic!("{e}"));
        while mcu.uart_baud().is_none() {
            mcu.step().expect("boots");
        }
        mcu.run_cycles(16_000 * 30).expect("runs");
        // The same pose 30 times (requests of one length at a steady cadence), then poses far
        // apart.
        let pose = |k: u16| {
            if k < 30 {
                Pose::rotation(0.1, -0.05, 0.08)
            } else {
                Pose::rotation(if k.is_multiple_of(2) { 0.25 } else { -0.25 }, 0.0, 0.0)
            }
        };
        let mut requests = vec![
            Request::Hello {
                version: PROTOCOL_VERSION,
            },
            Request::SetBodyPose(pose(0)),
            Request::SetOutputs { enabled: true },
        ];
        requests.extend((1..60).map(|k| Request::SetBodyPose(pose(k))));
        mcu.capture_pulses(true);
        for (seq, r) in requests.into_iter().enumerate() {
            mcu.uart_write(&frame(seq as u16, r));
            let start = mcu.cycle();
            let mut delimiters = 0;
            while delimiters < 2 {
                assert!(
                    mcu.cycle() < start + 16_000_000,
                    "no answer to request {seq}"
                );
                mcu.step().expect("runs");
                delimiters += mcu.uart_take().iter().filter(|(_, b)| *b == 0).count();
            }
            mcu.run_cycles(16_000 * gap_ms).expect("runs");
        }
        mcu.run_cycles(16_000 * 200).expect("runs");
        let pulses = mcu.take_pulses();
        let mut last: [Option<quad_host::emu::Pulse>; 12] = [None; 12];
        let (mut worst, mut steps) = (0.0f64, 0);
        for p in &pulses {
            if let Some(q) = last[p.channel] {
                steps += 1;
                let (step, allowed) = integration_tests::pins::step_and_bound_rad(
                    &q,
                    p,
                    f64::from(STANDARD_US_PER_RAD),
                    f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S),
                );
                worst = worst.max(step);
                assert!(
                    step <= allowed,
                    "gap {gap_ms} ms: channel {} stepped {step:.4} rad in one period (bound {allowed:.4})",
                    p.channel
                );
            }
            last[p.channel] = Some(*p);
        }
        println!(
            "gap {gap_ms} ms: {steps} pulse-to-pulse steps, largest {worst:.4} rad (limiter {:.4} rad per period)",
            DEFAULT_JOINT_SPEED_LIMIT_RAD_S * 0.02
        );
        assert!(steps > 100, "{steps} steps seen");
        // The poses are far apart: the limiter is what bounds the steps.
        assert!(worst > 0.5 * f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S) * 0.02);
    }
}
