//! Group `batch`: the batch solves of `kin_core::batch` on one thread against the scalar
//! solves over the same inputs, in the same run. One iteration solves the whole set, so the
//! time per target is criterion's time per iteration over the set's size (criterion prints it
//! as the throughput, elements/s).
//!
//! - `leg_ik_scalar`: the 10,000 seeded reachable leg targets (both presets, all legs, see
//!   `common/mod.rs`), one `leg::Solver::inverse` each (the solvers kept).
//! - `leg_ik_batch`: the same targets grouped by robot and leg, one `batch::leg_inverse` per
//!   group (rows `[x, y, z]` in, rows of angles out).
//! - `leg_ik_batch_avx2` / `leg_ik_batch_avx512`: `leg_ik_batch` by the entry points compiled
//!   for AVX2 (8 lanes) and AVX-512 (16 lanes), where the CPU has them.
//! - `leg_ik_batch_soa`: the same with `batch::leg_inverse_soa` (one slice per coordinate).
//! - `body_ik_scalar` / `body_ik_batch`: the 10,000 seeded body poses at seed 000's nominal
//!   stance, `body::Solver::inverse_at_stance_into` each / one `batch::body_inverse`
//!   (`body_ik_batch_avx512`: compiled for AVX-512).

// The AVX2 entry points of `kin_core::batch::avx2` are unsafe to call (the CPU must have
// AVX2, checked before each use).
#![allow(unsafe_code)]

mod common;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use kin_core::batch::{self, BodyFeet};
use kin_core::{body, leg, BodyConfig, BodySolution, LegId, ReachPolicy, Robot};
use std::hint::black_box;

/// The signature of `batch::leg_inverse` and of its compiled entry points.
type LegInverse = unsafe fn(
    &leg::Solver,
    LegId,
    ReachPolicy,
    &[f32],
    &mut [f32],
    &mut [u8],
) -> Result<(), batch::LengthMismatch>;

/// The signature of `batch::body_inverse` and of its compiled entry points.
type BodyInverse = unsafe fn(
    &body::Solver,
    &BodyConfig,
    ReachPolicy,
    &[f32],
    BodyFeet<'_>,
    &mut [f32],
    &mut [u8],
    &mut [i8],
) -> Result<(), batch::LengthMismatch>;

