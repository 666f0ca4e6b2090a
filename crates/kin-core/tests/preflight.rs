//! Preflight: seed 000's pose sweeps, the workspace margin against the IK, failure reporting
//! (first failing sample, leg, kind), joint-speed and joint-limit checks, sweep validation.

use kin_core::body::BodyConfig;
use kin_core::leg::Unreachable;
use kin_core::motion::laws::{Axis, Sway, SwayParams, SEED000_SWEEP_STANCE_HEIGHT_M};
use kin_core::motion::{Contact, Error, Frame, Param};
use kin_core::preflight::{self, workspace_margin, Boundary, Checker, FailureKind, Sweep};
use kin_core::{leg, Joint, JointAngles, JointLimits, LegId, Pose, ReachPolicy, Robot, Vec3};
use proptest::prelude::*;

/// Targets closer than this to a workspace boundary may be classified either way by rounding.
const BOUNDARY_BAND_M: f32 = 1e-5;
/// Smallest workspace margin accepted for seed 000's sweeps at the chosen stance height, m.
const SEED000_MIN_MARGIN_M: f32 = 0.03;

const SPEED: [f32; 3] = [preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3];

#[test]
fn seed000_pose_sweeps_are_all_reachable_with_margins() {
    // Table 4 ranges: roll ±28°, pitch ±21°, yaw ±21°; shahriar2023 at 0.40 m.
    assert_eq!(SEED000_SWEEP_STANCE_HEIGHT_M, 0.40);
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        let params = SwayParams::seed000(axis);
        let sway = Sway::new(params).unwrap();
        // 100 Hz over one 10 s period samples both extremes (t = 2.5 s and 7.5 s) exactly.
        let r = preflight::check(&sway, &Sweep::new(0.0, 10.0, 100.0).unwrap(), SPEED).unwrap();
        assert_eq!(r.samples, 1001);
        let (wl, ws) = r.min_workspace_margin().unwrap();
        let (jl, jm) = r.min_joint_margin().unwrap();
        let (il, ic) = r.min_inverse_condition().unwrap();
        println!(
            "seed 000 {} ±{:.0}°: min workspace margin {:.4} m ({wl} at {:.2} s, {}), min joint margin {:.4} rad ({jl}), min inverse condition {:.4} ({il})",
            axis.name(),
            params.amplitude_rad.to_degrees(),
            ws.value,
            ws.t_s,
            r.legs[wl.index()].workspace_boundary.unwrap().name(),
            jm.value,
            ic.value
        );
        assert!(r.ok(), "{axis:?}: {:?}", r.first_failure);
        assert!(ws.value > SEED000_MIN_MARGIN_M, "{axis:?}: {}", ws.value);
        assert!(ic.value > kin_core::jacobian::SINGULARITY_THRESHOLD);
    }
}

fn frame_with(feet: [Vec3; 4]) -> Frame {
    Frame {
        pose: Pose::default(),
        feet_in_world: feet,
        contact: [Contact::Stance; 4],
    }
}

#[test]
fn the_first_failing_sample_is_reported_with_time_leg_and_kind() {
    let robot = Robot::shahriar2023();
    let mut c = Checker::new(&robot, BodyConfig::default(), SPEED).unwrap();
    let stance = robot.stance_feet(0.4);
    for k in 0..10u32 {
        let t = k as f32 * 0.01;
        let mut feet = stance;
        if k >= 4 {
            // RL's foot 0.7 m below its hip: beyond 0.557 m of leg.
            feet[LegId::RL.index()].z = -0.7;
        }
        let out = c.push_frame(t, &frame_with(feet));
        assert_eq!(out[LegId::RL.index()].is_ok(), k < 4);
        assert!(out[LegId::FL.index()].is_ok());
    }
    let r = c.finish();
    assert_eq!(r.samples, 10);
    assert_eq!(r.failures, 6);
    let f = r.first_failure.unwrap();
    assert_eq!((f.sample, f.leg), (4, LegId::RL));
    assert!((f.t_s - 0.04).abs() < 1e-6);
    assert_eq!(f.kind, FailureKind::Unreachable(Unreachable::TooFar));
    let rl = &r.legs[LegId::RL.index()];
    assert_eq!(rl.failures, 6);
    assert!(rl.workspace_margin_m.unwrap().value < -0.1);
    assert_eq!(rl.workspace_boundary, Some(Boundary::Far));
    assert_eq!(r.legs[LegId::FL.index()].failures, 0);
}

