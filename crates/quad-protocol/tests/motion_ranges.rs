//! The ranges of the motion requests' numbers (`quad_protocol::range`): every field of
//! `StartMotion`, `SetVelocity` and `SetJointSpeedLimit` at its extremes — ±0, the smallest
//! subnormals, ±1e30, ±∞, NaN, the next float beyond each bound, the bounds themselves — gets
//! the nack the documented table gives, on both preset robots.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::Robot;
use quad_protocol::range::{self, reach_limit_m, ParamRange, Ranges, MIN_STANCE_HEIGHT_M};
use quad_protocol::{
    check_request, LegSet, MotionCommand, MotionParam, NackReason, ParamProblem as Problem, Request,
};
use seeded_rng::SplitMix64;
use std::f32::consts::{FRAC_PI_2, PI};

const ROBOTS: [Robot; 2] = [Robot::shahriar2023(), Robot::fernando2025()];

/// How a field's admissible values are documented (docs/protocol.md, "Motion field ranges").
#[derive(Debug, Clone, Copy)]
enum Kind {
    /// `[−max, max]`.
    Signed,
    /// `[min, max]`, `min > 0`; ≤ 0 is `NotPositive`.
    Positive,
    /// `[0, max]`; < 0 is `Negative`.
    NonNegative,
    /// `[min, max]`; outside is `OutOfRange` whatever the sign.
    Interval,
}

/// One numeric field: its parameter, its documented range, and the request that carries a
/// value in it (the other fields valid).
struct FieldCase {
    param: MotionParam,
    kind: Kind,
    min: f32,
    max: f32,
    request: fn(f32) -> Request,
}

fn sway(amplitude_rad: f32, period_s: f32, duration_s: Option<f32>) -> Request {
    Request::StartMotion(MotionCommand::Sway {
        axis: Axis::Roll,
        amplitude_rad,
        period_s,
        duration_s,
    })
}

fn yaw_turn(yaw_rate_rad_s: f32, step_period_s: f32, lift: f32, d: Option<f32>) -> Request {
    Request::StartMotion(MotionCommand::YawTurn {
        yaw_rate_rad_s,
        step_period_s,
        lift_height_m: lift,
        duration_s: d,
    })
}

fn foot_path(stride_m: f32, step_m: f32, duty: f32, cycle_s: f32, d: Option<f32>) -> Request {
    Request::StartMotion(MotionCommand::FootPath {
        path: PathKind::Ellipse,
        legs: LegSet::All,
        stride_m,
        step_height_m: step_m,
        duty_factor: duty,
        cycle_s,
        duration_s: d,
    })
}

fn walk(body_height_m: f32, step_height_m: f32, cycle_s: f32, timeout_ms: u16) -> Request {
    Request::StartMotion(MotionCommand::Walk {
        gait: Pattern::Trot,
        body_height_m,
        step_height_m,
        cycle_s,
        velocity_timeout_ms: timeout_ms,
    })
}

fn velocity(forward_m_s: f32, lateral_m_s: f32, yaw_rate_rad_s: f32) -> Request {
    Request::SetVelocity {
        forward_m_s,
        lateral_m_s,
        yaw_rate_rad_s,
    }
}

