//! The MPU-6050 on the firmware's TWI, in simavr: the flashed ELF with a virtual sensor at
//! 0x68 (`quad_host::emu`, `EmulatorConfig::imu`) fed by `quad_device::sim::imu` sources.
//!
//! - boot: `WHO_AM_I` read and `CONFIG_SEQUENCE` written, in order (the virtual sensor records
//!   the writes); no sensor → the firmware boots and an onboard motion runs as before; a
//!   wrong identity → `WrongId`;
//! - the trot steered at 20 Hz with the sensor read: the read rate from the bursts the sensor
//!   saw (≥ 100 Hz), no late servo frame, no UART byte lost, the worst frame (the firmware
//!   times each `Device::poll` with the sensor's step) ≤ 50 % of 20 ms, interrupts off within the UART's cover
//!   (the link checks it at every step);
//! - faults mid-run: NAK, stuck data, SDA held low → the right `ImuFault` reaches the device,
//!   and samples flow again once the fault clears.
//!
//! The device's sensor state is read from SRAM through the firmware's `IMU_WINDOW` symbol
//! (`firmware_avr::imu::Window`), the test's window until the protocol reports it.
//! `--nocapture` prints the figures of BENCHMARKS.md. All times are simulated.

use integration_tests::wire;
use kin_core::motion::gait::{GaitParams, Pattern};
use quad_device::imu::mpu6050::{CONFIG_SEQUENCE, READ_RATE_HZ};
use quad_device::imu::ImuFault;
use quad_device::sim::imu::{FaultWindow, Faulty, LevelStill, Noisy};
use quad_host::emu::elf::Elf;
use quad_host::emu::{build, SharedImuSource, CYCLES_PER_US, PERIOD_CYCLES};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::Link;
use quad_protocol::{DeviceToHost, MotionCommand, Request, PROTOCOL_VERSION};
use std::time::Duration;

/// The read rate the estimator needs, Hz.
const MIN_READ_RATE_HZ: f64 = 100.0;

/// The worst frame allowed (the frame's work and the sensor's step): half a servo frame, µs.
const MAX_FRAME_US: u16 = 10_000;

const STANCE_HEIGHT_M: f32 = 0.277;

/// The firmware's `imu::Window`, as read from SRAM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Window {
    samples: u32,
    fault: u8,
    who_am_i: u8,
    recoveries: u16,
    longest_frame_us: u16,
    bursts_skipped: u16,
}

impl Window {
    /// The fault as the device holds it.
    fn fault(&self) -> Option<&'static str> {
        match self.fault {
            0 => None,
            1 => Some("Absent"),
            2 => Some("WrongId"),
            3 => Some("Nak"),
            4 => Some("Stuck"),
            5 => Some("BusHeld"),
            _ => Some("unknown code"),
        }
    }
}

fn name_of(f: ImuFault) -> &'static str {
    match f {
        ImuFault::Absent => "Absent",
        ImuFault::WrongId { .. } => "WrongId",
        ImuFault::Nak => "Nak",
        ImuFault::Stuck => "Stuck",
        ImuFault::BusHeld => "BusHeld",
    }
}

struct Board {
    link: EmulatorLink,
    window_addr: u16,
    seq: u16,
}

impl Board {
    fn boot(imu: Option<SharedImuSource>) -> Board {
        let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
        let window_addr = Elf::read(&elf)
            .expect("the ELF reads")
            .data_symbol("IMU_WINDOW")
            .expect("the firmware has its IMU_WINDOW");
        let config = EmulatorConfig {
            imu,
            ..EmulatorConfig::new(115_200)
        };
        let link = EmulatorLink::boot(&elf, config).unwrap_or_else(|e| panic!("{e}"));
        let mut board = Board {
            link,
            window_addr,
            seq: 0,
        };
        board.ask(Request::Hello {
            version: PROTOCOL_VERSION,
        });
        board
    }

    fn window(&self) -> Window {
        let b = self.link.mcu().data_bytes(self.window_addr, 12);
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        Window {
            samples: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            fault: b[4],
            who_am_i: b[5],
            recoveries: u16_at(6),
            longest_frame_us: u16_at(8),
            bursts_skipped: u16_at(10),
        }
    }

