//! Reachability as a typed result: every `Unreachable` kind is produced where it should be, the
//! clamp policy lands on the workspace boundary and reports the distance it moved, and no input
//! (any f32 bit pattern) makes leg or body IK panic or return a non-finite angle.

mod common;

use common::*;
use kin_core::body::{self, BodyConfig, Pose};
use kin_core::{
    leg, IkError, Joint, JointAngles, JointLimits, LegId, ReachPolicy, Robot, RotationOrder,
    Unreachable, Vec3,
};
use proptest::prelude::*;

/// Largest allowed error of the clamp's reported distance and of the clamped foot's distance to
/// the workspace boundary (f32 arithmetic on lengths of ~1 m).
const CLAMP_TOL_M: f64 = 2.0e-6;
/// Cases of the arbitrary-bit-pattern property of leg IK.
const BITS_CASES: u32 = 3000;
/// Cases of the arbitrary-bit-pattern property of body IK (21 values each; slower to draw).
const BODY_BITS_CASES: u32 = 800;

fn reject(robot: &Robot, leg_id: LegId, p: Vec3) -> Result<JointAngles, IkError> {
    leg::Solver::new(robot)
        .inverse(leg_id, p, ReachPolicy::Reject)
        .map(|s| {
            assert!(s.angles.is_finite());
            s.angles
        })
}

fn kind(robot: &Robot, leg_id: LegId, p: Vec3) -> Unreachable {
    let e = reject(robot, leg_id, p).expect_err("target must be unreachable");
    assert_eq!(e.leg, leg_id);
    e.kind
}

/// The error of body IK on `feet` at the zero pose and default configuration, rejecting
/// unreachable targets (the pose must be refused).
fn rejected_at_rest(robot: &Robot, feet: &[Vec3; 4]) -> IkError {
    body::Solver::new(robot)
        .inverse(
            &Pose::default(),
            &BodyConfig::default(),
            feet,
            ReachPolicy::Reject,
        )
        .unwrap_err()
}

/// Foot in the hip frame of the zero-abduction leg plane at height `z` and forward offset `x`.
fn in_plane(robot: &Robot, leg_id: LegId, x: f32, z: f32) -> Vec3 {
    Vec3::new(x, leg_id.side() * robot.leg.d_lat_m, z)
}

#[test]
fn too_far_both_presets() {
    for (_, robot) in presets() {
        let reach = robot.leg.d_ax_m + robot.leg.femur_m + robot.leg.tibia_m;
        for leg_id in LegId::ALL {
            let p = in_plane(&robot, leg_id, 0.0, -(reach + 0.01));
            assert_eq!(kind(&robot, leg_id, p), Unreachable::TooFar);
            let p = in_plane(&robot, leg_id, 0.8, -0.6);
            assert_eq!(kind(&robot, leg_id, p), Unreachable::TooFar);
        }
    }
}

/// shahriar2023 has |Lb − Lc| = 3 mm: a foot within 3 mm of the hip joint is too close.
#[test]
fn too_close_shahriar2023() {
    let robot = Robot::shahriar2023();
    assert!((robot.leg.femur_m - robot.leg.tibia_m - 0.003).abs() < 1e-6);
    for leg_id in LegId::ALL {
        for p in [
            in_plane(&robot, leg_id, 0.001, -0.001),
            in_plane(&robot, leg_id, 0.0, 0.0), // exactly on the offset circle: w = 0
            in_plane(&robot, leg_id, -0.002, -0.0015),
        ] {
            assert_eq!(kind(&robot, leg_id, p), Unreachable::TooClose, "{p:?}");
        }
    }
}

#[test]
fn inside_offset_shahriar2023() {
    let robot = Robot::shahriar2023();
    for leg_id in LegId::ALL {
        for p in [
            Vec3::new(0.0, 0.0, -0.02),
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::new(-0.1, 0.03, 0.03),
            Vec3::new(0.0, 0.0, 0.0),
        ] {
            assert_eq!(kind(&robot, leg_id, p), Unreachable::InsideOffset, "{p:?}");
        }
    }
}

