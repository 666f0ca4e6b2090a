//! Seed 001's body-motion laws (eq. 6–11) with the fernando2025 robot: periodic joint angles,
//! stance feet fixed in the world, lifted feet on eq. 10 (corrected), no singular configuration
//! — and the errata of eq. 10–11 pinned against a literal f64 transcription.

use kin_core::jacobian::SINGULARITY_THRESHOLD;
use kin_core::motion::laws::{self, Axis, Sway, SwayParams, YawTurn, YawTurnParams};
use kin_core::motion::{self, Contact, Motion, Param};
use kin_core::preflight::{self, Sweep};
use kin_core::{body, leg, paper, DefaultMath, LegId, ReachPolicy, Robot, Vec3};
use std::f64::consts::PI;

/// Largest allowed change of a joint angle between `t` and `t + period` (issue 5).
const PERIODIC_TOL_RAD: f32 = 1e-4;
/// Largest allowed drift of a stance foot in the world and deviation of a lifted foot from
/// eq. 10, measured through FK of the solved angles (issue 5).
const FOOT_TOL_M: f64 = 1e-6;
/// Time step of the sampled runs, s (not a divisor of the periods, so that the samples do not
/// land on the switching instants of eq. 11).
const DT_S: f32 = 0.0137;

/// FK of the solved angles of `motion` at `t`: the feet in the world frame.
fn solved_feet<T: Motion>(motion: &T, t: f32) -> ([Vec3; 4], [f32; 12], motion::Frame) {
    let (frame, sol) =
        motion::solve::<DefaultMath>(motion, t, ReachPolicy::Reject).expect("reachable");
    let feet = body::forward(
        motion.robot(),
        &frame.pose,
        &motion.body_config(),
        &sol.angles(),
    );
    (feet, sol.flat(), frame)
}

