//! Trot / walk generator: footfall pattern, no-slip stance feet for straight and turning
//! commands, periodic joint angles, body odometry, C1 lift-off with the Bézier swing, and
//! parameter validation.

use kin_core::motion::gait::{Gait, GaitParams, Pattern, Velocity};
use kin_core::motion::path::PathKind;
use kin_core::motion::{self, Contact, Error, Motion, Param};
use kin_core::{body, preflight, DefaultMath, LegId, ReachPolicy, Robot, Vec3};

/// Largest allowed drift of a stance foot in the world, m.
const DRIFT_TOL_M: f32 = 1e-6;
/// Largest allowed change of a joint angle over one cycle, rad.
const PERIODIC_TOL_RAD: f32 = 1e-4;
const DT_S: f32 = 0.0031;

fn trot(v: Velocity, swing: PathKind) -> Gait {
    let mut p = GaitParams::new(Pattern::Trot, Robot::shahriar2023(), 0.40);
    p.velocity = v;
    p.swing = swing;
    p.step_height_m = 0.06;
    Gait::new(p).unwrap()
}

/// Runs `gait` for `cycles` and returns the worst stance-foot drift in the world (frame level
/// and through FK of the solved angles).
fn stance_drift(gait: &Gait, cycles: f32) -> (f32, f32) {
    let cycle = gait.period_s().unwrap();
    let n = (cycles * cycle / DT_S) as u32;
    let mut start: [Option<(Vec3, Vec3)>; 4] = [None; 4];
    let (mut worst, mut worst_fk) = (0.0f32, 0.0f32);
    for k in 0..n {
        let t = k as f32 * DT_S;
        let (frame, sol) = motion::solve::<DefaultMath>(gait, t, ReachPolicy::Reject).unwrap();
        let fk = body::forward(
            gait.robot(),
            &frame.pose,
            &gait.body_config(),
            &sol.angles(),
        );
        for l in LegId::ALL {
            let i = l.index();
            if frame.contact[i] == Contact::Stance {
                let (s, sfk) = *start[i].get_or_insert((frame.feet_in_world[i], fk[i]));
                worst = worst.max((frame.feet_in_world[i] - s).norm());
                worst_fk = worst_fk.max((fk[i] - sfk).norm());
            } else {
                start[i] = None;
            }
        }
    }
    (worst, worst_fk)
}

#[test]
fn trot_pairs_diagonals_and_walk_keeps_three_feet_down() {
    let g = trot(Velocity::default(), PathKind::Bezier);
    let mut p = GaitParams::new(Pattern::Walk, Robot::shahriar2023(), 0.40);
    p.velocity.forward_m_s = 0.1;
    let w = Gait::new(p).unwrap();
    let (mut first_pair_swings, mut second_pair_swings) = (false, false);
    for k in 0..1000 {
        let t = k as f32 * 0.001;
        let c = g.frame::<DefaultMath>(t).unwrap().contact;
        assert_eq!(c[LegId::FL.index()], c[LegId::RR.index()]);
        assert_eq!(c[LegId::FR.index()], c[LegId::RL.index()]);
        // The pairs take turns: never both in the air (duty 0.75: four feet down between).
        assert!(
            c[LegId::FL.index()] == Contact::Stance || c[LegId::FR.index()] == Contact::Stance,
            "t={t}: {c:?}"
        );
        first_pair_swings |= c[LegId::FL.index()] == Contact::Swing;
        second_pair_swings |= c[LegId::FR.index()] == Contact::Swing;
        let c = w.frame::<DefaultMath>(t).unwrap().contact;
        let down = c.iter().filter(|&&x| x == Contact::Stance).count();
        assert!(down >= 3, "t={t}: {c:?}");
    }
    assert!(
        first_pair_swings && second_pair_swings,
        "each pair swings once per cycle"
    );
}

#[test]
fn straight_trot_stance_feet_do_not_slip_and_the_body_advances() {
    let v = Velocity {
        forward_m_s: 0.15,
        lateral_m_s: 0.0,
        yaw_rad_s: 0.0,
    };
    let g = trot(v, PathKind::Bezier);
    let (drift, drift_fk) = stance_drift(&g, 3.0);
    println!("straight trot: stance drift {drift:.2e} m (frames), {drift_fk:.2e} m (FK of IK)");
    assert!(drift <= DRIFT_TOL_M && drift_fk <= DRIFT_TOL_M);
    let cycle = g.period_s().unwrap();
    let f = g.frame::<DefaultMath>(2.0 * cycle).unwrap();
    assert!((f.pose.x_m - 0.15 * 2.0 * cycle).abs() < 1e-6);
    // Stride = v · stance time (duty factor · cycle).
    let stance_s = Pattern::Trot.duty_factor() * cycle;
    assert!((g.step_length_m(LegId::FL) - 0.15 * stance_s).abs() < 1e-6);
}