    /// Restarts the window's worst frame (the host writes SRAM between two instructions, as a
    /// debugger does).
    fn reset_longest_frame(&mut self) {
        let addr = self.window_addr + 8;
        self.link.mcu_mut().write_data(addr, &[0, 0]);
    }

    fn ask(&mut self, request: Request) -> DeviceToHost {
        self.seq = self.seq.wrapping_add(1);
        let answer = wire::ask(&mut self.link, self.seq, request, Duration::from_secs(2));
        assert!(
            !matches!(answer, DeviceToHost::Nack { .. }),
            "{request:?}: {answer:?}"
        );
        answer
    }

    fn idle_s(&mut self, s: f64) {
        self.link
            .idle(Duration::from_secs_f64(s))
            .expect("the MCU runs");
    }

    fn now_s(&self) -> f64 {
        self.link.now().as_secs_f64()
    }

    fn wait_idle(&mut self) {
        for _ in 0..600 {
            self.idle_s(0.037);
            if let DeviceToHost::MotionAck { status, .. } = self.ask(Request::GetMotion) {
                if status.kind.is_none() {
                    return;
                }
            }
        }
        panic!("the motion did not end");
    }
}

fn noisy_level(seed: u64) -> SharedImuSource {
    SharedImuSource::new(Noisy::mpu6050(LevelStill, seed))
}

#[test]
fn boot_reads_who_am_i_and_writes_the_configuration_then_samples_flow() {
    let mut board = Board::boot(Some(noisy_level(1)));
    board.idle_s(0.5);
    let bus = board.link.imu_bus().expect("a sensor").clone();
    let w = board.window();
    println!(
        "{w:?}; writes {:x?}; {} bursts",
        bus.writes,
        bus.burst_cycles.len()
    );
    assert!(bus.who_am_i_reads >= 1, "WHO_AM_I read");
    assert_eq!(
        bus.writes,
        CONFIG_SEQUENCE.to_vec(),
        "the configuration, in order"
    );
    assert_eq!(w.who_am_i, 0x68);
    assert_eq!(w.fault(), None);
    assert!(w.samples > 40, "samples pushed: {}", w.samples);
    assert!(bus.burst_cycles.len() as u32 >= w.samples);
}

#[test]
fn without_a_sensor_the_firmware_boots_reports_absent_and_stands_up_as_before() {
    let mut board = Board::boot(None);
    assert!(board.link.imu_bus().is_none());
    board.idle_s(0.2);
    let w = board.window();
    assert_eq!(w.fault(), Some("Absent"), "{w:?}");
    assert_eq!(w.samples, 0);
    board.ask(Request::SetOutputs { enabled: true });
    board.ask(Request::StartMotion(MotionCommand::StandUp));
    board.wait_idle();
    match board.ask(Request::GetMotion) {
        DeviceToHost::MotionAck { status, .. } => assert_eq!(status.fault, None),
        other => panic!("{other:?}"),
    }
    let w = board.window();
    assert_eq!(w.fault(), Some("Absent"));
    assert_eq!(w.recoveries, 0, "the bus is left alone");
    assert_eq!(board.link.rx_overruns(), 0);
}

#[test]
fn a_wrong_identity_is_a_typed_fault_and_nothing_is_configured() {
    let source = Faulty {
        inner: Noisy::mpu6050(LevelStill, 2),
        windows: vec![FaultWindow {
            from_s: 0.0,
            until_s: None,
            fault: ImuFault::WrongId { who_am_i: 0x72 },
        }],
    };
    let mut board = Board::boot(Some(SharedImuSource::new(source)));
    board.idle_s(0.3);
    let w = board.window();
    assert_eq!(w.fault(), Some("WrongId"), "{w:?}");
    assert_eq!(w.who_am_i, 0x72);
    let bus = board.link.imu_bus().expect("a sensor");
    assert!(bus.writes.is_empty(), "{:x?}", bus.writes);
    assert!(bus.burst_cycles.is_empty());
}

