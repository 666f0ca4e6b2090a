//! Leg Jacobian (seed 001 eq. 4): analytic columns against central differences of the f64 FK
//! oracle, joint rates as its inverse, the singularity measure against nalgebra's SVD, and the
//! foot velocity seen from a moving body.

mod common;

use common::*;
use kin_core::jacobian::{self, SINGULARITY_THRESHOLD};
use kin_core::rotation::{self, RotationOrder};
use kin_core::{JointAngles, LegId, Mat3, Vec3};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Largest entry-wise difference between the analytic f32 Jacobian and central differences of
/// the f64 FK (m/rad).
const JACOBIAN_TOL: f64 = 2.0e-6;
/// Step of the central differences (rad); truncation error ~ step² · |FK'''| ≈ 1e-12 m/rad.
const FD_STEP_RAD: f64 = 1.0e-6;
/// Relative residual allowed for `J·q̇ = v`, scaled by the condition number.
const RATES_REL_TOL: f64 = 1.0e-5;
/// Absolute part of the inverse-condition tolerance against the SVD.
const CONDITION_ABS_TOL: f64 = 1.0e-3;
/// Relative part of the inverse-condition tolerance (measured worst: 0.36 % at σmin/σmax ≈ 0.01).
const CONDITION_REL_TOL: f64 = 1.0e-2;
/// Random configurations per preset and leg.
const SAMPLES: usize = 400;

fn to64(m: &Mat3) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| m.rows[i][j] as f64)
}

fn fd_jacobian(robot: &kin_core::Robot, leg: LegId, q: [f64; 3]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for c in 0..3 {
        let (mut qp, mut qm) = (q, q);
        qp[c] += FD_STEP_RAD;
        qm[c] -= FD_STEP_RAD;
        let col = (fk64(&robot.leg, leg, qp) - fk64(&robot.leg, leg, qm)) / (2.0 * FD_STEP_RAD);
        j.set_column(c, &col);
    }
    j
}

#[test]
fn analytic_jacobian_equals_finite_differences() {
    let mut rng = SplitMix64::new(0x1AC);
    for (_, robot) in presets() {
        for leg in LegId::ALL {
            for _ in 0..SAMPLES {
                let q = JointAngles::new(
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                );
                let j = to64(&jacobian::leg_jacobian(&robot.leg, leg, q));
                let fd = fd_jacobian(&robot, leg, q64(q));
                let err = (j - fd).abs().max();
                assert!(err <= JACOBIAN_TOL, "{leg} {q:?}: {err:e}\n{j}\n{fd}");
            }
        }
    }
}

#[test]
fn joint_rates_invert_the_jacobian() {
    let mut rng = SplitMix64::new(0x2A7E);
    let mut solved = 0;
    let mut refused = 0;
    for (_, robot) in presets() {
        for leg in LegId::ALL {
            for _ in 0..SAMPLES {
                let q = random_angles(&mut rng, &robot, 0.0);
                let v = Vec3::new(
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                );
                let j64 = fd_jacobian(&robot, leg, q64(q));
                let ic = jacobian::inverse_condition(&jacobian::leg_jacobian(&robot.leg, leg, q));
                match jacobian::joint_rates(&robot.leg, leg, q, v) {
                    Ok(rates) => {
                        assert!(ic >= SINGULARITY_THRESHOLD);
                        assert!(rates.iter().all(|r| r.is_finite()));
                        let qd = Vector3::from(rates.map(|r| r as f64));
                        let res = (j64 * qd - v64(v)).norm();
                        let bound = RATES_REL_TOL * v64(v).norm() / ic as f64;
                        assert!(res <= bound, "{leg} {q:?}: residual {res:e} > {bound:e}");
                        solved += 1;
                    }
                    Err(e) => {
                        assert!(ic < SINGULARITY_THRESHOLD, "refused at {ic}");
                        assert!(e.inverse_condition < SINGULARITY_THRESHOLD);
                        refused += 1;
                    }
                }
            }
        }
    }
    assert!(solved > 1000, "{solved} solved, {refused} refused");
}