fn batch_benches(c: &mut Criterion) {
    let robots = common::robots();
    let targets = common::leg_targets();
    let n = targets.len();
    let solvers = robots.map(|r| leg::Solver::new(&r));

    // The targets grouped by (robot, leg): rows and columns.
    let mut groups: Vec<(usize, LegId, Vec<[f32; 3]>)> = Vec::new();
    for r in 0..robots.len() {
        for leg in LegId::ALL {
            let rows: Vec<[f32; 3]> = targets
                .iter()
                .filter(|t| t.robot == r && t.leg == leg)
                .map(|t| t.foot_in_hip.to_array())
                .collect();
            groups.push((r, leg, rows));
        }
    }
    let columns: Vec<[Vec<f32>; 3]> = groups
        .iter()
        .map(|(_, _, rows)| core::array::from_fn(|k| rows.iter().map(|p| p[k]).collect()))
        .collect();
    let mut angles: Vec<Vec<[f32; 3]>> = groups.iter().map(|g| vec![[0.0; 3]; g.2.len()]).collect();
    let mut codes: Vec<Vec<u8>> = groups.iter().map(|g| vec![0; g.2.len()]).collect();
    // Every target solves, in the batch as in the scalar solve.
    for (k, (r, leg, rows)) in groups.iter().enumerate() {
        batch::leg_inverse(
            &solvers[*r],
            *leg,
            ReachPolicy::Reject,
            rows.as_flattened(),
            angles[k].as_flattened_mut(),
            &mut codes[k],
        )
        .expect("lengths match");
        assert!(codes[k].iter().all(|&c| c == batch::code::OK));
    }

    let mut group = c.benchmark_group("batch");
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("leg_ik_scalar", |b| {
        b.iter(|| {
            for t in black_box(&targets) {
                let _ =
                    black_box(solvers[t.robot].inverse(t.leg, t.foot_in_hip, ReachPolicy::Reject));
            }
        });
    });
    // The batch leg IK in each form this CPU runs: the portable one, then the entry points
    // compiled for AVX2 and AVX-512 (unsafe to call: each is listed only where the CPU has
    // its features).
    let mut forms: Vec<(&str, LegInverse)> = vec![("leg_ik_batch", batch::leg_inverse)];
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx2") {
            forms.push(("leg_ik_batch_avx2", batch::avx2::leg_inverse));
        }
        if has_avx512() {
            forms.push(("leg_ik_batch_avx512", batch::avx512::leg_inverse));
        }
    }
    for (name, solve) in forms {
        group.bench_function(name, |b| {
            b.iter(|| {
                for (k, (r, leg, rows)) in black_box(&groups).iter().enumerate() {
                    // SAFETY: the CPU has the form's features (checked when it was listed).
                    let _ = unsafe {
                        solve(
                            &solvers[*r],
                            *leg,
                            ReachPolicy::Reject,
                            rows.as_flattened(),
                            angles[k].as_flattened_mut(),
                            &mut codes[k],
                        )
                    };
                }
                black_box(&angles);
            });
        });
    }
    let mut soa_out: Vec<[Vec<f32>; 3]> = groups
        .iter()
        .map(|g| core::array::from_fn(|_| vec![0.0; g.2.len()]))
        .collect();
    group.bench_function("leg_ik_batch_soa", |b| {
        b.iter(|| {
            for (k, (r, leg, _)) in black_box(&groups).iter().enumerate() {
                let [x, y, z] = &columns[k];
                let [a, h, q] = &mut soa_out[k];
                let _ = batch::leg_inverse_soa(
                    &solvers[*r],
                    *leg,
                    ReachPolicy::Reject,
                    [x, y, z],
                    a,
                    h,
                    q,
                    &mut codes[k],
                );
            }
            black_box(&soa_out);
        });
    });

    let robot = Robot::shahriar2023();
    let config = BodyConfig::default();
    let height_m = common::STANCE_HEIGHT_SHAHRIAR_M;
    let poses = common::body_poses();
    let pose_rows: Vec<[f32; 6]> = poses.iter().map(|p| p.to_array()).collect();
    let solver = body::Solver::new(&robot);
    let m = poses.len();
    let mut body_angles = vec![[0.0f32; 12]; m];
    let (mut body_codes, mut body_legs) = (vec![0u8; m], vec![0i8; m]);
    group.throughput(Throughput::Elements(m as u64));
    group.bench_function("body_ik_scalar", |b| {
        let mut sol = BodySolution::default();
        b.iter(|| {
            for p in black_box(&poses) {
                let _ = solver.inverse_at_stance_into(
                    p,
                    &config,
                    height_m,
                    ReachPolicy::Reject,
                    &mut sol,
                );
                black_box(&sol);
            }
        });
    });
    // The batch body IK, portable and (where the CPU has it) compiled for AVX-512.
    let mut forms: Vec<(&str, BodyInverse)> = vec![("body_ik_batch", batch::body_inverse)];
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        forms.push(("body_ik_batch_avx512", batch::avx512::body_inverse));
    }
    for (name, solve) in forms {
        group.bench_function(name, |b| {
            b.iter(|| {
                // SAFETY: the CPU has the form's features (checked when it was listed).
                let _ = unsafe {
                    solve(
                        &solver,
                        &config,
                        ReachPolicy::Reject,
                        black_box(pose_rows.as_flattened()),
                        BodyFeet::Stance { height_m },
                        body_angles.as_flattened_mut(),
                        &mut body_codes,
                        &mut body_legs,
                    )
                };
                black_box(&body_angles);
            });
        });
    }
    assert!(body_codes.iter().all(|&c| c == batch::code::OK));
    group.finish();
}

/// True when the CPU runs `batch::avx512`.
#[cfg(target_arch = "x86_64")]
fn has_avx512() -> bool {
    std::is_x86_feature_detected!("avx512f")
        && std::is_x86_feature_detected!("avx512vl")
        && std::is_x86_feature_detected!("avx512bw")
        && std::is_x86_feature_detected!("avx512dq")
}

criterion_group!(benches, batch_benches);
criterion_main!(benches);
