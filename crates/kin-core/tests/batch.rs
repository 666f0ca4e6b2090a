//! The batch solves (`kin_core::batch`) against the scalar ones, bit for bit: every result and
//! reach code of a batch equals the scalar solve's for the same target, on the three host
//! backends (`Fast`, `Libm`, `SoftFloat`), both presets and knee bends, all legs, both
//! policies. Targets: proptest over a box enclosing the whole workspace with special values
//! mixed in (±0, NaN, ±∞, huge, subnormal), and enumerated edges (the reach boundaries ± a
//! few ulps, the offset circle, the quadrant boundaries y = 0 / z = 0 with both zeros, the
//! joint limits ± an ulp), on every tail length `0..=LANES + 1` and beyond (three portable
//! chunks and one more, a full AVX-512 chunk and nine more). The entry points compiled for
//! AVX2 and AVX-512 (`batch::avx2`, `batch::avx512`) give the portable ones' bits, each
//! where the CPU runs it.

// The compiled entry points are unsafe to call: each call is behind the CPU's check.
#![allow(unsafe_code)]

/// Runs `$body` once for each module of compiled entry points this CPU runs, named `$form`
/// inside it (`batch::avx2`, then `batch::avx512`).
macro_rules! each_compiled_form {
    ($form:ident => $body:block) => {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") {
                use kin_core::batch::avx2 as $form;
                $body
            }
            if std::is_x86_feature_detected!("avx512f")
                && std::is_x86_feature_detected!("avx512vl")
                && std::is_x86_feature_detected!("avx512bw")
                && std::is_x86_feature_detected!("avx512dq")
            {
                use kin_core::batch::avx512 as $form;
                $body
            }
        }
    };
}

use kin_core::batch::{self, code, BodyFeet, LANES, NO_LEG};
use kin_core::math::{Fast, Libm, SoftFloat};
use kin_core::{
    body, leg, BodyConfig, BodySolution, KneeBend, LegId, Math, Pose, ReachPolicy, Robot,
    RotationOrder, Vec3,
};
use proptest::prelude::*;
use seeded_rng::SplitMix64;

const POLICIES: [ReachPolicy; 2] = [ReachPolicy::Reject, ReachPolicy::Clamp];

fn robots() -> Vec<Robot> {
    let mut out = Vec::new();
    for r in [Robot::shahriar2023(), Robot::fernando2025()] {
        out.push(r);
        out.push(r.with_knee_bend(KneeBend::Forward));
    }
    out
}

fn bits3(a: [f32; 3]) -> [u32; 3] {
    a.map(f32::to_bits)
}

/// The scalar leg solve's answer as the batch reports it.
fn scalar_leg<M: Math>(
    s: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    p: [f32; 3],
) -> ([f32; 3], u8) {
    match s.inverse(leg, Vec3::from_array(p), policy) {
        Ok(sol) => (
            sol.angles.to_array(),
            sol.clamped.map_or(code::OK, |c| batch::code_of(c.kind)),
        ),
        Err(e) => ([0.0; 3], batch::code_of(e.kind)),
    }
}