/// `inverse_condition` ≈ σmin/σmax of nalgebra's SVD of the same matrix. With one small singular
/// value (the leg's usual singularities: straight or folded knee, foot level with the axis) the
/// f32 closed form is within 1 % + 1e-3; everywhere it classifies against
/// `SINGULARITY_THRESHOLD` as the SVD does outside a ±10 % band. (Where two singular values are
/// small at once — straight knee *and* foot level with the axis — its f32 eigenvalues of JᵀJ
/// lose the two small ones together and it can read ≈ 0 for an SVD value of ≈ 0.01: still
/// singular.)
#[test]
fn inverse_condition_matches_svd() {
    let mut rng = SplitMix64::new(0xC0D);
    let mut near_singular = 0;
    let mut compared = 0;
    for (_, robot) in presets() {
        for leg in LegId::ALL {
            for i in 0..SAMPLES * 5 {
                let mut q = JointAngles::new(
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                );
                if i % 4 == 0 {
                    q.knee_rad = rng.range(-0.05, 0.05) as f32; // close to the straight knee
                    near_singular += 1;
                }
                let j = jacobian::leg_jacobian(&robot.leg, leg, q);
                let got = jacobian::inverse_condition(&j) as f64;
                let s = to64(&j).svd(false, false).singular_values;
                let mut sv = [s[0], s[1], s[2]];
                sv.sort_by(|a, b| a.total_cmp(b));
                let want = sv[0] / sv[2];
                assert!((0.0..=1.0).contains(&got), "{got}");
                let threshold = SINGULARITY_THRESHOLD as f64;
                if want >= 1.1 * threshold {
                    assert!(got >= threshold, "{leg} {q:?}: {got} vs SVD {want}");
                }
                if want <= 0.9 * threshold {
                    assert!(got < threshold, "{leg} {q:?}: {got} vs SVD {want}");
                }
                if sv[1] / sv[2] >= 0.2 {
                    compared += 1;
                    let tol = CONDITION_ABS_TOL + CONDITION_REL_TOL * want;
                    assert!(
                        (got - want).abs() <= tol,
                        "{leg} {q:?}: {got} vs SVD {want}"
                    );
                }
                let det = to64(&j).determinant().abs();
                let m = jacobian::manipulability(&j) as f64;
                assert!((m - det).abs() <= 1e-6 * (1.0 + det), "{m} vs {det}");
            }
        }
    }
    assert!(
        near_singular > 1000 && compared > 10_000,
        "{near_singular} {compared}"
    );
}

/// The leg's own measure (`leg_inverse_condition`, from the abduction-free Gram matrix, the
/// one the host's preflight and the device's start check use) is the measure of the full
/// Jacobian: against nalgebra's SVD with the tolerances of `inverse_condition_matches_svd`,
/// the same classification against `SINGULARITY_THRESHOLD` outside its ±10 % band; so is the
/// device's (`leg::Solver::inverse_condition` on the firmware's `SoftFloat` backend).
#[test]
fn leg_inverse_condition_is_the_jacobian_measure() {
    use kin_core::leg;
    use kin_core::math::SoftFloat;
    let mut rng = SplitMix64::new(0x1C0D);
    let mut compared = 0;
    for (_, robot) in presets() {
        let device = leg::Solver::<SoftFloat>::with_math(&robot);
        for leg in LegId::ALL {
            for i in 0..SAMPLES * 5 {
                let mut q = JointAngles::new(
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                    rng.range(-3.0, 3.0) as f32,
                );
                if i % 4 == 0 {
                    q.knee_rad = rng.range(-0.05, 0.05) as f32;
                }
                let host = jacobian::leg_inverse_condition(&robot.leg, leg, q) as f64;
                let on_device = device.inverse_condition(leg, q) as f64;
                let j = jacobian::leg_jacobian(&robot.leg, leg, q);
                let s = to64(&j).svd(false, false).singular_values;
                let mut sv = [s[0], s[1], s[2]];
                sv.sort_by(|a, b| a.total_cmp(b));
                let want = sv[0] / sv[2];
                let threshold = SINGULARITY_THRESHOLD as f64;
                for got in [host, on_device] {
                    assert!((0.0..=1.0).contains(&got), "{got}");
                    if want >= 1.1 * threshold {
                        assert!(got >= threshold, "{leg} {q:?}: {got} vs SVD {want}");
                    }
                    if want <= 0.9 * threshold {
                        assert!(got < threshold, "{leg} {q:?}: {got} vs SVD {want}");
                    }
                    if sv[1] / sv[2] >= 0.2 {
                        compared += 1;
                        let tol = CONDITION_ABS_TOL + CONDITION_REL_TOL * want;
                        assert!(
                            (got - want).abs() <= tol,
                            "{leg} {q:?}: {got} vs SVD {want}"
                        );
                    }
                }
            }
        }
    }
    assert!(compared > 10_000, "{compared}");
}

