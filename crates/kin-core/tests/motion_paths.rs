//! Foot paths: shape (end points, apex, ground contact), C0 everywhere, C1 at the swing/stance
//! joins exactly where `c1_at_joins` says so, seed 000's rectangle and the rect-path motion.

use kin_core::motion::laws::{LegPaths, LegPathsParams};
use kin_core::motion::path::{
    AnyPath, Bezier, Cycloid, Ellipse, FootPath, PathKind, Rectangle, Semicircle, Stride,
};
use kin_core::motion::{Contact, Error, Motion, Param, Phase};
use kin_core::{preflight, DefaultMath, LegId, Vec3};

/// Geometric tolerance of the shape checks, m.
const TOL_M: f32 = 1e-6;
/// Phase step of the finite differences at the joins, cycles.
const H: f32 = 1e-3;

fn p(x: f32) -> Phase {
    Phase::new(x).unwrap()
}

fn all_paths(stride: Stride) -> [AnyPath; 5] {
    PathKind::ALL.map(|k| AnyPath::new(k, stride))
}

fn strides() -> Vec<Stride> {
    let mut v = Vec::new();
    for (l, h) in [(0.1, 0.05), (0.3, 0.1), (0.05, 0.2)] {
        for d in [0.25, 0.5, 0.75] {
            v.push(Stride::new(l, h, d).unwrap());
        }
    }
    v
}

fn max_step(path: &AnyPath, n: u32) -> f32 {
    let mut worst = 0.0f32;
    let mut prev = path.offset::<DefaultMath>(p(0.0));
    for k in 1..=n {
        let cur = path.offset::<DefaultMath>(p(k as f32 / n as f32)); // k = n wraps to phase 0
        worst = worst.max((cur - prev).norm());
        prev = cur;
    }
    worst
}

#[test]
fn every_path_is_c0_its_largest_step_shrinks_with_the_phase_step() {
    for s in strides() {
        for path in all_paths(s) {
            let coarse = max_step(&path, 1_000);
            let fine = max_step(&path, 10_000);
            // A jump would keep the largest step at its size; a continuous path divides it by 10.
            assert!(
                fine < 0.15 * coarse,
                "{:?} {s:?}: {coarse} → {fine}",
                path.kind()
            );
            // And it is bounded by the path's length per cycle.
            let bound =
                4.0 * (s.length_m() + 2.0 * s.height_m()) / (1.0 - s.duty_factor()) / 1_000.0;
            assert!(coarse < bound, "{:?}: {coarse} vs {bound}", path.kind());
        }
    }
}

#[test]
fn every_path_lifts_off_behind_lands_in_front_peaks_at_its_height_and_stands_on_the_ground() {
    for s in strides() {
        for path in all_paths(s) {
            let (l, d) = (s.length_m(), s.duty_factor());
            let h = if path.kind() == PathKind::Semicircle {
                0.5 * l
            } else {
                s.height_m()
            };
            let swing = 1.0 - d;
            let lift_off = path.offset::<DefaultMath>(p(0.0));
            assert!((lift_off - Vec3::new(-0.5 * l, 0.0, 0.0)).norm() < TOL_M);
            let touch = path.offset::<DefaultMath>(p(swing));
            assert!((touch - Vec3::new(0.5 * l, 0.0, 0.0)).norm() < TOL_M);
            let apex = path.offset::<DefaultMath>(p(0.5 * swing));
            assert!((apex.z - h).abs() < TOL_M, "{:?}: {apex:?}", path.kind());
            assert_eq!(path.contact(p(0.5 * swing)), Contact::Swing);
            for k in 0..100 {
                let ph = swing + d * k as f32 / 100.0;
                let o = path.offset::<DefaultMath>(p(ph));
                assert_eq!(path.contact(p(ph)), Contact::Stance);
                assert!(o.z.abs() < TOL_M && o.y == 0.0);
                // Constant stance speed L/d per cycle.
                let want = 0.5 * l - l * (ph - swing) / d;
                assert!((o.x - want).abs() < TOL_M, "{:?}", path.kind());
            }
            // Never below the ground, never above the apex (+ the Bézier's margin of 0).
            for k in 0..1000 {
                let o = path.offset::<DefaultMath>(p(k as f32 / 1000.0));
                assert!(o.z >= -TOL_M && o.z <= h + TOL_M, "{:?} {o:?}", path.kind());
            }
        }
    }
}

/// One-sided velocities (per cycle) at phase `at`, second-order differences.
fn one_sided(path: &AnyPath, at: f32) -> (Vec3, Vec3) {
    let o = |d: f32| path.offset::<DefaultMath>(p(at + d));
    let left = (o(0.0) * 3.0 - o(-H) * 4.0 + o(-2.0 * H)) * (0.5 / H);
    let right = (o(H) * 4.0 - o(0.0) * 3.0 - o(2.0 * H)) * (0.5 / H);
    (left, right)
}

#[test]
fn c1_at_the_joins_exactly_where_claimed() {
    for s in strides() {
        for path in all_paths(s) {
            let stance_speed = s.length_m() / s.duty_factor();
            let scale = stance_speed.max(s.height_m() / (1.0 - s.duty_factor()));
            for join in [0.0, 1.0 - s.duty_factor()] {
                let (l, r) = one_sided(&path, join);
                let jump = (l - r).norm();
                if path.c1_at_joins() {
                    // First-order differences differ by O(H·|p''|); well below the speed.
                    assert!(
                        jump < 0.02 * scale,
                        "{:?} at {join}: {l:?} vs {r:?}",
                        path.kind()
                    );
                } else {
                    assert!(
                        jump > 0.3 * stance_speed.min(s.height_m() / (1.0 - s.duty_factor())),
                        "{:?} at {join}: claimed not C1 but {l:?} ≈ {r:?}",
                        path.kind()
                    );
                }
            }
            // The vertical component of the cycloid is C1 at the joins.
            if path.kind() == PathKind::Cycloid {
                let (l, r) = one_sided(&path, 1.0 - s.duty_factor());
                assert!((l.z - r.z).abs() < 0.02 * scale);
            }
        }
    }
    assert!(AnyPath::new(PathKind::Bezier, strides()[0]).c1_at_joins());
}

