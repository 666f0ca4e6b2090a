//! The release firmware ELF in simavr, black box through its UART and its pins: the avr-libc
//! link, the ELF's code, memory, handshake, the twelve servo outputs against the host's own IK
//! and calibration, refusals, unreadable frames, the link-loss failsafe, a soak with line
//! corruption, and the watchdog.
//!
//! The firmware is built once per test process (`quad_host::emu::build`, nightly toolchain
//! via `firmware-avr/rust-toolchain.toml`); a test fails — never skips — when it cannot be
//! built. All times are simulated.

use integration_tests::avr_bench::{self, STACK_PAINT, STANCE_HEIGHT_M};
use integration_tests::symbols;
use integration_tests::wire::frame;
use kin_core::body::{self, Pose};
use kin_core::{BodyConfig, ReachPolicy, RotationOrder};
use quad_host::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, AVR_ANGLE_TOLERANCE_RAD,
};
use quad_host::emu::{build, elf, Pulse, CYCLES_PER_TICK, PERIOD_CYCLES, SERVO_PINS};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::{Faults, Link};
use quad_protocol::{
    DeviceToHost, Flags, LinkLossAction, LinkTimeout, NackReason, Request, RobotPreset,
    MAX_DECODED_LEN, PROTOCOL_VERSION,
};
use seeded_rng::SplitMix64 as Rng;
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

/// A pulse may differ from the expected width by one timer tick (0.5 µs), beyond the
/// uncertainty of seeing its edges between simavr steps (`Pulse::width_could_be`).
const PULSE_TOLERANCE_CYCLES: u64 = CYCLES_PER_TICK;

/// The ATmega2560's flash available to an application (256 KiB minus the 8 KiB bootloader
/// section of the Arduino Mega), bytes.
const FLASH_HARDWARE_LIMIT_BYTES: u64 = 248 * 1024;

/// SRAM of the ATmega2560, bytes; the stack must stay clear of the static data with a margin.
const SRAM_BYTES: u64 = 8 * 1024;

/// Margin kept between the deepest stack and the static data, bytes.
const SRAM_MARGIN_BYTES: u64 = 1024;

/// The firmware's watchdog timeout (`firmware_avr::app::WATCHDOG_TIMEOUT`, "250 ms"): 32,768
/// cycles of the watchdog's 128 kHz oscillator, ms.
const WATCHDOG_TIMEOUT_MS: u64 = 256;

/// WDTCSR bits: WDE, WDIE, and the prescaler WDP3..0 of 250 ms (0b0100).
const WDTCSR_WDE: u8 = 1 << 3;
const WDTCSR_WDIE: u8 = 1 << 6;
const WDTCSR_WDP_MASK: u8 = 0b0010_0111;
const WDTCSR_WDP_250MS: u8 = 0b0000_0100;

/// MCUSR's watchdog-reset flag.
const MCUSR_WDRF: u8 = 1 << 3;

fn firmware(bin: &str) -> PathBuf {
    build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"))
}

/// Both builds pass the same tests: `firmware` (115,200 baud) and `firmware-1mbaud`.
const BAUDS: [u32; 2] = [115_200, 1_000_000];

/// The firmware built for `config.baud`, booted.
fn boot(config: EmulatorConfig) -> EmulatorLink {
    let bin = build::firmware_for_baud(config.baud).expect("a firmware for this line rate");
    EmulatorLink::boot(&firmware(bin), config).unwrap_or_else(|e| panic!("{e}"))
}

