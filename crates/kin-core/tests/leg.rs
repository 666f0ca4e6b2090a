//! Leg kinematics over the whole workspace of both presets: IK∘FK and FK∘IK round trips
//! (proptest), the quadrant boundaries of seed 000 §2.2, the θ1 wrap at 2π, the DH form, and
//! seed 000's "50 random points" test.
//!
//! Every result is compared with an independent f64 oracle (`common::fk64`, `common::ik64`).

mod common;

use common::*;
use kin_core::paper;
use kin_core::{
    leg, JointAngles, JointLimits, KneeBend, LegId, ReachPolicy, Robot, Unreachable, Vec3,
};
use nalgebra::{Matrix4, Vector3, Vector4};
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Cases per round-trip property (each case is one leg solve and a few f64 FKs).
const ROUND_TRIP_CASES: u32 = 4000;

fn robot_of(index: usize, forward: bool) -> Robot {
    let r = presets()[index].1;
    if forward {
        r.with_knee_bend(KneeBend::Forward)
    } else {
        r
    }
}

/// Checks one IK answer against the f64 oracle's verdict for the same f32 target.
/// Returns the crate's angles when it solved.
fn check_against_oracle(robot: &Robot, leg_id: LegId, target: Vec3) -> Option<JointAngles> {
    let p = v64(target);
    let verdict = ik64(robot, leg_id, [p.x, p.y, p.z]);
    let got = leg::Solver::new(robot).inverse(leg_id, target, ReachPolicy::Reject);
    if let Ok(sol) = &got {
        assert!(sol.angles.is_finite(), "non-finite angles {sol:?}");
        assert!(sol.clamped.is_none(), "Reject policy reported a clamp");
        let foot = fk64(&robot.leg, leg_id, q64(sol.angles));
        let err = (foot - p).norm();
        assert!(
            err <= FOOT_TOL_M,
            "{leg_id} target {target:?}: foot error {err:e} m (angles {:?})",
            sol.angles
        );
        match robot.knee_bend {
            KneeBend::Backward => assert!(sol.angles.knee_rad <= 0.0),
            KneeBend::Forward => assert!(sol.angles.knee_rad >= 0.0),
        }
    }
    if verdict.margin <= BOUNDARY_BAND {
        // f32 rounding may decide either way this close to a boundary; an answer, if any, was
        // checked above.
        return got.ok().map(|s| s.angles);
    }
    match (verdict.result, got) {
        (Ok(q), Ok(sol)) => {
            let sk = q[2].sin().abs();
            if verdict.w_m.abs() > SINGULAR_W_MARGIN_M && sk > SINGULAR_SIN_KNEE_MARGIN {
                for (j, (want, got)) in q.iter().zip(q64(sol.angles)).enumerate() {
                    assert!(
                        ang_diff(*want, got) <= ANGLE_TOL_RAD,
                        "{leg_id} target {target:?}: joint {j} {got} vs exact {want}"
                    );
                }
            }
            Some(sol.angles)
        }
        (Err(kind), Err(e)) => {
            assert_eq!(e.leg, leg_id);
            assert_eq!(kind_of(e.kind), Some(kind), "target {target:?}");
            None
        }
        (want, got) => panic!("{leg_id} target {target:?}: oracle {want:?}, crate {got:?}"),
    }
}

fn joint_space() -> impl Strategy<Value = (usize, bool, usize, [f64; 3])> {
    (0usize..2, any::<bool>(), 0usize..4).prop_flat_map(|(r, fwd, l)| {
        let lim = robot_of(r, fwd).limits;
        let range = |j: usize| (lim.min_rad[j] as f64)..=(lim.max_rad[j] as f64);
        (
            Just(r),
            Just(fwd),
            Just(l),
            (range(0), range(1), range(2)).prop_map(|(a, h, k)| [a, h, k]),
        )
    })
}

/// A coordinate in `[-half, half]`, sometimes exactly zero (a quadrant boundary of seed 000
/// §2.2 when it is y or z).
fn coord(half: f64) -> impl Strategy<Value = f32> {
    prop_oneof![
        1 => Just(0.0f32),
        6 => (-half..=half).prop_map(|v| v as f32),
    ]
}

