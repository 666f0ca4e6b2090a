//! Body rotation matrices (all six orders against nalgebra) and full-body IK/FK round trips:
//! seed 000's pose ranges with shahriar2023, seed 001's roll and pitch laws with fernando2025,
//! with and without a pivot and a body translation.

mod common;

use common::*;
use kin_core::body::{self, BodyConfig, Pose};
use kin_core::paper;
use kin_core::rotation::{self, RotationOrder};
use kin_core::{leg, LegId, Mat3, ReachPolicy, Robot, Vec3};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;

/// Largest entry-wise difference between the crate's f32 rotation matrix and nalgebra's f64 one.
const ROTATION_TOL: f64 = 1.0e-6;
/// Largest allowed foot error of a full-body round trip, through the crate's f32 `body::forward`
/// (several f32 rotations of ~0.5 m vectors; measured ≤ 0.5 µm) and through the f64 body FK.
const BODY_FK_F32_TOL_M: f64 = 1.0e-6;
/// Cases of the rotation and full-body properties.
const BODY_CASES: u32 = 1500;

/// Stance height used for seed 000's pose ranges with shahriar2023 (leg reach 0.557 m, body
/// 0.6 × 0.28 m). At 0.40 m, 36 of the 48 extreme poses (±28°, ±21°, ±21°, six orders) put a
/// foot out of reach; at 0.32 m every pose of the range solves in every order.
const SEED000_STANCE_HEIGHT_M: f32 = 0.32;

/// Seed 001's stance: depth of the foot below the abduction axis in its initial pose (eq. 5),
/// l0 + (l1 + l2)·sin 60°.
fn seed001_stance_height_m() -> f32 {
    0.15 + 0.9 * 60f32.to_radians().sin()
}

fn elementary64(axis: u8, angle: f64) -> Rotation3<f64> {
    let ax = match axis {
        0 => Vector3::x_axis(),
        1 => Vector3::y_axis(),
        _ => Vector3::z_axis(),
    };
    Rotation3::from_axis_angle(&ax, angle)
}

/// The product of nalgebra's elementary rotations named by `order`, left to right.
fn nalgebra_matrix(order: RotationOrder, rpy: [f64; 3]) -> Matrix3<f64> {
    let [a, b, c] = order.axes();
    (elementary64(a, rpy[a as usize])
        * elementary64(b, rpy[b as usize])
        * elementary64(c, rpy[c as usize]))
    .into_inner()
}

fn to64(m: &Mat3) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| m.rows[i][j] as f64)
}

fn max_abs(m: Matrix3<f64>) -> f64 {
    m.iter().fold(0.0, |acc, v| acc.max(v.abs()))
}

