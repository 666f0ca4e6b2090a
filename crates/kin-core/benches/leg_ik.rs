//! Group `leg_ik`: one leg solve per iteration, over the same 10,000 seeded reachable targets
//! (both presets, all four legs, see `common/mod.rs`).
//!
//! - `kin_core`: `kin_core::leg::inverse` (the default `Fast` math backend; the robot's
//!   derived constants computed on each call).
//! - `kin_core_solver`: `kin_core::leg::Solver::inverse`, the constants prepared once.
//! - `kin_core_libm`: `kin_core::leg::inverse_with::<Libm>` (the reference backend).
//! - `k_crate`: the `k` crate's `JacobianIkSolver` on the same chain, position only, started
//!   from a nearby configuration (the generating angles plus up to ±[`K_START_OFFSET_RAD`] on
//!   each joint, as a controller tracking a moving foot would), Newton steps
//!   (`jacobian_multiplier = 1`) until the foot is within [`K_TOLERANCE_M`].
//!
//! Before timing, the k chain's FK is checked against `kin_core::leg::forward` and k's
//! convergence over all targets is printed.

mod common;

use common::{LegTarget, SplitMix64};
use criterion::{criterion_group, criterion_main, Criterion};
use k::prelude::*;
use k::{Isometry3, JointType, NodeBuilder, Translation3, Vector3};
use kin_core::math::Libm;
use kin_core::{leg, LegId, ReachPolicy, Robot};
use std::hint::black_box;

/// Largest offset of k's start configuration from the generating angles, per joint, rad.
const K_START_OFFSET_RAD: f64 = 0.1;
/// k's convergence tolerance on the foot position, m (the accuracy kin-core is held to).
const K_TOLERANCE_M: f64 = 1e-6;
/// k's iteration cap.
const K_MAX_TRIES: usize = 50;
/// Largest admissible difference between the k chain's FK and kin-core's f32 FK, m.
const K_FK_AGREEMENT_M: f64 = 2e-6;

/// The canonical leg as a `k` chain: revolute x (abduction) at the hip mount, offset
/// `[0, s·d_lat, −d_ax]`, revolute y (hip), link `[0, 0, −L_femur]`, revolute y (knee), link
/// `[0, 0, −L_tibia]` to the foot.
fn k_leg(robot: &Robot, leg: LegId) -> k::SerialChain<f64> {
    let g = &robot.leg;
    let s = leg.side() as f64;
    let abduction = NodeBuilder::new()
        .name("abduction")
        .joint_type(JointType::Rotational {
            axis: Vector3::x_axis(),
        })
        .into_node();
    let hip = NodeBuilder::new()
        .name("hip")
        .translation(Translation3::new(
            0.0,
            s * g.d_lat_m as f64,
            -(g.d_ax_m as f64),
        ))
        .joint_type(JointType::Rotational {
            axis: Vector3::y_axis(),
        })
        .into_node();
    let knee = NodeBuilder::new()
        .name("knee")
        .translation(Translation3::new(0.0, 0.0, -(g.femur_m as f64)))
        .joint_type(JointType::Rotational {
            axis: Vector3::y_axis(),
        })
        .into_node();
    let foot = NodeBuilder::new()
        .name("foot")
        .translation(Translation3::new(0.0, 0.0, -(g.tibia_m as f64)))
        .joint_type(JointType::Fixed)
        .into_node();
    k::connect![abduction => hip => knee => foot];
    k::SerialChain::from_end(&foot)
}

fn k_foot(arm: &k::SerialChain<f64>) -> [f64; 3] {
    let t = arm.end_transform().translation.vector;
    [t.x, t.y, t.z]
}