/// How close to the abduction offset's circle (`|w|`, m) an in-limit foot may be refused as
/// `InsideOffset`: the solver tests `A² ≥ La²` where `A² − La² = w²`, and the f32 foot carries
/// `A²` (about 2e-3 m²) only to about 1e-7 of itself, i.e. `w` to a few 1e-5 m.
const OFFSET_CIRCLE_BAND_M: f64 = 1.0e-4;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(ROUND_TRIP_CASES))]

    /// IK∘FK: joint angles sampled within the limits of both presets, all legs, both knee
    /// bends → FK → IK gives the same foot (≤ 1 µm in f64) and, away from singularities and on
    /// the canonical branch (`w < 0`), the same angles.
    #[test]
    fn ik_of_fk_returns_same_foot_and_angles((r, fwd, l, q) in joint_space()) {
        let robot = robot_of(r, fwd);
        let leg_id = LegId::ALL[l];
        let q32 = JointAngles::new(q[0] as f32, q[1] as f32, q[2] as f32);
        let target = leg::forward(&robot.leg, leg_id, q32);
        let got = check_against_oracle(&robot, leg_id, target);
        let w = w_of(&robot.leg, q64(q32));
        let sk = q64(q32)[2].sin().abs();
        let interior = (0..3).all(|j| {
            robot.limits.margin(kin_core::Joint::ALL[j], q32.get(kin_core::Joint::ALL[j])) as f64
                > BOUNDARY_BAND
        });
        if w < -SINGULAR_W_MARGIN_M && sk > SINGULAR_SIN_KNEE_MARGIN && interior {
            // Canonical branch, well conditioned, strictly inside the limits: must solve and
            // give back the sampled angles.
            let got = got.expect("a foot produced by in-limit angles must be solvable");
            for (j, (a, b)) in q64(q32).iter().zip(q64(got)).enumerate() {
                prop_assert!(ang_diff(*a, b) <= ANGLE_TOL_RAD, "joint {j}: {a} -> {b}");
            }
        }
        if r == 0 && interior && w.abs() > OFFSET_CIRCLE_BAND_M {
            // shahriar2023 limits abduction and hip only to a full turn: the other abduction
            // branch (w > 0) is always admissible, so every in-limit foot solves. Not next to
            // the abduction offset's circle (w = 0, see `OFFSET_CIRCLE_BAND_M`).
            prop_assert!(got.is_some(), "shahriar2023 foot {target:?} from {q32:?} unsolved");
        }
    }

    /// FK∘IK: feet sampled in a box enclosing the whole workspace (including exact y = 0 and
    /// z = 0), both presets, all legs, both bends. Reachable targets solve with FK(IK(p)) = p
    /// (≤ 1 µm, f64 FK); unreachable ones give the oracle's error kind.
    #[test]
    fn fk_of_ik_matches_target_over_workspace_box(
        r in 0usize..2, fwd in any::<bool>(), l in 0usize..4,
        x in coord(1.0), y in coord(1.0), z in coord(1.0),
    ) {
        let robot = robot_of(r, fwd);
        let g = robot.leg;
        let reach = (g.d_lat_m + g.d_ax_m + g.femur_m + g.tibia_m) * 1.05;
        let target = Vec3::new(x * reach, y * reach, z * reach);
        check_against_oracle(&robot, LegId::ALL[l], target);
    }

    /// FK∘IK on the quadrant boundaries of seed 000 §2.2 (y = 0 or z = 0 in the hip frame, feet
    /// above and below the hip), with the planar distance drawn inside the reachable annulus.
    #[test]
    fn quadrant_boundaries_round_trip(
        r in 0usize..2, fwd in any::<bool>(), l in 0usize..4,
        axis in 0usize..4, x_frac in -1.0f64..1.0, radial in 0.0f64..1.0,
    ) {
        let mut robot = robot_of(r, fwd);
        robot.limits = JointLimits::FULL_TURN;
        let g = robot.leg;
        let (d, dax) = (g.d_lat_m as f64, g.d_ax_m as f64);
        let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
        // Planar distance D of the hip-flexion joint to the foot inside the annulus.
        let dist = (l1 - l2).abs() + 0.01 + radial * (l1 + l2 - (l1 - l2).abs() - 0.02);
        let u = x_frac * dist * 0.9;
        let v = -(dist * dist - u * u).sqrt(); // hip-flexion frame, below the joint
        let w = v - dax; // un-abducted height
        if w > -1e-3 {
            // l0 hangs the hip joint below the axis; such a short planar reach lies above it.
            return Ok(());
        }
        let a_len = (w * w + d * d).sqrt(); // distance of the foot from the abduction axis
        let (y, z) = match axis {
            0 => (a_len, 0.0),
            1 => (0.0, a_len),
            2 => (-a_len, 0.0),
            _ => (0.0, -a_len),
        };
        let target = Vec3::new(u as f32, y as f32, z as f32);
        let q = check_against_oracle(&robot, LegId::ALL[l], target);
        prop_assert!(q.is_some(), "boundary target {target:?} not solved");
    }
}

