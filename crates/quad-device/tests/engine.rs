//! The motion engine through the device at 50 Hz: every output step within the limiter's bound,
//! stand-up / sit / rest, each motion for its duration, the engine's setpoints equal to
//! kin-core's motion + IK, the stop and the velocity timeout of a walk, and refused parameters
//! that move nothing.

mod common;

use common::*;
use kin_core::body::Pose;
use kin_core::motion::gait::{Pattern, Velocity};
use kin_core::motion::laws::{self, Axis};
use kin_core::motion::path::PathKind;
use kin_core::motion::{self, Motion};
use kin_core::preflight::{Failure, FailureKind};
use kin_core::{BodyConfig, DefaultMath, LegId, ReachPolicy, Unreachable, Vec3};
use quad_device::engine::{self, rest_angles, Error, FRAME_MS};
use quad_device::{Config, Device};
use quad_protocol::{
    LegSet, MotionCommand as Request, MotionKind, MotionStage, Request as Wire, ServoId,
};

/// Rounding allowance on the limiter's bound, rad.
const STEP_TOL_RAD: f32 = 1e-6;
/// Most frames any test motion may take, stand-up and stop included.
const MAX_FRAMES: u32 = 20_000;

struct Rig {
    dev: Dev,
    clock: VirtualClock,
    /// Largest output change in one frame seen, rad.
    max_step_rad: f32,
    frames: u32,
}

impl Rig {
    fn new(config: Config) -> Rig {
        let clock = VirtualClock::default();
        clock.set_ms(1_000);
        let dev = Device::new(
            config,
            Outputs::logging(),
            clock.clone(),
            RamEeprom::erased(),
        )
        .unwrap();
        Rig {
            dev,
            clock,
            max_step_rad: 0.0,
            frames: 0,
        }
    }

    fn bound(&self) -> f32 {
        self.dev.limiter().max_step_rad()
    }

    /// One frame: the clock 20 ms on, one poll; checks the step of every output.
    fn frame(&mut self) {
        let before = self.dev.output_angles().copied();
        self.clock.advance_ms(FRAME_MS);
        self.dev.poll();
        self.frames += 1;
        if let (Some(a), Some(b)) = (before, self.dev.output_angles()) {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                let d = (y - x).abs();
                self.max_step_rad = self.max_step_rad.max(d);
                assert!(
                    d <= self.bound() + STEP_TOL_RAD,
                    "{:?}: step {d} rad > {} at frame {}",
                    ServoId::ALL[i],
                    self.bound(),
                    self.frames
                );
            }
        }
        assert_writes_in_travel(&self.dev);
    }

    /// Frames until the engine is idle.
    fn until_idle(&mut self) {
        let start = self.frames;
        while self.dev.motion_status().kind.is_some() {
            self.frame();
            assert!(self.frames - start < MAX_FRAMES, "the motion never ends");
        }
    }

    fn start(&mut self, r: Request) {
        self.dev
            .start_motion(&r)
            .unwrap_or_else(|e| panic!("{r:?}: {e}"));
    }

    fn stand(&mut self) {
        self.start(Request::StandUp);
        self.until_idle();
        self.max_step_rad = 0.0;
    }

    fn outputs(&self) -> [f32; 12] {
        *self.dev.output_angles().expect("outputs on")
    }
}

fn stance(config: &Config) -> [f32; 12] {
    kin_core::body::Solver::<DefaultMath>::with_math(&config.robot)
        .inverse_at_stance(
            &Pose::default(),
            &body_config(config),
            config.pose_config.stance_height_m,
            ReachPolicy::Reject,
        )
        .unwrap()
        .flat()
}

fn body_config(config: &Config) -> BodyConfig {
    BodyConfig {
        order: config.pose_config.order,
        pivot_m: Vec3::ZERO,
    }
}

fn parameter(e: Error) -> &'static str {
    match e {
        Error::Parameter(
            motion::Error::NonFinite(n)
            | motion::Error::NotPositive(n)
            | motion::Error::Negative(n),
        ) => n.name(),
        Error::Parameter(
            motion::Error::OutOfRange { parameter, .. }
            | motion::Error::BeyondReach { parameter, .. },
        ) => parameter.name(),
        other => panic!("not a parameter error: {other:?}"),
    }
}