/// Checks the k chains against kin-core's FK and reports k's convergence on every target.
fn check_k(
    robots: &[Robot; 2],
    arms: &[Vec<k::SerialChain<f64>>],
    targets: &[LegTarget],
    starts: &[[f64; 3]],
    solver: &k::JacobianIkSolver<f64>,
    constraints: &k::Constraints,
) {
    let mut worst_fk = 0.0f64;
    let (mut converged, mut worst_err) = (0usize, 0.0f64);
    for (t, start) in targets.iter().zip(starts) {
        let arm = &arms[t.robot][t.leg.index()];
        arm.set_joint_positions_unchecked(&t.angles_rad);
        let kf = k_foot(arm);
        let ours = leg::forward(
            &robots[t.robot].leg,
            t.leg,
            common::angles_f32(t.angles_rad),
        );
        for (a, b) in kf.iter().zip(ours.to_array()) {
            worst_fk = worst_fk.max((a - b as f64).abs());
        }
        arm.set_joint_positions_unchecked(start);
        let p = t.foot_in_hip;
        let goal = Isometry3::translation(p.x as f64, p.y as f64, p.z as f64);
        if solver
            .solve_with_constraints(arm, &goal, constraints)
            .is_ok()
        {
            converged += 1;
            let kf = k_foot(arm);
            let err = ((kf[0] - p.x as f64).powi(2)
                + (kf[1] - p.y as f64).powi(2)
                + (kf[2] - p.z as f64).powi(2))
            .sqrt();
            worst_err = worst_err.max(err);
        }
    }
    assert!(
        worst_fk <= K_FK_AGREEMENT_M,
        "k chain FK disagrees with kin_core::leg::forward by {worst_fk:e} m"
    );
    eprintln!(
        "k_crate check: FK agrees with kin-core within {worst_fk:.1e} m; IK converged on \
         {converged}/{} targets (start ±{K_START_OFFSET_RAD} rad, tol {K_TOLERANCE_M:e} m), \
         worst error of the converged {worst_err:.1e} m",
        targets.len()
    );
}

fn leg_ik(c: &mut Criterion) {
    let robots = common::robots();
    let targets = common::leg_targets();
    let n = targets.len();
    // Every target must be solved by kin-core (the set is reachable by construction).
    for t in &targets {
        leg::Solver::new(&robots[t.robot])
            .inverse(t.leg, t.foot_in_hip, ReachPolicy::Reject)
            .expect("generated target is reachable");
    }
    let inputs: Vec<(usize, LegId, kin_core::Vec3)> = targets
        .iter()
        .map(|t| (t.robot, t.leg, t.foot_in_hip))
        .collect();

    // The robots go through `black_box` too: the compiler must not fold the presets' lengths
    // into the code (the free functions compute the derived constants on every call).
    let mut group = c.benchmark_group("leg_ik");
    group.bench_function("kin_core", |b| {
        let mut i = 0;
        b.iter(|| {
            let (r, leg, p) = *black_box(&inputs[i]);
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(leg::Solver::new(black_box(&robots[r])).inverse(leg, p, ReachPolicy::Reject))
        });
    });
    let solvers = robots.map(|r| leg::Solver::new(&r));
    group.bench_function("kin_core_solver", |b| {
        let mut i = 0;
        b.iter(|| {
            let (r, leg, p) = *black_box(&inputs[i]);
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(black_box(&solvers[r]).inverse(leg, p, ReachPolicy::Reject))
        });
    });
    group.bench_function("kin_core_libm", |b| {
        let mut i = 0;
        b.iter(|| {
            let (r, leg, p) = *black_box(&inputs[i]);
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(
                leg::Solver::<Libm>::with_math(black_box(&robots[r])).inverse(
                    leg,
                    p,
                    ReachPolicy::Reject,
                ),
            )
        });
    });

    let arms: Vec<Vec<k::SerialChain<f64>>> = robots
        .iter()
        .map(|r| LegId::ALL.iter().map(|&l| k_leg(r, l)).collect())
        .collect();
    let mut rng = SplitMix64::new(common::SEED ^ 0x4B);
    let starts: Vec<[f64; 3]> = targets
        .iter()
        .map(|t| {
            t.angles_rad
                .map(|a| a + rng.range(-K_START_OFFSET_RAD, K_START_OFFSET_RAD))
        })
        .collect();
    let goals: Vec<Isometry3<f64>> = targets
        .iter()
        .map(|t| {
            let p = t.foot_in_hip;
            Isometry3::translation(p.x as f64, p.y as f64, p.z as f64)
        })
        .collect();
    let solver = k::JacobianIkSolver::new(K_TOLERANCE_M, 1.0, 1.0, K_MAX_TRIES);
    let constraints = k::Constraints {
        rotation_x: false,
        rotation_y: false,
        rotation_z: false,
        ..Default::default()
    };
    check_k(&robots, &arms, &targets, &starts, &solver, &constraints);
    group.bench_function("k_crate", |b| {
        let mut i = 0;
        b.iter(|| {
            let t = &targets[i];
            let arm = &arms[t.robot][t.leg.index()];
            arm.set_joint_positions_unchecked(&starts[i]);
            let result = solver.solve_with_constraints(arm, black_box(&goals[i]), &constraints);
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(result).ok()
        });
    });
    group.finish();
}

criterion_group!(benches, leg_ik);
criterion_main!(benches);
