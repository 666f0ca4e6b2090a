//! The two papers: angle-convention adapters, and every erratum of `docs/papers.md` pinned by a
//! test named after it. Printed formulas are transcribed as printed (in f64) and compared with
//! the geometry of the crate's chain.

mod common;

use common::*;
use kin_core::paper::{self, Seed000Angles, Seed001Angles};
use kin_core::rotation::{self, RotationOrder};
use kin_core::{leg, JointAngles, JointLimits, LegGeometry, LegId, ReachPolicy, Robot, Vec3};
use nalgebra::{Matrix3, Matrix4, Vector3};
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};

/// Agreement of two f64 evaluations of the same geometry.
const EXACT_TOL: f64 = 1.0e-12;
/// Agreement of an f64 transcription with the crate's f32 results (angles in rad, lengths in m).
const F32_TOL: f64 = 2.0e-6;
/// A printed formula counts as wrong when it misses the geometry by more than this (rad or m).
const WRONG_BY: f64 = 1.0e-3;
/// Cases of the adapter round-trip properties.
const ADAPTER_CASES: u32 = 2000;

// ---------------------------------------------------------------------------------------------
// Adapters
// ---------------------------------------------------------------------------------------------

/// Seed 001 eq. 5: φ = 120°, α = 60°, β = 0 is canonical hip 30°, knee −60°, with the foot
/// straight below the hip at depth l0 + (l1 + l2)·sin 60° ≈ 0.9294 m (f64 oracle).
#[test]
fn seed001_initial_pose_is_hip_30_knee_minus_60() {
    let q = paper::from_seed001(paper::SEED001_INITIAL);
    assert!((q.abduction_rad as f64).abs() < F32_TOL);
    assert!((q.hip_rad as f64 - 30f64.to_radians()).abs() < F32_TOL);
    assert!((q.knee_rad as f64 + 60f64.to_radians()).abs() < F32_TOL);
    let robot = Robot::fernando2025();
    let depth = 0.15 + 0.9 * 60f64.to_radians().sin();
    assert!((depth - 0.9294).abs() < 1e-4);
    for leg_id in LegId::ALL {
        let foot = fk64(&robot.leg, leg_id, q64(q));
        assert!(
            (foot - Vector3::new(0.0, 0.0, -depth)).norm() < F32_TOL,
            "{foot}"
        );
        // And back: IK of that foot is the initial pose.
        let target = Vec3::new(0.0, 0.0, -depth as f32);
        let sol = leg::Solver::new(&robot)
            .inverse(leg_id, target, ReachPolicy::Reject)
            .unwrap();
        let s = paper::to_seed001(sol.angles);
        assert!((s.phi_rad as f64 - 120f64.to_radians()).abs() < 1e-5);
        assert!((s.alpha_rad as f64 - 60f64.to_radians()).abs() < 1e-5);
        assert!((s.beta_rad as f64).abs() < 1e-6);
    }
}

/// Seed 001 eq. 3's link vectors, with Γβ applied to the whole leg (see erratum 5): the points
/// A, B, K relative to O for `[β, α, φ]`.
fn seed001_leg64(g: &LegGeometry, [b, a, f]: [f64; 3]) -> [Vector3<f64>; 3] {
    let (l0, l1, l2) = (g.d_ax_m as f64, g.femur_m as f64, g.tibia_m as f64);
    let gb = Matrix3::new(1.0, 0.0, 0.0, 0.0, b.cos(), -b.sin(), 0.0, b.sin(), b.cos());
    let r_oa = gb * Vector3::new(0.0, 0.0, -l0);
    let r_ab = Vector3::new(-l1 * a.cos(), 0.0, -l1 * a.sin());
    let r_bk = Vector3::new(-l2 * f.cos(), 0.0, -l2 * f.sin());
    [r_oa, r_oa + gb * r_ab, r_oa + gb * (r_ab + r_bk)]
}

fn seed001_leg(g: &LegGeometry, s: Seed001Angles) -> [Vector3<f64>; 3] {
    seed001_leg64(g, [s.beta_rad, s.alpha_rad, s.phi_rad].map(|v| v as f64))
}