/// Handshake, the benchmark stance (0.277 m, zyx), calibration read-back, outputs on.
fn connect(link: EmulatorLink) -> PoseStream<EmulatorLink> {
    let setup = StreamSetup {
        robot: avr_bench::robot(),
        preset: RobotPreset::Shahriar2023,
        stance_height_m: Some(STANCE_HEIGHT_M),
        order: Some(RotationOrder::Zyx),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    PoseStream::connect(Client::new(link, ClientConfig::emulator()), setup)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The twelve pulse widths the host expects for `pose`: its own kin-core IK mapped through the
/// device's calibration, in timer ticks.
fn host_pulses(stream: &PoseStream<EmulatorLink>, pose: &Pose) -> [u16; 12] {
    let angles = body::Solver::new(&avr_bench::robot())
        .inverse_at_stance(
            pose,
            &BodyConfig::default(),
            STANCE_HEIGHT_M,
            ReachPolicy::Reject,
        )
        .expect("the host solves the pose")
        .flat();
    std::array::from_fn(|i| {
        stream.calibration()[i]
            .pulse_half_us(angles[i])
            .expect("within the servo's travel")
    })
}

/// The next complete pulse of every channel; panics if one is missing.
fn pins(stream: &mut PoseStream<EmulatorLink>) -> [Pulse; 12] {
    let seen = stream
        .client_mut()
        .link_mut()
        .next_pulses()
        .expect("the MCU runs");
    std::array::from_fn(|ch| {
        seen[ch].unwrap_or_else(|| {
            let (port, bit) = SERVO_PINS[ch];
            panic!("channel {ch} (P{port}{bit}): no pulse")
        })
    })
}

/// Frames the joint-speed limiter may take to bring the outputs to a new target: the largest
/// joint travel (2π) at its step per 20 ms frame, plus one.
fn limiter_frames() -> u32 {
    let step_rad = quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S * 0.02;
    (2.0 * std::f32::consts::PI / step_rad).ceil() as u32 + 1
}

/// The pins once the outputs have reached `want_ticks`: every output passes the joint-speed
/// limiter, so a new target is on the pins after a few frames (at most [`limiter_frames`]).
fn settled_pins(stream: &mut PoseStream<EmulatorLink>, want_ticks: &[u16; 12]) -> [Pulse; 12] {
    let mut got = pins(stream);
    for _ in 0..limiter_frames() {
        let there = got.iter().zip(want_ticks).all(|(p, &w)| {
            p.width_could_be(u64::from(w) * CYCLES_PER_TICK, PULSE_TOLERANCE_CYCLES)
        });
        if there {
            break;
        }
        got = pins(stream);
    }
    got
}

fn assert_pins(got: &[Pulse; 12], want_ticks: &[u16; 12], what: &str) {
    for (ch, (p, &w)) in got.iter().zip(want_ticks).enumerate() {
        let want = u64::from(w) * CYCLES_PER_TICK;
        let (port, bit) = SERVO_PINS[ch];
        assert!(
            p.width_could_be(want, PULSE_TOLERANCE_CYCLES),
            "{what}: channel {ch} (P{port}{bit}) high {} cycles, want {want}: {p:?}",
            p.high_cycles
        );
    }
}

#[test]
fn avr_libc_float_routines_are_linked_not_weak_fallbacks() {
    let symbols = symbols::of_elf(&firmware(build::FIRMWARE));
    let kind_of = |name: &str| symbols::named(&symbols, name).first().map(|s| s.kind);
    for name in ["sqrt", "__mulsf3", "__addsf3", "__divsf3"] {
        let kind = kind_of(name).unwrap_or_else(|| panic!("{name} not in the firmware"));
        // `__addsf3`/`__mulsf3` are avr-libc-math's fast paths in front of avr-libc's own
        // routines (`avr_float` checks which), `sqrt` avr-libc-math's with avr-libc's bits
        // (`avr_sqrt`); the others avr-libc's. Never a weak fallback.
        assert_eq!(
            kind, 'T',
            "{name} must be a strong symbol (avr-libc's or avr-libc-math's)"
        );
    }
    // Functions the backend may or may not use: never compiler-builtins' 64-bit fallbacks.
    for name in ["atan2", "sin", "cos", "acos"] {
        assert_ne!(kind_of(name), Some('W'), "{name} is a weak fallback");
    }
}

/// A miscompilation seen with LLVM's AVR backend (nightly 1.97): in a function whose stack
/// frame exceeds the 63-byte displacement, an access to a far stack slot saved SREG in r0
/// while r0 still held the low byte of a `mul` result. The firmware avoids large frames where
/// it can (quad-device's handlers are out of line); this scans the linked code for the
/// pattern: a multiplication followed, before r0 is read, by `in r0, SREG`.
#[test]
fn no_mul_result_is_clobbered_by_a_frame_pointer_adjustment() {
    for bin in [build::FIRMWARE, build::FIRMWARE_1MBAUD] {
        let out = Command::new("avr-objdump")
            .arg("-d")
            .arg(firmware(bin))
            .output()
            .expect("avr-objdump (binutils-avr) runs");
        assert!(out.status.success());
        let text = String::from_utf8_lossy(&out.stdout);
        let mut func = "";
        let mut pending: Option<&str> = None;
        let mut hits = Vec::new();
        let mut muls = 0;
        for line in text.lines() {
            if line.ends_with(">:") {
                func = line;
                pending = None;
                continue;
            }
            let fields: Vec<&str> = line.split('\t').collect();
            let (Some(ins), ops) = (fields.get(2).map(|s| s.trim()), fields.get(3)) else {
                continue;
            };
            let ops = ops.map_or("", |o| o.split(';').next().unwrap_or("").trim());
            let regs: Vec<&str> = ops.split(',').map(str::trim).collect();
            if matches!(ins, "mul" | "muls" | "mulsu" | "fmul" | "fmuls" | "fmulsu") {
                muls += 1;
                pending = Some(line);
                continue;
            }
            let Some(m) = pending else { continue };
            if ins == "in" && regs.first() == Some(&"r0") {
                hits.push(format!("{func}\n  {m}\n  {line}"));
                pending = None;
            } else if regs.contains(&"r0") || ins.starts_with('b') || ins.contains("jmp") {
                // r0 read (the product taken), or control flow: stop following.
                pending = None;
            } else if matches!(ins, "ret" | "reti" | "call" | "rcall") {
                pending = None;
            }
        }
        assert!(muls > 0, "{bin}: the scan found no multiplication at all");
        assert!(
            hits.is_empty(),
            "{bin}: r0 (a mul result) overwritten with SREG before use:\n{}",
            hits.join("\n")
        );
    }
}

#[test]
fn flash_and_sram_fit_the_board() {
    let path = firmware(build::FIRMWARE);
    let image = elf::Elf::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let sizes = image.sizes();
    let heap_start = image.data_symbol("__heap_start").expect("__heap_start");
    let mut stream = connect(boot(EmulatorConfig::new(115_200)));
    for pose in avr_bench::targets().poses.iter().take(4) {
        assert!(matches!(
            stream.send(pose).expect("link"),
            PoseResult::Acked { .. }
        ));
    }
    let mcu = stream.client().link().mcu();
    let painted = u64::from(mcu.painted_stack_bytes(heap_start, STACK_PAINT));
    let peak = u64::from(mcu.stack_peak_bytes());
    eprintln!(
        "flash {} B, static SRAM {} B, stack {painted} B (paint) / {peak} B (SP)",
        sizes.flash_bytes, sizes.sram_static_bytes
    );
    assert!(sizes.flash_bytes <= FLASH_HARDWARE_LIMIT_BYTES);
    // The paint shows the deepest byte written, the stack pointer the deepest frame
    // allocated (a frame's lowest slots may stay unwritten): close, paint never deeper.
    assert!(
        painted > 0 && painted <= peak && peak - painted <= 128,
        "paint {painted} B vs stack pointer {peak} B"
    );
    assert!(
        sizes.sram_static_bytes + painted.max(peak) + SRAM_MARGIN_BYTES <= SRAM_BYTES,
        "the stack comes within {SRAM_MARGIN_BYTES} B of the static data"
    );
}

/// The tables the firmware reads with `lpm` are seen by the budget's check (kin-core's kernel
/// cells, by name) and lie in the lowest 64 KB of flash, in every firmware build.
#[test]
fn tables_read_with_lpm_lie_in_the_lowest_64_kb() {
    for bin in [build::FIRMWARE, build::FIRMWARE_1MBAUD, build::BENCH] {
        let path = firmware(bin);
        let objects = elf::Elf::read(&path)
            .unwrap_or_else(|e| panic!("{e}"))
            .flash_objects();
        for table in ["ATAN_CELLS", "SIN_COS_CELLS"] {
            assert!(
                objects
                    .iter()
                    .any(|o| o.name.contains(table) && o.size_bytes > 0),
                "{bin}: no {table} among the flash objects {objects:?}"
            );
        }
        let beyond = integration_tests::budget::lpm_reach_violations(&path);
        assert!(beyond.is_empty(), "{bin}: beyond lpm's reach: {beyond:?}");
    }
}

#[test]
fn handshake_then_outputs_stay_low_until_enabled() {
    for baud in BAUDS {
        handshake_then_outputs_stay_low_until_enabled_at(baud);
    }
}

/// [`handshake_then_outputs_stay_low_until_enabled`] with the firmware of one line rate.
fn handshake_then_outputs_stay_low_until_enabled_at(baud: u32) {
    let mut link = boot(EmulatorConfig::new(baud));
    for (port, bit) in SERVO_PINS {
        assert!(link.mcu().is_output(port, bit), "P{port}{bit} is an output");
    }
    link.idle(Duration::from_millis(25)).expect("runs");
    assert_eq!(link.mcu().servo_levels(), 0);
    let mut client = Client::new(link, ClientConfig::emulator());
    // Before the handshake, motion is refused.
    let early = client
        .request(Request::SetBodyPose(Pose::default()))
        .expect_err("refused before Hello");
    assert!(early.to_string().contains("hello"), "{early}");
    let info = client.hello().expect("handshake");
    assert_eq!(info.version, PROTOCOL_VERSION);
    assert_eq!(info.robot, RobotPreset::Shahriar2023);
    assert_eq!(info.max_frame_len as usize, MAX_DECODED_LEN);
    let rb = client.ack(Request::GetState).expect("state");
    assert!(!rb.flags.contains(Flags::OUTPUTS_ENABLED));
    assert!(
        rb.flags.contains(Flags::CALIBRATION_DEFAULT),
        "erased EEPROM"
    );
    assert_eq!(rb.pulses_half_us, [0; 12]);
    assert!(rb.angles_rad.iter().all(|a| a.is_finite()));
    // Still no pulse after a motion request with the outputs off.
    client
        .ack(Request::SetBodyPose(Pose::rotation(0.05, 0.0, 0.0)))
        .expect("solved while off");
    let link = client.link_mut();
    let seen = link.next_pulses().expect("runs");
    assert!(seen.iter().all(Option::is_none), "no pulse while off");
    assert_eq!(link.pulse_stats().errors, 0);
}

#[test]
fn fifty_random_targets_put_the_host_calibration_of_the_host_ik_on_all_twelve_pins() {
    for baud in BAUDS {
        fifty_random_targets_put_the_host_calibration_of_the_host_ik_on_all_twelve_pins_at(baud);
    }
}

/// [`fifty_random_targets_put_the_host_calibration_of_the_host_ik_on_all_twelve_pins`] with the firmware of one line rate.
fn fifty_random_targets_put_the_host_calibration_of_the_host_ik_on_all_twelve_pins_at(baud: u32) {
    let targets = avr_bench::targets();
    assert_eq!(targets.poses.len(), 50);
    let mut stream = connect(boot(EmulatorConfig::new(baud)));
    for (i, pose) in targets.poses.iter().enumerate() {
        let result = stream.send(pose).expect("link");
        assert!(
            matches!(result, PoseResult::Acked { .. }),
            "target {i}: {result:?}"
        );
        let want = host_pulses(&stream, pose);
        let got = settled_pins(&mut stream, &want);
        assert_pins(&got, &want, &format!("target {i}"));
    }
    let stats = stream.stats();
    assert_eq!(stats.acked, 50);
    assert_eq!(stats.readback_mismatches, 0);
    assert!(stats.max_angle_err_rad <= AVR_ANGLE_TOLERANCE_RAD);
    let pulses = stream.client_mut().link_mut().pulse_stats();
    assert_eq!(pulses.errors, 0, "{:?}", pulses.first_error);
    assert!(pulses.checked >= 50 * 12);
}

#[test]
fn unreachable_target_is_nacked_and_the_pins_keep_their_pulses() {
    for baud in BAUDS {
        unreachable_target_is_nacked_and_the_pins_keep_their_pulses_at(baud);
    }
}

/// [`unreachable_target_is_nacked_and_the_pins_keep_their_pulses`] with the firmware of one line rate.
fn unreachable_target_is_nacked_and_the_pins_keep_their_pulses_at(baud: u32) {
    let targets = avr_bench::targets();
    let mut stream = connect(boot(EmulatorConfig::new(baud)));
    let pose = targets.poses[7];
    assert!(matches!(
        stream.send(&pose).expect("link"),
        PoseResult::Acked { .. }
    ));
    let settled = host_pulses(&stream, &pose);
    let before = settled_pins(&mut stream, &settled);
    // Body lifted 1 m: no leg reaches.
    let lifted = Pose {
        z_m: 1.0,
        ..Pose::default()
    };
    let result = stream.send(&lifted).expect("link");
    assert!(
        matches!(result, PoseResult::Nacked(NackReason::Unreachable { .. })),
        "{result:?}"
    );
    // A non-finite target is refused too.
    let nan = Pose {
        roll_rad: f32::NAN,
        ..Pose::default()
    };
    assert!(matches!(
        stream.send(&nan).expect("link"),
        PoseResult::Nacked(NackReason::NonFinite)
    ));
    let want = host_pulses(&stream, &pose);
    assert_pins(&before, &want, "before the refusals");
    let after = pins(&mut stream);
    assert_pins(&after, &want, "after the refusals");
    let rb = stream.client_mut().ack(Request::GetState).expect("state");
    assert_eq!(
        rb.pulses_half_us,
        host_pulses(&stream, &pose),
        "the held target is the last reachable one"
    );
    assert_eq!(stream.stats().nacked, 2);
    assert_eq!(stream.client_mut().link_mut().pulse_stats().errors, 0);
}

/// Sends raw bytes and collects the answers that arrive within `wait`.
fn raw_exchange(link: &mut EmulatorLink, bytes: &[u8], wait: Duration) -> Vec<DeviceToHost> {
    integration_tests::wire::answers(link, bytes, wait, None)
}

#[test]
fn garbage_and_bad_crc_frames_are_nacked_and_the_next_good_frame_works() {
    for baud in BAUDS {
        garbage_and_bad_crc_frames_are_nacked_and_the_next_good_frame_works_at(baud);
    }
}

/// [`garbage_and_bad_crc_frames_are_nacked_and_the_next_good_frame_works`] with the firmware of one line rate.
fn garbage_and_bad_crc_frames_are_nacked_and_the_next_good_frame_works_at(baud: u32) {
    let mut link = boot(EmulatorConfig::new(baud));
    // Long enough for the oversize frame (258 bytes, 24 ms) and an answer.
    let wait = Duration::from_millis(60);
    let hello = frame(
        1,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    );
    assert!(matches!(
        raw_exchange(&mut link, &hello, wait)[..],
        [DeviceToHost::HelloAck { seq: 1, .. }]
    ));
    let nack = |reason| DeviceToHost::Nack { seq: None, reason };

    // A good frame with one bit flipped in its CRC.
    let mut bad_crc = frame(2, Request::GetState);
    let n = bad_crc.len();
    bad_crc[n - 2] ^= 0x10;
    assert_eq!(
        raw_exchange(&mut link, &bad_crc, wait),
        [nack(NackReason::BadCrc)]
    );

    // Line noise that is not COBS, ended by a delimiter.
    let garbage = [0x00, 0x07, 0x41, 0x42, 0x00];
    assert_eq!(
        raw_exchange(&mut link, &garbage, wait),
        [nack(NackReason::BadFrame)]
    );

    // A frame longer than the device's buffer.
    let mut oversize = vec![0x00];
    oversize.extend(std::iter::repeat_n(0x55, 2 * MAX_DECODED_LEN));
    oversize.push(0x00);
    assert_eq!(
        raw_exchange(&mut link, &oversize, wait),
        [nack(NackReason::Oversize)]
    );

    // The next good frame works, and the device counted the bad ones.
    let answers = raw_exchange(&mut link, &frame(3, Request::GetState), wait);
    let [DeviceToHost::Ack { seq: 3, readback }] = &answers[..] else {
        panic!("{answers:?}");
    };
    assert_eq!(readback.frames_bad, 3);
    assert_eq!(readback.frames_ok, 2);
    assert_eq!(link.mcu().resets().count, 0);
}

#[test]
fn link_loss_stops_the_outputs_within_the_timeout() {
    for baud in BAUDS {
        link_loss_stops_the_outputs_within_the_timeout_at(baud);
    }
}

/// [`link_loss_stops_the_outputs_within_the_timeout`] with the firmware of one line rate.
fn link_loss_stops_the_outputs_within_the_timeout_at(baud: u32) {
    const TIMEOUT_MS: u64 = 100;
    // The main loop's poll interval is far below 1 ms; the outputs stop after the pulse in
    // progress (at most 2.5 ms) and the last pulse started up to one period before.
    const LATE_MS: u64 = 25;
    let mut stream = connect(boot(EmulatorConfig::new(baud)));
    assert!(matches!(
        stream.send(&avr_bench::targets().poses[3]).expect("link"),
        PoseResult::Acked { .. }
    ));
    let sent = stream.client().link().now();
    stream
        .client_mut()
        .ack(Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: TIMEOUT_MS as u16,
            action: LinkLossAction::Disable,
        }))
        .expect("timeout set");
    // The last valid frame reached the device between `sent` and `answered`.
    let answered = stream.client().link().now();
    let link = stream.client_mut().link_mut();
    link.idle(Duration::from_millis(TIMEOUT_MS + 100))
        .expect("runs");
    let timeout = Duration::from_millis(TIMEOUT_MS);
    for (ch, p) in link.last_pulses().iter().enumerate() {
        let p = p.unwrap_or_else(|| panic!("channel {ch} pulsed before the link loss"));
        let rise = quad_host::emu::cycles_to_duration(p.rise_cycle);
        let period = quad_host::emu::cycles_to_duration(PERIOD_CYCLES);
        assert!(
            rise + period >= sent + timeout,
            "channel {ch}: pulses stopped at {rise:?}, before the timeout"
        );
        assert!(
            rise <= answered + timeout + Duration::from_millis(LATE_MS),
            "channel {ch}: still pulsing at {rise:?}"
        );
    }
    assert_eq!(link.mcu().servo_levels(), 0, "all pins low");
    let seen = link.next_pulses().expect("runs");
    assert!(
        seen.iter().all(Option::is_none),
        "no pulse after the failsafe"
    );
    // The next valid frame reports the failsafe once; the outputs stay off until enabled.
    let rb = stream.client_mut().ack(Request::GetState).expect("state");
    assert!(rb.flags.contains(Flags::FAILSAFE_ACTIVE));
    assert!(!rb.flags.contains(Flags::OUTPUTS_ENABLED));
    let rb = stream.client_mut().ack(Request::GetState).expect("state");
    assert!(!rb.flags.contains(Flags::FAILSAFE_ACTIVE));
    assert_eq!(stream.client_mut().link_mut().pulse_stats().errors, 0);
}

