//! What the host expects of an answer: the angles it solves itself or the nack the device must
//! give ([`expected`]), the judgement of an answer ([`judge`]) and of a readback
//! ([`check_readback`]), and how angles are compared ([`AngleCheck`]).

use super::{answer_name, Verdict};
use crate::link;
use kin_core::body;
use kin_core::{BodyConfig, Pose, ReachPolicy, Robot, Vec3};
use quad_protocol::servo::Calibration;
use quad_protocol::{DeviceToHost, Flags, NackReason, PoseConfig, Readback, ServoId};

/// Bound on |device angle − host angle| for the ATmega2560 firmware, whose math backend
/// (`avr_libc_math::AvrFast`: avr-libc `sqrt`, kin-core's fixed-point `atan2` and `sin_cos`
/// kernels) differs from the host's, rad: the backend's documented worst case (about 4e-6 rad
/// per angle) with margin. Measured in the emulator tests (`tests/tests/avr_firmware.rs`,
/// `angle_tolerance_bounds_the_firmware_against_the_host`): 4.8e-6 rad over 100 seeded poses.
/// 2e-5 rad is 0.001°, far below a servo's resolution (about 0.1° per 0.5 µs tick).
pub const AVR_ANGLE_TOLERANCE_RAD: f32 = 2e-5;

/// How the device's angles are compared with the host's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AngleCheck {
    /// The same bits (both sides run the same kin-core math backend).
    Exact,
    /// |device − host| ≤ the bound, rad.
    Within(f32),
}

impl AngleCheck {
    /// The check that suits `target`: the same bits for the simulated controller (the host's
    /// math), [`AVR_ANGLE_TOLERANCE_RAD`] for the ATmega2560's.
    pub fn for_target(target: &link::Target) -> AngleCheck {
        if target.runs_host_math() {
            AngleCheck::Exact
        } else {
            AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD)
        }
    }
}

/// The host's expectation for one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expected {
    /// An ack with these angles.
    Angles([f32; 12]),
    /// A nack with this reason.
    Nack(NackReason),
}

/// Why a pose's answer disagreed with the host (see [`super::PoseStream::send`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Mismatch {
    /// A readback angle differs from the host's beyond the [`AngleCheck`].
    #[error("{servo}: device angle {device_rad} rad, host {host_rad} rad")]
    Angle {
        /// The joint.
        servo: ServoId,
        /// The device's angle, rad.
        device_rad: f32,
        /// The host's, rad.
        host_rad: f32,
    },
    /// A readback pulse differs from the calibration's mapping of the device's angle.
    #[error(
        "{servo}: device pulse {device_half_us} half-µs, host mapping {}",
        host_pulse(host_half_us)
    )]
    Pulse {
        /// The joint.
        servo: ServoId,
        /// The device's pulse, half-µs.
        device_half_us: u16,
        /// The host's mapping, half-µs (`None`: beyond the servo's travel).
        host_half_us: Option<u16>,
    },
    /// The device acked a pose the host rejects.
    #[error("device acked, host rejects: {0}")]
    AckedHostRejects(NackReason),
    /// The device nacked a pose the host solves.
    #[error("device nacked ({0}), host solves")]
    NackedHostSolves(NackReason),
    /// Both nacked, for different reasons.
    #[error("device nacked ({device}), host rejects with {host}")]
    Reasons {
        /// The device's reason.
        device: NackReason,
        /// The host's.
        host: NackReason,
    },
    /// An answer of another kind than an ack or a nack.
    #[error("unexpected answer {}", answer_name(.0))]
    Unexpected(DeviceToHost),
}

/// The host's mapping of a pulse, for messages.
fn host_pulse(half_us: &Option<u16>) -> String {
    match half_us {
        Some(p) => format!("{p} half-µs"),
        None => "beyond the servo's travel".to_owned(),
    }
}