/// The robot of seed 000 with no limits beyond a full turn on every joint (its Algorithm 1
/// treats every quadrant).
fn shahriar_full_turn(bend: KneeBend) -> Robot {
    Robot {
        limits: JointLimits::FULL_TURN,
        ..Robot::shahriar2023().with_knee_bend(bend)
    }
}

/// Seed 000 Algorithm 1 done right, in the hip frame (y left, z up): α1 = angle of the foot
/// from +y towards +z in [0, 2π), α3 = π/2 − asin(La/A), θ1 = α1 + α3 (left) or α1 − α3
/// (right), wrapped to [0, 2π) for both sides.
fn algorithm1_done_right(leg_id: LegId, y: f64, z: f64, la: f64) -> f64 {
    let a_len = y.hypot(z);
    let alpha1 = wrap_2pi64(z.atan2(y));
    let alpha3 = FRAC_PI_2 - (la / a_len).asin();
    wrap_2pi64(if leg_id.is_left() {
        alpha1 + alpha3
    } else {
        alpha1 - alpha3
    })
}

/// Largest allowed difference between the crate's θ1 (via `paper::to_seed000`) and Algorithm 1
/// done right in f64.
const THETA1_TOL_RAD: f64 = 2.0e-5;

/// Seed 000 §2.2: feet in all four quadrants of the y–z plane (including above the hip and
/// exactly on the axes), on a robot with full-turn limits: θ1 from the crate equals Algorithm 1
/// done right, and the foot is reached.
#[test]
fn seed000_quadrants_theta1_matches_algorithm1_done_right() {
    let mut rng = SplitMix64::new(0x5EED_0000);
    let mut per_quadrant = [0usize; 4];
    for bend in [KneeBend::Backward, KneeBend::Forward] {
        let robot = shahriar_full_turn(bend);
        let g = robot.leg;
        let la = g.d_lat_m as f64;
        for leg_id in LegId::ALL {
            // Exact quadrant boundaries first, then random angles all around.
            let mut alphas = vec![0.0, FRAC_PI_2, PI, 1.5 * PI];
            alphas.extend((0..200).map(|_| rng.range(0.0, 2.0 * PI)));
            for alpha1 in alphas {
                let a_len = rng.range(la + 0.02, 0.45);
                let x = rng.range(-0.2, 0.2);
                let (mut y, mut z) = (a_len * alpha1.cos(), a_len * alpha1.sin());
                if alpha1 == FRAC_PI_2 || alpha1 == 1.5 * PI {
                    y = 0.0;
                }
                if alpha1 == 0.0 || alpha1 == PI {
                    z = 0.0;
                }
                let target = Vec3::new(x as f32, y as f32, z as f32);
                let p = v64(target);
                let sol = leg::Solver::new(&robot)
                    .inverse(leg_id, target, ReachPolicy::Reject)
                    .unwrap_or_else(|e| panic!("{leg_id} {target:?}: {e}"));
                let err = (fk64(&g, leg_id, q64(sol.angles)) - p).norm();
                assert!(err <= FOOT_TOL_M, "{leg_id} {target:?}: foot error {err:e}");
                let theta1 = paper::to_seed000(leg_id, sol.angles).theta1_rad as f64;
                assert!(
                    (0.0..2.0 * PI).contains(&theta1),
                    "θ1 = {theta1} outside [0, 2π)"
                );
                let want = algorithm1_done_right(leg_id, p.y, p.z, la);
                assert!(
                    ang_diff(theta1, want) <= THETA1_TOL_RAD,
                    "{leg_id} {target:?}: θ1 {theta1} vs Algorithm 1 {want}"
                );
                let quadrant = (wrap_2pi64(p.z.atan2(p.y)) / FRAC_PI_2) as usize % 4;
                per_quadrant[quadrant] += 1;
            }
        }
    }
    // Every quadrant, above (z > 0) and below the hip, was exercised.
    assert!(per_quadrant.iter().all(|&n| n > 100), "{per_quadrant:?}");
}

