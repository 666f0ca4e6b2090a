//! The replay of an onboard motion ([`quad_host::replay`]) against what a device showed: the
//! simulated device's frames (the same engine on the same math) pass exactly, and one wrong
//! frame — a readback or a pin period perturbed — fails naming the frame and the joint.

use kin_core::motion::gait::{Pattern, Velocity};
use kin_core::{Joint, LegId, Robot};
use quad_device::engine::{self, FRAME_MS};
use quad_device::Config;
use quad_host::emu::{Pulse, CYCLES_PER_TICK};
use quad_host::replay::{self, Commands, Replay};
use quad_protocol::{MotionCommand, MotionStage};

fn config() -> replay::Config {
    let c = Config::shahriar2023();
    replay::Config {
        robot: Robot::shahriar2023(),
        calibration: quad_device::default_calibration::<kin_core::DefaultMath>(
            &c.robot,
            &c.pose_config,
        ),
        stance_height_m: c.pose_config.stance_height_m,
        order: c.pose_config.order,
        joint_speed_limit_rad_s: engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S,
    }
}

/// A trot from the stance: 3 cm/s from run frame 5, 5 cm/s turning from 60, stopped at 130.
fn trot() -> Replay {
    let c = config();
    let stance = kin_core::body::Solver::new(&c.robot)
        .inverse_at_stance(
            &kin_core::Pose::default(),
            &kin_core::BodyConfig::about_centre(c.order),
            c.stance_height_m,
            kin_core::ReachPolicy::Reject,
        )
        .unwrap()
        .flat();
    let v = |forward_m_s, yaw_rad_s| Velocity {
        forward_m_s,
        lateral_m_s: 0.0,
        yaw_rad_s,
    };
    replay::replay(
        &c,
        &Commands {
            request: MotionCommand::walk(Pattern::Trot, c.stance_height_m),
            outputs_rad: Some(stance),
            velocities: vec![(5, v(0.03, 0.0)), (60, v(0.05, 0.1))],
            stop_frame: Some(130),
        },
    )
    .unwrap()
}

/// The pulses a frame shows on the pins, as the emulator reports them.
fn pins_of(r: &Replay) -> Vec<[Option<Pulse>; 12]> {
    r.frames
        .iter()
        .map(|f| {
            core::array::from_fn(|i| {
                Some(Pulse {
                    channel: i,
                    rise_cycle: 0,
                    high_cycles: u64::from(f.pulses_half_us[i]) * CYCLES_PER_TICK,
                    rise_step_cycles: 1,
                    fall_step_cycles: 1,
                })
            })
        })
        .collect()
}

#[test]
fn the_replay_runs_the_stride_the_stop_and_the_leave() {
    let r = trot();
    let run: Vec<_> = r
        .frames
        .iter()
        .filter(|f| f.stage == MotionStage::Run)
        .collect();
    assert_eq!(run.last().unwrap().frame, 130);
    assert!(r.frames.iter().any(|f| f.stage == MotionStage::Stopping));
    // The feet move: the joints are not the stance all along.
    let first = r.frames[0].target_rad;
    assert!(r.frames.iter().any(|f| f
        .target_rad
        .iter()
        .zip(&first)
        .any(|(a, b)| (a - b).abs() > 0.05)));
    // Each frame's output step is within the limiter's.
    let step = engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S * FRAME_MS as f32 / 1000.0;
    for w in r.frames.windows(2) {
        for (a, b) in w[0].outputs_rad.iter().zip(&w[1].outputs_rad) {
            assert!((a - b).abs() <= step * 1.0001);
        }
    }
}

#[test]
fn the_pins_of_every_frame_pass_held_or_skipped_frames_too() {
    let r = trot();
    let mut pins = pins_of(&r);
    assert_eq!(r.check_pins(&pins, CYCLES_PER_TICK), Ok(r.frames.len() - 1));
    // A period shown twice (a late tick) and one skipped (a catch-up).
    pins.insert(40, pins[40]);
    pins.remove(90);
    assert!(r.check_pins(&pins, CYCLES_PER_TICK).is_ok());
}

#[test]
fn a_tampered_pin_period_fails_naming_its_frame_and_joint() {
    let r = trot();
    let mut pins = pins_of(&r);
    // Frame 77 of the record, the RL knee a few ticks long.
    let p = pins[77][8].as_mut().unwrap();
    p.high_cycles += 6 * CYCLES_PER_TICK;
    let m = r.check_pins(&pins, CYCLES_PER_TICK).unwrap_err();
    assert_eq!(m.index, 77);
    let want = r.frames[77];
    assert_eq!((m.stage, m.frame), (want.stage, want.frame));
    let joint = m.joint.unwrap();
    assert_eq!((joint.leg, joint.joint), (LegId::RL, Joint::Knee));
    let text = m.to_string();
    assert!(
        text.contains("pins 77") && text.contains("RL Knee"),
        "{text}"
    );
}

#[test]
fn a_perturbed_readback_fails_naming_its_frame_and_joint() {
    let r = trot();
    let f = *r
        .frames
        .iter()
        .find(|f| f.stage == MotionStage::Run && f.frame == 100)
        .unwrap();
    let mut readback = quad_protocol::Readback {
        angles_rad: f.target_rad,
        pulses_half_us: f.pulses_half_us,
        flags: quad_protocol::Flags::default(),
        frames_ok: 0,
        frames_bad: 0,
    };
    let label = (MotionStage::Run, 100);
    assert_eq!(r.check_readback(3, label, &readback, 0.0), Ok(0.0));
    readback.angles_rad[4] += 1e-3;
    let m = r.check_readback(3, label, &readback, 1e-4).unwrap_err();
    assert_eq!((m.stage, m.frame, m.index), (MotionStage::Run, 100, 3));
    let joint = m.joint.unwrap();
    assert_eq!((joint.leg, joint.joint), (LegId::FR, Joint::Hip));
    // A frame number the motion never had.
    let m = r
        .check_readback(4, (MotionStage::Run, 9_999), &readback, 1e-4)
        .unwrap_err();
    assert_eq!(m.joint, None);
}

#[test]
fn a_wrong_velocity_frame_is_a_different_replay() {
    // The same commands one frame later: the frames after it differ (what the device's
    // reported frame numbers pin down).
    let r = trot();
    let c = config();
    let late = replay::replay(
        &c,
        &Commands {
            request: MotionCommand::walk(Pattern::Trot, c.stance_height_m),
            outputs_rad: Some(r.frames[0].outputs_rad),
            velocities: vec![
                (
                    6,
                    Velocity {
                        forward_m_s: 0.03,
                        lateral_m_s: 0.0,
                        yaw_rad_s: 0.0,
                    },
                ),
                (
                    60,
                    Velocity {
                        forward_m_s: 0.05,
                        lateral_m_s: 0.0,
                        yaw_rad_s: 0.1,
                    },
                ),
            ],
            stop_frame: Some(130),
        },
    )
    .unwrap();
    assert!(late.check_pins(&pins_of(&r), CYCLES_PER_TICK).is_err());
}