fn dist(a: Vec3, b: [f64; 3]) -> f64 {
    let d = [a.x as f64 - b[0], a.y as f64 - b[1], a.z as f64 - b[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

fn max_abs_diff(a: &[f32; 12], b: &[f32; 12]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn seed001_stance_height_comes_from_the_initial_pose() {
    let robot = Robot::fernando2025();
    let feet = laws::seed001_stance(&robot);
    let q = paper::from_seed001(paper::SEED001_INITIAL);
    let expected = 0.15 + 0.9 * (60f64).to_radians().sin();
    for l in LegId::ALL {
        let f = feet[l.index()];
        let hip = robot.hip_in_body(l);
        assert!(
            (f.x - hip.x).abs() < 1e-6 && (f.y - hip.y).abs() < 1e-6,
            "{l}: {f:?}"
        );
        assert!((f.z as f64 + expected).abs() < 1e-6, "{l}: {f:?}");
        assert_eq!(
            leg::forward(&robot.leg, l, q),
            f - hip,
            "FK of the initial pose"
        );
    }
    assert!((expected - 0.9294).abs() < 1e-4);
}

/// Preflight of `motion` over `[0, period_s]` at 100 Hz with the default joint speed limit:
/// prints its minima under `label`, asserts it passes and that no leg nears a singularity.
fn assert_preflight_passes(motion: &impl Motion, period_s: f32, label: &str) {
    let report = preflight::check(
        motion,
        &Sweep::new(0.0, period_s, 100.0).unwrap(),
        [preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3],
    )
    .unwrap();
    let (leg, ic) = report.min_inverse_condition().unwrap();
    let (_, ws) = report.min_workspace_margin().unwrap();
    let (_, jm) = report.min_joint_margin().unwrap();
    println!(
        "{label} preflight: min inverse condition {:.4} ({leg} at {:.2} s), min workspace margin {:.4} m, min joint margin {:.4} rad",
        ic.value, ic.t_s, ws.value, jm.value
    );
    assert!(report.ok(), "{:?}", report.first_failure);
    assert!(ic.value > SINGULARITY_THRESHOLD);
}

fn check_sway(axis: Axis) {
    let sway = Sway::new(SwayParams::seed001(axis)).unwrap();
    let period = sway.period_s().unwrap();
    assert_eq!(period, 20.0);
    let fixed = sway.params().feet_in_world;
    let n = (period / DT_S) as u32 + 1;
    let (mut worst_periodic, mut worst_foot) = (0.0f32, 0.0f64);
    for k in 0..n {
        let t = k as f32 * DT_S;
        let (feet, q, frame) = solved_feet(&sway, t);
        let (_, q_next, _) = solved_feet(&sway, t + period);
        worst_periodic = worst_periodic.max(max_abs_diff(&q, &q_next));
        assert_eq!(frame.contact, [Contact::Stance; 4]);
        // Eq. 6 / eq. 8 directly.
        let angle = 0.2 * (2.0 * PI * t as f64 / 20.0).sin();
        let got = match axis {
            Axis::Roll => frame.pose.roll_rad,
            Axis::Pitch => frame.pose.pitch_rad,
            Axis::Yaw => frame.pose.yaw_rad,
        };
        assert!((got as f64 - angle).abs() < 1e-6, "t={t}: {got} vs {angle}");
        for l in LegId::ALL {
            let f = fixed[l.index()];
            worst_foot =
                worst_foot.max(dist(feet[l.index()], [f.x as f64, f.y as f64, f.z as f64]));
        }
    }
    println!(
        "seed 001 {} sway: max |q(t) − q(t+T)| = {worst_periodic:.2e} rad, max foot drift = {worst_foot:.2e} m",
        axis.name()
    );
    assert!(worst_periodic < PERIODIC_TOL_RAD, "{worst_periodic}");
    assert!(worst_foot <= FOOT_TOL_M, "{worst_foot}");

    assert_preflight_passes(&sway, period, &format!("seed 001 {} sway", axis.name()));
}

#[test]
fn seed001_roll_sway_eq6_periodic_feet_fixed_not_singular() {
    check_sway(Axis::Roll);
}

#[test]
fn seed001_pitch_sway_eq8_periodic_feet_fixed_not_singular() {
    check_sway(Axis::Pitch);
}

// ---------------------------------------------------------------------------------------------
// Eq. 9–11, transcribed literally in f64 (the oracle), with the corrections as options.

fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// `(a) mod (b)` as Mathematica's `Mod` (floored, result in `[0, b)`).
fn floored_mod(a: f64, b: f64) -> f64 {
    a.rem_euclid(b)
}

/// `(a) mod (b)` as C's `fmod` / Rust's `%` (truncated, takes the sign of `a`).
fn truncated_mod(a: f64, b: f64) -> f64 {
    a % b
}

/// Eq. 11 as printed, with the given `mod`.
fn delta13(t: f64, t1: f64, m: fn(f64, f64) -> f64) -> f64 {
    (sgn((2.0 * PI * t / t1).sin()) + 1.0) * m(t, t1) + (t + t1 / 2.0 - m(t - t1 / 2.0, t1))
}

fn delta24(t: f64, t1: f64, m: fn(f64, f64) -> f64) -> f64 {
    (sgn((2.0 * PI * t / t1 - PI).sin()) + 1.0) * m(t + t1 / 2.0, t1) + (t - m(t - t1, t1))
}

/// Seed 001's hip offsets ρ of legs 1..4 = FL, FR, RR, RL.
const RHO: [(f64, f64); 4] = [(0.5, 0.25), (0.5, -0.25), (-0.5, -0.25), (-0.5, 0.25)];
const OMEGA: f64 = 0.085;
const T1: f64 = 6.0;
const H_K: f64 = 0.3;

/// Our leg of seed 001's leg `i` (1-based).
fn leg_of(i: usize) -> LegId {
    [LegId::FL, LegId::FR, LegId::RR, LegId::RL][i - 1]
}

/// Eq. 10 as printed: `(ρ·sin(ωΔ + α), −ρ·cos(ωΔ + α))` with `α = arctan(ρy/ρx)`.
fn eq10_literal_xy(i: usize, t: f64) -> (f64, f64) {
    let (px, py) = RHO[i - 1];
    let rho = (px * px + py * py).sqrt();
    let alpha = (py / px).atan();
    let d = if i % 2 == 1 {
        delta13(t, T1, floored_mod)
    } else {
        delta24(t, T1, floored_mod)
    };
    (
        rho * (OMEGA * d + alpha).sin(),
        -rho * (OMEGA * d + alpha).cos(),
    )
}

/// Eq. 10 corrected: `ρ·(cos(α − ωΔ), sin(α − ωΔ))` with `α = atan2(ρy, ρx)`, and the
/// half-wave lift above the ground `z = −H`.
fn eq10_corrected(i: usize, t: f64, stance_height: f64) -> [f64; 3] {
    let (px, py) = RHO[i - 1];
    let rho = (px * px + py * py).sqrt();
    let alpha = py.atan2(px);
    let (d, wave) = if i % 2 == 1 {
        (delta13(t, T1, floored_mod), (2.0 * PI * t / T1).sin())
    } else {
        (delta24(t, T1, floored_mod), (2.0 * PI * t / T1 - PI).sin())
    };
    let z = 0.5 * (sgn(wave) + 1.0) * H_K * wave;
    let a = alpha - OMEGA * d;
    [rho * a.cos(), rho * a.sin(), z - stance_height]
}

#[test]
fn eq11_deltas_as_printed_are_right_with_a_floored_mod() {
    // Δ13 ramps at twice the time rate while (1, 3) swing and holds while they stand; Δ24 the
    // same half a period later. Both advance by exactly T1 per period.
    for k in 0..3 {
        for j in 1..100 {
            let tau = j as f64 * T1 / 100.0;
            if (tau - T1 / 2.0).abs() < 1e-9 {
                continue; // sgn(sin) = 0 at the switch; see the next test
            }
            let t = k as f64 * T1 + tau;
            let (e13, e24) = if tau < T1 / 2.0 {
                (2.0 * tau, 0.0)
            } else {
                (T1, 2.0 * (tau - T1 / 2.0))
            };
            let want13 = k as f64 * T1 + e13;
            let want24 = k as f64 * T1 + e24;
            assert!((delta13(t, T1, floored_mod) - want13).abs() < 1e-9, "t={t}");
            assert!((delta24(t, T1, floored_mod) - want24).abs() < 1e-9, "t={t}");
        }
    }
    // And the f32 implementation agrees.
    let turn = YawTurn::new(YawTurnParams::seed001()).unwrap();
    for j in 0..600 {
        let t = j as f32 * 0.03 + 0.001;
        let (d13, d24) = turn.deltas_in_period_s(t);
        let k = (t as f64 / T1).floor() * T1;
        assert!((d13 as f64 + k - delta13(t as f64, T1, floored_mod)).abs() < 1e-4);
        assert!((d24 as f64 + k - delta24(t as f64, T1, floored_mod)).abs() < 1e-4);
    }
}

#[test]
fn erratum_eq11_truncated_mod_and_sgn_zero_break_the_deltas() {
    // A C-style fmod (sign of the dividend) makes Δ13 start at T1 instead of 0 during the
    // first half period: the swing foot would jump at t = 0⁺.
    let t = 0.1;
    assert!((delta13(t, T1, floored_mod) - 0.2).abs() < 1e-12);
    assert!((delta13(t, T1, truncated_mod) - (0.2 + T1)).abs() < 1e-12);
    // At the switching instant t = T1/2 the exact sgn(sin π) = 0 gives an isolated outlier
    // Δ13 = 1.5·T1 between the one-sided limits T1 and T1.
    let at_switch = 1.0 * (T1 / 2.0) + (T1 / 2.0 + T1 / 2.0 - floored_mod(0.0, T1)); // sgn + 1 = 1
    assert_eq!(at_switch, 1.5 * T1);
    assert!((delta13(T1 / 2.0 - 1e-9, T1, floored_mod) - T1).abs() < 1e-6);
    assert!((delta13(T1 / 2.0 + 1e-9, T1, floored_mod) - T1).abs() < 1e-6);
    // In floating point sin(π) is not 0 but its sign picks one side at random: f64 evaluates
    // Δ24 at t = T1 as 2·T1 (sin(2π − π) = +1.2e-16), a one-sample jump of ω·T1 in the foot.
    assert!((delta24(T1 - 1e-9, T1, floored_mod) - T1).abs() < 1e-6);
    assert!((delta24(T1 + 1e-9, T1, floored_mod) - T1).abs() < 1e-6);
    assert_eq!(delta24(T1, T1, floored_mod), 2.0 * T1);
}

#[test]
fn erratum_eq10_arctan_puts_the_rear_legs_on_the_front_legs() {
    // α = arctan(ρy/ρx) gives leg 3 (RR) the angle of leg 1 (FL) and leg 4 (RL) that of leg 2.
    let at = |i: usize| {
        let (px, py) = RHO[i - 1];
        ((py / px).atan(), py.atan2(px))
    };
    assert_eq!(at(1).0, at(3).0);
    assert_eq!(at(2).0, at(4).0);
    assert!((at(3).1 - (at(1).1 - PI)).abs() < 1e-12);
    assert!((at(4).1 - (PI - at(1).1)).abs() < 1e-12);
}

#[test]
fn erratum_eq10_printed_form_starts_a_quarter_turn_off() {
    // At t = 0 (Δ = 0) the printed (ρ sin α, −ρ cos α) puts leg 1 at (0.25, −0.5), not at its
    // stance point (0.5, 0.25): the polar angle is α − π/2.
    let (x, y) = eq10_literal_xy(1, 0.0);
    assert!(
        (x - 0.25).abs() < 1e-12 && (y + 0.5).abs() < 1e-12,
        "({x}, {y})"
    );
    let c = eq10_corrected(1, 0.0, 0.0);
    assert!((c[0] - 0.5).abs() < 1e-12 && (c[1] - 0.25).abs() < 1e-12);
}

#[test]
fn erratum_eq10_printed_form_turns_the_feet_against_the_body() {
    // ψ = ψ0 − ω t turns the body clockwise, while the printed angle ωΔ + α grows: after one
    // step period the feet have turned +ωT1 and the body −ωT1, so relative to the body the feet
    // drift by 2ωT1 per period and the leg angles cannot be periodic. The corrected α − ωΔ keeps
    // each foot at its place relative to the body after every period.
    for i in 1..=4 {
        let (x0, y0) = eq10_literal_xy(i, 0.0);
        // (Just after T1: exactly at T1 eq. 11 has an outlier, see above.)
        let (x1, y1) = eq10_literal_xy(i, T1 + 1e-9);
        let turned = (y1.atan2(x1) - y0.atan2(x0) + PI).rem_euclid(2.0 * PI) - PI;
        assert!((turned - OMEGA * T1).abs() < 1e-8, "leg {i}: {turned}");
        let c0 = eq10_corrected(i, 0.0, 0.0);
        let c1 = eq10_corrected(i, T1 + 1e-9, 0.0);
        let turned = (c1[1].atan2(c1[0]) - c0[1].atan2(c0[0]) + PI).rem_euclid(2.0 * PI) - PI;
        assert!((turned + OMEGA * T1).abs() < 1e-8, "leg {i}: {turned}");
    }
}

#[test]
fn seed001_yaw_turn_eq9_11_stance_fixed_swing_on_eq10_periodic_not_singular() {
    let turn = YawTurn::new(YawTurnParams::seed001()).unwrap();
    let stance_height = -turn.params().stance_feet[0].z as f64;
    assert!((stance_height - 0.9294).abs() < 1e-4);
    // Leg numbering and radii.
    for i in 1..=4 {
        let l = leg_of(i);
        let (px, py) = RHO[i - 1];
        assert!((turn.rho_m()[l.index()] as f64 - (px * px + py * py).sqrt()).abs() < 1e-6);
        assert!((turn.alpha_rad()[l.index()] as f64 - py.atan2(px)).abs() < 1e-6);
        assert_eq!(laws::in_pair_13(l), i % 2 == 1);
    }
    let period = turn.period_s().unwrap();
    assert_eq!(period, 6.0);
    let span = 3.0 * period;
    let n = (span / DT_S) as u32;
    let mut stance_start: [Option<Vec3>; 4] = [None; 4];
    let (mut worst_drift, mut worst_swing, mut worst_periodic) = (0.0f64, 0.0f64, 0.0f32);
    let (mut swing_samples, mut stance_samples) = (0u32, 0u32);
    for k in 0..n {
        let t = k as f32 * DT_S;
        let (feet, q, frame) = solved_feet(&turn, t);
        // Eq. 9.
        let psi = -OMEGA * t as f64;
        let dpsi = (frame.pose.yaw_rad as f64 - psi).rem_euclid(2.0 * PI);
        assert!(
            dpsi.min(2.0 * PI - dpsi) < 2e-6,
            "t={t}: yaw {}",
            frame.pose.yaw_rad
        );
        if t + period < span {
            let (_, q_next, _) = solved_feet(&turn, t + period);
            worst_periodic = worst_periodic.max(max_abs_diff(&q, &q_next));
        }
        for i in 1..=4 {
            let l = leg_of(i);
            let f = feet[l.index()];
            match frame.contact[l.index()] {
                Contact::Stance => {
                    stance_samples += 1;
                    let start = *stance_start[l.index()].get_or_insert(f);
                    worst_drift =
                        worst_drift.max(dist(f, [start.x as f64, start.y as f64, start.z as f64]));
                    // A stance foot stands on the ground.
                    assert!((f.z as f64 + stance_height).abs() < FOOT_TOL_M);
                    let want = eq10_corrected(i, t as f64, stance_height);
                    worst_swing = worst_swing.max(dist(f, want));
                }
                Contact::Swing => {
                    swing_samples += 1;
                    stance_start[l.index()] = None;
                    let want = eq10_corrected(i, t as f64, stance_height);
                    worst_swing = worst_swing.max(dist(f, want));
                }
            }
        }
    }
    println!(
        "seed 001 yaw turn: max |q(t) − q(t+T1)| = {worst_periodic:.2e} rad, stance drift {worst_drift:.2e} m, max |foot − eq. 10| {worst_swing:.2e} m ({swing_samples} swing, {stance_samples} stance samples)"
    );
    assert!(swing_samples > 1000 && stance_samples > 1000);
    assert!(worst_periodic < PERIODIC_TOL_RAD, "{worst_periodic}");
    assert!(worst_drift <= FOOT_TOL_M, "{worst_drift}");
    assert!(worst_swing <= FOOT_TOL_M, "{worst_swing}");

    assert_preflight_passes(&turn, period, "seed 001 yaw turn");
}

#[test]
fn yaw_turn_swing_moves_twice_as_fast_as_the_body_and_lands_where_the_body_will_be() {
    let turn = YawTurn::new(YawTurnParams::seed001()).unwrap();
    let t1 = 6.0f32;
    // FL lifts at 0 and lands at T1/2, ω·T1 further along its circle; the body has turned only
    // ω·T1/2 by then, and catches up by the end of the period.
    let a = |t: f32| {
        let f = turn.frame::<DefaultMath>(t).unwrap().feet_in_world[LegId::FL.index()];
        (f.y as f64).atan2(f.x as f64)
    };
    let alpha1 = 0.25f64.atan2(0.5);
    assert!((a(0.0) - alpha1).abs() < 1e-6);
    assert!((a(0.5 * t1) - (alpha1 - OMEGA * T1)).abs() < 1e-5);
    assert!((a(0.99 * t1) - (alpha1 - OMEGA * T1)).abs() < 1e-5);
    // Apex at T1/4, h_K above the ground.
    let f = turn.frame::<DefaultMath>(0.25 * t1).unwrap();
    let ground = turn.params().stance_feet[0].z;
    assert!((f.feet_in_world[LegId::FL.index()].z - ground - 0.3).abs() < 1e-6);
    assert!((f.feet_in_world[LegId::FR.index()].z - ground).abs() < 1e-7);
    assert_eq!(f.contact[LegId::RR.index()], Contact::Swing);
    assert_eq!(f.contact[LegId::RL.index()], Contact::Stance);
}

#[test]
fn yaw_turn_far_in_time_stays_periodic_relative_to_the_body() {
    // One hour in: ψ ≈ −306 rad; the angles still repeat those of the first period.
    let turn = YawTurn::new(YawTurnParams::seed001()).unwrap();
    let k = 600.0f32; // 600 periods = 3600 s
    let mut worst = 0.0f32;
    for j in 0..60 {
        let tau = j as f32 * 0.1 + 0.013;
        let (_, q0, _) = solved_feet(&turn, tau);
        let (_, q1, _) = solved_feet(&turn, k * 6.0 + tau);
        worst = worst.max(max_abs_diff(&q0, &q1));
    }
    println!("yaw turn after 3600 s: max angle difference to the first period {worst:.2e} rad");
    assert!(worst < 1e-3, "{worst}");
}

#[test]
fn bad_parameters_are_named() {
    use kin_core::motion::Error;
    let mut p = YawTurnParams::seed001();
    p.step_period_s = -6.0;
    assert_eq!(YawTurn::new(p), Err(Error::NotPositive(Param::StepPeriodS)));
    let mut p = YawTurnParams::seed001();
    p.yaw_rate_rad_s = f32::NAN;
    assert_eq!(YawTurn::new(p), Err(Error::NonFinite(Param::YawRateRadS)));
    let mut p = YawTurnParams::seed001();
    p.lift_height_m = 1.0;
    assert!(matches!(
        YawTurn::new(p),
        Err(Error::OutOfRange {
            parameter: Param::LiftHeightM,
            ..
        })
    ));
    let mut p = YawTurnParams::seed001();
    p.lift_height_m = 0.8; // below the hips, but the leg cannot fold that far
    assert!(matches!(
        YawTurn::new(p),
        Err(Error::BeyondReach {
            parameter: Param::LiftHeightM,
            ..
        })
    ));
    let mut p = SwayParams::seed001(Axis::Roll);
    p.period_s = 0.0;
    assert_eq!(Sway::new(p), Err(Error::NotPositive(Param::PeriodS)));
    let mut p = SwayParams::seed001(Axis::Roll);
    p.amplitude_rad = 1.2;
    assert!(matches!(
        Sway::new(p),
        Err(Error::BeyondReach {
            parameter: Param::AmplitudeRad,
            ..
        })
    ));
    let sway = Sway::new(SwayParams::seed001(Axis::Pitch)).unwrap();
    assert_eq!(
        sway.frame::<DefaultMath>(f32::NAN),
        Err(Error::NonFinite(Param::TS))
    );
}
