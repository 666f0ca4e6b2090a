//! Seeded inputs shared by the benchmarks (`benches/*.rs`) and `tests/bench_accuracy.rs`, so
//! that every solver is timed and checked on exactly the same targets.
//!
//! The targets are generated without kin-core: seeded random joint angles inside the preset
//! limits, mapped to a foot position by an f64 closed-form FK written here, then rounded to f32.
#![allow(dead_code)]

use kin_core::{JointAngles, LegId, Robot, Vec3};

/// Seed of every random input.
pub const SEED: u64 = 0x000D_EC0D_E5EE_D000;

/// Number of leg targets.
pub const N_TARGETS: usize = 10_000;

/// Number of body poses.
pub const N_POSES: usize = 10_000;

/// Generated joint angles stay this far inside each preset limit, rad, so that f32 rounding
/// of a solution exactly on a limit cannot turn a reachable target into a `joint_limit` error.
pub const LIMIT_MARGIN_RAD: f64 = 1e-3;

/// The un-abducted foot must lie at least this far below the hip plane (the IK's abduction
/// branch, `w ≤ 0`), m.
pub const BRANCH_MARGIN_M: f64 = 1e-4;

/// Seed 000's body-pose test ranges (§4.2): roll ±28°, pitch ±21°, yaw ±21°.
pub const POSE_RANGE_DEG: [f64; 3] = [28.0, 21.0, 21.0];

/// Stance height of the body-pose benchmark: seed 000 Table 4 body height `bh`, m.
pub const STANCE_HEIGHT_SHAHRIAR_M: f32 = 0.277;

pub use seeded_rng::SplitMix64;

/// One reachable leg target.
#[derive(Debug, Clone, Copy)]
pub struct LegTarget {
    /// Index into [`robots`].
    pub robot: usize,
    /// The leg.
    pub leg: LegId,
    /// The joint angles the target was generated from, rad (f64).
    pub angles_rad: [f64; 3],
    /// The foot in the hip frame, rounded to f32: the IK input.
    pub foot_in_hip: Vec3,
}

/// The two presets, in the order [`LegTarget::robot`] indexes.
pub fn robots() -> [Robot; 2] {
    [Robot::shahriar2023(), Robot::fernando2025()]
}

/// Names of [`robots`].
pub const ROBOT_NAMES: [&str; 2] = ["shahriar2023", "fernando2025"];

/// The canonical chain in f64, closed form:
/// `Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L_femur] + Ry(h+k)·[0,0,−L_tibia])`.
/// Returns the foot and the un-abducted in-plane depth `w`.
pub fn foot_in_hip_f64(robot: &Robot, leg: LegId, q: [f64; 3]) -> ([f64; 3], f64) {
    let g = &robot.leg;
    let (d_lat, d_ax) = (g.d_lat_m as f64, g.d_ax_m as f64);
    let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
    let [a, h, k] = q;
    let u = -l1 * h.sin() - l2 * (h + k).sin();
    let w = -d_ax - l1 * h.cos() - l2 * (h + k).cos();
    let y = leg.side() as f64 * d_lat;
    let (sa, ca) = a.sin_cos();
    ([u, ca * y - sa * w, sa * y + ca * w], w)
}

/// The [`N_TARGETS`] leg targets: alternately each robot, cycling through the four legs.
pub fn leg_targets() -> Vec<LegTarget> {
    let robots = robots();
    let mut rng = SplitMix64::new(SEED);
    let mut out = Vec::with_capacity(N_TARGETS);
    let mut i = 0usize;
    while out.len() < N_TARGETS {
        let r = out.len() % 2;
        let leg = LegId::ALL[(out.len() / 2) % 4];
        let robot = &robots[r];
        let q: [f64; 3] = core::array::from_fn(|j| {
            let lo = robot.limits.min_rad[j] as f64 + LIMIT_MARGIN_RAD;
            let hi = robot.limits.max_rad[j] as f64 - LIMIT_MARGIN_RAD;
            rng.range(lo, hi)
        });
        i += 1;
        let (p, w) = foot_in_hip_f64(robot, leg, q);
        if w > -BRANCH_MARGIN_M {
            // The other abduction branch: the IK (by convention) returns a different solution.
            continue;
        }
        out.push(LegTarget {
            robot: r,
            leg,
            angles_rad: q,
            foot_in_hip: Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32),
        });
    }
    assert!(
        i < 4 * N_TARGETS,
        "target generation rejected too many samples"
    );
    out
}

/// The [`N_POSES`] body poses (roll, pitch, yaw in seed 000's ranges; no translation).
pub fn body_poses() -> Vec<kin_core::Pose> {
    let mut rng = SplitMix64::new(SEED ^ 0xB0D7);
    (0..N_POSES)
        .map(|_| {
            let [r, p, y] = POSE_RANGE_DEG.map(|deg| rng.range(-deg, deg).to_radians() as f32);
            kin_core::Pose::rotation(r, p, y)
        })
        .collect()
}

/// `JointAngles` from an f64 array.
pub fn angles_f32(q: [f64; 3]) -> JointAngles {
    JointAngles::new(q[0] as f32, q[1] as f32, q[2] as f32)
}
