//! The onboard motions of the release firmware in simavr, black box through its UART and its
//! twelve servo pins: stand-up, a trot with a changing velocity command, seed 001's roll and
//! pitch sways and yaw turn, and sit. At every servo frame watched: every channel pulses once
//! per 20 ms period (no missed or late frame), and no joint moves more than the limiter's bound
//! between two consecutive frames (measured on the pins, through the calibration's gain).
//!
//! The trot runs for `QUAD_TROT_S` seconds of emulated time (default [`TROT_S`], bounded for
//! CI on two cores; `BENCHMARKS.md` has the 60 s figures). All times are simulated.

use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S;
use quad_host::emu::{build, Pulse, CYCLES_PER_US, PERIOD_CYCLES};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::Link;
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, HostToDevice, MotionCommand, MotionKind,
    Request, ServoId, MAX_DECODED_LEN, MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use std::time::{Duration, Instant};

/// Default emulated trot, s.
const TROT_S: f32 = 6.0;

/// A servo period may come late by at most this much (the timer runs the frames, the main
/// loop only updates the compare values), cycles: 50 µs.
const PERIOD_SLACK_CYCLES: u64 = 50 * CYCLES_PER_US;

struct Rig {
    link: EmulatorLink,
    acc: Accumulator<MAX_DECODED_LEN>,
    seq: u16,
    answers: Vec<DeviceToHost>,
    us_per_rad: [f64; 12],
    /// Last pulse of each channel in the watched run of frames.
    last: Option<[Pulse; 12]>,
    frames: u64,
    late: u64,
    max_step_rad: f64,
    max_allowed_rad: f64,
}

impl Rig {
    fn boot() -> Rig {
        let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
        let link = EmulatorLink::boot(&elf, EmulatorConfig::new(115_200))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut rig = Rig {
            link,
            acc: Accumulator::new(),
            seq: 0,
            answers: Vec::new(),
            us_per_rad: [0.0; 12],
            last: None,
            frames: 0,
            late: 0,
            max_step_rad: 0.0,
            max_allowed_rad: 0.0,
        };
        assert!(matches!(
            rig.ask(Request::Hello {
                version: PROTOCOL_VERSION
            }),
            DeviceToHost::HelloAck { .. }
        ));
        for servo in ServoId::ALL {
            match rig.ask(Request::GetCalibration { servo }) {
                DeviceToHost::Calibration { calibration, .. } => {
                    rig.us_per_rad[servo.index()] = f64::from(calibration.us_per_rad);
                }
                other => panic!("{other:?}"),
            }
        }
        rig
    }

    fn stance_height_m(&mut self) -> f32 {
        match self.ask(Request::Hello {
            version: PROTOCOL_VERSION,
        }) {
            DeviceToHost::HelloAck { info, .. } => info.pose_config.stance_height_m,
            other => panic!("{other:?}"),
        }
    }

    /// Sends `request` and watches frames until its answer arrived.
    fn ask(&mut self, request: Request) -> DeviceToHost {
        self.seq = self.seq.wrapping_add(1);
        let mut buf = [0u8; MAX_FRAME_LEN];
        let frame = encode_frame(
            &HostToDevice {
                seq: self.seq,
                request,
            },
            &mut buf,
        )
        .expect("encodes");
        self.link.send(frame).expect("send");
        // A motion start checks its samples (body IK each) before it answers.
        for _ in 0..250 {
            self.frame();
            if let Some(i) = self.answers.iter().position(|a| a.seq() == Some(self.seq)) {
                return self.answers.remove(i);
            }
        }
        panic!("no answer to {request:?}");
    }