/// Seeded reachable poses (seed 000's ranges, a different seed than the benchmark's).
fn soak_poses(n: usize) -> Vec<Pose> {
    let robot = avr_bench::robot();
    let mut rng = Rng::new(0x50A6_0001);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let [r, p, y] = avr_bench::POSE_RANGE_DEG.map(|d| (rng.range(-d, d) as f32).to_radians());
        let pose = Pose {
            roll_rad: r,
            pitch_rad: p,
            yaw_rad: y,
            x_m: rng.range(-0.02, 0.02) as f32,
            y_m: rng.range(-0.02, 0.02) as f32,
            z_m: rng.range(-0.02, 0.02) as f32,
        };
        if body::Solver::new(&robot)
            .inverse_at_stance(
                &pose,
                &BodyConfig::default(),
                STANCE_HEIGHT_M,
                ReachPolicy::Reject,
            )
            .is_ok()
        {
            out.push(pose);
        }
    }
    out
}

#[test]
fn soak_of_1000_poses_with_line_corruption_has_no_wrong_pulse_and_no_reset() {
    let faults: Faults = "drop=0.0005,flip=0.0005,dup=0.01,trunc=0.01,stall=0.005,stall_ms=30"
        .parse()
        .expect("faults");
    let config = EmulatorConfig {
        faults,
        seed: 7,
        ..EmulatorConfig::new(1_000_000)
    };
    let link = EmulatorLink::boot(&firmware(build::FIRMWARE_1MBAUD), config)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut stream = connect(link);
    let poses = soak_poses(1000);
    for (i, pose) in poses.iter().enumerate() {
        // An ack whose readback passed the check, or a nack with the host's own reason (a few
        // poses take a servo beyond its default travel).
        let result = stream.send(pose).expect("link");
        assert!(
            matches!(result, PoseResult::Acked { .. } | PoseResult::Nacked(_)),
            "pose {i}: {result:?}"
        );
    }
    let stats = stream.stats();
    assert_eq!(stats.acked + stats.nacked, 1000);
    assert!(stats.nacked < 50, "{} poses refused", stats.nacked);
    assert_eq!((stats.lost, stats.readback_mismatches), (0, 0));
    assert!(stats.max_angle_err_rad <= AVR_ANGLE_TOLERANCE_RAD);
    let link = stream.client_mut().link_mut();
    let line = link.line_stats();
    assert!(
        line.dropped > 0 && line.flipped > 0 && line.truncated > 0 && line.duplicated > 0,
        "faults were injected: {line:?}"
    );
    let pulses = link.pulse_stats();
    assert_eq!(pulses.errors, 0, "{:?}", pulses.first_error);
    assert!(pulses.checked > 1000);
    assert_eq!(link.mcu().resets().count, 0, "no reset during the soak");
    eprintln!(
        "soak: {:.1} poses/s (simulated), {} retries, line {line:?}",
        stats.poses_per_s, stats.retries
    );
}