#[test]
fn joint_limit_names_the_joint() {
    // shahriar2023: knee beyond −2.8 (folded) and above −0.05 (straight).
    let robot = Robot::shahriar2023();
    for leg_id in LegId::ALL {
        let folded = in_plane(&robot, leg_id, 0.0, -0.05);
        assert_eq!(
            kind(&robot, leg_id, folded),
            Unreachable::JointLimit(Joint::Knee)
        );
        let straight = in_plane(&robot, leg_id, 0.0, -0.5569);
        assert_eq!(
            kind(&robot, leg_id, straight),
            Unreachable::JointLimit(Joint::Knee)
        );
    }
    // fernando2025: abduction ±0.8, hip ±1.6.
    let robot = Robot::fernando2025();
    for leg_id in LegId::ALL {
        let p = leg::forward(&robot.leg, leg_id, JointAngles::new(1.2, 0.0, -0.5));
        assert_eq!(
            kind(&robot, leg_id, p),
            Unreachable::JointLimit(Joint::Abduction)
        );
        let p = leg::forward(&robot.leg, leg_id, JointAngles::new(-1.0, 0.0, -0.5));
        assert_eq!(
            kind(&robot, leg_id, p),
            Unreachable::JointLimit(Joint::Abduction)
        );
        let p = leg::forward(&robot.leg, leg_id, JointAngles::new(0.0, 1.8, -1.0));
        assert_eq!(kind(&robot, leg_id, p), Unreachable::JointLimit(Joint::Hip));
        // Hip below −1.6 with the foot below the axis needs the forward knee.
        let fwd = robot.with_knee_bend(kin_core::KneeBend::Forward);
        let p = leg::forward(&robot.leg, leg_id, JointAngles::new(0.0, -1.7, 1.0));
        assert_eq!(kind(&fwd, leg_id, p), Unreachable::JointLimit(Joint::Hip));
    }
}

#[test]
fn non_finite_in_each_coordinate() {
    for (_, robot) in presets() {
        for leg_id in LegId::ALL {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                for i in 0..3 {
                    let mut a = [0.0, 0.0, -0.4];
                    a[i] = bad;
                    let p = Vec3::from_array(a);
                    for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
                        let e = leg::Solver::new(&robot)
                            .inverse(leg_id, p, policy)
                            .unwrap_err();
                        assert_eq!(
                            e,
                            IkError {
                                leg: leg_id,
                                kind: Unreachable::NonFinite
                            }
                        );
                    }
                }
            }
        }
    }
}

/// Body IK: a NaN or infinity in any pose field, any pivot coordinate or any foot coordinate is
/// `NonFinite`; a bad foot names its own leg.
#[test]
fn body_non_finite_in_each_input() {
    let robot = Robot::shahriar2023();
    let feet = robot.stance_feet(0.35);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for i in 0..6 {
            let mut a = [0.0; 6];
            a[i] = bad;
            let pose = Pose::from_array(a);
            let e = body::Solver::new(&robot)
                .inverse(&pose, &BodyConfig::default(), &feet, ReachPolicy::Clamp)
                .unwrap_err();
            assert_eq!(e.kind, Unreachable::NonFinite, "pose field {i}");
        }
        for i in 0..3 {
            let mut c = [0.0; 3];
            c[i] = bad;
            let config = BodyConfig {
                order: RotationOrder::Zyx,
                pivot_m: Vec3::from_array(c),
            };
            let e = body::Solver::new(&robot)
                .inverse(&Pose::default(), &config, &feet, ReachPolicy::Reject)
                .unwrap_err();
            assert_eq!(e.kind, Unreachable::NonFinite, "pivot {i}");
        }
        for leg_id in LegId::ALL {
            for i in 0..3 {
                let mut f = feet;
                let mut a = f[leg_id.index()].to_array();
                a[i] = bad;
                f[leg_id.index()] = Vec3::from_array(a);
                let e = rejected_at_rest(&robot, &f);
                assert_eq!(
                    e,
                    IkError {
                        leg: leg_id,
                        kind: Unreachable::NonFinite
                    }
                );
            }
        }
    }
}

/// Body IK is all-or-nothing and names the first unreachable leg (order FL, FR, RL, RR).
#[test]
fn body_rejects_pose_and_names_the_leg() {
    let robot = Robot::fernando2025();
    let mut feet = robot.stance_feet(0.9);
    feet[LegId::RL.index()].z = -2.0;
    let e = rejected_at_rest(&robot, &feet);
    assert_eq!(
        e,
        IkError {
            leg: LegId::RL,
            kind: Unreachable::TooFar
        }
    );
    feet[LegId::FR.index()].y = 0.0; // inside no offset for fernando2025, but too close? no:
    feet[LegId::FR.index()].z = -2.0;
    let e = rejected_at_rest(&robot, &feet);
    assert_eq!(e.leg, LegId::FR);
    // Under Clamp the same pose solves, reporting the clamped legs.
    let sol = body::Solver::new(&robot)
        .inverse(
            &Pose::default(),
            &BodyConfig::default(),
            &feet,
            ReachPolicy::Clamp,
        )
        .unwrap();
    assert!(sol.any_clamped());
    assert!(sol.leg(LegId::FL).clamped.is_none());
    assert!(sol.leg(LegId::RL).clamped.is_some());
}