/// Straight knee (knee = 0) is singular: `joint_rates` refuses with a typed error and the
/// measure is ~0; so is a foot level with the abduction axis (w = 0).
#[test]
fn straight_knee_is_singular() {
    for (_, robot) in presets() {
        for leg in LegId::ALL {
            for (a, h) in [(0.0, 0.0), (0.3, -0.4), (-0.2, 1.0)] {
                let q = JointAngles::new(a, h, 0.0);
                let j = jacobian::leg_jacobian(&robot.leg, leg, q);
                let ic = jacobian::inverse_condition(&j);
                assert!(ic < 1e-3, "{ic}");
                let e = jacobian::joint_rates(&robot.leg, leg, q, Vec3::new(0.1, 0.0, 0.0))
                    .unwrap_err();
                assert!(e.inverse_condition < SINGULARITY_THRESHOLD);
                assert!(e.inverse_condition.is_finite());
            }
        }
    }
    // Foot level with the abduction axis: hip = 90°, knee = −1 rad with the planar foot on the
    // axis level (shahriar2023, d_ax = 0): w = −L1·cos h − L2·cos(h + k).
    let robot = kin_core::Robot::shahriar2023();
    let (l1, l2) = (robot.leg.femur_m as f64, robot.leg.tibia_m as f64);
    let k = -1.0f64;
    // Solve L1·cos h + L2·cos(h + k) = 0 for h: tan h = (L1 + L2 cos k)/(L2 sin k).
    let h = ((l1 + l2 * k.cos()) / (l2 * k.sin())).atan();
    let q = JointAngles::new(0.2, h as f32, k as f32);
    assert!(w_of(&robot.leg, q64(q)).abs() < 1e-6);
    let ic = jacobian::inverse_condition(&jacobian::leg_jacobian(&robot.leg, LegId::FL, q));
    assert!(ic < 1e-3, "{ic}");
    assert!(jacobian::joint_rates(&robot.leg, LegId::FL, q, Vec3::new(0.0, 0.1, 0.0)).is_err());
}

/// Seed 001's initial pose is well conditioned: σmin/σmax ≈ 0.215 (nalgebra SVD of the f64 Jacobian: 0.2150).
#[test]
fn seed001_initial_pose_condition() {
    let robot = kin_core::Robot::fernando2025();
    let q = kin_core::paper::from_seed001(kin_core::paper::SEED001_INITIAL);
    let ic = jacobian::inverse_condition(&jacobian::leg_jacobian(&robot.leg, LegId::FL, q));
    assert!((ic - 0.215).abs() < 0.001, "{ic}");
}

/// Seed 001 eq. 4 solved for the leg: a foot held in the world while the body moves has, in its
/// hip frame, the velocity given by `foot_velocity_in_hip`; checked against central
/// differences of `Rᵀ(t)·(f − T(t) − c) + c − hip` in f64.
#[test]
fn foot_velocity_in_hip_matches_differentiated_pose() {
    let mut rng = SplitMix64::new(0xF00);
    for order in RotationOrder::ALL {
        for _ in 0..50 {
            let q = [(); 3].map(|_| rng.range(-0.5, 0.5));
            let qd = [(); 3].map(|_| rng.range(-1.0, 1.0));
            let t0 = Vector3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), 0.0);
            let v_body = Vector3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.1);
            let v_foot = Vector3::new(rng.range(-0.5, 0.5), 0.0, rng.range(-0.5, 0.5));
            let c = Vector3::new(0.05, -0.02, 0.01);
            let foot0 = Vector3::new(0.3, 0.2, -0.35);
            let rot = |s: f64| {
                let [a, b, cc] = order.axes();
                let e = |axis: u8, ang: f64| {
                    let ax = match axis {
                        0 => Vector3::x_axis(),
                        1 => Vector3::y_axis(),
                        _ => Vector3::z_axis(),
                    };
                    Rotation3::from_axis_angle(&ax, ang)
                };
                let qq = [0, 1, 2].map(|i| q[i] + s * qd[i]);
                e(a, qq[a as usize]) * e(b, qq[b as usize]) * e(cc, qq[cc as usize])
            };
            let local = |s: f64| {
                let f = foot0 + v_foot * s;
                let t = t0 + v_body * s;
                rot(s).inverse() * (f - t - c) + c
            };
            let dt = 1e-6;
            let want = (local(dt) - local(-dt)) / (2.0 * dt);
            let r = rotation::matrix::<kin_core::DefaultMath>(
                order,
                q[0] as f32,
                q[1] as f32,
                q[2] as f32,
            );
            let omega =
                rotation::angular_velocity(order, q.map(|v| v as f32), qd.map(|v| v as f32));
            let f32v = |v: Vector3<f64>| Vec3::new(v.x as f32, v.y as f32, v.z as f32);
            let got = jacobian::foot_velocity_in_hip(
                &r,
                f32v(foot0 - t0 - c),
                f32v(v_foot),
                f32v(v_body),
                omega,
            );
            assert!(
                (v64(got) - want).norm() < 1e-5,
                "{order}: {got:?} vs {want}"
            );
        }
    }
}