#[test]
fn watchdog_is_on_survives_a_long_eeprom_save_and_resets_a_hung_cpu() {
    for baud in BAUDS {
        watchdog_is_on_survives_a_long_eeprom_save_and_resets_a_hung_cpu_at(baud);
    }
}

/// [`watchdog_is_on_survives_a_long_eeprom_save_and_resets_a_hung_cpu`] with the firmware of one line rate.
fn watchdog_is_on_survives_a_long_eeprom_save_and_resets_a_hung_cpu_at(baud: u32) {
    let mut stream = connect(boot(EmulatorConfig::new(baud)));
    let wdtcsr = stream.client().link().mcu().wdtcsr();
    assert_eq!(wdtcsr & WDTCSR_WDE, WDTCSR_WDE, "watchdog in reset mode");
    assert_eq!(wdtcsr & WDTCSR_WDIE, 0, "no interrupt mode");
    assert_eq!(wdtcsr & WDTCSR_WDP_MASK, WDTCSR_WDP_250MS, "250 ms");

    // Saving the calibration writes ~190 EEPROM bytes at 3.4 ms each: far longer than the
    // watchdog timeout. The firmware feeds the watchdog while it waits.
    let link = stream.client().link();
    let t0 = link.now();
    let rb = stream
        .client_mut()
        .ack(Request::SaveCalibration)
        .expect("saved");
    let save = stream.client().link().now() - t0;
    assert!(
        save > Duration::from_millis(2 * WATCHDOG_TIMEOUT_MS),
        "the save took {save:?}"
    );
    assert!(!rb.flags.contains(Flags::CALIBRATION_DEFAULT));
    assert_eq!(stream.client().link().mcu().resets().count, 0);

    // Hang the CPU the way a runaway program would: in the C runtime's final `cli; rjmp .`.
    let image = elf::Elf::read(stream.client().link().elf()).expect("ELF");
    let exit = image.symbol("_exit").expect("_exit in the ELF");
    assert!(matches!(
        stream.send(&avr_bench::targets().poses[0]).expect("link"),
        PoseResult::Acked { .. }
    ));
    let link = stream.client_mut().link_mut();
    let hang_at = link.now();
    link.mcu_mut().jump(exit);
    link.idle(Duration::from_millis(WATCHDOG_TIMEOUT_MS * 3 / 2))
        .expect("runs");
    let resets = link.mcu().resets();
    assert_eq!(resets.count, 1, "the watchdog reset the MCU");
    assert_eq!(
        resets.last_mcusr & MCUSR_WDRF,
        MCUSR_WDRF,
        "by the watchdog"
    );
    let after = quad_host::emu::cycles_to_duration(resets.last_cycle.expect("reset"));
    let hung = after - hang_at;
    // The watchdog's own oscillator in simavr is exact; the last feed was shortly before.
    assert!(
        hung <= Duration::from_millis(WATCHDOG_TIMEOUT_MS + 5),
        "reset {hung:?} after the hang"
    );
    // After the reset: pins low, no pulses, a new handshake needed, the saved calibration back.
    assert_eq!(link.mcu().servo_levels(), 0);
    let seen = link.next_pulses().expect("runs");
    assert!(seen.iter().all(Option::is_none), "no pulse after the reset");
    let mut client = Client::new(&mut *link, ClientConfig::emulator());
    let refused = client
        .request(Request::SetBodyPose(Pose::default()))
        .expect_err("handshake needed");
    assert!(refused.to_string().contains("hello"), "{refused}");
    client.hello().expect("handshake after the reset");
    let rb = client.ack(Request::GetState).expect("state");
    assert!(
        !rb.flags.contains(Flags::CALIBRATION_DEFAULT),
        "the saved calibration was loaded"
    );
    assert!(!rb.flags.contains(Flags::OUTPUTS_ENABLED));
}