/// Seed 001 eq. 4's leg matrix J_i = ∂r_K/∂(β, α, φ). With hip = π/2 − α and knee = α − φ it
/// is the crate's Jacobian (w.r.t. abduction, hip, knee) times [[1,0,0],[0,−1,0],[0,1,−1]].
#[test]
fn seed001_eq4_leg_jacobian_via_adapter() {
    let robot = Robot::fernando2025();
    let chain = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, -1.0);
    let mut rng = SplitMix64::new(4);
    for _ in 0..200 {
        let s = [
            rng.range(-0.8, 0.8),
            rng.range(0.0, 2.0),
            rng.range(0.5, 3.0),
        ]
        .map(|v| v as f32 as f64);
        let step = 1e-6;
        let mut j_paper = Matrix3::zeros();
        for c in 0..3 {
            let (mut sp, mut sm) = (s, s);
            sp[c] += step;
            sm[c] -= step;
            let col = (seed001_leg64(&robot.leg, sp)[2] - seed001_leg64(&robot.leg, sm)[2])
                / (2.0 * step);
            j_paper.set_column(c, &col);
        }
        let q = paper::from_seed001(Seed001Angles {
            beta_rad: s[0] as f32,
            alpha_rad: s[1] as f32,
            phi_rad: s[2] as f32,
        });
        let j = kin_core::jacobian::leg_jacobian(&robot.leg, LegId::FL, q);
        let j = Matrix3::from_fn(|r, c| j.rows[r][c] as f64);
        assert!(
            (j * chain - j_paper).abs().max() <= 1e-5,
            "{j_paper} vs {}",
            j * chain
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(ADAPTER_CASES))]

    /// Seed 000 adapter: θ1, θ2 ∈ [0, 2π), θ3 = −knee, and `from_seed000 ∘ to_seed000` is the
    /// identity on the circle for every leg.
    #[test]
    fn seed000_adapter_round_trips(l in 0usize..4, a in -3.2f32..3.2, h in -3.2f32..3.2,
                                   k in -3.2f32..3.2) {
        let leg_id = LegId::ALL[l];
        let q = JointAngles::new(a, h, k);
        let s = paper::to_seed000(leg_id, q);
        prop_assert!((0.0..2.0 * std::f32::consts::PI).contains(&s.theta1_rad));
        prop_assert!((0.0..2.0 * std::f32::consts::PI).contains(&s.theta2_rad));
        prop_assert_eq!(s.theta3_rad, -k);
        let back = paper::from_seed000(leg_id, s);
        for (x, y) in q64(back).iter().zip(q64(q)) {
            prop_assert!(ang_diff(*x, y) <= F32_TOL, "{back:?} vs {q:?}");
        }
        let s2 = paper::to_seed000(leg_id, back);
        prop_assert!(ang_diff(s2.theta1_rad as f64, s.theta1_rad as f64) <= F32_TOL);
        prop_assert!(ang_diff(s2.theta2_rad as f64, s.theta2_rad as f64) <= F32_TOL);
    }

    /// Seed 001 adapter: round trip both ways, and the crate's FK equals eq. 1/3's chain (with
    /// the consistent r_OA) evaluated on the adapted angles.
    #[test]
    fn seed001_adapter_round_trips(l in 0usize..4, b in -1.0f32..1.0, al in -1.0f32..3.0,
                                   ph in -1.0f32..4.0) {
        let s = Seed001Angles { beta_rad: b, alpha_rad: al, phi_rad: ph };
        let q = paper::from_seed001(s);
        let back = paper::to_seed001(q);
        prop_assert!((back.beta_rad - b).abs() <= 1e-6);
        prop_assert!((back.alpha_rad - al).abs() <= 1e-6);
        prop_assert!((back.phi_rad - ph).abs() <= 1e-6);
        let q2 = paper::from_seed001(paper::to_seed001(q));
        for (x, y) in q64(q2).iter().zip(q64(q)) {
            prop_assert!((x - y).abs() <= 1e-6);
        }
        let robot = Robot::fernando2025();
        let leg_id = LegId::ALL[l];
        let foot = seed001_leg(&robot.leg, s)[2];
        prop_assert!((fk64(&robot.leg, leg_id, q64(q)) - foot).norm() <= F32_TOL);
        prop_assert!((v64(leg::forward(&robot.leg, leg_id, q)) - foot).norm() <= F32_TOL);
    }
}

/// Seed 001's leg numbering: leg 1 = FL at ρ = (0.5, 0.25), 2 = FR, 3 = RR, 4 = RL
/// (ρx1 = ρx2 = −ρx3 = −ρx4 = 0.5 m, ρy1 = −ρy2 = −ρy3 = ρy4 = 0.25 m).
#[test]
fn seed001_leg_numbering() {
    let robot = Robot::fernando2025();
    let rho = [(0.5, 0.25), (0.5, -0.25), (-0.5, -0.25), (-0.5, 0.25)];
    let legs = [LegId::FL, LegId::FR, LegId::RR, LegId::RL];
    for (leg_id, (x, y)) in legs.into_iter().zip(rho) {
        let hip = robot.hip_in_body(leg_id);
        assert_eq!((hip.x, hip.y, hip.z), (x, y, 0.0), "{leg_id}");
    }
}

// ---------------------------------------------------------------------------------------------
// Erratum 1: seed 000 eq. 4.15 uses L_c where the cosine rule needs L_c².
// ---------------------------------------------------------------------------------------------