#[test]
fn stand_up_enables_at_the_rest_pose_and_ramps_to_the_stance_and_back() {
    for config in [Config::fernando2025(), Config::shahriar2023()] {
        let mut rig = Rig::new(config);
        assert!(!rig.dev.outputs_enabled());
        rig.start(Request::StandUp);
        let rest = rest_angles(&config.robot).unwrap();
        assert!(rig.dev.outputs_enabled());
        assert_eq!(rig.outputs(), rest, "enabled at the rest pose");
        let first = rig.dev.outputs().writes()[0];
        for (i, p) in first.iter().enumerate() {
            assert_eq!(Ok(*p), rig.dev.calibration()[i].pulse_half_us(rest[i]));
        }
        rig.until_idle();
        assert_eq!(
            rig.outputs(),
            stance(&config),
            "stand-up ends at the stance"
        );
        assert!(rig.max_step_rad > 0.5 * rig.bound(), "it ramped");
        rig.start(Request::Sit);
        rig.until_idle();
        assert_eq!(rig.outputs(), rest, "sit ends at the rest pose");
        assert!(rig.dev.outputs_enabled());
        rig.start(Request::StandUp);
        rig.until_idle();
        rig.start(Request::Rest);
        rig.until_idle();
        assert!(!rig.dev.outputs_enabled(), "rest stops the outputs");
        assert_eq!(rig.dev.readback().angles_rad, rest);
    }
}

#[test]
fn a_direct_setpoint_is_approached_frame_by_frame_after_the_enabling_frame() {
    let config = Config::fernando2025();
    let mut rig = Rig::new(config);
    hello(&mut rig.dev);
    ask(&mut rig.dev, 1, Wire::SetOutputs { enabled: true });
    rig.frame();
    let pose = Pose {
        roll_rad: 0.2,
        z_m: -0.1,
        ..Pose::default()
    };
    let writes = rig.dev.outputs().writes().len();
    let answer = ask(&mut rig.dev, 2, Wire::SetBodyPose(pose));
    let quad_protocol::DeviceToHost::Ack { readback, .. } = answer else {
        panic!("{answer:?}")
    };
    assert_eq!(
        rig.dev.outputs().writes().len(),
        writes,
        "nothing written at once"
    );
    let target = readback.angles_rad;
    let mut frames = 0;
    while rig.outputs() != target {
        rig.frame();
        frames += 1;
        assert!(frames < 200);
    }
    assert!(frames > 1, "more than one frame");
    assert!(
        (rig.max_step_rad - rig.bound()).abs() <= STEP_TOL_RAD,
        "at the limiter's speed"
    );
    // A late loop (five frames) still moves each output by one step only.
    ask(&mut rig.dev, 3, Wire::SetBodyPose(Pose::default()));
    let before = rig.outputs();
    rig.clock.advance_ms(5 * FRAME_MS);
    rig.dev.poll();
    let after = rig.outputs();
    let step = before
        .iter()
        .zip(&after)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(step <= rig.bound() + STEP_TOL_RAD && step > 0.0);
}

/// Runs `request` after a stand-up and checks, in its run stage, the engine's setpoint against
/// `expected(t)` (kin-core's motion + IK) bit for bit while the limiter is not active.
fn run_law(config: Config, request: Request, expected: impl Fn(f32) -> [f32; 12]) -> Rig {
    let mut rig = Rig::new(config);
    rig.stand();
    rig.start(request);
    let mut compared = 0;
    let mut ran = 0;
    while rig.dev.motion_status().kind.is_some() {
        rig.frame();
        let st = rig.dev.motion_status();
        if st.kind.is_some() && st.stage == MotionStage::Run {
            ran += 1;
            let target = rig.dev.readback().angles_rad;
            assert_eq!(st.fault, None);
            if rig.outputs() == target {
                let want = expected(st.t_s);
                for (i, (a, b)) in target.iter().zip(&want).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "joint {i} at {} s", st.t_s);
                }
                compared += 1;
            }
        }
        assert!(rig.frames < MAX_FRAMES);
    }
    assert!(ran > 0 && compared * 10 >= ran * 9, "{compared} of {ran}");
    assert_eq!(rig.outputs(), stance(&config), "ends at the stance");
    rig
}

