//! The longest interrupts-off stretch while bytes arrive, per scenario and line rate, on the
//! firmware in simavr: pose streaming, every onboard motion polled at many phases of its frames,
//! and a trot and a walk steered at 20 Hz (teleop). Each stays within one byte time at 1 Mbaud
//! (160 cycles), well inside the two-byte receive buffer's cover that the emulator link checks
//! in every test. `--nocapture` prints the figures of BENCHMARKS.md.

use integration_tests::wire;
use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::Pose;
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::Link;
use quad_protocol::{DeviceToHost, LegSet, MotionCommand, Request, PROTOCOL_VERSION};
use std::time::Duration;

/// One byte time at the fastest supported line rate (10 bits of 16 cycles), cycles.
const BYTE_CYCLES_AT_1MBAUD: u64 = 160;

const STANCE_HEIGHT_M: f32 = 0.277;

struct Run {
    link: EmulatorLink,
    seq: u16,
}

impl Run {
    fn boot(bin: &str, baud: u32) -> Run {
        let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
        let link =
            EmulatorLink::boot(&elf, EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
        let mut run = Run { link, seq: 0 };
        run.ask(Request::Hello {
            version: PROTOCOL_VERSION,
        });
        run
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

    /// `request` every `gap` for `span`.
    fn repeat(&mut self, request: Request, gap: Duration, span: Duration) {
        let end = self.link.now() + span;
        while self.link.now() < end {
            self.link.idle(gap).expect("runs");
            self.ask(request);
        }
    }

    fn wait_idle(&mut self) {
        for _ in 0..600 {
            self.link.idle(Duration::from_millis(37)).expect("runs");
            if let DeviceToHost::MotionAck { status, .. } = self.ask(Request::GetMotion) {
                if status.kind.is_none() {
                    return;
                }
            }
        }
        panic!("the motion did not end");
    }

    /// The longest stretch while receiving since the last call, cycles.
    fn take_longest(&mut self) -> u64 {
        let n = self.link.mcu().interrupts_off().longest_receiving_cycles;
        self.link.mcu_mut().reset_interrupts_off();
        n
    }
}

fn motion_then_stop(run: &mut Run, motion: MotionCommand, steer: Option<Request>) {
    run.ask(Request::StartMotion(motion));
    match steer {
        // Teleop: a velocity command every 50 ms.
        Some(v) => run.repeat(v, Duration::from_millis(50), Duration::from_secs(3)),
        None => run.repeat(
            Request::GetMotion,
            Duration::from_millis(37),
            Duration::from_secs(2),
        ),
    }
    run.ask(Request::StopMotion);
    run.wait_idle();
}

#[test]
fn interrupts_off_while_receiving_stay_within_one_byte_time_in_every_scenario() {
    let velocity = Request::SetVelocity {
        forward_m_s: 0.04,
        lateral_m_s: 0.0,
        yaw_rate_rad_s: 0.1,
    };
    let walk = |gait| MotionCommand::Walk {
        gait,
        body_height_m: STANCE_HEIGHT_M,
        step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * STANCE_HEIGHT_M,
        cycle_s: GaitParams::DEFAULT_CYCLE_S,
        velocity_timeout_ms: 500,
    };
    let sway = |axis| MotionCommand::Sway {
        axis,
        amplitude_rad: 0.15,
        period_s: 2.0,
        duration_s: None,
    };
    let mut problems = Vec::new();
    for (bin, baud) in [
        (build::FIRMWARE, 115_200u32),
        (build::FIRMWARE_1MBAUD, 1_000_000),
    ] {
        let mut run = Run::boot(bin, baud);
        run.take_longest();
        let mut figures: Vec<(&str, u64)> = Vec::new();
        run.ask(Request::SetOutputs { enabled: true });
        for i in 0..40 {
            let a = 0.005 * i as f32;
            run.ask(Request::SetBodyPose(Pose::rotation(a, -a, 0.5 * a)));
        }
        figures.push(("pose streaming", run.take_longest()));
        run.ask(Request::StartMotion(MotionCommand::StandUp));
        run.wait_idle();
        figures.push(("stand up", run.take_longest()));
        for (name, axis) in [
            ("roll sway", Axis::Roll),
            ("pitch sway", Axis::Pitch),
            ("yaw sway", Axis::Yaw),
        ] {
            motion_then_stop(&mut run, sway(axis), None);
            figures.push((name, run.take_longest()));
        }
        let turn = MotionCommand::YawTurn {
            yaw_rate_rad_s: 0.2,
            step_period_s: 1.0,
            lift_height_m: 0.03,
            duration_s: None,
        };
        motion_then_stop(&mut run, turn, None);
        figures.push(("yaw turn", run.take_longest()));
        let path = MotionCommand::FootPath {
            path: PathKind::Ellipse,
            legs: LegSet::All,
            stride_m: 0.06,
            step_height_m: 0.03,
            duty_factor: 0.5,
            cycle_s: 2.0,
            duration_s: None,
        };
        motion_then_stop(&mut run, path, None);
        figures.push(("foot path, all legs", run.take_longest()));
        motion_then_stop(&mut run, walk(Pattern::Trot), Some(velocity));
        figures.push(("trot steered at 20 Hz", run.take_longest()));
        motion_then_stop(&mut run, walk(Pattern::Walk), Some(velocity));
        figures.push(("walk steered at 20 Hz", run.take_longest()));
        for (name, m) in [("sit", MotionCommand::Sit), ("rest", MotionCommand::Rest)] {
            run.ask(Request::StartMotion(m));
            run.wait_idle();
            figures.push((name, run.take_longest()));
        }
        for (name, cycles) in figures {
            println!("{bin} @ {baud}: {name}: longest interrupts-off stretch while receiving {cycles} cycles");
            if cycles > BYTE_CYCLES_AT_1MBAUD {
                problems.push(format!("{bin} @ {baud}, {name}: {cycles} cycles"));
            }
        }
        assert_eq!(run.link.rx_overruns(), 0, "{bin}: bytes lost");
    }
    assert!(
        problems.is_empty(),
        "stretches beyond one byte time at 1 Mbaud ({BYTE_CYCLES_AT_1MBAUD} cycles):\n{}",
        problems.join("\n")
    );
}