/// Seed 000's side-view quantities for a foot of the shahriar2023 leg: R (eq. 4.12) and R1
/// (angle of R from +x towards +z) in the tilted leg plane, where z is the un-abducted height
/// `w = −√(y² + z² − La²)`.
fn side_view(robot: &Robot, foot: Vector3<f64>) -> (f64, f64) {
    let la = robot.leg.d_lat_m as f64;
    let w = -(foot.y * foot.y + foot.z * foot.z - la * la)
        .max(0.0)
        .sqrt();
    (foot.x.hypot(w), wrap_2pi64(w.atan2(foot.x)))
}

#[test]
fn erratum_seed000_eq4_15_lc_squared() {
    let robot = Robot::shahriar2023();
    let (lb, lc) = (robot.leg.femur_m as f64, robot.leg.tibia_m as f64);
    let mut rng = SplitMix64::new(415);
    let (mut nan, mut wrong) = (0, 0);
    for _ in 0..500 {
        let leg_id = LegId::ALL[(rng.next_u64() % 4) as usize];
        let q = JointAngles::new(
            rng.range(-0.6, 0.6) as f32,
            rng.range(-1.2, 1.2) as f32,
            rng.range(-2.6, -0.2) as f32,
        );
        if w_of(&robot.leg, q64(q)) > -0.01 {
            continue; // foot not below the hip in the leg plane: the other abduction branch
        }
        let foot = fk64(&robot.leg, leg_id, q64(q));
        let (r, r1) = side_view(&robot, foot);
        // R2 measured on the chain: the angle at the hip joint between the femur and line R.
        let pts = leg::joint_points(&robot.leg, leg_id, q);
        let femur = v64(pts.knee) - v64(pts.hip_joint);
        let to_foot = v64(pts.foot) - v64(pts.hip_joint);
        let r2_chain = femur.angle(&to_foot);

        let printed = ((lb * lb + r * r - lc) / (2.0 * lb * r)).acos(); // eq. 4.15 as printed
        let corrected = ((lb * lb + r * r - lc * lc) / (2.0 * lb * r)).acos();
        assert!(
            (corrected - r2_chain).abs() <= F32_TOL,
            "{corrected} vs {r2_chain}"
        );
        if printed.is_nan() {
            nan += 1; // |argument| > 1: no angle at all
        } else {
            assert!(
                (printed - r2_chain).abs() > WRONG_BY,
                "{printed} vs {r2_chain}"
            );
            wrong += 1;
        }
        // With the correction, eq. 4.17 θ2 = R1 − R2 and eq. 4.21 θ3 = π − R3 are the crate's
        // seed 000 angles of the same configuration.
        let s = paper::to_seed000(leg_id, q);
        assert!(
            ang_diff(wrap_2pi64(r1 - corrected), s.theta2_rad as f64) <= F32_TOL,
            "{q:?} r1 {r1} r2 {corrected} th2 {}",
            s.theta2_rad
        );
        let r3 = ((lb * lb + lc * lc - r * r) / (2.0 * lb * lc)).acos(); // eq. 4.16
        assert!((PI - r3 - s.theta3_rad as f64).abs() <= 1e-5);
    }
    assert!(nan > 0 && wrong > 0, "NaN {nan}, wrong {wrong}");
}

// ---------------------------------------------------------------------------------------------
// Erratum 2: seed 000's DH chain (eq. 3.2–3.6, Table 1) vs its IK (§2.2).
// ---------------------------------------------------------------------------------------------

