//! The release firmware in simavr refuses every motion field at its extremes exactly as the
//! host's range check does (`quad_protocol::range::check_request`): each numeric field of
//! `StartMotion`, `SetVelocity` and `SetJointSpeedLimit` sent at ±0, the smallest subnormals,
//! ±1e30, ±∞, NaN and the next float beyond each of its bounds gets the host's typed nack,
//! and nothing moves — the pins keep their pulses, the readback its angles, no motion starts.
//! The host's own path ([`Session::motion`]) refuses the same requests with the same reason
//! without sending them. All times are simulated.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use quad_host::client::{self, Client, ClientConfig};
use quad_host::emu::{build, Pulse, CYCLES_PER_TICK};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink, PULSE_TOLERANCE_CYCLES};
use quad_host::ops::onboard::{self, Session};
use quad_protocol::range::{self, Ranges};
use quad_protocol::{
    check_request, LegSet, MotionCommand, MotionParam, NackReason, Request, RobotPreset,
};
use std::time::Duration;

/// The smallest positive subnormal.
const SUBNORMAL: f32 = f32::from_bits(1);

/// The longest the stand-up may take, link time.
const STAND_LIMIT: Duration = Duration::from_secs(10);

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

/// The request that carries a value in one field, the other fields valid.
type Carrier = fn(f32) -> Request;

/// Every numeric field of the motion requests: its parameter and its [`Carrier`].
fn fields() -> Vec<(MotionParam, Carrier)> {
    use MotionParam as P;
    vec![
        (P::AmplitudeRad, |v| {
            Request::StartMotion(MotionCommand::Sway {
                axis: Axis::Roll,
                amplitude_rad: v,
                period_s: 4.0,
                duration_s: None,
            })
        }),
        (P::PeriodS, |v| {
            Request::StartMotion(MotionCommand::Sway {
                axis: Axis::Pitch,
                amplitude_rad: 0.1,
                period_s: v,
                duration_s: None,
            })
        }),
        (P::DurationS, |v| {
            Request::StartMotion(MotionCommand::Sway {
                axis: Axis::Roll,
                amplitude_rad: 0.1,
                period_s: 4.0,
                duration_s: Some(v),
            })
        }),
        (P::YawRateRadS, |v| {
            Request::StartMotion(MotionCommand::YawTurn {
                yaw_rate_rad_s: v,
                step_period_s: 2.0,
                lift_height_m: 0.03,
                duration_s: None,
            })
        }),
        (P::StepPeriodS, |v| {
            Request::StartMotion(MotionCommand::YawTurn {
                yaw_rate_rad_s: 0.085,
                step_period_s: v,
                lift_height_m: 0.03,
                duration_s: None,
            })
        }),
        (P::LiftHeightM, |v| {
            Request::StartMotion(MotionCommand::YawTurn {
                yaw_rate_rad_s: 0.085,
                step_period_s: 2.0,
                lift_height_m: v,
                duration_s: None,
            })
        }),
        (P::StrideM, |v| foot_path(v, 0.02, 0.5, 2.0, None)),
        (P::StepHeightM, |v| foot_path(0.05, v, 0.5, 2.0, None)),
        (P::DutyFactor, |v| foot_path(0.05, 0.02, v, 2.0, None)),
        (P::CycleS, |v| foot_path(0.05, 0.02, 0.5, v, None)),
        (P::DurationS, |v| foot_path(0.05, 0.02, 0.5, 2.0, Some(v))),
        (P::BodyHeightM, |v| walk(v, 0.03, 0.8)),
        (P::StepHeightM, |v| walk(0.25, v, 0.8)),
        (P::CycleS, |v| walk(0.25, 0.03, v)),
        (P::ForwardMS, |v| Request::SetVelocity {
            forward_m_s: v,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
        }),
        (P::LateralMS, |v| Request::SetVelocity {
            forward_m_s: 0.0,
            lateral_m_s: v,
            yaw_rate_rad_s: 0.0,
        }),
        (P::YawRateRadS, |v| Request::SetVelocity {
            forward_m_s: 0.0,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: v,
        }),
        (P::JointSpeedLimitRadS, |v| Request::SetJointSpeedLimit {
            joint_speed_limit_rad_s: v,
        }),
    ]
}

fn foot_path(stride_m: f32, step_m: f32, duty: f32, cycle_s: f32, d: Option<f32>) -> Request {
    Request::StartMotion(MotionCommand::FootPath {
        path: PathKind::Rectangle,
        legs: LegSet::All,
        stride_m,
        step_height_m: step_m,
        duty_factor: duty,
        cycle_s,
        duration_s: d,
    })
}

