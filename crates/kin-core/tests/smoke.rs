//! Fast sanity checks of the core conventions.
use kin_core::*;

#[test]
fn seed001_initial_pose_is_hip_30_knee_minus_60_foot_below_hip() {
    let q = paper::from_seed001(paper::SEED001_INITIAL);
    assert!((q.hip_rad - 30f32.to_radians()).abs() < 1e-6);
    assert!((q.knee_rad + 60f32.to_radians()).abs() < 1e-6);
    let robot = Robot::fernando2025();
    let foot = leg::forward(&robot.leg, LegId::FL, q);
    let depth = 0.15 + 0.9 * 60f32.to_radians().sin();
    assert!(foot.x.abs() < 1e-6 && foot.y.abs() < 1e-6, "{foot:?}");
    assert!((foot.z + depth).abs() < 1e-6, "{foot:?}");
}

#[test]
fn round_trip_grid_both_presets() {
    for robot in [Robot::shahriar2023(), Robot::fernando2025()] {
        for bend in [KneeBend::Backward, KneeBend::Forward] {
            let robot = robot.with_knee_bend(bend);
            for leg in LegId::ALL {
                for i in 0..7 {
                    for j in 0..7 {
                        for k in 0..5 {
                            let lim = robot.limits;
                            let t = |idx: usize, n: f32, x: usize| {
                                lim.min_rad[idx]
                                    + (lim.max_rad[idx] - lim.min_rad[idx]) * (x as f32 + 0.5) / n
                            };
                            let q = JointAngles::new(
                                t(0, 7.0, i) * 0.99,
                                t(1, 7.0, j) * 0.99,
                                t(2, 5.0, k),
                            );
                            let foot = leg::forward(&robot.leg, leg, q);
                            let sol =
                                leg::Solver::new(&robot).inverse(leg, foot, ReachPolicy::Reject);
                            let Ok(sol) = sol else { continue };
                            let back = leg::forward(&robot.leg, leg, sol.angles);
                            assert!((back - foot).norm() < 2e-6, "{leg} {q:?} {:?}", sol.angles);
                            assert!((leg::forward_dh(&robot.leg, leg, q) - foot).norm() < 2e-6);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn robot_equality_is_field_by_field_float_equality() {
    let r = Robot::shahriar2023();
    assert_eq!(r, r);
    assert!(r.equals(&r));
    assert_ne!(r, Robot::fernando2025());
    assert_ne!(r, r.with_knee_bend(KneeBend::Forward));
    let (mut z, mut p) = (r, r);
    z.leg.d_ax_m = -0.0;
    p.leg.d_ax_m = 0.0;
    assert_eq!(z, p, "-0 == +0, as the float operator has it");
    let mut l = r;
    l.limits.max_rad[2] += 0.1;
    assert_ne!(r, l);
    let mut n = r;
    n.body_width_m = f32::NAN;
    assert_ne!(n, n, "a NaN field is unequal to itself");
}

/// Both presets pass the check at compile time (`validate` is a `const fn`).
const _: () = assert!(Robot::shahriar2023().validate().is_ok());
const _: () = assert!(Robot::fernando2025().validate().is_ok());