/// Both batch forms (rows and structure of arrays) against the scalar solve on backend `M`.
fn check_leg_on<M: Math>(robot: &Robot, leg: LegId, policy: ReachPolicy, feet: &[[f32; 3]]) {
    let s = leg::Solver::<M>::with_math(robot);
    let n = feet.len();
    let mut angles = vec![[f32::NAN; 3]; n];
    let mut codes = vec![u8::MAX; n];
    batch::leg_inverse(
        &s,
        leg,
        policy,
        feet.as_flattened(),
        angles.as_flattened_mut(),
        &mut codes,
    )
    .unwrap();
    let cols: [Vec<f32>; 3] = core::array::from_fn(|k| feet.iter().map(|p| p[k]).collect());
    let (mut a, mut h, mut k) = (vec![f32::NAN; n], vec![f32::NAN; n], vec![f32::NAN; n]);
    let mut codes_soa = vec![u8::MAX; n];
    batch::leg_inverse_soa(
        &s,
        leg,
        policy,
        [&cols[0], &cols[1], &cols[2]],
        &mut a,
        &mut h,
        &mut k,
        &mut codes_soa,
    )
    .unwrap();
    each_compiled_form!(form => {
        let mut angles2 = vec![[f32::NAN; 3]; n];
        let mut codes2 = vec![u8::MAX; n];
        // SAFETY: the CPU supports the form's features (checked by the macro).
        unsafe {
            form::leg_inverse(
                &s,
                leg,
                policy,
                feet.as_flattened(),
                angles2.as_flattened_mut(),
                &mut codes2,
            )
        }
        .unwrap();
        assert_eq!(
            angles2.iter().map(|a| bits3(*a)).collect::<Vec<_>>(),
            angles.iter().map(|a| bits3(*a)).collect::<Vec<_>>()
        );
        assert_eq!(codes2, codes);
        let (mut a2, mut h2, mut k2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        // SAFETY: as above.
        unsafe {
            form::leg_inverse_soa(
                &s,
                leg,
                policy,
                [&cols[0], &cols[1], &cols[2]],
                &mut a2,
                &mut h2,
                &mut k2,
                &mut codes2,
            )
        }
        .unwrap();
        for i in 0..n {
            assert_eq!(bits3([a2[i], h2[i], k2[i]]), bits3(angles[i]));
        }
        assert_eq!(codes2, codes);
    });
    for (i, p) in feet.iter().enumerate() {
        let (want, want_code) = scalar_leg(&s, leg, policy, *p);
        let name = core::any::type_name::<M>();
        assert_eq!(
            (bits3(angles[i]), codes[i]),
            (bits3(want), want_code),
            "{name} {leg} {policy:?} row {i} of {n}: {p:?}: batch {:?}, scalar {want:?}",
            angles[i]
        );
        assert_eq!(
            (bits3([a[i], h[i], k[i]]), codes_soa[i]),
            (bits3(want), want_code),
            "{name} soa {leg} {policy:?} row {i} of {n}: {p:?}"
        );
    }
}

fn check_leg(robot: &Robot, leg: LegId, policy: ReachPolicy, feet: &[[f32; 3]]) {
    check_leg_on::<Fast>(robot, leg, policy, feet);
    check_leg_on::<Libm>(robot, leg, policy, feet);
    check_leg_on::<SoftFloat>(robot, leg, policy, feet);
}

/// `x` moved by `k` ulps (towards +∞ for k > 0 on positive x).
fn ulps(x: f32, k: i32) -> f32 {
    if x == 0.0 {
        return f32::from_bits(k.unsigned_abs()) * k.signum() as f32;
    }
    f32::from_bits((x.to_bits() as i32 + k) as u32)
}

/// Feet on and beside the reach boundaries, the offset circle, the quadrant boundaries and
/// the joint limits of `robot`'s `leg`.
fn edge_feet(robot: &Robot, leg: LegId) -> Vec<[f32; 3]> {
    let g = robot.leg;
    let sd = leg.side() * g.d_lat_m;
    let (l1, l2) = (g.femur_m, g.tibia_m);
    let mut out = Vec::new();
    // The planar distance at (L1 + L2) and |L1 − L2| from the hip-flexion joint, straight
    // below it and along x, each ± a few ulps; the offset circle |(y, z)| = d_lat ± ulps.
    for dist in [l1 + l2, (l1 - l2).abs()] {
        for k in -3..=3 {
            let d = ulps(dist, k);
            out.push([0.0, sd, -d - g.d_ax_m]);
            out.push([d, sd, -g.d_ax_m]);
            out.push([-d, sd, -g.d_ax_m]);
        }
    }
    for k in -3..=3 {
        out.push([0.1, ulps(sd, k), 0.0]);
        out.push([0.1, 0.0, ulps(g.d_lat_m, k)]);
        out.push([0.1, 0.0, -ulps(g.d_lat_m, k)]);
    }
    // The quadrant boundaries of seed 000 §2.2: y = ±0 or z = ±0, feet above and below the
    // hip, left and right, at a reachable distance.
    let a = 0.6 * (l1 + l2);
    for (y, z) in [
        (0.0, -a),
        (-0.0, -a),
        (0.0, a),
        (-0.0, a),
        (a, 0.0),
        (a, -0.0),
        (-a, 0.0),
        (-a, -0.0),
        (0.0, 0.0),
        (-0.0, -0.0),
    ] {
        for x in [0.0, -0.0, 0.05, -0.05] {
            out.push([x, y, z]);
        }
    }
    // The joint limits ± an ulp, and a grid of angles by π/8 (the atan2 octant edges), by FK.
    let (lo, hi) = (robot.limits.min_rad, robot.limits.max_rad);
    let mut angles = Vec::new();
    for j in 0..3 {
        for lim in [lo[j], hi[j]] {
            for k in -1..=1 {
                let mut q = [0.5 * (lo[0] + hi[0]), -0.4, -0.9];
                if robot.knee_bend == KneeBend::Forward {
                    q[2] = 0.9;
                }
                q[j] = ulps(lim, k);
                angles.push(q);
            }
        }
    }
    for a in -8..=8 {
        for h in -8..=8 {
            for k in [-6, -4, -2, 2, 4, 6] {
                let e = core::f32::consts::FRAC_PI_8;
                angles.push([a as f32 * e, h as f32 * e, k as f32 * e]);
            }
        }
    }
    for q in angles {
        let f = leg::forward(&g, leg, kin_core::JointAngles::from_array(q));
        out.push(f.to_array());
    }
    // Special values.
    for v in [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        3e38,
        -3e38,
        1e20,
        1e-40,
    ] {
        out.push([v, sd, -0.2]);
        out.push([0.0, v, -0.2]);
        out.push([0.0, sd, v]);
    }
    out
}

#[test]
fn leg_batch_equals_scalar_on_the_enumerated_edges() {
    for robot in robots() {
        for leg in LegId::ALL {
            let feet = edge_feet(&robot, leg);
            for policy in POLICIES {
                check_leg(&robot, leg, policy, &feet);
            }
        }
    }
}

#[test]
fn leg_batch_equals_scalar_on_every_tail_length() {
    let robot = Robot::shahriar2023();
    let feet = edge_feet(&robot, LegId::FR);
    for n in 0..=3 * LANES + 1 {
        for start in [0, 5, 17] {
            let slice = &feet[start..start + n];
            for policy in POLICIES {
                check_leg(&robot, LegId::FR, policy, slice);
            }
        }
    }
    // Around the blocks of `leg_inverse` (rows taken apart and put back together a block at a
    // time): one short of a block, a block, one more, two blocks and a tail of 17.
    let b = batch::BLOCK_ROWS;
    let many: Vec<[f32; 3]> = feet.iter().cycle().take(2 * b + 17).copied().collect();
    for n in [b - 1, b, b + 1, 2 * b, 2 * b + 17] {
        for policy in POLICIES {
            check_leg(&robot, LegId::FR, policy, &many[..n]);
        }
    }
}

#[test]
fn leg_batch_failed_rows_hold_zeros_and_never_nan() {
    let robot = Robot::fernando2025();
    let s = leg::Solver::new(&robot);
    let feet = edge_feet(&robot, LegId::RL);
    let mut angles = vec![[1.0; 3]; feet.len()];
    let mut codes = vec![0; feet.len()];
    for policy in POLICIES {
        batch::leg_inverse(
            &s,
            LegId::RL,
            policy,
            feet.as_flattened(),
            angles.as_flattened_mut(),
            &mut codes,
        )
        .unwrap();
        for (a, c) in angles.iter().zip(&codes) {
            assert!(a.iter().all(|v| v.is_finite()), "{a:?}");
            if policy == ReachPolicy::Reject && *c != code::OK {
                assert_eq!(*a, [0.0; 3]);
            }
        }
    }
    assert!(codes.contains(&code::NON_FINITE));
}

#[test]
fn wrong_lengths_are_refused_before_anything_is_written() {
    let s = leg::Solver::new(&Robot::shahriar2023());
    let feet = [[0.0, 0.05, -0.2]; 3];
    let mut angles = [[7.0; 3]; 2];
    let mut codes = [9; 3];
    let e = batch::leg_inverse(
        &s,
        LegId::FL,
        ReachPolicy::Reject,
        feet.as_flattened(),
        angles.as_flattened_mut(),
        &mut codes,
    )
    .unwrap_err();
    assert_eq!((e.what, e.expected, e.got), ("angles_rad", 9, 6));
    assert_eq!((angles, codes), ([[7.0; 3]; 2], [9; 3]));
    // Not whole rows.
    let e = batch::leg_inverse(
        &s,
        LegId::FL,
        ReachPolicy::Reject,
        &feet.as_flattened()[..8],
        &mut [0.0; 6],
        &mut codes[..2],
    )
    .unwrap_err();
    assert_eq!((e.what, e.expected, e.got), ("feet_in_hip_m", 6, 8));
    assert_eq!(e.to_string(), "feet_in_hip_m: 8 elements, expected 6");
}

/// A foot coordinate: mostly a uniform value over the box, sometimes a special one.
fn coord(half: f32) -> impl Strategy<Value = f32> {
    prop_oneof![
        12 => -half..=half,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => prop_oneof![
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(3e38f32),
            Just(-1e25f32),
            Just(1e-42f32),
        ],
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// Random batches of feet over a box enclosing the workspace: every row equals the scalar
    /// solve on every backend.
    #[test]
    fn leg_batch_equals_scalar_over_the_workspace(
        r in 0usize..4, l in 0usize..4, clamp in any::<bool>(),
        feet in prop::collection::vec((coord(1.0), coord(1.0), coord(1.0)), 0..(3 * LANES + 2)),
    ) {
        let robot = robots()[r];
        let g = robot.leg;
        let reach = (g.d_lat_m + g.d_ax_m + g.femur_m + g.tibia_m) * 1.05;
        let feet: Vec<[f32; 3]> = feet.iter().map(|&(x, y, z)| [x * reach, y * reach, z * reach]).collect();
        let policy = if clamp { ReachPolicy::Clamp } else { ReachPolicy::Reject };
        check_leg(&robot, LegId::ALL[l], policy, &feet);
    }

    /// Random joint angles (beyond the limits too, with special values): the batch FK equals
    /// `leg::forward` bit for bit, `NON_FINITE` and zeros for a non-finite row.
    #[test]
    fn leg_fk_batch_equals_scalar(
        r in 0usize..4, l in 0usize..4,
        rows in prop::collection::vec((coord(4.0), coord(4.0), coord(4.0)), 0..(3 * LANES + 2)),
    ) {
        let robot = robots()[r];
        let leg = LegId::ALL[l];
        let q: Vec<[f32; 3]> = rows.iter().map(|&(a, h, k)| [a, h, k]).collect();
        let mut feet = vec![[f32::NAN; 3]; q.len()];
        let mut codes = vec![u8::MAX; q.len()];
        batch::leg_forward::<kin_core::DefaultMath>(&robot.leg, leg, q.as_flattened(), feet.as_flattened_mut(), &mut codes).unwrap();
        each_compiled_form!(form => {
            let (mut feet2, mut codes2) = (vec![[0.0; 3]; q.len()], vec![0; q.len()]);
            // SAFETY: the CPU supports the form's features (checked by the macro).
            unsafe { form::leg_forward::<kin_core::DefaultMath>(&robot.leg, leg, q.as_flattened(), feet2.as_flattened_mut(), &mut codes2) }.unwrap();
            prop_assert_eq!(feet2.iter().map(|f| bits3(*f)).collect::<Vec<_>>(), feet.iter().map(|f| bits3(*f)).collect::<Vec<_>>());
            prop_assert_eq!(&codes2, &codes);
        });
        for (i, a) in q.iter().enumerate() {
            if a.iter().all(|v| v.is_finite()) {
                let want = leg::forward(&robot.leg, leg, kin_core::JointAngles::from_array(*a));
                prop_assert_eq!((bits3(feet[i]), codes[i]), (bits3(want.to_array()), code::OK));
            } else {
                prop_assert_eq!((feet[i], codes[i]), ([0.0; 3], code::NON_FINITE));
            }
        }
    }
}

/// The scalar body IK's answer as the batch reports it.
fn scalar_body<M: Math>(
    s: &body::Solver<M>,
    config: &BodyConfig,
    policy: ReachPolicy,
    pose: [f32; 6],
    feet: BodyFeet<'_>,
    j: usize,
) -> ([f32; 12], u8, i8) {
    let pose = Pose::from_array(pose);
    let mut sol = BodySolution::default();
    let r = match feet {
        BodyFeet::Stance { height_m } => {
            s.inverse_at_stance_into(&pose, config, height_m, policy, &mut sol)
        }
        BodyFeet::Same(f) => s.inverse_into(&pose, config, f, policy, &mut sol),
        BodyFeet::PerPose(f) => {
            let feet: [Vec3; 4] = core::array::from_fn(|k| {
                Vec3::new(
                    f[12 * j + 3 * k],
                    f[12 * j + 3 * k + 1],
                    f[12 * j + 3 * k + 2],
                )
            });
            s.inverse_into(&pose, config, &feet, policy, &mut sol)
        }
    };
    match r {
        Ok(()) => match sol.clamped.iter().position(Option::is_some) {
            Some(k) => (
                sol.angles_rad,
                batch::code_of(sol.clamped[k].unwrap().kind),
                k as i8,
            ),
            None => (sol.angles_rad, code::OK, NO_LEG),
        },
        Err(e) => ([0.0; 12], batch::code_of(e.kind), e.leg.index() as i8),
    }
}

fn check_body_on<M: Math>(
    robot: &Robot,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[[f32; 6]],
    feet: BodyFeet<'_>,
) {
    let s = body::Solver::<M>::with_math(robot);
    let n = poses.len();
    let mut angles = vec![[f32::NAN; 12]; n];
    let (mut codes, mut legs) = (vec![u8::MAX; n], vec![i8::MAX; n]);
    batch::body_inverse(
        &s,
        config,
        policy,
        poses.as_flattened(),
        feet,
        angles.as_flattened_mut(),
        &mut codes,
        &mut legs,
    )
    .unwrap();
    each_compiled_form!(form => {
        let mut angles2 = vec![[f32::NAN; 12]; n];
        let (mut codes2, mut legs2) = (vec![u8::MAX; n], vec![i8::MAX; n]);
        // SAFETY: the CPU supports the form's features (checked by the macro).
        unsafe {
            form::body_inverse(
                &s,
                config,
                policy,
                poses.as_flattened(),
                feet,
                angles2.as_flattened_mut(),
                &mut codes2,
                &mut legs2,
            )
        }
        .unwrap();
        let bits = |v: &Vec<[f32; 12]>| v.iter().map(|a| a.map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(
            (bits(&angles2), &codes2, &legs2),
            (bits(&angles), &codes, &legs)
        );
    });
    for (j, p) in poses.iter().enumerate() {
        let (want, c, l) = scalar_body(&s, config, policy, *p, feet, j);
        assert_eq!(
            (angles[j].map(f32::to_bits), codes[j], legs[j]),
            (want.map(f32::to_bits), c, l),
            "{} {policy:?} {config:?} pose {j} of {n}: {p:?}",
            core::any::type_name::<M>()
        );
    }
}

fn check_body(
    robot: &Robot,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[[f32; 6]],
    feet: BodyFeet<'_>,
) {
    check_body_on::<Fast>(robot, config, policy, poses, feet);
    check_body_on::<Libm>(robot, config, policy, poses, feet);
    check_body_on::<SoftFloat>(robot, config, policy, poses, feet);
}

fn random_poses(rng: &mut SplitMix64, n: usize, scale: f32) -> Vec<[f32; 6]> {
    let mut u =
        |lo: f32, hi: f32| lo + (hi - lo) * (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
    (0..n)
        .map(|i| {
            let mut p = [
                u(-0.5, 0.5) * scale,
                u(-0.5, 0.5) * scale,
                u(-0.8, 0.8) * scale,
                u(-0.06, 0.06) * scale,
                u(-0.06, 0.06) * scale,
                u(-0.08, 0.08) * scale,
            ];
            // Now and then a non-finite value.
            if i % 13 == 7 {
                p[i % 6] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][i % 3];
            }
            p
        })
        .collect()
}

#[test]
fn body_batch_equals_scalar_on_every_feet_form_and_order() {
    let mut rng = SplitMix64::new(0xb0d7_ba7c);
    for robot in robots() {
        let stance = 0.6 * (robot.leg.femur_m + robot.leg.tibia_m) + robot.leg.d_ax_m;
        let same = robot.stance_feet(stance);
        for order in RotationOrder::ALL {
            let config = BodyConfig::about_centre(order);
            for scale in [0.2, 1.0, 3.0] {
                for n in [0, 1, LANES - 1, LANES, LANES + 1, 3 * LANES + 5] {
                    let poses = random_poses(&mut rng, n, scale);
                    let per_pose: Vec<[[f32; 3]; 4]> = poses
                        .iter()
                        .enumerate()
                        .map(|(i, _)| {
                            let mut f = same.map(|v| v.to_array());
                            f[i % 4][i % 3] += 0.02 * (i as f32 - 3.0) * scale;
                            if i % 17 == 11 {
                                f[(i + 1) % 4][2] = f32::NAN;
                            }
                            f
                        })
                        .collect();
                    for policy in POLICIES {
                        let forms = [
                            BodyFeet::Stance { height_m: stance },
                            BodyFeet::Same(&same),
                            BodyFeet::PerPose(per_pose.as_flattened().as_flattened()),
                        ];
                        for feet in forms {
                            check_body(&robot, &config, policy, &poses, feet);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn body_batch_with_a_pivot_equals_scalar() {
    let mut rng = SplitMix64::new(0x9170);
    let robot = Robot::shahriar2023();
    let config = BodyConfig {
        order: RotationOrder::Zxy,
        pivot_m: Vec3::new(0.03, -0.01, -0.05),
    };
    let poses = random_poses(&mut rng, 4 * LANES + 3, 1.5);
    for policy in POLICIES {
        check_body(
            &robot,
            &config,
            policy,
            &poses,
            BodyFeet::Stance { height_m: 0.277 },
        );
    }
}