/// What the host makes of `pose` on a device with `pose_config` and `calibration`: after the
/// range check the device runs too (`quad_protocol::range`), the angles of kin-core's
/// `inverse_at_stance` (reject policy) when every one maps to a pulse within its servo's
/// travel, else the nack the device must answer. The check every body pose of the host passes
/// before it is sent.
pub fn expected(
    robot: &Robot,
    pose_config: &PoseConfig,
    calibration: &[Calibration; 12],
    pose: &Pose,
) -> Expected {
    if let Err(reason) = quad_protocol::range::check_pose(pose, robot) {
        return Expected::Nack(reason);
    }
    let config = BodyConfig {
        order: pose_config.order,
        pivot_m: Vec3::ZERO,
    };
    match body::Solver::new(robot).inverse_at_stance(
        pose,
        &config,
        pose_config.stance_height_m,
        ReachPolicy::Reject,
    ) {
        Err(e) => Expected::Nack(e.into()),
        Ok(solution) => expected_angles(calibration, solution.flat()),
    }
}

/// `angles` through `calibration`: the angles, or the first servo out of its travel.
pub(super) fn expected_angles(calibration: &[Calibration; 12], angles: [f32; 12]) -> Expected {
    for s in ServoId::ALL {
        if let Err(fault) = calibration[s.index()].pulse_half_us(angles[s.index()]) {
            return Expected::Nack(NackReason::ServoRange {
                leg: s.leg,
                joint: s.joint,
                fault,
            });
        }
    }
    Expected::Angles(angles)
}

/// The readback check of one answer against the host's expectation: a nack must carry the
/// host's reason; an ack must pass [`check_readback`]. A `HelloRequired` nack (the device was
/// reset) is accepted so that the stream can set the session up again.
pub fn judge(
    check: AngleCheck,
    calibration: &[Calibration; 12],
    answer: &DeviceToHost,
    expected: &Expected,
) -> Verdict {
    match (answer, expected) {
        (
            DeviceToHost::Nack {
                reason: NackReason::HelloRequired,
                ..
            },
            _,
        ) => Verdict::Accept,
        (DeviceToHost::Nack { reason, .. }, Expected::Nack(want)) if reason == want => {
            Verdict::Accept
        }
        (DeviceToHost::Ack { readback, .. }, Expected::Angles(want))
            if check_readback(check, calibration, readback, want).is_ok() =>
        {
            Verdict::Accept
        }
        _ => Verdict::Reject,
    }
}

/// Compares a readback with the host's angles `want`: each angle by `check`, each pulse equal
/// to `calibration`'s mapping of the **device's** angle (0 while the outputs are off). Returns
/// the largest angle difference, rad.
///
/// # Errors
/// A description of the first disagreement.
pub fn check_readback(
    check: AngleCheck,
    calibration: &[Calibration; 12],
    rb: &Readback,
    want: &[f32; 12],
) -> Result<f32, Mismatch> {
    let mut max_err = 0.0f32;
    for (i, (&got, &w)) in rb.angles_rad.iter().zip(want).enumerate() {
        let err = (got - w).abs();
        let ok = match check {
            AngleCheck::Exact => got.to_bits() == w.to_bits(),
            AngleCheck::Within(tol) => err <= tol,
        };
        if !ok {
            return Err(Mismatch::Angle {
                servo: ServoId::ALL[i],
                device_rad: got,
                host_rad: w,
            });
        }
        max_err = max_err.max(err);
    }
    let enabled = rb.flags.contains(Flags::OUTPUTS_ENABLED);
    for (i, &p) in rb.pulses_half_us.iter().enumerate() {
        let want = if enabled {
            calibration[i].pulse_half_us(rb.angles_rad[i]).ok()
        } else {
            Some(0)
        };
        if want != Some(p) {
            return Err(Mismatch::Pulse {
                servo: ServoId::ALL[i],
                device_half_us: p,
                host_half_us: want,
            });
        }
    }
    Ok(max_err)
}