#[test]
fn seed001_sways_and_yaw_turn_run_for_their_duration_as_kin_core_computes_them() {
    let config = Config::fernando2025();
    let feet = config.robot.stance_feet(config.pose_config.stance_height_m);
    for axis in [Axis::Roll, Axis::Pitch] {
        let mut p = laws::SwayParams::seed001(axis);
        p.feet_in_world = feet;
        p.order = config.pose_config.order;
        let sway = laws::Sway::new(p).unwrap();
        let rig = run_law(config, Request::seed001_sway(axis, Some(20.0)), |t| {
            motion::solve::<DefaultMath>(&sway, t, ReachPolicy::Reject)
                .unwrap()
                .1
                .flat()
        });
        // One period of 1000 frames, the approach and the leave are short.
        assert!(rig.frames >= 1000 && rig.frames < 1100, "{}", rig.frames);
    }
    let mut p = laws::YawTurnParams::seed001();
    p.stance_feet = feet;
    p.order = config.pose_config.order;
    let turn = laws::YawTurn::new(p).unwrap();
    // Counter-clockwise positive: seed 001's clockwise ω_z is a negative yaw rate.
    let request = Request::seed001_yaw_turn(Some(12.0));
    assert!(matches!(request, Request::YawTurn { yaw_rate_rad_s, .. } if yaw_rate_rad_s < 0.0));
    let rig = run_law(config, request, |t| {
        motion::solve::<DefaultMath>(&turn, t, ReachPolicy::Reject)
            .unwrap()
            .1
            .flat()
    });
    assert!(rig.frames >= 600, "{}", rig.frames);
}

#[test]
fn the_stable_turn_runs_on_both_presets_as_kin_core_computes_it() {
    for config in [Config::shahriar2023(), Config::fernando2025()] {
        let h = config.pose_config.stance_height_m;
        let mut p = laws::StableTurnParams::new(config.robot, h);
        p.order = config.pose_config.order;
        let turn = laws::StableTurn::new(p).unwrap();
        let request = Request::stable_turn(h, Some(p.cycle_s));
        let rig = run_law(config, request, |t| {
            motion::solve::<DefaultMath>(&turn, t, ReachPolicy::Reject)
                .unwrap()
                .1
                .flat()
        });
        // One cycle of 1000 frames, the approach and the leave (from the shifted body) short.
        assert!(rig.frames >= 1000 && rig.frames < 1200, "{}", rig.frames);
    }
}

#[test]
fn seed000_foot_paths_run_on_one_leg_or_all_four() {
    let config = Config::shahriar2023();
    let stance_feet = config.robot.stance_feet(config.pose_config.stance_height_m);
    for path in PathKind::ALL {
        for leg in [None, Some(LegId::RL)] {
            let Request::FootPath {
                stride_m,
                step_height_m,
                duty_factor,
                cycle_s,
                ..
            } = Request::seed000_rectangle(leg.map_or(LegSet::All, LegSet::One), None)
            else {
                unreachable!()
            };
            let request = Request::FootPath {
                path,
                legs: leg.map_or(LegSet::All, LegSet::One),
                stride_m,
                step_height_m,
                duty_factor,
                cycle_s,
                duration_s: Some(3.0),
            };
            let paths = laws::LegPaths::new(laws::LegPathsParams {
                robot: config.robot,
                path: motion::path::AnyPath::new(
                    path,
                    motion::path::Stride::new(stride_m, step_height_m, duty_factor).unwrap(),
                ),
                cycle_s,
                phase_offsets: [0.0; 4],
                stance_feet,
            })
            .unwrap();
            run_law(config, request, |t| {
                let mut f = paths.frame::<DefaultMath>(t).unwrap();
                for l in LegId::ALL {
                    if leg.is_some_and(|x| x != l) {
                        f.feet_in_world[l.index()] = stance_feet[l.index()];
                    }
                }
                kin_core::body::Solver::<DefaultMath>::with_math(&config.robot)
                    .inverse(
                        &f.pose,
                        &paths.body_config(),
                        &f.feet_in_world,
                        ReachPolicy::Reject,
                    )
                    .unwrap()
                    .flat()
            });
        }
    }
}