fn rz_trans(theta: f64, a: f64) -> Matrix4<f64> {
    let (s, c) = theta.sin_cos();
    Matrix4::new(
        c,
        -s,
        0.0,
        a * c, //
        s,
        c,
        0.0,
        a * s, //
        0.0,
        0.0,
        1.0,
        0.0, //
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

/// T01·T12·T23·T34 exactly as printed in eq. 3.2–3.5.
fn seed000_dh_product(la: f64, lb: f64, lc: f64, t: [f64; 3]) -> Matrix4<f64> {
    let t01 = Matrix4::new(
        0.0, 0.0, 1.0, 0.0, //
        0.0, 1.0, 0.0, 0.0, //
        -1.0, 0.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    );
    let (s1, c1) = t[0].sin_cos();
    let t12 = Matrix4::new(
        c1,
        0.0,
        s1,
        la * c1, //
        s1,
        0.0,
        -c1,
        la * s1, //
        0.0,
        1.0,
        0.0,
        0.0, //
        0.0,
        0.0,
        0.0,
        1.0,
    );
    t01 * t12 * rz_trans(t[1], lb) * rz_trans(t[2], lc)
}

#[test]
fn erratum_seed000_dh_chain_puts_la_in_the_leg_plane() {
    let preset = Robot::shahriar2023();
    let (la, lb, lc) = (
        preset.leg.d_lat_m as f64,
        preset.leg.femur_m as f64,
        preset.leg.tibia_m as f64,
    );
    // The geometry the printed DH chain describes: La along the leg plane (like seed 001's l0).
    let in_plane = LegGeometry {
        d_lat_m: 0.0,
        d_ax_m: preset.leg.d_ax_m + preset.leg.d_lat_m,
        ..preset.leg
    };
    let mut rng = SplitMix64::new(36);
    let mut worst_r_orthogonality = f64::INFINITY;
    for _ in 0..300 {
        let t = [(); 3].map(|_| rng.range(-PI, PI) as f32 as f64);
        let (s1, c1) = t[0].sin_cos();
        let (s2, c2) = t[1].sin_cos();
        let (s23, c23) = (t[1] + t[2]).sin_cos();
        let m = seed000_dh_product(la, lb, lc, t);
        let p = Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
        // Eq. 3.6's printed S ("Lcc" = Lc·cos) equals the product.
        let printed_s = Vector3::new(
            lc * s23 + lb * s2,
            (la + lc * c23 + lb * c2) * s1,
            -c1 * (la + lc * c23 + lb * c2),
        );
        assert!((p - printed_s).norm() <= EXACT_TOL);
        // The product's rotation: the printed R is right except R[1][1], printed cos θ3 where the
        // product has −sin θ1·sin(θ2 + θ3).
        let printed_r = Matrix3::new(
            s23,
            c23,
            0.0, //
            c23 * s1,
            t[2].cos(),
            -c1, //
            -c23 * c1,
            s23 * c1,
            -s1,
        );
        let r = m.fixed_view::<3, 3>(0, 0).into_owned();
        let mut fixed = printed_r;
        fixed[(1, 1)] = -s1 * s23;
        assert!((r - fixed).abs().max() <= EXACT_TOL);
        worst_r_orthogonality = worst_r_orthogonality.min(
            (printed_r * printed_r.transpose() - Matrix3::identity())
                .abs()
                .max(),
        );

        // S is the crate's closed form with d_lat = 0, d_ax = La, under θ1 = a, θ2 = −h,
        // θ3 = −k, in the hip frame (x forward, y left, z up) ...
        for leg_id in LegId::ALL {
            let q = [t[0], -t[1], -t[2]];
            assert!((fk64(&in_plane, leg_id, q) - p).norm() <= EXACT_TOL * 10.0);
            let q32 = JointAngles::new(q[0] as f32, q[1] as f32, q[2] as f32);
            assert!((v64(leg::forward(&in_plane, leg_id, q32)) - p).norm() <= F32_TOL);
            // ... and not the geometry seed 000's IK assumes (shahriar2023: La ⟂ leg plane): the
            // two differ by La·√2 whatever the angles, Rx(a)·((0, s·La, 0) − (0, 0, −La)).
            let gap = (fk64(&preset.leg, leg_id, q) - p).norm();
            assert!((gap - la * 2f64.sqrt()).abs() <= EXACT_TOL * 10.0, "{gap}");
            // Seed 000's front view (eq. 4.1, 4.6, φ = 90°): A² = La² + ℓ², ℓ the in-plane
            // length. The DH chain's foot instead has A = |La + ℓ_y| (collinear).
            let ell = lc * c23 + lb * c2;
            let a_len = p.y.hypot(p.z);
            assert!((a_len - (la + ell).abs()).abs() <= EXACT_TOL);
            if ell.abs() > 0.01 {
                assert!((a_len - la.hypot(ell)).abs() > WRONG_BY);
            }
        }
    }
    // The printed R is not a rotation matrix: R·Rᵀ ≠ I for every sampled configuration.
    assert!(worst_r_orthogonality > 1e-4, "{worst_r_orthogonality}");
    // The crate's own DH table (leg::dh_table) is the corrected chain; `leg::forward_dh` equals
    // the closed form (tests/leg.rs dh_form_equals_closed_form). Here: its first row carries
    // d_ax as the link length and its second row d_lat as the offset.
    let q = JointAngles::new(0.1, 0.2, -0.3);
    let rows = leg::dh_table(&preset.leg, LegId::FL, q);
    assert_eq!((rows[0].a_m, rows[0].d_m), (0.0, 0.0));
    assert_eq!((rows[1].a_m, rows[1].d_m), (0.28, 0.044));
    assert_eq!((rows[2].a_m, rows[2].d_m), (0.277, 0.0));
    let rows = leg::dh_table(&in_plane, LegId::FR, q);
    assert_eq!((rows[0].a_m, rows[1].d_m), (0.044, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Erratum 3: seed 000 Algorithm 2's order dictionary.
// ---------------------------------------------------------------------------------------------

#[test]
fn erratum_seed000_alg2_rotation_order_keys() {
    // The printed dictionary; values list the matrices multiplied left to right (rotX = roll
    // about x, rotY = pitch about y, rotZ = yaw about z).
    let printed: [(&str, [char; 3]); 6] = [
        ("xzy", ['y', 'z', 'x']),
        ("xzy", ['y', 'z', 'x']),
        ("yxz", ['z', 'x', 'y']),
        ("yzy", ['x', 'z', 'y']),
        ("xzy", ['y', 'x', 'z']),
        ("zyx", ['x', 'y', 'z']),
    ];
    // A Python dict literal keeps the last value of a repeated key.
    let dict: BTreeMap<&str, [char; 3]> = printed.iter().copied().collect();
    assert_eq!(dict.len(), 4, "three 'xzy' entries collapse into one");
    assert_eq!(dict["xzy"], ['y', 'x', 'z'], "only the last 'xzy' survives");
    assert!(
        !dict.contains_key("xyz"),
        "the default order='xyz' raises KeyError"
    );
    assert!(dict.contains_key("yzy") && RotationOrder::parse("yzy").is_none());
    // The matrices are defined as rotP, rotQ, rotR but used as rotX, rotY, rotZ (NameError),
    // and `3d_matrix` is not a Python identifier (SyntaxError).
    let defined = ["rotP", "rotQ", "rotR"];
    assert!(["rotX", "rotY", "rotZ"]
        .iter()
        .all(|u| !defined.contains(u)));
    assert!("3d_matrix".starts_with(|c: char| c.is_ascii_digit()));

    let (roll, pitch, yaw) = (0.3f32, -0.2f32, 0.25f32);
    let axis = |c: char| match c {
        'x' => rotation::rot_x(roll),
        'y' => rotation::rot_y(pitch),
        _ => rotation::rot_z(yaw),
    };
    let product = |m: [char; 3]| axis(m[0]).mul_mat(&axis(m[1])).mul_mat(&axis(m[2]));
    let ours = |o: RotationOrder| rotation::matrix::<kin_core::DefaultMath>(o, roll, pitch, yaw);
    let close = |a: &kin_core::Mat3, b: &kin_core::Mat3| {
        (0..3).all(|i| (0..3).all(|j| (a.rows[i][j] - b.rows[i][j]).abs() < 1e-6))
    };
    // The code names an order by the sequence in which the rotations act on a vector (rightmost
    // factor first): its keys are our names reversed. Where the key is right, it matches:
    let reversed = |key: &str| {
        let k: String = key.chars().rev().collect();
        RotationOrder::parse(&k)
    };
    for (i, (key, m)) in printed.iter().enumerate() {
        let named = reversed(key).map(ours);
        let is_right = named.is_some_and(|n| close(&n, &product(*m)));
        // Entries 1, 2 ('xzy'), 3 ('yxz') and 6 ('zyx') are right; entry 4 is 'yzx' misspelt,
        // entry 5 is 'zxy' filed under 'xzy'.
        assert_eq!(
            is_right,
            [true, true, true, false, false, true][i],
            "entry {}",
            i + 1
        );
    }
    assert!(close(&product(printed[3].1), &ours(RotationOrder::Xzy)));
    assert!(close(&product(printed[4].1), &ours(RotationOrder::Yxz)));
    // The surviving 'xzy' is not the product its name means (Ry·Rz·Rx).
    assert!(!close(&product(dict["xzy"]), &ours(RotationOrder::Yzx)));
    // The published default 'xyz' in the code's naming is Rz·Ry·Rx: our default `Zyx`.
    assert_eq!(RotationOrder::default(), RotationOrder::Zyx);
    assert!(close(&product(['z', 'y', 'x']), &ours(RotationOrder::Zyx)));
    // Our six orders are six different matrices.
    for (i, a) in RotationOrder::ALL.iter().enumerate() {
        for b in &RotationOrder::ALL[i + 1..] {
            assert!(!close(&ours(*a), &ours(*b)), "{a} = {b}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Erratum 4: seed 000 §3.3's root sum square error.
// ---------------------------------------------------------------------------------------------

#[test]
fn erratum_seed000_s3_3_rsse_arithmetic() {
    let deviations_pct: [f64; 3] = [2.59, 3.64, 20.83];
    let rsse = deviations_pct.iter().map(|d| d * d).sum::<f64>().sqrt();
    let round2 = |v: f64| (v * 100.0).round() / 100.0;
    assert_eq!(round2(rsse), 21.30);
    assert_ne!(round2(rsse), 21.10, "printed RSSE");
    assert_eq!(round2(100.0 - rsse), 78.70);
    assert_ne!(round2(100.0 - rsse), 78.90, "printed accuracy");
    // The printed accuracy is 100 % minus the printed RSSE.
    assert!((100.0 - 21.10 - 78.9f64).abs() < 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Erratum 5: seed 001 eq. 3's r_OA has the opposite y sign of Γβ·(0, 0, −l0).
// ---------------------------------------------------------------------------------------------

#[test]
fn erratum_seed001_eq3_r_oa_sign() {
    let robot = Robot::fernando2025();
    let l0 = robot.leg.d_ax_m as f64;
    for beta in [-0.5f64, -0.1, 0.2, 0.6] {
        let printed = Vector3::new(0.0, -l0 * beta.sin(), -l0 * beta.cos());
        let gb = Matrix3::new(
            1.0,
            0.0,
            0.0, //
            0.0,
            beta.cos(),
            -beta.sin(), //
            0.0,
            beta.sin(),
            beta.cos(),
        );
        let consistent = gb * Vector3::new(0.0, 0.0, -l0);
        assert!((printed - consistent).norm() > WRONG_BY);
        assert!((printed.y + consistent.y).abs() <= EXACT_TOL && printed.z == consistent.z);
        // The printed l0 link turns by −β while Γβ turns the rest of the leg by +β.
        let minus = Matrix3::new(
            1.0,
            0.0,
            0.0, //
            0.0,
            beta.cos(),
            beta.sin(), //
            0.0,
            -beta.sin(),
            beta.cos(),
        );
        assert!((printed - minus * Vector3::new(0.0, 0.0, -l0)).norm() <= EXACT_TOL);
        // The crate: Rx(β) for the whole leg. Hip joint A and foot K of its chain equal eq. 1/3
        // with the consistent r_OA, and miss the printed one by 2·l0·|sin β|.
        let s = Seed001Angles {
            beta_rad: beta as f32,
            alpha_rad: 1.0,
            phi_rad: 2.2,
        };
        let q = paper::from_seed001(s);
        let pts = leg::joint_points(&robot.leg, LegId::FL, q);
        let chain = seed001_leg(&robot.leg, s);
        assert!((v64(pts.hip_joint) - chain[0]).norm() <= F32_TOL);
        assert!((v64(pts.foot) - chain[2]).norm() <= F32_TOL);
        let with_printed = chain[2] - chain[0] + printed;
        let miss = (v64(pts.foot) - with_printed).norm();
        assert!(
            (miss - 2.0 * l0 * beta.sin().abs()).abs() <= F32_TOL,
            "{miss}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Erratum 6: the others.
// ---------------------------------------------------------------------------------------------

/// Seed 000 eq. 4.2–4.5 as printed: α1 from atan(y/z).
fn printed_alpha1(y: f64, z: f64, atan_arg_swapped: bool) -> f64 {
    let t = if atan_arg_swapped {
        (z / y).atan()
    } else {
        (y / z).atan()
    };
    match (y > 0.0, z > 0.0) {
        (true, true) => t,                    // case 1, eq. 4.2
        (false, true) => -t.abs() + PI,       // case 2, eq. 4.3
        (false, false) => t.abs() + PI,       // case 3, eq. 4.4
        (true, false) => -t.abs() + 2.0 * PI, // case 4, eq. 4.5
    }
}

/// 6a. Eq. 4.2–4.5 compute α1 from atan(y/z), an angle from the z axis, though α1 is defined
/// (Table 3) from +y: each case lands in the right quadrant but at the mirror angle; atan(z/y)
/// gives the defined angle. (y = 0 or z = 0 fall between the cases.)
#[test]
fn erratum_seed000_eq4_2_alpha1_measured_from_z() {
    for (y, z) in [
        (0.1f64, 0.3f64),
        (-0.1, 0.3),
        (-0.3, -0.1),
        (0.2, -0.35),
        (0.2, 0.2),
    ] {
        let defined = wrap_2pi64(z.atan2(y));
        let printed = printed_alpha1(y, z, false);
        let swapped = printed_alpha1(y, z, true);
        assert!((swapped - defined).abs() <= EXACT_TOL, "({y}, {z})");
        let quadrant = |a: f64| (a / FRAC_PI_2).floor();
        assert_eq!(quadrant(printed), quadrant(defined));
        if (y.abs() - z.abs()).abs() > 1e-9 {
            assert!((printed - defined).abs() > WRONG_BY, "({y}, {z})");
        } else {
            assert!((printed - defined).abs() <= EXACT_TOL);
        }
    }
}

/// 6b. Eq. 4.13 (R1 = atan(z/x) + π, "left legs") is the angle of line R only for x < 0 and
/// eq. 4.14 (R1 = −|atan(z/x)| + 2π, "right legs") only for x > 0 (foot below the hip): the
/// choice depends on the sign of x, not on the side of the leg.
#[test]
fn erratum_seed000_eq4_13_r1_quadrant() {
    for (x, z) in [(-0.1f64, -0.4f64), (-0.3, -0.2), (0.1, -0.4), (0.3, -0.2)] {
        let defined = wrap_2pi64(z.atan2(x));
        let eq4_13 = (z / x).atan() + PI;
        let eq4_14 = -(z / x).atan().abs() + 2.0 * PI;
        let (ok13, ok14) = (
            (eq4_13 - defined).abs() <= EXACT_TOL,
            (eq4_14 - defined).abs() <= EXACT_TOL,
        );
        assert_eq!((ok13, ok14), (x < 0.0, x > 0.0), "x = {x}");
    }
}

/// 6c. Algorithm 1 wraps θ1 into [0, 2π) only for left legs: a right leg whose coxa points
/// between −z and +y (θ1 ∈ (3π/2, 2π)) gets θ1 = α1 − α3 < 0. The crate's θ1 (via
/// `paper::to_seed000`) is in [0, 2π) and 2π above the printed value.
#[test]
fn erratum_seed000_alg1_right_leg_theta1_not_wrapped() {
    let robot = Robot {
        limits: JointLimits::FULL_TURN,
        ..Robot::shahriar2023()
    };
    let la = robot.leg.d_lat_m as f64;
    for leg_id in [LegId::FR, LegId::RR] {
        for a in [1.7f32, 2.2, 3.0] {
            let q = JointAngles::new(a, 0.3, -1.0);
            let target = leg::forward(&robot.leg, leg_id, q);
            let sol = leg::Solver::new(&robot)
                .inverse(leg_id, target, ReachPolicy::Reject)
                .unwrap();
            let p = v64(target);
            let alpha1 = wrap_2pi64(p.z.atan2(p.y));
            let alpha3 = FRAC_PI_2 - (la / p.y.hypot(p.z)).asin();
            let printed = alpha1 - alpha3; // is_right branch, no wrap
            assert!(printed < 0.0, "{printed}");
            let theta1 = paper::to_seed000(leg_id, sol.angles).theta1_rad as f64;
            assert!(
                (theta1 - (printed + 2.0 * PI)).abs() <= 1e-5,
                "{theta1} vs {printed}"
            );
            assert!((fk64(&robot.leg, leg_id, q64(sol.angles)) - p).norm() <= FOOT_TOL_M);
        }
    }
}

/// 6d. Table 3 calls L_c "femur to end-effector"; the chain's L_c is the knee-to-foot link (the
/// femur-to-foot distance changes with the knee).
#[test]
fn erratum_seed000_table3_lc_is_knee_to_foot() {
    let robot = Robot::shahriar2023();
    let lc = robot.leg.tibia_m as f64;
    let mut femur_to_foot = Vec::new();
    for k in [-0.3f32, -1.0, -2.0] {
        let pts = leg::joint_points(&robot.leg, LegId::FL, JointAngles::new(0.0, 0.2, k));
        assert!(((v64(pts.foot) - v64(pts.knee)).norm() - lc).abs() <= F32_TOL);
        femur_to_foot.push((v64(pts.foot) - v64(pts.hip_joint)).norm());
    }
    assert!((femur_to_foot[0] - femur_to_foot[2]).abs() > 0.1);
}

/// 6e. Seed 001 says "angles α_i, β_i characterize the rotation of links A_iB_i and B_iK_i" and
/// lists the hinges O, A, B with "φ_i, α_i, β_i"; eq. 3 has r_OA(β), r_AB(α), r_BK(φ): α and φ
/// turn AB and BK, β turns the hinge at O.
#[test]
fn erratum_seed001_alpha_phi_characterize_ab_bk() {
    let robot = Robot::fernando2025();
    let base = Seed001Angles {
        beta_rad: 0.1,
        alpha_rad: 1.0,
        phi_rad: 2.0,
    };
    let points =
        |s: Seed001Angles| leg::joint_points(&robot.leg, LegId::FL, paper::from_seed001(s));
    let p0 = points(base);
    let moved = |a: Vec3, b: Vec3| (v64(a) - v64(b)).norm() > WRONG_BY;
    // φ moves only K.
    let p = points(Seed001Angles {
        phi_rad: 2.3,
        ..base
    });
    assert!(!moved(p.hip_joint, p0.hip_joint) && !moved(p.knee, p0.knee) && moved(p.foot, p0.foot));
    // α moves B (and K), not A.
    let p = points(Seed001Angles {
        alpha_rad: 1.3,
        ..base
    });
    assert!(!moved(p.hip_joint, p0.hip_joint) && moved(p.knee, p0.knee));
    // β turns the hinge at O: A moves.
    let p = points(Seed001Angles {
        beta_rad: 0.4,
        ..base
    });
    assert!(moved(p.hip_joint, p0.hip_joint));
}

/// 6f. Seed 001 eq. 10 with α_i = arctan(ρy/ρx): at Δ = 0 leg 1's foot is at
/// (ρ·sin α1, −ρ·cos α1) = (0.25, −0.5), not below its hip (0.5, 0.25); and arctan loses the
/// quadrant of the rear legs (leg 3 gets leg 1's angle). atan2 with (ρ·cos, ρ·sin) starts
/// every foot at its hip's direction.
#[test]
fn erratum_seed001_eq10_arctan_phase() {
    let robot = Robot::fernando2025();
    let legs = [LegId::FL, LegId::FR, LegId::RR, LegId::RL]; // seed 001 legs 1..4
    let hips = legs.map(|l| robot.hip_in_body(l));
    let rho_of = |h: Vec3| (h.x as f64).hypot(h.y as f64);
    let printed = |h: Vec3| {
        let a = (h.y as f64 / h.x as f64).atan();
        (rho_of(h) * a.sin(), -rho_of(h) * a.cos())
    };
    let (x1, y1) = printed(hips[0]);
    assert!(
        (x1 - 0.25).abs() < 1e-6 && (y1 + 0.5).abs() < 1e-6,
        "({x1}, {y1})"
    );
    let (x3, y3) = printed(hips[2]);
    assert!((x3 - x1).abs() < 1e-12 && (y3 - y1).abs() < 1e-12);
    for h in hips {
        let a = (h.y as f64).atan2(h.x as f64);
        let (x, y) = (rho_of(h) * a.cos(), rho_of(h) * a.sin());
        assert!((x - h.x as f64).abs() < 1e-6 && (y - h.y as f64).abs() < 1e-6);
        let (px, py) = printed(h);
        assert!((px - h.x as f64).hypot(py - h.y as f64) > 0.1);
    }
}

/// 6g. Seed 001 writes the body rotation Γ_{ψθγ} in eq. 1 and Γ_{ψγθ} in the text, both "=
/// Γψ·Γθ·Γγ". The product as written (course ψ about z, roll θ about x, pitch γ about y) is the
/// crate's `Zxy`, and the subscript orders are not interchangeable.
#[test]
fn erratum_seed001_eq1_gamma_subscripts() {
    let (psi, theta, gamma): (f64, f64, f64) = (0.3, 0.2, -0.15);
    let g_psi = Matrix3::new(
        psi.cos(),
        -psi.sin(),
        0.0,
        psi.sin(),
        psi.cos(),
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let g_theta = Matrix3::new(
        1.0,
        0.0,
        0.0,
        0.0,
        theta.cos(),
        -theta.sin(),
        0.0,
        theta.sin(),
        theta.cos(),
    );
    let g_gamma = Matrix3::new(
        gamma.cos(),
        0.0,
        gamma.sin(),
        0.0,
        1.0,
        0.0,
        -gamma.sin(),
        0.0,
        gamma.cos(),
    );
    let to64 = |m: kin_core::Mat3| Matrix3::from_fn(|i, j| m.rows[i][j] as f64);
    let ours = |o| {
        to64(rotation::matrix::<kin_core::DefaultMath>(
            o,
            theta as f32,
            gamma as f32,
            psi as f32,
        ))
    };
    let written = g_psi * g_theta * g_gamma;
    assert!((ours(RotationOrder::Zxy) - written).abs().max() <= F32_TOL);
    assert!((g_psi * g_gamma * g_theta - written).abs().max() > WRONG_BY);
}

/// Seed 000's side view is the tilted leg plane: eq. 4.12's R must use the un-abducted height
/// w, not the hip-frame z (they agree only for θ1 with a vertical leg plane).
#[test]
fn seed000_eq4_12_uses_the_tilted_z() {
    let robot = Robot::shahriar2023();
    let q = JointAngles::new(0.4, 0.3, -1.2);
    let foot = fk64(&robot.leg, LegId::FL, q64(q));
    let (r_tilted, _) = side_view(&robot, foot);
    let (l1, l2) = (robot.leg.femur_m as f64, robot.leg.tibia_m as f64);
    let from_knee = (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * (q.knee_rad as f64).cos()).sqrt();
    assert!((r_tilted - from_knee).abs() <= F32_TOL);
    assert!((foot.x.hypot(foot.z) - from_knee).abs() > WRONG_BY);
}

/// The seed 000 θ-adapter's meaning: θ1 is the direction of the coxa La (hip mount → hip joint)
/// from +y towards +z; θ2 the femur direction in the leg plane from +x towards +z.
#[test]
fn seed000_adapter_angles_are_link_directions() {
    let robot = Robot::shahriar2023();
    let mut rng = SplitMix64::new(2);
    for _ in 0..200 {
        let leg_id = LegId::ALL[(rng.next_u64() % 4) as usize];
        let q = random_angles(&mut rng, &robot, 0.0);
        let s: Seed000Angles = paper::to_seed000(leg_id, q);
        let pts = leg::joint_points(&robot.leg, leg_id, q);
        let coxa = v64(pts.hip_joint);
        assert!(ang_diff(coxa.z.atan2(coxa.y), s.theta1_rad as f64) <= F32_TOL);
        // Femur in the leg plane: un-abduct with Rx(−a).
        let femur = v64(pts.knee) - v64(pts.hip_joint);
        let a = q.abduction_rad as f64;
        let w = -a.sin() * femur.y + a.cos() * femur.z;
        assert!(ang_diff(w.atan2(femur.x), s.theta2_rad as f64) <= F32_TOL);
    }
}