/// Independent f64 full-body FK: `R·(hip + foot_in_hip − c) + c + t` with nalgebra's R.
fn body_fk64(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    angles: &[kin_core::JointAngles; 4],
) -> [Vector3<f64>; 4] {
    let r = nalgebra_matrix(
        config.order,
        [pose.roll_rad, pose.pitch_rad, pose.yaw_rad].map(|a| a as f64),
    );
    let c = v64(config.pivot_m);
    let t = v64(pose.translation());
    LegId::ALL.map(|l| {
        let hip = v64(robot.hip_in_body(l));
        r * (hip + fk64(&robot.leg, l, q64(angles[l.index()])) - c) + c + t
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(BODY_CASES))]

    /// All six orders equal the products of nalgebra's elementary rotations; every matrix is
    /// orthonormal with determinant 1.
    #[test]
    fn six_orders_equal_nalgebra_products(
        roll in -3.2f64..3.2, pitch in -3.2f64..3.2, yaw in -3.2f64..3.2,
    ) {
        let rpy = [roll as f32, pitch as f32, yaw as f32];
        for order in RotationOrder::ALL {
            let m = rotation::matrix::<kin_core::DefaultMath>(order, rpy[0], rpy[1], rpy[2]);
            let want = nalgebra_matrix(order, rpy.map(|a| a as f64));
            prop_assert!(max_abs(to64(&m) - want) <= ROTATION_TOL, "{order}");
            let m64 = to64(&m);
            prop_assert!(max_abs(m64 * m64.transpose() - Matrix3::identity()) <= ROTATION_TOL);
            prop_assert!((m64.determinant() - 1.0).abs() <= ROTATION_TOL);
        }
        // zyx is nalgebra's roll-pitch-yaw (roll first, then pitch, then yaw).
        let zyx = rotation::matrix::<kin_core::DefaultMath>(RotationOrder::Zyx, rpy[0], rpy[1], rpy[2]);
        let euler = Rotation3::from_euler_angles(rpy[0] as f64, rpy[1] as f64, rpy[2] as f64);
        prop_assert!(max_abs(to64(&zyx) - euler.into_inner()) <= ROTATION_TOL);
    }

    /// Seed 000's ranges (roll ±28°, pitch ±21°, yaw ±21°), all six orders, with and without a
    /// pivot (±5 cm) and a body translation (±3 cm), shahriar2023 at the stance height above:
    /// every leg agrees with the f64 oracle on reachability; solved poses round-trip through
    /// `body::forward` and through an f64 body FK.
    #[test]
    fn seed000_pose_ranges_round_trip(
        roll_deg in -28.0f32..=28.0, pitch_deg in -21.0f32..=21.0, yaw_deg in -21.0f32..=21.0,
        o in 0usize..6, with_offsets in any::<bool>(),
        pivot in proptest::array::uniform3(-0.05f32..0.05),
        shift in proptest::array::uniform3(-0.03f32..0.03),
    ) {
        let robot = Robot::shahriar2023();
        let mut pose = Pose::rotation(
            roll_deg.to_radians(), pitch_deg.to_radians(), yaw_deg.to_radians());
        let mut config = BodyConfig { order: RotationOrder::ALL[o], pivot_m: Vec3::ZERO };
        if with_offsets {
            config.pivot_m = Vec3::from_array(pivot);
            (pose.x_m, pose.y_m, pose.z_m) = (shift[0], shift[1], shift[2]);
        }
        let feet = robot.stance_feet(SEED000_STANCE_HEIGHT_M);
        let res = body::Solver::new(&robot).inverse(&pose, &config, &feet, ReachPolicy::Reject);
        if !with_offsets {
            prop_assert!(res.is_ok(), "pure rotation {pose:?} {}: {res:?}", config.order);
        }
        check_body(&robot, &pose, &config, &feet, res)?;
    }

    /// `body::forward` ∘ `body::inverse` = identity for random feet, poses, orders and pivots
    /// on both presets (legs drawn within their limits, then moved into the world).
    #[test]
    fn body_forward_inverts_inverse_both_presets(
        r in 0usize..2, o in 0usize..6,
        rpy in proptest::array::uniform3(-0.4f32..0.4),
        pivot in proptest::array::uniform3(-0.1f32..0.1),
        shift in proptest::array::uniform3(-0.1f32..0.1),
        seed in any::<u64>(),
    ) {
        let robot = presets()[r].1;
        let pose = Pose { roll_rad: rpy[0], pitch_rad: rpy[1], yaw_rad: rpy[2],
                          x_m: shift[0], y_m: shift[1], z_m: shift[2] };
        let config = BodyConfig { order: RotationOrder::ALL[o], pivot_m: Vec3::from_array(pivot) };
        let mut rng = SplitMix64::new(seed);
        let angles = LegId::ALL.map(|_| random_angles(&mut rng, &robot, 0.05));
        let feet = body::forward(&robot, &pose, &config, &angles);
        let res = body::Solver::new(&robot).inverse(&pose, &config, &feet, ReachPolicy::Reject);
        check_body(&robot, &pose, &config, &feet, res)?;
    }
}