/// A walk's numbers, for the cases that change one of them.
struct Walk {
    body_height_m: f32,
    step_height_m: f32,
    cycle_s: f32,
    velocity_timeout_ms: u16,
}

fn walk_rig(config: Config, timeout_ms: u16) -> Rig {
    let mut rig = Rig::new(config);
    rig.stand();
    let mut w = Request::walk(Pattern::Trot, config.pose_config.stance_height_m);
    if let Request::Walk {
        velocity_timeout_ms,
        ..
    } = &mut w
    {
        *velocity_timeout_ms = timeout_ms;
    }
    rig.start(w);
    while rig.dev.motion_status().stage == MotionStage::Approach {
        rig.frame();
    }
    rig
}

#[test]
fn stop_while_trotting_finishes_the_stride_and_ends_at_the_stance() {
    for config in [Config::shahriar2023(), Config::fernando2025()] {
        let mut rig = walk_rig(config, 10_000);
        let mut k = 0u32;
        // A changing command, refreshed every frame, for 3 s.
        while k < 150 {
            let t = k as f32 * 0.02;
            let v = Velocity {
                forward_m_s: 0.05 + 0.05 * (0.8 * t).sin(),
                lateral_m_s: 0.02 * (0.5 * t).cos(),
                yaw_rad_s: -0.2 + 0.1 * t,
            };
            rig.dev.set_velocity(v).unwrap();
            rig.frame();
            k += 1;
        }
        assert_eq!(rig.dev.motion_status().kind, Some(MotionKind::Walk));
        rig.dev.stop_motion();
        assert_eq!(rig.dev.motion_status().stage, MotionStage::Stopping);
        assert_eq!(
            rig.dev.set_velocity(Velocity::default()),
            Err(Error::NotWalking)
        );
        let stop_frame = rig.frames;
        rig.until_idle();
        // At most two gait cycles to finish the strides, and a short ramp.
        assert!(
            rig.frames - stop_frame <= 100,
            "{}",
            rig.frames - stop_frame
        );
        assert_eq!(rig.outputs(), stance(&config));
        assert!(rig.max_step_rad <= rig.bound() + STEP_TOL_RAD);
        assert_eq!(rig.dev.motion_status().fault, None);
    }
}

#[test]
fn a_velocity_command_not_refreshed_stops_the_walk_cleanly() {
    let config = Config::shahriar2023();
    let mut rig = walk_rig(config, 300);
    rig.dev
        .set_velocity(Velocity {
            forward_m_s: 0.1,
            ..Velocity::default()
        })
        .unwrap();
    for _ in 0..15 {
        rig.frame();
        assert_eq!(rig.dev.motion_status().stage, MotionStage::Run);
    }
    for _ in 0..2 {
        rig.frame();
    }
    assert_eq!(
        rig.dev.motion_status().stage,
        MotionStage::Stopping,
        "after 300 ms"
    );
    rig.until_idle();
    assert_eq!(rig.outputs(), stance(&config));
}