/// θ1 wraps at 2π: feet whose θ1 lies just below 2π and just above 0 (left legs near abduction
/// 0, right legs near abduction ±π) give θ1 in [0, 2π), equal to Algorithm 1 done right, and
/// `from_seed000 ∘ to_seed000` is the identity on the circle.
#[test]
fn theta1_wraps_at_two_pi() {
    let robot = shahriar_full_turn(KneeBend::Backward);
    let la = robot.leg.d_lat_m as f64;
    let mut seen_low = 0;
    let mut seen_high = 0;
    for leg_id in LegId::ALL {
        let centre = if leg_id.is_left() { 0.0 } else { PI };
        for i in -20..=20 {
            let a = wrap_pi64(centre + i as f64 * 1.0e-3);
            let q = JointAngles::new(a as f32, 0.3, -0.9);
            let target = leg::forward(&robot.leg, leg_id, q);
            let sol = leg::Solver::new(&robot)
                .inverse(leg_id, target, ReachPolicy::Reject)
                .unwrap();
            let s = paper::to_seed000(leg_id, sol.angles);
            let theta1 = s.theta1_rad as f64;
            assert!((0.0..2.0 * PI).contains(&theta1), "θ1 = {theta1}");
            if theta1 < 0.1 {
                seen_low += 1;
            }
            if theta1 > 2.0 * PI - 0.1 {
                seen_high += 1;
            }
            let p = v64(target);
            let want = algorithm1_done_right(leg_id, p.y, p.z, la);
            assert!(
                ang_diff(theta1, want) <= THETA1_TOL_RAD,
                "{theta1} vs {want}"
            );
            let back = paper::from_seed000(leg_id, s);
            for (x, y) in q64(back).iter().zip(q64(sol.angles)) {
                assert!(ang_diff(*x, y) <= 1e-6, "{back:?} vs {:?}", sol.angles);
            }
        }
    }
    assert!(seen_low > 20 && seen_high > 20, "{seen_low} {seen_high}");
}

/// Largest allowed difference between the DH-chained FK and the closed form (both f32).
const DH_TOL_M: f64 = 2.0e-6;

/// DH: `leg::forward_dh` equals the closed form `leg::forward` for random angles, both presets,
/// all legs; and chaining the 4×4 DH transforms of `leg::dh_table` in f64 (independently of
/// `forward_dh`) equals the f64 oracle.
#[test]
fn dh_form_equals_closed_form() {
    let mut rng = SplitMix64::new(0xD4);
    for (_, robot) in presets() {
        for leg_id in LegId::ALL {
            for _ in 0..500 {
                let q = JointAngles::new(
                    rng.range(-PI, PI) as f32,
                    rng.range(-PI, PI) as f32,
                    rng.range(-PI, PI) as f32,
                );
                let closed = leg::forward(&robot.leg, leg_id, q);
                let dh = leg::forward_dh(&robot.leg, leg_id, q);
                assert!(
                    (v64(dh) - v64(closed)).norm() <= DH_TOL_M,
                    "{dh:?} vs {closed:?}"
                );
                // Base frame: x0 = −z_hip, y0 = y_hip, z0 = x_hip.
                let mut t = Matrix4::new(
                    0.0, 0.0, 1.0, 0.0, //
                    0.0, 1.0, 0.0, 0.0, //
                    -1.0, 0.0, 0.0, 0.0, //
                    0.0, 0.0, 0.0, 1.0,
                );
                for row in leg::dh_table(&robot.leg, leg_id, q) {
                    let (th, d, a, al) = (
                        row.theta_rad as f64,
                        row.d_m as f64,
                        row.a_m as f64,
                        row.alpha_rad as f64,
                    );
                    let (st, ct, sa, ca) = (th.sin(), th.cos(), al.sin(), al.cos());
                    t *= Matrix4::new(
                        ct,
                        -st * ca,
                        st * sa,
                        a * ct, //
                        st,
                        ct * ca,
                        -ct * sa,
                        a * st, //
                        0.0,
                        sa,
                        ca,
                        d, //
                        0.0,
                        0.0,
                        0.0,
                        1.0,
                    );
                }
                let p = t * Vector4::new(0.0, 0.0, 0.0, 1.0);
                let oracle = fk64(&robot.leg, leg_id, q64(q));
                // The table holds f32 values (−π/2 is not exact in f32): agreement to f32 rounding.
                assert!((Vector3::new(p.x, p.y, p.z) - oracle).norm() <= DH_TOL_M);
            }
        }
    }
}