fn walk(body_height_m: f32, step_height_m: f32, cycle_s: f32) -> Request {
    Request::StartMotion(MotionCommand::Walk {
        gait: Pattern::Trot,
        body_height_m,
        step_height_m,
        cycle_s,
        velocity_timeout_ms: 500,
    })
}

/// The requests of every field at its extremes that the host's range check refuses, with
/// the host's reason.
fn refused_extremes(ranges: &Ranges, robot: &kin_core::Robot) -> Vec<(Request, NackReason)> {
    let mut out = Vec::new();
    for (param, request) in fields() {
        let r = range::param_range(param, ranges).expect("a numeric field");
        let values = [
            0.0,
            -0.0,
            SUBNORMAL,
            -SUBNORMAL,
            1e30,
            -1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            next_down(r.min),
            next_up(r.max),
        ];
        for v in values {
            let request = request(v);
            if let Err(reason) = check_request(&request, robot) {
                assert!(
                    matches!(reason, NackReason::InvalidParameter { param: p, .. } if p == param),
                    "{request:?}: {reason:?}"
                );
                out.push((request, reason));
            }
        }
    }
    // The walk's timeout, an integer: 0 only.
    let zero_timeout = Request::StartMotion(MotionCommand::Walk {
        gait: Pattern::Walk,
        body_height_m: 0.25,
        step_height_m: 0.03,
        cycle_s: 0.8,
        velocity_timeout_ms: 0,
    });
    let reason = check_request(&zero_timeout, robot).expect_err("a zero timeout");
    out.push((zero_timeout, reason));
    out
}

/// Asserts that the next pulse of every pin is `pulses_half_us` wide (the readback's), within
/// one timer tick.
fn assert_pins(session: &mut Session<EmulatorLink>, pulses_half_us: &[u16; 12], when: &str) {
    let seen = session
        .client_mut()
        .link_mut()
        .next_pulses()
        .expect("the MCU runs");
    for (c, (pulse, &want)) in seen.iter().zip(pulses_half_us).enumerate() {
        let pulse: &Pulse = pulse.as_ref().expect("every output pulses");
        assert!(
            pulse.width_could_be(u64::from(want) * CYCLES_PER_TICK, PULSE_TOLERANCE_CYCLES),
            "{when}: channel {c} is {:.1} µs wide, the readback says {} half-µs",
            pulse.high_us(),
            want
        );
    }
}

#[test]
fn every_motion_field_at_its_extremes_is_refused_as_the_host_refuses_it_and_nothing_moves() {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(115_200)).unwrap_or_else(|e| panic!("{e}"));
    let client = Client::new(link, ClientConfig::emulator());
    let mut session =
        Session::connect(client, RobotPreset::Shahriar2023).unwrap_or_else(|e| panic!("{e}"));
    let robot = session.info().robot.robot().expect("a preset");
    let ranges = Ranges::of(&robot);
    session
        .start(&MotionCommand::StandUp)
        .unwrap_or_else(|e| panic!("{e}"));
    session
        .wait_idle(STAND_LIMIT, |_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let before = session.get().unwrap_or_else(|e| panic!("{e}"));
    assert_pins(&mut session, &before.readback.pulses_half_us, "before");

    let cases = refused_extremes(&ranges, &robot);
    // Every field: ±∞, two NaN signs… at least seven refused values each.
    assert!(cases.len() > 7 * fields().len(), "{} cases", cases.len());
    for (request, host) in &cases {
        // The device, sent the request as it is.
        match session.client_mut().request(*request) {
            Err(client::Error::Refused { reason, .. }) => {
                assert_eq!(reason, *host, "{request:?}");
            }
            other => panic!("{request:?}: {other:?}"),
        }
        // The host's path refuses it with the same reason, sending nothing.
        let sent = session.client_mut().counters().frames_sent;
        match session.motion(*request) {
            Err(onboard::Error::NotSent { reason, .. }) => assert_eq!(reason, *host),
            other => panic!("{request:?}: {other:?}"),
        }
        assert_eq!(session.client_mut().counters().frames_sent, sent);
    }

    // Nothing moved: no motion, the same readback, the same pulses on the pins.
    let after = session.get().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(after.status.kind, None);
    assert_eq!(after.status.fault, None);
    assert_eq!(after.readback.angles_rad, before.readback.angles_rad);
    assert_eq!(
        after.readback.pulses_half_us,
        before.readback.pulses_half_us
    );
    assert_pins(&mut session, &before.readback.pulses_half_us, "after");
    let pins = session.client_mut().link_mut().pulse_stats();
    assert_eq!(pins.errors, 0, "{:?}", pins.first_error);
}