/// Planar distance of a foot from the hip-flexion joint, and its distance from the abduction
/// axis, for the branch the IK uses (f64).
fn planar_and_radial(robot: &Robot, foot: nalgebra::Vector3<f64>) -> (f64, f64) {
    let g = robot.leg;
    let r = foot.y.hypot(foot.z);
    let w = -(r * r - (g.d_lat_m as f64).powi(2)).max(0.0).sqrt();
    (foot.x.hypot(w + g.d_ax_m as f64), r)
}

fn clamp_solve(robot: &Robot, leg_id: LegId, p: Vec3) -> (JointAngles, leg::Clamp) {
    let sol = leg::Solver::new(robot)
        .inverse(leg_id, p, ReachPolicy::Clamp)
        .expect("clamp solves");
    assert!(sol.angles.is_finite());
    let c = sol.clamped.expect("clamp reported");
    // The reported distance is |target − FK(angles)|.
    let reached = fk64(&robot.leg, leg_id, q64(sol.angles));
    let moved = (reached - v64(p)).norm();
    assert!(
        (c.distance_m as f64 - moved).abs() <= CLAMP_TOL_M,
        "reported {} vs {moved}",
        c.distance_m
    );
    (sol.angles, c)
}

/// Under `Clamp`, an unreachable target lands on the workspace boundary: planar distance
/// L1 + L2 (too far) or |L1 − L2| (too close), or the offset circle (inside offset), when the
/// joints have no limits inside that boundary (full-turn limits).
#[test]
fn clamp_lands_on_the_workspace_boundary_full_turn() {
    for (_, preset) in presets() {
        let robot = Robot {
            limits: JointLimits::FULL_TURN,
            ..preset
        };
        let g = robot.leg;
        let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
        for leg_id in LegId::ALL {
            // Too far: straight down, and forward-down.
            for p in [
                in_plane(&robot, leg_id, 0.0, -1.5),
                in_plane(&robot, leg_id, 0.9, -0.7),
                Vec3::new(-0.4, 0.6, -0.9),
            ] {
                let (q, c) = clamp_solve(&robot, leg_id, p);
                assert_eq!(c.kind, Unreachable::TooFar);
                let reached = fk64(&g, leg_id, q64(q));
                let (planar, _) = planar_and_radial(&robot, reached);
                assert!((planar - (l1 + l2)).abs() <= CLAMP_TOL_M, "{planar}");
                // Nearest point of the boundary along the ray from the hip joint.
                let (want_planar, _) = planar_and_radial(&robot, v64(p));
                assert!((c.distance_m as f64 - (want_planar - (l1 + l2))).abs() <= CLAMP_TOL_M);
            }
            if g.femur_m != g.tibia_m {
                let p = in_plane(&robot, leg_id, 0.001, -0.001);
                let (q, c) = clamp_solve(&robot, leg_id, p);
                assert_eq!(c.kind, Unreachable::TooClose);
                let (planar, _) = planar_and_radial(&robot, fk64(&g, leg_id, q64(q)));
                assert!((planar - (l1 - l2).abs()).abs() <= CLAMP_TOL_M, "{planar}");
            }
            if g.d_lat_m > 0.0 {
                let p = Vec3::new(0.3, 0.01, -0.02);
                let (q, c) = clamp_solve(&robot, leg_id, p);
                assert_eq!(c.kind, Unreachable::InsideOffset);
                let (_, radial) = planar_and_radial(&robot, fk64(&g, leg_id, q64(q)));
                assert!((radial - g.d_lat_m as f64).abs() <= CLAMP_TOL_M, "{radial}");
            }
        }
    }
}