/// Every numeric field of the motion requests, with the range docs/protocol.md states for
/// `robot` (the lengths are bounded by its reach limit).
fn fields(robot: &Robot) -> Vec<FieldCase> {
    use MotionParam as P;
    let reach = reach_limit_m(robot);
    let f = |param, kind, min, max, request| FieldCase {
        param,
        kind,
        min,
        max,
        request,
    };
    vec![
        f(P::AmplitudeRad, Kind::Signed, -FRAC_PI_2, FRAC_PI_2, |v| {
            sway(v, 4.0, Some(4.0))
        }),
        f(P::PeriodS, Kind::Positive, 0.1, 60.0, |v| {
            sway(0.1, v, Some(4.0))
        }),
        f(P::DurationS, Kind::Positive, 0.02, 3600.0, |v| {
            sway(0.1, 4.0, Some(v))
        }),
        f(P::YawRateRadS, Kind::Signed, -PI, PI, |v| {
            yaw_turn(v, 2.0, 0.03, None)
        }),
        f(P::StepPeriodS, Kind::Positive, 0.1, 60.0, |v| {
            yaw_turn(0.1, v, 0.03, None)
        }),
        f(P::LiftHeightM, Kind::NonNegative, 0.0, reach, |v| {
            yaw_turn(0.1, 2.0, v, None)
        }),
        f(P::DurationS, Kind::Positive, 0.02, 3600.0, |v| {
            yaw_turn(0.1, 2.0, 0.03, Some(v))
        }),
        f(P::StrideM, Kind::NonNegative, 0.0, reach, |v| {
            foot_path(v, 0.02, 0.5, 2.0, None)
        }),
        f(P::StepHeightM, Kind::NonNegative, 0.0, reach, |v| {
            foot_path(0.05, v, 0.5, 2.0, None)
        }),
        f(P::DutyFactor, Kind::Interval, 0.05, 0.95, |v| {
            foot_path(0.05, 0.02, v, 2.0, None)
        }),
        f(P::CycleS, Kind::Positive, 0.1, 60.0, |v| {
            foot_path(0.05, 0.02, 0.5, v, None)
        }),
        f(P::DurationS, Kind::Positive, 0.02, 3600.0, |v| {
            foot_path(0.05, 0.02, 0.5, 2.0, Some(v))
        }),
        f(
            P::BodyHeightM,
            Kind::Positive,
            MIN_STANCE_HEIGHT_M,
            reach,
            |v| walk(v, 0.03, 0.8, 500),
        ),
        f(P::StepHeightM, Kind::NonNegative, 0.0, reach, |v| {
            walk(0.25, v, 0.8, 500)
        }),
        f(P::CycleS, Kind::Positive, 0.1, 60.0, |v| {
            walk(0.25, 0.03, v, 500)
        }),
        f(P::ForwardMS, Kind::Signed, -10.0, 10.0, |v| {
            velocity(v, 0.0, 0.0)
        }),
        f(P::LateralMS, Kind::Signed, -10.0, 10.0, |v| {
            velocity(0.0, v, 0.0)
        }),
        f(P::YawRateRadS, Kind::Signed, -PI, PI, |v| {
            velocity(0.0, 0.0, v)
        }),
        f(
            P::JointSpeedLimitRadS,
            Kind::Positive,
            0.1,
            PI / 0.02,
            |v| Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s: v,
            },
        ),
    ]
}

/// The smallest positive subnormal.
const SUBNORMAL: f32 = f32::from_bits(1);

/// The next float above a finite `v`.
fn next_up(v: f32) -> f32 {
    if v == 0.0 {
        SUBNORMAL
    } else if v > 0.0 {
        f32::from_bits(v.to_bits() + 1)
    } else {
        f32::from_bits(v.to_bits() - 1)
    }
}

/// The next float below a finite `v`.
fn next_down(v: f32) -> f32 {
    -next_up(-v)
}

/// The extremes every field is sent at: its bounds, the next float beyond each, and the
/// values no field admits or every field must name.
fn extremes(c: &FieldCase) -> Vec<f32> {
    vec![
        0.0,
        -0.0,
        SUBNORMAL,
        -SUBNORMAL,
        1e30,
        -1e30,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        c.min,
        c.max,
        next_down(c.min),
        next_up(c.max),
    ]
}