    /// Watches one servo frame: one pulse per channel, a period after the last, each joint
    /// within the limiter's bound of its last position; then takes the device's answers.
    fn frame(&mut self) {
        let seen = self.link.next_pulses().expect("the MCU runs");
        let enabled = seen.iter().all(Option::is_some);
        if enabled {
            let now: [Pulse; 12] = std::array::from_fn(|c| seen[c].unwrap());
            if let Some(last) = self.last {
                self.frames += 1;
                for c in 0..12 {
                    let period = now[c].rise_cycle - last[c].rise_cycle;
                    if period > PERIOD_CYCLES + PERIOD_SLACK_CYCLES {
                        self.late += 1;
                    }
                    let (step, allowed) = integration_tests::pins::step_and_bound_rad(
                        &last[c],
                        &now[c],
                        self.us_per_rad[c],
                        f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S),
                    );
                    self.max_step_rad = self.max_step_rad.max(step);
                    self.max_allowed_rad = self.max_allowed_rad.max(allowed);
                    assert!(
                        step <= allowed,
                        "{:?}: {step} rad in one frame > {allowed}",
                        ServoId::ALL[c]
                    );
                }
            }
            self.last = Some(now);
        } else {
            self.last = None;
        }
        let mut buf = [0u8; 256];
        let n = self.link.recv(&mut buf, Duration::ZERO).expect("recv");
        let mut rest = &buf[..n];
        loop {
            match self.acc.feed::<DeviceToHost>(rest) {
                Feed::NeedMore => break,
                Feed::Frame { msg, remaining } => {
                    self.answers.push(msg);
                    rest = remaining;
                }
                other => panic!("unreadable answer: {other:?}"),
            }
        }
    }

    fn start(&mut self, m: MotionCommand) {
        match self.ask(Request::StartMotion(m)) {
            DeviceToHost::MotionAck { status, .. } => assert!(status.kind.is_some()),
            other => panic!("{m:?}: {other:?}"),
        }
    }

    fn running(&mut self) -> Option<MotionKind> {
        match self.ask(Request::GetMotion) {
            DeviceToHost::MotionAck { status, .. } => {
                assert_eq!(status.fault, None, "the motion stopped early");
                status.kind
            }
            other => panic!("{other:?}"),
        }
    }

    /// Frames until the motion ends (at most `max_s`).
    fn until_idle(&mut self, max_s: f32) {
        let max = (max_s * 50.0) as u32;
        let mut n = 0;
        while self.running().is_some() {
            for _ in 0..10 {
                self.frame();
            }
            n += 11;
            assert!(n < max, "the motion did not end within {max_s} s");
        }
    }
}

#[test]
fn onboard_stand_up_sways_yaw_turn_and_sit_keep_every_frame_and_the_speed_bound() {
    let mut rig = Rig::boot();
    rig.start(MotionCommand::StandUp);
    rig.until_idle(10.0);
    for axis in [Axis::Roll, Axis::Pitch] {
        rig.start(MotionCommand::Sway {
            axis,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: Some(2.0),
        });
        rig.until_idle(10.0);
    }
    rig.start(MotionCommand::YawTurn {
        yaw_rate_rad_s: 0.085,
        step_period_s: 2.0,
        lift_height_m: 0.03,
        duration_s: Some(2.0),
    });
    rig.until_idle(10.0);
    rig.start(MotionCommand::Sit);
    rig.until_idle(10.0);
    eprintln!(
        "{} frames watched, {} late, max joint step {:.4} rad (bound {:.4} rad + edge slack)",
        rig.frames,
        rig.late,
        rig.max_step_rad,
        DEFAULT_JOINT_SPEED_LIMIT_RAD_S * 0.02
    );
    assert_eq!(rig.late, 0, "late or missed servo frames");
    assert!(rig.frames > 300);
    assert!(rig.max_step_rad > 0.5 * f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S) * 0.02);
}