/// Checks a body IK answer: legs agree with the f64 oracle on reachability (the hip-frame
/// targets computed in f64), and solved poses reproduce the feet through `body::forward` (f32)
/// and the f64 body FK.
fn check_body(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet: &[Vec3; 4],
    res: Result<body::BodySolution, kin_core::IkError>,
) -> Result<(), TestCaseError> {
    let local =
        body::Solver::<kin_core::math::Libm>::with_math(robot).feet_in_hips(pose, config, feet);
    let verdicts = LegId::ALL.map(|l| {
        let p = v64(local[l.index()]);
        ik64(robot, l, [p.x, p.y, p.z])
    });
    match res {
        Ok(sol) => {
            prop_assert!(!sol.any_clamped());
            for v in &verdicts {
                prop_assert!(v.result.is_ok() || v.margin <= BOUNDARY_BAND, "{v:?}");
            }
            let angles = sol.angles();
            let back = body::forward(robot, pose, config, &angles);
            let back64 = body_fk64(robot, pose, config, &angles);
            for l in LegId::ALL {
                let want = v64(feet[l.index()]);
                let e32 = (v64(back[l.index()]) - want).norm();
                let e64 = (back64[l.index()] - want).norm();
                prop_assert!(e32 <= BODY_FK_F32_TOL_M, "{l}: body::forward error {e32:e}");
                prop_assert!(e64 <= BODY_FK_F32_TOL_M, "{l}: f64 body FK error {e64:e}");
            }
        }
        Err(e) => {
            // The named leg is the first one the oracle rejects (or one on a boundary).
            let first = verdicts.iter().position(|v| v.result.is_err());
            let named = e.leg.index();
            let v = verdicts[named];
            prop_assert!(
                Some(named) == first || v.margin <= BOUNDARY_BAND,
                "{e} but oracle {verdicts:?}"
            );
            if v.margin > BOUNDARY_BAND {
                prop_assert_eq!(Some(v.result.unwrap_err()), kind_of(e.kind));
            }
        }
    }
    Ok(())
}

/// The 48 extreme poses of seed 000's range (every sign of ±28°, ±21°, ±21°, six orders)
/// solve at the chosen stance height, and round-trip.
#[test]
fn seed000_extreme_poses_solve_at_stance_height() {
    let robot = Robot::shahriar2023();
    let feet = robot.stance_feet(SEED000_STANCE_HEIGHT_M);
    for order in RotationOrder::ALL {
        for sr in [-1.0f32, 1.0] {
            for sp in [-1.0f32, 1.0] {
                for sy in [-1.0f32, 1.0] {
                    let pose = Pose::rotation(
                        (28.0 * sr).to_radians(),
                        (21.0 * sp).to_radians(),
                        (21.0 * sy).to_radians(),
                    );
                    let config = BodyConfig {
                        order,
                        pivot_m: Vec3::ZERO,
                    };
                    let sol = body::Solver::new(&robot)
                        .inverse(&pose, &config, &feet, ReachPolicy::Reject)
                        .unwrap_or_else(|e| panic!("{order} {pose:?}: {e}"));
                    let back = body::forward(&robot, &pose, &config, &sol.angles());
                    for l in LegId::ALL {
                        let e = (v64(back[l.index()]) - v64(feet[l.index()])).norm();
                        assert!(e <= BODY_FK_F32_TOL_M, "{order} {l}: {e:e}");
                    }
                }
            }
        }
    }
}