/// With the presets' limits the clamp also respects the joint limits: a too-far target ends
/// with the knee at its straightest limit (planar distance of that knee angle), and a
/// joint-limit target with the joint at its limit; the distance moved is reported.
#[test]
fn clamp_with_preset_limits() {
    for (_, robot) in presets() {
        let g = robot.leg;
        let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
        for leg_id in LegId::ALL {
            let p = in_plane(&robot, leg_id, 0.0, -1.5);
            let (q, c) = clamp_solve(&robot, leg_id, p);
            assert_eq!(c.kind, Unreachable::TooFar);
            assert_eq!(q.knee_rad, robot.limits.max_rad[2]);
            let k = robot.limits.max_rad[2] as f64;
            let at_limit = (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * k.cos()).sqrt();
            let (planar, _) = planar_and_radial(&robot, fk64(&g, leg_id, q64(q)));
            assert!(
                (planar - at_limit).abs() <= CLAMP_TOL_M,
                "{planar} vs {at_limit}"
            );
            for joint in Joint::ALL {
                let mut q = JointAngles::new(0.1, 0.3, -1.0).to_array();
                q[joint as usize] = robot.limits.max_rad[joint as usize] + 0.3;
                let target = leg::forward(&g, leg_id, JointAngles::from_array(q));
                let Ok(sol) = leg::Solver::new(&robot).inverse(leg_id, target, ReachPolicy::Clamp)
                else {
                    panic!("clamp must solve");
                };
                if let Some(c) = sol.clamped {
                    let j = c.kind;
                    assert!(matches!(j, Unreachable::JointLimit(_)), "{j:?}");
                    assert!(robot.limits.first_violation(sol.angles).is_none());
                    let reached = fk64(&g, leg_id, q64(sol.angles));
                    let moved = (reached - v64(target)).norm();
                    assert!((c.distance_m as f64 - moved).abs() <= CLAMP_TOL_M);
                } else {
                    // The other abduction branch reached it within limits (shahriar2023's
                    // full-turn abduction and hip).
                    let reached = fk64(&g, leg_id, q64(sol.angles));
                    assert!((reached - v64(target)).norm() <= FOOT_TOL_M);
                }
            }
        }
    }
}

fn any_bits() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(f32::MAX),
        Just(f32::MIN),
        Just(f32::MIN_POSITIVE),
        Just(0.0),
        Just(-0.0),
        (-1.0f32..1.0),
        (-1e20f32..1e20),
    ]
}

fn check_leg_result(r: &Result<leg::LegSolution, IkError>, robot: &Robot, leg_id: LegId, p: Vec3) {
    if let Ok(sol) = r {
        assert!(sol.angles.is_finite(), "{sol:?}");
        if let Some(c) = sol.clamped {
            // The distance moved, even for targets whose squares overflow f32; infinite only
            // when the distance itself exceeds f32::MAX.
            let moved = (fk64(&robot.leg, leg_id, q64(sol.angles)) - v64(p)).norm();
            assert!(c.distance_m >= 0.0, "{c:?}");
            let near_max = moved > f32::MAX as f64 * (1.0 - 1e-6);
            if !(near_max && c.distance_m == f32::INFINITY) {
                assert!(
                    (c.distance_m as f64 - moved).abs() <= CLAMP_TOL_M + 1e-6 * moved,
                    "{c:?} vs {moved}"
                );
            }
            assert!(robot.limits.first_violation(sol.angles).is_none());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(BITS_CASES))]

    /// Leg IK on arbitrary f32 bit patterns: never panics, never a non-finite angle, and a
    /// finite target under `Clamp` always gets an answer.
    #[test]
    fn leg_ik_on_arbitrary_bits(r in 0usize..2, l in 0usize..4,
                                x in any_bits(), y in any_bits(), z in any_bits()) {
        let robot = presets()[r].1;
        let leg_id = LegId::ALL[l];
        let p = Vec3::new(x, y, z);
        for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
            let res = leg::Solver::new(&robot).inverse(leg_id, p, policy);
            check_leg_result(&res, &robot, leg_id, p);
            if !p.is_finite() {
                prop_assert_eq!(res.unwrap_err().kind, Unreachable::NonFinite);
            } else if policy == ReachPolicy::Clamp {
                prop_assert!(res.is_ok(), "finite {:?} under Clamp: {:?}", p, res);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(BODY_BITS_CASES))]

    /// Body IK on arbitrary f32 bit patterns in the pose, pivot and feet: never panics, never a
    /// non-finite angle.
    #[test]
    fn body_ik_on_arbitrary_bits(r in 0usize..2, o in 0usize..6,
                                 pose in proptest::array::uniform6(any_bits()),
                                 pivot in proptest::array::uniform3(any_bits()),
                                 feet in proptest::array::uniform12(any_bits())) {
        let robot = presets()[r].1;
        let config = BodyConfig { order: RotationOrder::ALL[o], pivot_m: Vec3::from_array(pivot) };
        let pose = Pose::from_array(pose);
        let feet: [Vec3; 4] = std::array::from_fn(|i| Vec3::new(feet[3*i], feet[3*i+1], feet[3*i+2]));
        for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
            if let Ok(sol) = body::Solver::new(&robot).inverse(&pose, &config, &feet, policy) {
                for l in sol.legs() {
                    prop_assert!(l.angles.is_finite());
                }
            }
        }
        // The same with sane feet and a random pose: the stance is only moved by the pose.
        let stance = robot.stance_feet(0.3);
        for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
            if let Ok(sol) = body::Solver::new(&robot).inverse(&pose, &config, &stance, policy) {
                for l in sol.legs() {
                    prop_assert!(l.angles.is_finite());
                }
            }
        }
    }
}