#[test]
fn joint_speed_over_the_limit_fails_and_the_maximum_is_reported() {
    let robot = Robot::fernando2025();
    let mut c = Checker::new(&robot, BodyConfig::default(), [1.0, 1.0, 1.0]).unwrap();
    let q = kin_core::paper::from_seed001(kin_core::paper::SEED001_INITIAL);
    let mut fast = q;
    fast.hip_rad += 0.05; // in 10 ms: 5 rad/s
    c.push_angles(0.0, &[q; 4]);
    c.push_angles(0.01, &[q, q, fast, q]);
    let r = c.finish();
    let f = r.first_failure.unwrap();
    assert_eq!((f.sample, f.leg), (1, LegId::RL));
    match f.kind {
        FailureKind::JointSpeed { joint, speed_rad_s } => {
            assert_eq!(joint, Joint::Hip);
            assert!((speed_rad_s - 5.0).abs() < 1e-3);
        }
        other => panic!("{other:?}"),
    }
    let (leg, e) = r.max_joint_speed(Joint::Hip).unwrap();
    assert_eq!(leg, LegId::RL);
    assert!((e.value - 5.0).abs() < 1e-3 && (e.t_s - 0.01).abs() < 1e-6);
    assert_eq!(r.failures, 1);
}

#[test]
fn joint_limit_violations_give_negative_margins() {
    let robot = Robot::fernando2025();
    let mut c = Checker::new(&robot, BodyConfig::default(), SPEED).unwrap();
    let q = JointAngles::new(0.0, 0.5, -0.01); // knee above its −0.05 limit
    c.push_angles(0.0, &[q; 4]);
    let r = c.finish();
    let (_, m) = r.min_joint_margin().unwrap();
    assert!((m.value + 0.04).abs() < 1e-6, "{}", m.value);
    assert_eq!(r.legs[0].joint_margin_joint, Some(Joint::Knee));
    assert_eq!(
        r.first_failure.unwrap().kind,
        FailureKind::Unreachable(Unreachable::JointLimit(Joint::Knee))
    );
    // Nearly straight knee: close to singular too.
    assert!(r.min_inverse_condition().unwrap().1.value < 0.05);
}

#[test]
fn sweeps_and_limits_are_validated_by_name() {
    assert_eq!(
        Sweep::new(0.0, -1.0, 100.0),
        Err(Error::Negative(Param::DurationS))
    );
    assert_eq!(
        Sweep::new(0.0, 1.0, 0.0),
        Err(Error::NotPositive(Param::RateHz))
    );
    assert_eq!(
        Sweep::new(f32::NAN, 1.0, 10.0),
        Err(Error::NonFinite(Param::StartS))
    );
    assert!(matches!(
        Sweep::new(0.0, 1e6, 1e3),
        Err(Error::OutOfRange {
            parameter: Param::DurationS,
            ..
        })
    ));
    assert_eq!(Sweep::new(0.0, 0.3, 10.0).unwrap().samples(), 4);
    assert_eq!(
        Sweep::new(0.0, 3600.0, 1000.0).unwrap().samples(),
        3_600_001
    );
    assert!(matches!(
        Checker::new(
            &Robot::shahriar2023(),
            BodyConfig::default(),
            [1.0, 0.0, 1.0]
        ),
        Err(Error::NotPositive(Param::MaxJointSpeedRadS))
    ));
}

#[test]
fn a_nan_frame_fails_as_non_finite_without_poisoning_the_figures() {
    let robot = Robot::shahriar2023();
    let mut c = Checker::new(&robot, BodyConfig::default(), SPEED).unwrap();
    let mut feet = robot.stance_feet(0.4);
    let _ = c.push_frame(0.0, &frame_with(feet));
    feet[1].x = f32::NAN;
    let out = c.push_frame(0.01, &frame_with(feet));
    assert_eq!(out[1], Err(Unreachable::NonFinite));
    let r = c.finish();
    assert_eq!(r.failures, 1);
    for l in &r.legs {
        assert!(l.workspace_margin_m.unwrap().value.is_finite());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    /// The margin's sign agrees with the IK (limits removed): positive ⇒ reachable, negative ⇒
    /// refused, outside a rounding band around the boundary.
    #[test]
    fn workspace_margin_sign_matches_the_ik(
        preset in 0usize..2,
        leg_i in 0usize..4,
        x in -1.2f32..1.2, y in -1.2f32..1.2, z in -1.2f32..1.2,
    ) {
        let mut robot = [Robot::shahriar2023(), Robot::fernando2025()][preset];
        robot.limits = JointLimits::FULL_TURN;
        let leg_id = LegId::ALL[leg_i];
        let foot = Vec3::new(x, y, z);
        let (m, _) = workspace_margin(&robot, foot).unwrap();
        let ok = leg::Solver::new(&robot).inverse(leg_id, foot, ReachPolicy::Reject).is_ok();
        if m > BOUNDARY_BAND_M {
            prop_assert!(ok, "margin {m} but refused");
        } else if m < -BOUNDARY_BAND_M {
            prop_assert!(!ok, "margin {m} but reached");
        }
    }
}