/// `leg::joint_points` lies on the chain: hip mount at the origin, links of the right lengths,
/// foot equal to `leg::forward`.
#[test]
fn joint_points_have_link_lengths() {
    let mut rng = SplitMix64::new(0x1057);
    for (_, robot) in presets() {
        let g = robot.leg;
        for leg_id in LegId::ALL {
            for _ in 0..200 {
                let q = random_angles(&mut rng, &robot, 0.0);
                let pts = leg::joint_points(&g, leg_id, q);
                let len = |a: Vec3, b: Vec3| (v64(a) - v64(b)).norm();
                let tol = 1e-6;
                assert_eq!(pts.hip_mount, Vec3::ZERO);
                let off = ((g.d_lat_m as f64).powi(2) + (g.d_ax_m as f64).powi(2)).sqrt();
                assert!((len(pts.hip_joint, pts.hip_mount) - off).abs() < tol);
                assert!((len(pts.knee, pts.hip_joint) - g.femur_m as f64).abs() < tol);
                assert!((len(pts.foot, pts.knee) - g.tibia_m as f64).abs() < tol);
                assert!((v64(pts.foot) - fk64(&g, leg_id, q64(q))).norm() < tol);
            }
        }
    }
}

/// Seed 000 §3.1/§5, reproduced: 50 random reachable foot targets (per leg, drawn in the box
/// |x|, |y|, |z| ≤ La + Lb of its Table 4 and kept when the f64 oracle says they are reachable
/// with 1 mm / 1 mrad to spare) all solve without error, and FK of the answer is the target.
#[test]
fn seed000_fifty_random_points_all_solve() {
    let robot = Robot::shahriar2023();
    let g = robot.leg;
    let bound = (g.d_lat_m + g.femur_m) as f64;
    let mut rng = SplitMix64::new(50);
    for leg_id in LegId::ALL {
        let mut solved = 0;
        let mut drawn = 0;
        while solved < 50 {
            drawn += 1;
            assert!(drawn < 10_000, "reachable points are too rare");
            let target = Vec3::new(
                rng.range(-bound, bound) as f32,
                rng.range(-bound, bound) as f32,
                rng.range(-bound, bound) as f32,
            );
            let p = v64(target);
            let verdict = ik64(&robot, leg_id, [p.x, p.y, p.z]);
            if verdict.result.is_err() || verdict.margin < 1e-3 {
                continue;
            }
            let sol = leg::Solver::new(&robot)
                .inverse(leg_id, target, ReachPolicy::Reject)
                .unwrap_or_else(|e| panic!("point {solved}: {target:?} -> {e}"));
            let err = (fk64(&g, leg_id, q64(sol.angles)) - p).norm();
            assert!(err <= FOOT_TOL_M, "point {solved}: error {err:e}");
            solved += 1;
        }
    }
}

/// The knee-bend option picks the mirrored planar solution: same foot, knee of the other sign,
/// and the knee limits mirrored with it.
#[test]
fn knee_bend_forward_mirrors_the_knee() {
    for (_, robot) in presets() {
        let fwd = robot.with_knee_bend(KneeBend::Forward);
        assert_eq!(fwd.limits.min_rad[2], -robot.limits.max_rad[2]);
        assert_eq!(fwd.limits.max_rad[2], -robot.limits.min_rad[2]);
        for leg_id in LegId::ALL {
            let q = JointAngles::new(0.1, 0.2, -1.0);
            let target = leg::forward(&robot.leg, leg_id, q);
            let back = leg::Solver::new(&robot)
                .inverse(leg_id, target, ReachPolicy::Reject)
                .unwrap();
            let front = leg::Solver::new(&fwd)
                .inverse(leg_id, target, ReachPolicy::Reject)
                .unwrap();
            assert!((back.angles.knee_rad + 1.0).abs() < 1e-5);
            assert!((front.angles.knee_rad - 1.0).abs() < 1e-5);
            assert!((front.angles.abduction_rad - back.angles.abduction_rad).abs() < 1e-6);
            let foot = fk64(&robot.leg, leg_id, q64(front.angles));
            assert!((foot - v64(target)).norm() <= FOOT_TOL_M);
        }
    }
}

/// Sanity of the oracle itself against the crate's unreachable vocabulary.
#[test]
fn oracle_kind_mapping_is_total() {
    for u in [
        Unreachable::TooFar,
        Unreachable::TooClose,
        Unreachable::InsideOffset,
        Unreachable::JointLimit(kin_core::Joint::Knee),
    ] {
        assert!(kind_of(u).is_some());
    }
    assert!(kind_of(Unreachable::NonFinite).is_none());
}