#[test]
fn bezier_apex_is_exact_and_its_end_tangents_match_the_stance() {
    let b = Bezier::new(Stride::new(0.2, 0.08, 0.6).unwrap());
    let cp = b.control_points();
    let sigma = 0.4f32;
    let v0 = 5.0 * (cp[1].0 - cp[0].0) / sigma;
    let v5 = 5.0 * (cp[5].0 - cp[4].0) / sigma;
    assert!((v0 + 0.2 / 0.6).abs() < 1e-6 && (v5 + 0.2 / 0.6).abs() < 1e-6);
    assert!((b.offset::<DefaultMath>(p(0.2)).z - 0.08).abs() < 1e-7);
}

#[test]
fn seed000_rectangle_matches_fig8() {
    // Fig. 8: foot between −0.2 and −0.15 below the hip, travel 0.1.
    let r = Rectangle::seed000();
    let (mut zmin, mut zmax, mut xmin, mut xmax) = (1f32, -1f32, 1f32, -1f32);
    for k in 0..3000 {
        let o = r.offset::<DefaultMath>(p(k as f32 / 3000.0));
        let z = o.z - Rectangle::SEED000_STANCE_HEIGHT_M;
        zmin = zmin.min(z);
        zmax = zmax.max(z);
        xmin = xmin.min(o.x);
        xmax = xmax.max(o.x);
    }
    assert!((zmin + 0.2).abs() < TOL_M && (zmax + 0.15).abs() < TOL_M);
    assert!((xmax - xmin - 0.1).abs() < TOL_M);
    // Constant speed round the loop: perimeter 0.3 per cycle.
    let fine = max_step(&AnyPath::Rectangle(r), 3000);
    assert!((fine - 0.3 / 3000.0).abs() < 1e-6, "{fine}");
    // The rectangle's corners are where it is not C1.
    assert!(!r.c1_at_joins());
}

#[test]
fn shapes_are_what_their_names_say() {
    let s = Stride::new(0.2, 0.06, 0.5).unwrap();
    let semi = Semicircle::new(0.2, 0.5).unwrap();
    let ell = Ellipse::new(s);
    let cyc = Cycloid::new(s);
    for k in 0..50 {
        let ph = 0.5 * k as f32 / 50.0;
        let o = semi.offset::<DefaultMath>(p(ph));
        assert!((o.x.hypot(o.z) - 0.1).abs() < 1e-6);
        let o = ell.offset::<DefaultMath>(p(ph));
        assert!(((o.x / 0.1).powi(2) + (o.z / 0.06).powi(2) - 1.0).abs() < 1e-5);
    }
    // Cycloid: zero velocity at lift-off and touch-down (within the swing).
    let d = (cyc.offset::<DefaultMath>(p(1e-3)) - cyc.offset::<DefaultMath>(p(0.0))).norm() / 1e-3;
    assert!(d < 0.01, "{d}");
}

#[test]
fn path_parameters_are_validated_by_name() {
    assert_eq!(
        Stride::new(-0.1, 0.05, 0.5),
        Err(Error::Negative(Param::StrideM))
    );
    assert_eq!(
        Stride::new(0.1, f32::NAN, 0.5),
        Err(Error::NonFinite(Param::StepHeightM))
    );
    assert!(matches!(
        Stride::new(0.1, 0.05, 1.0),
        Err(Error::OutOfRange {
            parameter: Param::DutyFactor,
            ..
        })
    ));
    assert_eq!(
        Phase::new(f32::INFINITY),
        Err(Error::NonFinite(Param::Phase))
    );
    assert_eq!(Phase::new(-0.25).unwrap().value(), 0.75);
    assert_eq!(Phase::new(-1e-12).unwrap().value(), 0.0);
    assert_eq!(PathKind::parse("Bezier"), Some(PathKind::Bezier));
    assert_eq!(PathKind::parse("spline"), None);
}

#[test]
fn rect_path_motion_is_reachable_and_periodic() {
    let m = LegPaths::new(LegPathsParams::seed000()).unwrap();
    let report = preflight::check(
        &m,
        &preflight::Sweep::new(0.0, 3.0, 200.0).unwrap(),
        [preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3],
    )
    .unwrap();
    let (_, ws) = report.min_workspace_margin().unwrap();
    println!(
        "seed 000 rectangle: min workspace margin {:.4} m, min inverse condition {:.4}",
        ws.value,
        report.min_inverse_condition().unwrap().1.value
    );
    assert!(report.ok(), "{:?}", report.first_failure);
    let a = m.frame::<DefaultMath>(0.4).unwrap();
    let b = m.frame::<DefaultMath>(3.4).unwrap();
    for l in LegId::ALL {
        assert!((a.feet_in_world[l.index()] - b.feet_in_world[l.index()]).norm() < 1e-6);
    }
    // An unreachable path is refused at construction, naming it.
    let mut params = LegPathsParams::seed000();
    params.path = AnyPath::new(PathKind::Ellipse, Stride::new(0.1, 0.25, 0.5).unwrap());
    assert!(matches!(
        LegPaths::new(params),
        Err(Error::BeyondReach {
            parameter: Param::Path,
            ..
        })
    ));
}