#[test]
fn angle_tolerance_bounds_the_firmware_against_the_host() {
    for baud in BAUDS {
        angle_tolerance_bounds_the_firmware_against_the_host_at(baud);
    }
}

/// [`angle_tolerance_bounds_the_firmware_against_the_host`] with the firmware of one line rate.
fn angle_tolerance_bounds_the_firmware_against_the_host_at(baud: u32) {
    // The bound the client applies to the ATmega2560's angles, checked on 100 poses: every
    // readback within it, and the bound not looser than ten times the largest difference.
    let mut stream = connect(boot(EmulatorConfig::new(baud)));
    for pose in soak_poses(100) {
        let result = stream.send(&pose).expect("link");
        assert!(
            matches!(result, PoseResult::Acked { .. } | PoseResult::Nacked(_)),
            "{result:?}"
        );
    }
    assert!(stream.stats().acked >= 90);
    let worst = stream.stats().max_angle_err_rad;
    eprintln!("largest |firmware - host| angle: {worst:e} rad");
    assert!(worst <= AVR_ANGLE_TOLERANCE_RAD);
    assert!(
        worst * 10.0 >= AVR_ANGLE_TOLERANCE_RAD,
        "AVR_ANGLE_TOLERANCE_RAD {AVR_ANGLE_TOLERANCE_RAD:e} is far looser than {worst:e}"
    );
}

#[test]
fn flash_script_writes_the_built_elf_with_the_wiring_bootloader_protocol() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_owned();
    for (baud, bin) in [
        ("115200", build::FIRMWARE),
        ("1000000", build::FIRMWARE_1MBAUD),
    ] {
        let mut cmd = Command::new("bash");
        cmd.current_dir(&root).args([
            "scripts/flash.sh",
            "--baud",
            baud,
            "--dry-run",
            "/dev/ttyACM0",
        ]);
        // As from a shell: no settings of the cargo running this test.
        for (key, _) in std::env::vars() {
            if (key.starts_with("CARGO_") && key != "CARGO_HOME")
                || key.starts_with("RUSTC")
                || key == "RUSTFLAGS"
                || key == "RUSTUP_TOOLCHAIN"
                || key == "CARGO"
            {
                cmd.env_remove(key);
            }
        }
        let out = cmd.output().expect("bash runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let elf = firmware(bin);
        assert_eq!(
            stdout.lines().last().unwrap_or(""),
            format!(
                "avrdude -c wiring -p atmega2560 -P /dev/ttyACM0 -b 115200 -D -U flash:w:{}:e",
                elf.display()
            )
        );
    }
}
