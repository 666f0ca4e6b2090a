//! Group `body_ik`: one body pose → twelve joint angles per iteration
//! (`kin_core::body::inverse_at_stance`), over 10,000 seeded poses in seed 000's ranges
//! (roll ±28°, pitch ±21°, yaw ±21°), the seed 000 robot at its stance height `bh` = 0.277 m,
//! rotation order `zyx` about the body centre.
//!
//! - `kin_core`: the default `Fast` math backend (the robot's constants derived on each call).
//! - `kin_core_solver`: `kin_core::body::Solver::inverse_at_stance`, the constants prepared
//!   once.
//! - `kin_core_libm`: the `Libm` reference backend.

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use kin_core::math::Libm;
use kin_core::{body, BodyConfig, ReachPolicy, Robot};
use std::hint::black_box;

fn body_ik(c: &mut Criterion) {
    let robot = Robot::shahriar2023();
    let config = BodyConfig::default();
    let height_m = common::STANCE_HEIGHT_SHAHRIAR_M;
    let poses = common::body_poses();
    let n = poses.len();
    for p in &poses {
        body::Solver::new(&robot)
            .inverse_at_stance(p, &config, height_m, ReachPolicy::Reject)
            .expect("seed 000 pose ranges are reachable at the nominal stance");
    }

    // Robot, configuration and height go through `black_box` too: the compiler must not fold
    // the preset into the code (the free functions derive its constants on every call).
    let mut group = c.benchmark_group("body_ik");
    group.bench_function("kin_core", |b| {
        let mut i = 0;
        b.iter(|| {
            let p = &poses[i];
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(body::Solver::new(black_box(&robot)).inverse_at_stance(
                black_box(p),
                black_box(&config),
                black_box(height_m),
                ReachPolicy::Reject,
            ))
        });
    });
    let solver = body::Solver::new(&robot);
    group.bench_function("kin_core_solver", |b| {
        let mut i = 0;
        b.iter(|| {
            let p = &poses[i];
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(black_box(&solver).inverse_at_stance(
                black_box(p),
                black_box(&config),
                black_box(height_m),
                ReachPolicy::Reject,
            ))
        });
    });
    group.bench_function("kin_core_libm", |b| {
        let mut i = 0;
        b.iter(|| {
            let p = &poses[i];
            i = if i + 1 == n { 0 } else { i + 1 };
            black_box(
                body::Solver::<Libm>::with_math(black_box(&robot)).inverse_at_stance(
                    black_box(p),
                    black_box(&config),
                    black_box(height_m),
                    ReachPolicy::Reject,
                ),
            )
        });
    });
    group.finish();
}

criterion_group!(benches, body_ik);
criterion_main!(benches);