/// What the documented table gives for `v`, by the float comparisons.
fn documented(c: &FieldCase, v: f32) -> Result<(), NackReason> {
    let problem = if !v.is_finite() {
        Problem::NonFinite
    } else if (c.min..=c.max).contains(&v) {
        return Ok(());
    } else if v > c.max {
        Problem::OutOfRange
    } else {
        match c.kind {
            Kind::Positive if v <= 0.0 => Problem::NotPositive,
            Kind::NonNegative => Problem::Negative,
            Kind::Signed | Kind::Positive | Kind::Interval => Problem::OutOfRange,
        }
    };
    Err(NackReason::InvalidParameter {
        param: c.param,
        problem,
    })
}

#[test]
fn the_valid_requests_of_the_cases_pass() {
    for robot in &ROBOTS {
        for c in fields(robot) {
            let mid = if c.min > 0.0 { c.min } else { 0.5 * c.max };
            let r = (c.request)(mid);
            assert_eq!(check_request(&r, robot), Ok(()), "{r:?}");
        }
    }
}

#[test]
fn every_field_at_its_extremes_gets_the_documented_nack() {
    let mut refused = 0;
    for robot in &ROBOTS {
        for c in fields(robot) {
            for v in extremes(&c) {
                let request = (c.request)(v);
                let want = documented(&c, v);
                assert_eq!(check_request(&request, robot), want, "{request:?}");
                refused += usize::from(want.is_err());
            }
        }
    }
    // Per field: ±∞, two NaNs, ±1e30 on one side at least, the two floats beyond the bounds.
    assert!(refused >= 2 * 19 * 7, "{refused}");
}

#[test]
fn the_bounds_are_admitted_and_the_next_floats_beyond_them_are_not() {
    for robot in &ROBOTS {
        for c in fields(robot) {
            for v in [c.min, c.max] {
                assert_eq!(
                    check_request(&(c.request)(v), robot),
                    Ok(()),
                    "{:?} {v}",
                    c.param
                );
            }
            for v in [next_down(c.min), next_up(c.max)] {
                assert!(
                    check_request(&(c.request)(v), robot).is_err(),
                    "{:?} {v:e}",
                    c.param
                );
            }
        }
    }
}

#[test]
fn the_constants_are_the_documented_ranges() {
    let robot = Robot::shahriar2023();
    let ranges = Ranges::of(&robot);
    for c in fields(&robot) {
        let r = range::param_range(c.param, &ranges).expect("a numeric field");
        assert_eq!((r.min, r.max), (c.min, c.max), "{:?}", c.param);
    }
    for p in [
        MotionParam::Path,
        MotionParam::Velocity,
        MotionParam::Stance,
        MotionParam::VelocityTimeoutMs,
    ] {
        assert_eq!(range::param_range(p, &ranges), None);
    }
}

/// Issue 28: a sway of ±1e30 or 1e6 rad was acked by the firmware (3 rad refused only by a
/// servo's travel) while the host's maths refused it; now both refuse it by its range.
#[test]
fn regression_a_huge_sway_amplitude_is_out_of_range() {
    for a in [1e30, -1e30, 1e6, 3.0, -1.6] {
        assert_eq!(
            check_request(&sway(a, 4.0, None), &Robot::shahriar2023()),
            Err(NackReason::InvalidParameter {
                param: MotionParam::AmplitudeRad,
                problem: Problem::OutOfRange,
            }),
            "{a}"
        );
    }
}

/// Issue 28: a joint-speed limit of 1e-45 rad/s ("finite and > 0") was accepted and froze
/// the outputs (its step per frame rounds to 0).
#[test]
fn regression_a_subnormal_joint_speed_limit_is_out_of_range() {
    let limit = |v| Request::SetJointSpeedLimit {
        joint_speed_limit_rad_s: v,
    };
    let out = |problem| {
        Err(NackReason::InvalidParameter {
            param: MotionParam::JointSpeedLimitRadS,
            problem,
        })
    };
    let robot = Robot::fernando2025();
    assert_eq!(
        check_request(&limit(1e-45), &robot),
        out(Problem::OutOfRange)
    );
    assert_eq!(
        check_request(&limit(0.05), &robot),
        out(Problem::OutOfRange)
    );
    assert_eq!(
        check_request(&limit(-0.0), &robot),
        out(Problem::NotPositive)
    );
    assert_eq!(check_request(&limit(3.0), &robot), Ok(()));
    assert_eq!(check_request(&limit(100.0), &robot), Ok(()));
}