/// Cycles a servo period may exceed 20 ms by (as `avr_motion`).
const PERIOD_SLACK_CYCLES: u64 = 50 * CYCLES_PER_US;

/// What one steered trot showed.
#[derive(Debug)]
struct Trot {
    span_s: f64,
    command_hz: f64,
    burst_hz: f64,
    sample_hz: f64,
    skipped: u16,
    frames: u64,
    late: u64,
    gaps: u64,
    bytes_lost: u64,
    worst_frame_us: u16,
    interrupts_off_receiving_cycles: u64,
    fault: Option<&'static str>,
}

/// Stand-up, then a trot for `trot_s` with a velocity command every 50 ms.
fn steered_trot(imu: Option<SharedImuSource>, trot_s: f64) -> Trot {
    let mut board = Board::boot(imu);
    board.ask(Request::SetOutputs { enabled: true });
    board.ask(Request::StartMotion(MotionCommand::StandUp));
    board.wait_idle();
    board.ask(Request::StartMotion(MotionCommand::Walk {
        gait: Pattern::Trot,
        body_height_m: STANCE_HEIGHT_M,
        step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * STANCE_HEIGHT_M,
        cycle_s: GaitParams::DEFAULT_CYCLE_S,
        velocity_timeout_ms: 500,
    }));
    // Only the trot's frames.
    board.idle_s(0.1);
    board.reset_longest_frame();
    board.link.mcu_mut().reset_interrupts_off();
    board.link.reset_pulse_steps();
    let start_s = board.now_s();
    let start_cycle = board.link.mcu().cycle();
    let samples_before = board.window().samples;
    let mut late = 0u64;
    let mut frames = 0u64;
    let mut k = 0u32;
    while board.now_s() - start_s < trot_s {
        let slot_end = start_s + 0.05 * f64::from(k + 1);
        let (vx, wz) =
            [(0.02, 0.0), (0.03, 0.05), (0.0, -0.08), (-0.02, 0.0)][(k / 20 % 4) as usize];
        match board.ask(Request::SetVelocity {
            forward_m_s: vx,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: wz,
        }) {
            DeviceToHost::MotionAck { status, .. } => assert!(status.kind.is_some()),
            other => panic!("{other:?}"),
        }
        // Two consecutive frames watched every fourth slot (watching takes two periods; the
        // other slots make the time up, so that the commands keep their 20 Hz on average).
        if k.is_multiple_of(4) {
            let a = board.link.next_pulses().expect("runs");
            let b = board.link.next_pulses().expect("runs");
            for c in 0..12 {
                if let (Some(p), Some(q)) = (a[c], b[c]) {
                    frames += 1;
                    if q.rise_cycle - p.rise_cycle > PERIOD_CYCLES + PERIOD_SLACK_CYCLES {
                        late += 1;
                    }
                }
            }
        }
        let left = slot_end - board.now_s();
        if left > 0.0 {
            board.idle_s(left);
        }
        k += 1;
    }
    let span_s = board.now_s() - start_s;
    let end_cycle = board.link.mcu().cycle();
    let bursts = board.link.imu_bus().map_or(0, |bus| {
        bus.burst_cycles
            .iter()
            .filter(|&&c| c >= start_cycle && c < end_cycle)
            .count()
    });
    let w = board.window();
    Trot {
        span_s,
        command_hz: f64::from(k) / span_s,
        burst_hz: bursts as f64 / span_s,
        sample_hz: f64::from(w.samples - samples_before) / span_s,
        skipped: w.bursts_skipped,
        frames,
        late,
        gaps: board.link.pulse_steps().gaps,
        bytes_lost: board.link.rx_overruns(),
        worst_frame_us: w.longest_frame_us,
        interrupts_off_receiving_cycles: board.link.mcu().interrupts_off().longest_receiving_cycles,
        fault: w.fault(),
    }
}

/// One byte time at the fastest supported line rate (as `avr_interrupts`), cycles.
const BYTE_CYCLES_AT_1MBAUD: u64 = 160;