#[test]
fn onboard_stable_turn_keeps_every_frame_and_the_speed_bound() {
    let mut rig = Rig::boot();
    rig.start(MotionCommand::StandUp);
    rig.until_idle(10.0);
    let h = rig.stance_height_m();
    let MotionCommand::StableTurn {
        yaw_per_cycle_rad,
        lift_height_m,
        shift_fraction,
        ..
    } = MotionCommand::stable_turn(h, None)
    else {
        unreachable!("stable_turn is a stable turn")
    };
    // One 4 s cycle: every leg shifts and swings once, a second each.
    rig.start(MotionCommand::StableTurn {
        yaw_per_cycle_rad,
        cycle_s: 4.0,
        lift_height_m,
        shift_fraction,
        duration_s: Some(4.0),
    });
    assert_eq!(rig.running(), Some(MotionKind::StableTurn));
    rig.until_idle(20.0);
    eprintln!(
        "stable turn: {} frames watched, {} late, max joint step {:.4} rad",
        rig.frames, rig.late, rig.max_step_rad
    );
    assert_eq!(rig.late, 0, "late or missed servo frames");
    assert!(rig.frames > 200);
}

#[test]
fn onboard_trot_with_a_changing_velocity_keeps_every_frame_and_the_speed_bound() {
    let wall = Instant::now();
    let trot_s: f32 = std::env::var("QUAD_TROT_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(TROT_S);
    let mut rig = Rig::boot();
    let h = rig.stance_height_m();
    rig.start(MotionCommand::StandUp);
    rig.until_idle(10.0);

    rig.start(MotionCommand::Walk {
        gait: Pattern::Trot,
        body_height_m: h,
        step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
        cycle_s: GaitParams::DEFAULT_CYCLE_S,
        velocity_timeout_ms: 500,
    });
    let trot_frames_before = rig.frames;
    let trot_start = rig.link.now();
    let mut k = 0u32;
    while (rig.link.now() - trot_start).as_secs_f32() < trot_s {
        // A velocity command at 10 Hz, changing every second.
        let phase = (k / 10) % 4;
        let (vx, wz) = [(0.02, 0.0), (0.03, 0.05), (0.0, -0.08), (-0.02, 0.0)][phase as usize];
        match rig.ask(Request::SetVelocity {
            forward_m_s: vx,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: wz,
        }) {
            DeviceToHost::MotionAck { status, .. } => {
                assert_eq!(status.kind, Some(MotionKind::Walk))
            }
            other => panic!("velocity ({vx}, {wz}): {other:?}"),
        }
        for _ in 0..3 {
            rig.frame();
        }
        k += 1;
    }
    let trot_frames = rig.frames - trot_frames_before;
    let trot_late = rig.late;
    assert!(matches!(
        rig.ask(Request::StopMotion),
        DeviceToHost::MotionAck { .. }
    ));
    rig.until_idle(10.0);

    for axis in [Axis::Roll, Axis::Pitch] {
        rig.start(MotionCommand::Sway {
            axis,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: Some(2.0),
        });
        rig.until_idle(10.0);
    }
    rig.start(MotionCommand::YawTurn {
        yaw_rate_rad_s: 0.085,
        step_period_s: 2.0,
        lift_height_m: 0.03,
        duration_s: Some(2.0),
    });
    rig.until_idle(10.0);
    rig.start(MotionCommand::Sit);
    rig.until_idle(10.0);

    eprintln!(
        "trot {trot_s} s emulated: {trot_frames} frames watched, {trot_late} late; all motions: \
         {} frames watched, {} late, max joint step {:.4} rad (bound {:.4} rad + edge slack, \
         worst allowed {:.4}); wall {:.1} s",
        rig.frames,
        rig.late,
        rig.max_step_rad,
        DEFAULT_JOINT_SPEED_LIMIT_RAD_S * 0.02,
        rig.max_allowed_rad,
        wall.elapsed().as_secs_f64()
    );
    assert_eq!(rig.late, 0, "late or missed servo frames");
    assert!(trot_frames as f32 >= 0.9 * trot_s * 50.0 * 0.75);
    assert!(rig.max_step_rad > 0.5 * f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S) * 0.02);
}

/// Cut points of [`a_link_cut_anywhere_in_a_trot_stride_ends_it_at_the_stance`] spread over one
/// gait cycle.
const LINK_CUTS: u32 = 20;

/// The link-loss failsafe's timeout in that test, ms.
const LINK_TIMEOUT_MS: u16 = 200;