/// Seed 001 eq. 6 and 8: roll θ(t) = 0.2·sin(2πt/20) and pitch γ(t) = 0.2·sin(2πt/20), feet held
/// (eq. 7), fernando2025 at its initial-pose stance height, order zxy (Γψ·Γθ·Γγ): every instant
/// solves and round-trips; at t = 0 the legs are in seed 001's initial pose.
#[test]
fn seed001_roll_and_pitch_laws_round_trip() {
    let robot = Robot::fernando2025();
    let h = seed001_stance_height_m();
    assert!((h - 0.929_422_9).abs() < 1e-6);
    let feet = robot.stance_feet(h);
    let config = BodyConfig {
        order: RotationOrder::Zxy,
        pivot_m: Vec3::ZERO,
    };
    let (amplitude_rad, period_s) = (0.2f32, 20.0f32);
    for law in 0..2 {
        let mut max_beta = 0.0f32;
        for i in 0..=400 {
            let t = i as f32 * 0.05;
            let angle = amplitude_rad * (2.0 * std::f32::consts::PI * t / period_s).sin();
            let pose = if law == 0 {
                Pose::rotation(angle, 0.0, 0.0)
            } else {
                Pose::rotation(0.0, angle, 0.0)
            };
            let sol = body::Solver::new(&robot)
                .inverse(&pose, &config, &feet, ReachPolicy::Reject)
                .unwrap_or_else(|e| panic!("law {law} t = {t}: {e}"));
            let angles = sol.angles();
            let back = body::forward(&robot, &pose, &config, &angles);
            let back64 = body_fk64(&robot, &pose, &config, &angles);
            for l in LegId::ALL {
                let want = v64(feet[l.index()]);
                assert!((v64(back[l.index()]) - want).norm() <= BODY_FK_F32_TOL_M);
                assert!((back64[l.index()] - want).norm() <= BODY_FK_F32_TOL_M);
                max_beta = max_beta.max(paper::to_seed001(angles[l.index()]).beta_rad.abs());
            }
            if i == 0 {
                for q in angles {
                    let s = paper::to_seed001(q);
                    let want = paper::SEED001_INITIAL;
                    assert!((s.alpha_rad - want.alpha_rad).abs() < 1e-5, "{s:?}");
                    assert!((s.phi_rad - want.phi_rad).abs() < 1e-5, "{s:?}");
                    assert!(s.beta_rad.abs() < 1e-6, "{s:?}");
                }
            }
        }
        // Roll turns the leg planes (β ≈ roll, feet held); pitch leaves them nearly upright.
        if law == 0 {
            assert!(
                max_beta > 0.15 && max_beta < 0.25,
                "roll: max |β| = {max_beta}"
            );
        } else {
            assert!(max_beta < 0.05, "pitch: max |β| = {max_beta}");
        }
    }
}

/// The nominal stance: feet straight below the hips in the zero-abduction leg plane, i.e. all
/// abductions zero and every foot at the stance height.
#[test]
fn nominal_stance_is_zero_abduction() {
    for ((_, robot), h) in presets().into_iter().zip([0.3f32, 0.8]) {
        let sol = body::Solver::new(&robot)
            .inverse_at_stance(
                &Pose::default(),
                &BodyConfig::default(),
                h,
                ReachPolicy::Reject,
            )
            .unwrap();
        for (l, s) in LegId::ALL.iter().map(|&l| (l, sol.leg(l))) {
            assert!(s.angles.abduction_rad.abs() < 1e-6, "{l}: {s:?}");
            let foot = leg::forward(&robot.leg, l, s.angles);
            assert!((foot.z + h).abs() < 1e-6 && foot.x.abs() < 1e-6);
        }
    }
}

/// `rotation::angular_velocity` equals the body-frame-independent ω of Ṙ·Rᵀ = [ω]×, by central
/// differences of the f64 rotation.
#[test]
fn angular_velocity_matches_rotation_derivative() {
    let mut rng = SplitMix64::new(0xA11);
    for order in RotationOrder::ALL {
        for _ in 0..50 {
            let q = [(); 3].map(|_| rng.range(-1.0, 1.0));
            let qd = [(); 3].map(|_| rng.range(-1.0, 1.0));
            let dt = 1e-6;
            let at = |s: f64| nalgebra_matrix(order, [0, 1, 2].map(|i| q[i] + s * qd[i]));
            let rdot = (at(dt) - at(-dt)) / (2.0 * dt);
            let w = rdot * at(0.0).transpose();
            let want = Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
            let got = rotation::angular_velocity(order, q.map(|v| v as f32), qd.map(|v| v as f32));
            assert!(
                (v64(got) - want).norm() < 1e-5,
                "{order}: {got:?} vs {want}"
            );
        }
    }
}