#[test]
fn the_walk_timeout_must_be_positive() {
    let robot = Robot::shahriar2023();
    assert_eq!(
        check_request(&walk(0.25, 0.03, 0.8, 0), &robot),
        Err(NackReason::InvalidParameter {
            param: MotionParam::VelocityTimeoutMs,
            problem: Problem::NotPositive,
        })
    );
    for ms in [1, u16::MAX] {
        assert_eq!(check_request(&walk(0.25, 0.03, 0.8, ms), &robot), Ok(()));
    }
}

#[test]
fn the_first_field_refused_in_declaration_order_is_named() {
    let robot = Robot::shahriar2023();
    let named = |r: Request| match check_request(&r, &robot) {
        Err(NackReason::InvalidParameter { param, .. }) => param,
        other => panic!("{r:?}: {other:?}"),
    };
    assert_eq!(
        named(sway(f32::NAN, -1.0, Some(0.0))),
        MotionParam::AmplitudeRad
    );
    assert_eq!(named(sway(0.1, -1.0, Some(0.0))), MotionParam::PeriodS);
    assert_eq!(
        named(foot_path(-1.0, 9.0, 2.0, 0.0, None)),
        MotionParam::StrideM
    );
    assert_eq!(named(walk(0.0, -1.0, 0.0, 0)), MotionParam::BodyHeightM);
    assert_eq!(
        named(walk(0.25, 0.03, 0.8, 0)),
        MotionParam::VelocityTimeoutMs
    );
    assert_eq!(named(velocity(0.0, 11.0, 4.0)), MotionParam::LateralMS);
    // The requests without numbers pass.
    for r in [
        Request::StartMotion(MotionCommand::StandUp),
        Request::StartMotion(MotionCommand::Sit),
        Request::StartMotion(MotionCommand::Rest),
        Request::StopMotion,
        Request::GetMotion,
    ] {
        assert_eq!(check_request(&r, &robot), Ok(()));
    }
}

/// The check compares bits: the same answer as the float comparisons of the table for any
/// bit pattern of the value, on any range of each kind.
#[test]
fn the_bitwise_check_is_the_float_comparison_for_every_pattern() {
    let mut rng = SplitMix64::new(28);
    let mut any = || f32::from_bits(rng.next_u64() as u32);
    for _ in 0..20_000 {
        let (a, b) = (any().abs(), any().abs());
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        let (lo, hi) = (a.min(b), a.max(b));
        let cases = [
            (Kind::Signed, ParamRange::symmetric(hi), -hi, hi),
            (
                Kind::Positive,
                ParamRange::positive(lo.max(SUBNORMAL), hi),
                lo.max(SUBNORMAL),
                hi,
            ),
            (Kind::NonNegative, ParamRange::non_negative(hi), 0.0, hi),
            (Kind::Interval, ParamRange::interval(lo, hi), lo, hi),
        ];
        for (kind, r, min, max) in cases {
            let c = FieldCase {
                param: MotionParam::Other,
                kind,
                min,
                max,
                request: |_| Request::GetState,
            };
            for v in [
                any(),
                lo,
                hi,
                -lo,
                -hi,
                next_down(lo),
                next_up(hi),
                0.0,
                -0.0,
            ] {
                let want = documented(&c, v).map_err(|e| match e {
                    NackReason::InvalidParameter { problem, .. } => problem,
                    other => panic!("{other:?}"),
                });
                assert_eq!(r.check(v), want, "{kind:?} [{min:e}, {max:e}] {v:e}");
            }
        }
    }
}
