//! Accuracy on the benchmark inputs: the same 10,000 seeded reachable leg targets and 10,000
//! body poses that `benches/leg_ik.rs` and `benches/body_ik.rs` time, solved by kin-core and
//! mapped back through an independent f64 forward kinematics (a chain of nalgebra isometries,
//! neither kin-core's closed form nor the target generator's).

#[path = "../benches/common/mod.rs"]
mod common;

use kin_core::math::{Fast, Libm};
use kin_core::{body, leg, BodyConfig, JointAngles, LegId, Math, ReachPolicy, Robot, Vec3};
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Vector3};

/// Largest admissible distance between a target and the f64 FK of its IK solution, m.
const FOOT_ERROR_MAX_M: f64 = 1e-6;

/// Largest admissible distance between the generator's f32 target and the f64 chain at the
/// generating angles, m (f32 rounding of coordinates below 1.3 m).
const GENERATOR_AGREEMENT_M: f64 = 1e-7;

/// The canonical leg as a chain of f64 isometries: revolute x (abduction), offset
/// `[0, s·d_lat, −d_ax]`, revolute y (hip), link `[0, 0, −L_femur]`, revolute y (knee), link
/// `[0, 0, −L_tibia]`.
fn foot_in_hip_f64(robot: &Robot, leg: LegId, q: [f64; 3]) -> Vector3<f64> {
    let g = &robot.leg;
    let s = leg.side() as f64;
    let rot = |axis: Vector3<f64>, a: f64| {
        Isometry3::from_parts(Translation3::identity(), Rotation3::new(axis * a).into())
    };
    let link = |x: f64, y: f64, z: f64| {
        Isometry3::from_parts(Translation3::new(x, y, z), Default::default())
    };
    let chain = rot(Vector3::x(), q[0])
        * link(0.0, s * g.d_lat_m as f64, -(g.d_ax_m as f64))
        * rot(Vector3::y(), q[1])
        * link(0.0, 0.0, -(g.femur_m as f64))
        * rot(Vector3::y(), q[2])
        * link(0.0, 0.0, -(g.tibia_m as f64));
    (chain * Point3::origin()).coords
}

fn to_f64(v: Vec3) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn angles_f64(q: JointAngles) -> [f64; 3] {
    q.to_array().map(|a| a as f64)
}

/// Worst foot error over all benchmark leg targets for backend `M`, m.
fn worst_leg_error<M: Math>() -> f64 {
    let robots = common::robots();
    let mut worst = 0.0f64;
    for t in common::leg_targets() {
        let robot = &robots[t.robot];
        let q = leg::Solver::<M>::with_math(robot)
            .inverse(t.leg, t.foot_in_hip, ReachPolicy::Reject)
            .unwrap_or_else(|e| panic!("{} target {:?}: {e}", common::ROBOT_NAMES[t.robot], t));
        let err =
            (foot_in_hip_f64(robot, t.leg, angles_f64(q.angles)) - to_f64(t.foot_in_hip)).norm();
        worst = worst.max(err);
    }
    worst
}

#[test]
fn benchmark_targets_are_what_the_generator_says() {
    let targets = common::leg_targets();
    assert_eq!(targets.len(), common::N_TARGETS);
    let robots = common::robots();
    let mut per_leg = [[0usize; 4]; 2];
    for t in &targets {
        per_leg[t.robot][t.leg.index()] += 1;
        let p = foot_in_hip_f64(&robots[t.robot], t.leg, t.angles_rad);
        let err = (p - to_f64(t.foot_in_hip)).norm();
        assert!(
            err <= GENERATOR_AGREEMENT_M,
            "{t:?}: chain and generator differ by {err:e} m"
        );
    }
    // Both presets and all four legs, equally.
    assert_eq!(per_leg, [[common::N_TARGETS / 8; 4]; 2]);
}

#[test]
fn leg_ik_then_f64_fk_within_1_um_on_every_benchmark_target() {
    let fast = worst_leg_error::<Fast>();
    let libm = worst_leg_error::<Libm>();
    eprintln!(
        "worst foot error over {} targets: Fast {fast:.3e} m, Libm {libm:.3e} m",
        common::N_TARGETS
    );
    assert!(fast <= FOOT_ERROR_MAX_M, "Fast backend: {fast:e} m");
    assert!(libm <= FOOT_ERROR_MAX_M, "Libm backend: {libm:e} m");
}

#[test]
fn body_ik_then_f64_fk_within_1_um_on_every_benchmark_pose() {
    let robot = Robot::shahriar2023();
    let height_m = common::STANCE_HEIGHT_SHAHRIAR_M;
    let feet = robot.stance_feet(height_m);
    let config = BodyConfig::default();
    let mut worst = 0.0f64;
    for pose in common::body_poses() {
        let sol = body::Solver::new(&robot)
            .inverse_at_stance(&pose, &config, height_m, ReachPolicy::Reject)
            .unwrap_or_else(|e| panic!("{pose:?}: {e}"));
        // zyx: R = Rz(yaw)·Ry(pitch)·Rx(roll), nalgebra's from_euler_angles(roll, pitch, yaw).
        let r = Rotation3::from_euler_angles(
            pose.roll_rad as f64,
            pose.pitch_rad as f64,
            pose.yaw_rad as f64,
        );
        for leg in LegId::ALL {
            let foot_in_hip = foot_in_hip_f64(&robot, leg, angles_f64(sol.leg(leg).angles));
            let foot_in_world =
                r * (to_f64(robot.hip_in_body(leg)) + foot_in_hip) + to_f64(pose.translation());
            worst = worst.max((foot_in_world - to_f64(feet[leg.index()])).norm());
        }
    }
    eprintln!(
        "worst foot error over {} body poses: {worst:.3e} m",
        common::N_POSES
    );
    assert!(worst <= FOOT_ERROR_MAX_M, "{worst:e} m");
}