#[test]
fn turning_crab_trot_stance_feet_do_not_slip() {
    let v = Velocity {
        forward_m_s: 0.1,
        lateral_m_s: -0.05,
        yaw_rad_s: 0.4,
    };
    for swing in PathKind::ALL {
        let g = trot(v, swing);
        let (drift, drift_fk) = stance_drift(&g, 2.0);
        assert!(
            drift <= DRIFT_TOL_M && drift_fk <= 2.0 * DRIFT_TOL_M,
            "{swing:?}: {drift} {drift_fk}"
        );
    }
    // The body turns at the commanded rate and moves on a circle of radius |v|/ω.
    let g = trot(v, PathKind::Bezier);
    let t = 2.0;
    let f = g.frame::<DefaultMath>(t).unwrap();
    assert!((f.pose.yaw_rad - 0.8).abs() < 1e-6);
    let r = (0.1f32.hypot(0.05)) / 0.4;
    let chord = f.pose.x_m.hypot(f.pose.y_m);
    assert!((chord - 2.0 * r * (0.4f32 * t / 2.0).sin()).abs() < 1e-5);
}

#[test]
fn joint_angles_repeat_every_cycle_while_the_body_moves_on() {
    let v = Velocity {
        forward_m_s: 0.12,
        lateral_m_s: 0.03,
        yaw_rad_s: -0.3,
    };
    let g = trot(v, PathKind::Cycloid);
    let cycle = g.period_s().unwrap();
    let mut worst = 0.0f32;
    for k in 0..300 {
        let t = k as f32 * DT_S;
        let (_, a) = motion::solve::<DefaultMath>(&g, t, ReachPolicy::Reject).unwrap();
        let (_, b) = motion::solve::<DefaultMath>(&g, t + cycle, ReachPolicy::Reject).unwrap();
        for (x, y) in a.flat().iter().zip(b.flat()) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst < PERIODIC_TOL_RAD, "{worst}");
}

#[test]
fn bezier_lift_off_and_touch_down_are_smooth_in_the_world() {
    // Straight command: the Bézier swing starts and ends with the stance velocity in the body
    // frame, i.e. at rest in the world.
    let v = Velocity {
        forward_m_s: 0.2,
        ..Velocity::default()
    };
    let g = trot(v, PathKind::Bezier);
    let cycle = g.period_s().unwrap();
    let h = 1e-4 * cycle;
    let foot = |t: f32| g.frame::<DefaultMath>(t).unwrap().feet_in_world[LegId::FL.index()];
    for join in [cycle, 1.5 * cycle] {
        // FL lifts off at t = k·cycle and lands half a cycle later.
        let after = (foot(join + h) - foot(join)).norm() / h;
        let before = (foot(join) - foot(join - h)).norm() / h;
        assert!(after < 0.01 && before < 0.01, "{join}: {before} {after}");
    }
}

#[test]
fn gait_preflight_is_clean() {
    let v = Velocity {
        forward_m_s: 0.2,
        lateral_m_s: 0.0,
        yaw_rad_s: 0.2,
    };
    let g = trot(v, PathKind::Bezier);
    let r = preflight::check(
        &g,
        &preflight::Sweep::new(0.0, 2.0 * g.period_s().unwrap(), 500.0).unwrap(),
        [preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3],
    )
    .unwrap();
    println!(
        "trot 0.2 m/s, 0.2 rad/s: max hip speed {:.3} rad/s, min workspace margin {:.4} m",
        r.max_joint_speed(kin_core::Joint::Hip).unwrap().1.value,
        r.min_workspace_margin().unwrap().1.value
    );
    assert!(r.ok(), "{:?}", r.first_failure);
}

#[test]
fn gait_parameters_are_validated_by_name() {
    let base = GaitParams::new(Pattern::Trot, Robot::shahriar2023(), 0.40);
    let with = |f: &dyn Fn(&mut GaitParams)| {
        let mut p = base;
        f(&mut p);
        Gait::new(p)
    };
    assert_eq!(
        with(&|p| p.cycle_s = -1.0),
        Err(Error::NotPositive(Param::CycleS))
    );
    assert_eq!(
        with(&|p| p.stance_height_m = 0.0),
        Err(Error::NotPositive(Param::StanceHeightM))
    );
    assert_eq!(
        with(&|p| p.velocity.forward_m_s = f32::NAN),
        Err(Error::NonFinite(Param::ForwardMS))
    );
    assert_eq!(
        with(&|p| p.step_height_m = -0.01),
        Err(Error::Negative(Param::StepHeightM))
    );
    assert!(matches!(
        with(&|p| p.duty_factor = 1.0),
        Err(Error::OutOfRange {
            parameter: Param::DutyFactor,
            ..
        })
    ));
    assert!(matches!(
        with(&|p| p.step_height_m = 0.45),
        Err(Error::OutOfRange {
            parameter: Param::StepHeightM,
            ..
        })
    ));
    // Below the hips but too close to them for the knee's fold limit.
    assert!(matches!(
        with(&|p| p.step_height_m = 0.35),
        Err(Error::BeyondReach {
            parameter: Param::StepHeightM,
            ..
        })
    ));
    assert!(matches!(
        with(&|p| p.velocity.forward_m_s = 3.0),
        Err(Error::BeyondReach {
            parameter: Param::Velocity,
            ..
        })
    ));
    assert!(matches!(
        with(&|p| p.stance_height_m = 0.6),
        Err(Error::BeyondReach {
            parameter: Param::StanceHeightM,
            ..
        })
    ));
    let msg = format!("{}", with(&|p| p.step_height_m = 0.35).unwrap_err());
    assert!(msg.contains("step_height_m"), "{msg}");
}