#[test]
fn the_trot_steered_at_20_hz_keeps_its_frames_while_the_sensor_is_read_at_100_hz_or_more() {
    let trot_s: f64 = std::env::var("QUAD_IMU_TROT_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let with = steered_trot(Some(noisy_level(3)), trot_s);
    let without = steered_trot(None, trot_s);
    for (name, t) in [("with the sensor", &with), ("without", &without)] {
        println!(
            "trot {name}: {:.2} s, velocity commands at {:.1} Hz; sensor bursts {:.1} Hz \
             (configured {READ_RATE_HZ} Hz), samples pushed {:.1} Hz, {} reads skipped; {} \
             channel frames watched, {} late, {} gaps; {} bytes lost; worst frame {} µs ({:.1} % \
             of 20 ms); longest interrupts-off stretch while receiving {} cycles",
            t.span_s,
            t.command_hz,
            t.burst_hz,
            t.sample_hz,
            t.skipped,
            t.frames,
            t.late,
            t.gaps,
            t.bytes_lost,
            t.worst_frame_us,
            f64::from(t.worst_frame_us) / 200.0,
            t.interrupts_off_receiving_cycles,
        );
        assert!(t.command_hz >= 19.5, "{name}: {t:?}");
        assert!(t.frames > 0, "{name}: {t:?}");
        assert_eq!(t.late, 0, "{name}: late servo frames");
        assert_eq!(t.gaps, 0, "{name}: missed servo frames");
        assert_eq!(t.bytes_lost, 0, "{name}: UART bytes lost");
        assert!(t.worst_frame_us <= MAX_FRAME_US, "{name}: {t:?}");
        assert!(
            t.interrupts_off_receiving_cycles <= BYTE_CYCLES_AT_1MBAUD,
            "{name}: {t:?}"
        );
    }
    assert!(with.burst_hz >= MIN_READ_RATE_HZ, "{with:?}");
    assert!(with.sample_hz >= MIN_READ_RATE_HZ, "{with:?}");
    assert_eq!(with.fault, None);
    assert_eq!(without.fault, Some("Absent"));
}

/// Boots with `fault` injected from 1.0 s to 2.0 s; checks that it reaches the device and
/// that samples flow again after.
fn fault_then_recovery(fault: ImuFault) -> Window {
    let source = Faulty {
        inner: Noisy::mpu6050(LevelStill, 4),
        windows: vec![FaultWindow {
            from_s: 1.0,
            until_s: Some(2.0),
            fault,
        }],
    };
    let mut board = Board::boot(Some(SharedImuSource::new(source)));
    board.idle_s(0.9 - board.now_s());
    let before = board.window();
    assert_eq!(before.fault(), None, "{fault:?}: before: {before:?}");
    assert!(before.samples > 50);
    board.idle_s(0.5);
    let during = board.window();
    assert_eq!(
        during.fault(),
        Some(name_of(fault)),
        "{fault:?}: during: {during:?}"
    );
    // Still there near the window's end: no sample got through meanwhile.
    board.idle_s(0.5);
    let late = board.window();
    assert_eq!(
        late.fault(),
        Some(name_of(fault)),
        "{fault:?}: late: {late:?}"
    );
    assert_eq!(
        late.samples, during.samples,
        "{fault:?}: no sample while it lasts"
    );
    board.idle_s(1.1);
    let after = board.window();
    assert_eq!(after.fault(), None, "{fault:?}: after: {after:?}");
    assert!(
        after.samples >= during.samples + 50,
        "{fault:?}: samples flow again: {during:?} → {after:?}"
    );
    println!("{fault:?}: before {before:?}\n  during {during:?}\n  after {after:?}");
    after
}

#[test]
fn a_nak_mid_run_is_reported_and_the_sensor_is_read_again_when_it_answers() {
    let after = fault_then_recovery(ImuFault::Nak);
    assert_eq!(after.recoveries, 0, "SDA stayed high: no bus recovery");
}

#[test]
fn stuck_data_mid_run_is_reported_and_fresh_data_clears_it() {
    fault_then_recovery(ImuFault::Stuck);
}

#[test]
fn sda_held_low_mid_run_is_a_held_bus_recovered_by_clocking_scl() {
    let after = fault_then_recovery(ImuFault::BusHeld);
    assert!(after.recoveries >= 1, "{after:?}");
}