#[test]
fn a_link_cut_anywhere_in_a_trot_stride_ends_it_at_the_stance() {
    let mut rig = Rig::boot();
    let h = rig.stance_height_m();
    match rig.ask(Request::SetLinkTimeout(quad_protocol::LinkTimeout {
        timeout_ms: LINK_TIMEOUT_MS,
        action: quad_protocol::LinkLossAction::Hold,
    })) {
        DeviceToHost::Configured { .. } => {}
        other => panic!("SetLinkTimeout: {other:?}"),
    }
    rig.start(MotionCommand::StandUp);
    rig.until_idle(10.0);
    let stance = match rig.ask(Request::GetState) {
        DeviceToHost::Ack { readback, .. } => readback.angles_rad,
        other => panic!("GetState: {other:?}"),
    };
    let cycle_s = GaitParams::DEFAULT_CYCLE_S;
    for cut in 0..LINK_CUTS {
        rig.start(MotionCommand::Walk {
            gait: Pattern::Trot,
            body_height_m: h,
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
            cycle_s,
            velocity_timeout_ms: 500,
        });
        // Steered at 20 Hz for one cycle plus this cut's share of the next, then silence.
        let start = rig.link.now();
        let cut_at = Duration::from_secs_f32(cycle_s * (1.0 + cut as f32 / LINK_CUTS as f32));
        while rig.link.now() - start < cut_at {
            let answer = rig.ask(Request::SetVelocity {
                forward_m_s: 0.04,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.05,
            });
            assert!(
                matches!(answer, DeviceToHost::MotionAck { .. }),
                "{answer:?}"
            );
            rig.frame();
            rig.frame();
        }
        // The link is gone: every frame watched (the limiter's bound asserted) until the
        // failsafe has acted and well beyond.
        let silent = rig.link.now();
        while rig.link.now() - silent < Duration::from_millis(u64::from(LINK_TIMEOUT_MS) + 300) {
            rig.frame();
        }
        // Back: the motion ends (its stride finished, a ramp to the stance), reported.
        match rig.ask(Request::GetState) {
            DeviceToHost::Ack { readback, .. } => assert!(
                readback
                    .flags
                    .contains(quad_protocol::Flags::FAILSAFE_ACTIVE),
                "cut {cut}: the failsafe's action is reported on reconnect"
            ),
            other => panic!("GetState: {other:?}"),
        }
        let max = 200;
        let mut n = 0;
        loop {
            match rig.ask(Request::GetMotion) {
                DeviceToHost::MotionAck { status, .. } if status.kind.is_none() => break,
                DeviceToHost::MotionAck { .. } => {}
                other => panic!("GetMotion: {other:?}"),
            }
            for _ in 0..5 {
                rig.frame();
            }
            n += 1;
            assert!(n < max, "cut {cut}: the trot did not end");
        }
        // Every foot down: the target at the stance, and the pins there.
        let pulses_half_us = match rig.ask(Request::GetState) {
            DeviceToHost::Ack { readback, .. } => {
                assert_eq!(
                    readback.angles_rad, stance,
                    "cut {cut}: the trot ended away from the stance"
                );
                readback.pulses_half_us
            }
            other => panic!("GetState: {other:?}"),
        };
        for _ in 0..5 {
            rig.frame();
        }
        let pins = rig.link.next_pulses().expect("runs");
        // A period watched outside `frame`: the next frame starts a new run.
        rig.last = None;
        for (c, pin) in pins.iter().enumerate() {
            let width_us = pin.expect("the outputs are on").high_us();
            let readback_us = f64::from(pulses_half_us[c]) / 2.0;
            assert!(
                (width_us - readback_us).abs() <= 1.0,
                "cut {cut}: {:?} pulses {width_us} µs, the stance's {readback_us} µs",
                ServoId::ALL[c]
            );
        }
    }
    println!(
        "link cut at {LINK_CUTS} points of a trot stride: every trot ended at the stance, \
         {} frames watched, largest joint step {:.4} rad (bound {:.4}), {} late",
        rig.frames, rig.max_step_rad, rig.max_allowed_rad, rig.late
    );
    assert_eq!(rig.late, 0);
}