#[test]
fn bad_parameters_are_refused_by_name_and_move_nothing() {
    let config = Config::shahriar2023();
    let mut rig = Rig::new(config);
    // With the outputs off, every motion but the stand-up needs them.
    assert_eq!(
        rig.dev
            .start_motion(&Request::seed001_sway(Axis::Roll, None)),
        Err(Error::OutputsOff)
    );
    assert!(rig.dev.outputs().writes().is_empty());
    rig.stand();
    let sway = |a: f32, t: f32, d: Option<f32>| Request::Sway {
        axis: Axis::Roll,
        amplitude_rad: a,
        period_s: t,
        duration_s: d,
    };
    let turn = |w: f32, t: f32, h: f32| Request::YawTurn {
        yaw_rate_rad_s: w,
        step_period_s: t,
        lift_height_m: h,
        duration_s: None,
    };
    let path = |s: f32, h: f32, c: f32| Request::FootPath {
        path: PathKind::Rectangle,
        legs: LegSet::All,
        stride_m: s,
        step_height_m: h,
        duty_factor: 0.5,
        cycle_s: c,
        duration_s: None,
    };
    let walk = |f: fn(&mut Walk)| {
        let Request::Walk {
            gait,
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
        } = Request::walk(Pattern::Trot, config.pose_config.stance_height_m)
        else {
            unreachable!()
        };
        let mut w = Walk {
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
        };
        f(&mut w);
        Request::Walk {
            gait,
            body_height_m: w.body_height_m,
            step_height_m: w.step_height_m,
            cycle_s: w.cycle_s,
            velocity_timeout_ms: w.velocity_timeout_ms,
        }
    };
    let cases = [
        (sway(0.2, f32::NAN, None), "period_s"),
        (sway(0.2, -1.0, None), "period_s"),
        (sway(0.2, 0.0, None), "period_s"),
        (sway(f32::INFINITY, 10.0, None), "amplitude_rad"),
        (sway(0.1, 10.0, Some(0.0)), "duration_s"),
        (sway(0.1, 10.0, Some(-3.0)), "duration_s"),
        (sway(0.1, 10.0, Some(f32::NAN)), "duration_s"),
        (turn(f32::NAN, 6.0, 0.05), "yaw_rate_rad_s"),
        (turn(0.1, 0.0, 0.05), "step_period_s"),
        (turn(0.1, 6.0, -0.05), "lift_height_m"),
        (turn(0.1, 6.0, 0.5), "lift_height_m"),
        (path(0.1, 0.05, 0.0), "cycle_s"),
        (path(-0.1, 0.05, 3.0), "stride_m"),
        (path(0.1, f32::NAN, 3.0), "step_height_m"),
        (walk(|w| w.cycle_s = 0.0), "cycle_s"),
        (walk(|w| w.step_height_m = 0.45), "step_height_m"),
        (walk(|w| w.body_height_m = f32::NAN), "stance_height_m"),
        (walk(|w| w.velocity_timeout_ms = 0), "velocity_timeout_ms"),
    ];
    let writes = rig.dev.outputs().writes().len();
    let held = rig.dev.readback();
    for (request, name) in cases {
        let e = rig.dev.start_motion(&request).unwrap_err();
        assert_eq!(parameter(e), name, "{request:?}: {e}");
        assert_eq!(rig.dev.motion_status().kind, None);
        for _ in 0..3 {
            rig.frame();
        }
        assert_eq!(
            rig.dev.outputs().writes().len(),
            writes,
            "{request:?} moved a servo"
        );
        assert_eq!(rig.dev.readback(), held);
    }
    // Beyond reach: refused by a start-check sample (the per-frame IK) naming the leg.
    for request in [sway(1.5, 10.0, None), path(0.8, 0.05, 3.0)] {
        match rig.dev.start_motion(&request) {
            Err(Error::Preflight(Failure {
                kind: FailureKind::Unreachable(Unreachable::TooFar),
                ..
            })) => {}
            other => panic!("{request:?}: {other:?}"),
        }
        assert_eq!(rig.dev.motion_status().kind, None);
        assert_eq!(rig.dev.outputs().writes().len(), writes);
        assert_eq!(rig.dev.readback(), held);
    }
    // A walk refuses velocities beyond its reach, by component; the walk keeps running.
    rig.start(walk(|_| {}));
    assert_eq!(rig.dev.start_motion(&Request::Sit), Err(Error::Busy));
    for (v, name) in [
        (
            Velocity {
                forward_m_s: 5.0,
                ..Velocity::default()
            },
            "forward_m_s",
        ),
        (
            Velocity {
                lateral_m_s: f32::NAN,
                ..Velocity::default()
            },
            "lateral_m_s",
        ),
        (
            Velocity {
                yaw_rad_s: 20.0,
                ..Velocity::default()
            },
            "yaw_rad_s",
        ),
    ] {
        assert_eq!(parameter(rig.dev.set_velocity(v).unwrap_err()), name);
        assert_eq!(rig.dev.motion_status().kind, Some(MotionKind::Walk));
    }
    assert_eq!(
        parameter(rig.dev.set_joint_speed_limit(0.0).unwrap_err()),
        "joint_speed_limit_rad_s"
    );
    assert_eq!(
        parameter(rig.dev.set_joint_speed_limit(f32::NAN).unwrap_err()),
        "joint_speed_limit_rad_s"
    );
    assert_eq!(
        rig.dev.limiter().speed_rad_s(),
        engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S
    );
}
