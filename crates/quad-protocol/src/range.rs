//! The admissible range of every request field: one check, [`check_request`], that the device
//! runs on every request it reads and the host runs before sending, so that both refuse the
//! same requests with the same [`NackReason`].
//!
//! Why ranges on finite values: the IK is only meaningful, and host and device only agree, on
//! values a robot can take. Far outside them the device's fast sine/cosine kernels lose
//! accuracy (they reduce the angle in single precision) while the host's do not, and a body
//! shifted by 10³⁸ m is not a pose but a corrupted request. The limits:
//!
//! | field | admissible | refusal |
//! |---|---|---|
//! | body roll, pitch, yaw | `[−π, π]` rad | [`Field::BodyRoll`] … |
//! | body x, y, z | `|v| ≤` [`reach_limit_m`] | [`Field::BodyX`] … |
//! | foot x (y, z) in the body frame | `|v| ≤` half the body length (width, 0) + [`reach_limit_m`] | [`Field::Foot`] |
//! | joint angle | `[−π, π]` rad (the robot's joint limits then apply) | [`Field::JointAngle`] |
//! | stance height | `[`[`MIN_STANCE_HEIGHT_M`]`, reach_limit_m]` | ≤ 0: [`NackReason::InvalidArgument`]; else [`Field::StanceHeight`] |
//!
//! The lengths are bounded by twice the leg's span ([`reach_limit_m`]), not by the span itself:
//! near the edge of the reach the IK answers, naming the leg and the fault
//! ([`NackReason::Unreachable`]); the range only keeps out values that are no pose at all.
//!
//! A NaN or infinite value is [`NackReason::NonFinite`] (for the stance height
//! [`NackReason::InvalidArgument`], as in protocol 1.x); a finite value outside its range is
//! [`NackReason::OutOfRange`] naming the field. Calibrations have their own check
//! ([`crate::servo::Calibration::validate`]); the other fields (sequence numbers, flags, enum
//! indices, `timeout_ms`) admit every value their type can hold. The motion requests' parameters
//! are checked by the device's motion engine, which knows how they bound each other.

use crate::msg::{Field, NackReason, PoseConfig, Request};
use core::f32::consts::PI;
use kin_core::{Joint, LegId, Pose, Robot};

/// The lowest admissible stance height, m: below it the hips sit on the feet' level, a
/// stance no legged robot of this shape takes (the bound only has to keep absurd values such
/// as 1e-45 m out; the IK refuses what the geometry cannot reach).
pub const MIN_STANCE_HEIGHT_M: f32 = 0.01;

/// The farthest a foot can be from its hip, m: `d_lat + d_ax + femur + tibia` (the leg
/// stretched, its offsets in line — more than any real pose reaches).
pub const fn leg_span_m(robot: &Robot) -> f32 {
    let l = &robot.leg;
    l.d_lat_m + l.d_ax_m + l.femur_m + l.tibia_m
}

/// The bound of every length in a request, m: twice [`leg_span_m`] (see the module docs).
pub const fn reach_limit_m(robot: &Robot) -> f32 {
    2.0 * leg_span_m(robot)
}

/// The bounds a robot's requests are checked against (see the module docs), computed once:
/// by a `const fn`, so that a device whose robot is a constant computes them at compile time
/// and [`check_request_in`] does no arithmetic on the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranges {
    /// `|x|`, `|y|`, `|z|` bounds of a foot in the body frame, m; `[2]` is [`reach_limit_m`].
    feet_m: [f32; 3],
}

impl Ranges {
    /// The bounds for `robot`.
    pub const fn of(robot: &Robot) -> Ranges {
        let span = reach_limit_m(robot);
        Ranges {
            feet_m: [
                0.5 * robot.body_length_m + span,
                0.5 * robot.body_width_m + span,
                span,
            ],
        }
    }

    /// [`reach_limit_m`] of the robot.
    pub const fn reach_limit_m(&self) -> f32 {
        self.feet_m[2]
    }
}

/// The first of `values` whose magnitude exceeds its bound (`bounds` repeated: value `i` has
/// bound `bounds[i % bounds.len()]`), once all are finite. One loop for the pose, the feet and
/// the joints: on the ATmega2560 each unrolled comparison is a soft-float call with its
/// register moves.
///
/// # Errors
/// [`NackReason::NonFinite`] when a value is NaN or infinite.
#[inline(never)]
fn first_beyond(values: &[f32], bounds: &[f32]) -> Result<Option<usize>, NackReason> {
    if !values.iter().all(|v| v.is_finite()) {
        return Err(NackReason::NonFinite);
    }
    Ok(values
        .iter()
        .zip(bounds.iter().cycle())
        .position(|(&v, &bound)| magnitude_beyond(v, bound)))
}

/// `|v| > bound` for a finite `v`, compared by the bits where that is the same: the bits of
/// two floats without sign bit order as their values (a NaN bound without sign bit lies above
/// every finite `|v|`, and `>` against a NaN is false). An integer compare on the AVR instead
/// of a soft-float call per value; a bound with its sign bit set takes the float compare.
#[inline]
fn magnitude_beyond(v: f32, bound: f32) -> bool {
    if bound.is_sign_negative() {
        v.abs() > bound
    } else {
        v.abs().to_bits() > bound.to_bits()
    }
}

/// Checks every field of `request` for `robot` (see the module docs for the ranges).
///
/// # Errors
/// [`NackReason::NonFinite`], [`NackReason::OutOfRange`] naming the first field out of range
/// (in declaration order), or [`NackReason::InvalidArgument`] for a stance height that is not
/// positive.
pub fn check_request(request: &Request, robot: &Robot) -> Result<(), NackReason> {
    check_request_in(request, &Ranges::of(robot))
}

/// [`check_request`] with the robot's bounds computed already ([`Ranges::of`]).
///
/// # Errors
/// As [`check_request`].
pub fn check_request_in(request: &Request, ranges: &Ranges) -> Result<(), NackReason> {
    match request {
        Request::SetBodyPose(pose) => pose_in(pose, ranges),
        Request::SetFeet { feet_in_body_m } => feet_in(feet_in_body_m, ranges),
        Request::SetJoints { angles_rad } => check_joints(angles_rad),
        Request::SetPoseConfig(p) => pose_config_in(p, ranges),
        Request::Hello { .. }
        | Request::GetState
        | Request::SetOutputs { .. }
        | Request::SetLinkTimeout(_)
        | Request::SetCalibration { .. }
        | Request::GetCalibration { .. }
        | Request::SaveCalibration => Ok(()),
        // A motion's parameters depend on each other and on the robot's reach: the device's
        // motion engine checks them before the motion starts and names the parameter it
        // refuses (`NackReason::InvalidParameter`, `NackReason::Preflight`).
        Request::StartMotion(_)
        | Request::StopMotion
        | Request::GetMotion
        | Request::SetVelocity { .. }
        | Request::SetJointSpeedLimit { .. } => Ok(()),
    }
}

/// A body pose: finite, angles within `[−π, π]`, translations within [`reach_limit_m`].
///
/// # Errors
/// As [`check_request`].
pub fn check_pose(pose: &Pose, robot: &Robot) -> Result<(), NackReason> {
    pose_in(pose, &Ranges::of(robot))
}

fn pose_in(pose: &Pose, ranges: &Ranges) -> Result<(), NackReason> {
    let Pose {
        roll_rad,
        pitch_rad,
        yaw_rad,
        x_m,
        y_m,
        z_m,
    } = *pose;
    let values = [roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m];
    let span = ranges.reach_limit_m();
    // An angle in `[−π, π]` is one of magnitude ≤ π.
    let field = match first_beyond(&values, &[PI, PI, PI, span, span, span])? {
        None => return Ok(()),
        Some(0) => Field::BodyRoll,
        Some(1) => Field::BodyPitch,
        Some(2) => Field::BodyYaw,
        Some(3) => Field::BodyX,
        Some(4) => Field::BodyY,
        Some(_) => Field::BodyZ,
    };
    Err(NackReason::OutOfRange { field })
}

/// Four feet in the body frame: finite, each within the body's half size plus
/// [`reach_limit_m`] per axis.
///
/// # Errors
/// As [`check_request`].
pub fn check_feet(feet_in_body_m: &[[f32; 3]; 4], robot: &Robot) -> Result<(), NackReason> {
    feet_in(feet_in_body_m, &Ranges::of(robot))
}

fn feet_in(feet_in_body_m: &[[f32; 3]; 4], ranges: &Ranges) -> Result<(), NackReason> {
    match first_beyond(feet_in_body_m.as_flattened(), &ranges.feet_m)? {
        None => Ok(()),
        Some(i) => Err(NackReason::OutOfRange {
            field: Field::Foot(LegId::ALL[i / 3]),
        }),
    }
}

/// Twelve joint angles: finite, within `[−π, π]`.
///
/// # Errors
/// As [`check_request`].
pub fn check_joints(angles_rad: &[f32; 12]) -> Result<(), NackReason> {
    // An angle in `[−π, π]` is one of magnitude ≤ π.
    match first_beyond(angles_rad, &[PI])? {
        None => Ok(()),
        Some(i) => Err(NackReason::OutOfRange {
            field: Field::JointAngle {
                leg: LegId::ALL[i / 3],
                joint: Joint::ALL[i % 3],
            },
        }),
    }
}

/// A pose configuration: a stance height in `[MIN_STANCE_HEIGHT_M, reach_limit_m]`.
///
/// # Errors
/// As [`check_request`].
pub fn check_pose_config(p: &PoseConfig, robot: &Robot) -> Result<(), NackReason> {
    pose_config_in(p, &Ranges::of(robot))
}

fn pose_config_in(p: &PoseConfig, ranges: &Ranges) -> Result<(), NackReason> {
    let h = p.stance_height_m;
    if !(h.is_finite() && h > 0.0) {
        return Err(NackReason::InvalidArgument);
    }
    if (MIN_STANCE_HEIGHT_M..=ranges.reach_limit_m()).contains(&h) {
        Ok(())
    } else {
        Err(NackReason::OutOfRange {
            field: Field::StanceHeight,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROBOT: Robot = Robot::shahriar2023();

    /// Computed at compile time, as a device with a constant robot does.
    const RANGES: Ranges = Ranges::of(&ROBOT);

    #[test]
    fn the_bitwise_magnitude_compare_is_the_float_compare() {
        let mut rng = seeded_rng::SplitMix64::new(7);
        let special = [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            PI,
            -PI,
            1.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for case in 0..200_000 {
            let mut any = || f32::from_bits(rng.next_u64() as u32);
            let v = match case % 4 {
                0 => special[case / 4 % special.len()],
                _ => any(),
            };
            let bound = match case % 3 {
                0 => special[case / 3 % special.len()],
                1 => f32::from_bits(v.abs().to_bits().wrapping_add(case as u32 % 3) - 1),
                _ => any(),
            };
            if v.is_finite() {
                assert_eq!(
                    magnitude_beyond(v, bound),
                    v.abs() > bound,
                    "{v:e} {bound:e}"
                );
            }
        }
    }

    #[test]
    fn ranges_computed_once_check_as_the_robot_does() {
        assert_eq!(RANGES.reach_limit_m(), reach_limit_m(&ROBOT));
        let feet = [[0.0, 0.0, -RANGES.reach_limit_m() - 1e-3]; 4];
        let r = Request::SetFeet {
            feet_in_body_m: feet,
        };
        assert_eq!(check_request_in(&r, &RANGES), check_request(&r, &ROBOT));
        assert_eq!(check_request_in(&r, &RANGES), out(Field::Foot(LegId::FL)));
    }

    fn out(field: Field) -> Result<(), NackReason> {
        Err(NackReason::OutOfRange { field })
    }

    #[test]
    fn a_huge_finite_angle_is_out_of_range_not_non_finite() {
        let pose = Pose {
            yaw_rad: 1e38,
            ..Pose::default()
        };
        assert_eq!(check_pose(&pose, &ROBOT), out(Field::BodyYaw));
        let pose = Pose {
            roll_rad: f32::NAN,
            yaw_rad: 1e38,
            ..Pose::default()
        };
        assert_eq!(check_pose(&pose, &ROBOT), Err(NackReason::NonFinite));
    }

    #[test]
    fn every_pose_field_is_named() {
        let span = reach_limit_m(&ROBOT);
        let big = span * 1.01;
        let cases = [
            (
                Pose {
                    roll_rad: -3.2,
                    ..Pose::default()
                },
                Field::BodyRoll,
            ),
            (
                Pose {
                    pitch_rad: 3.2,
                    ..Pose::default()
                },
                Field::BodyPitch,
            ),
            (
                Pose {
                    yaw_rad: 4.0,
                    ..Pose::default()
                },
                Field::BodyYaw,
            ),
            (
                Pose {
                    x_m: big,
                    ..Pose::default()
                },
                Field::BodyX,
            ),
            (
                Pose {
                    y_m: -big,
                    ..Pose::default()
                },
                Field::BodyY,
            ),
            (
                Pose {
                    z_m: 3.4e38,
                    ..Pose::default()
                },
                Field::BodyZ,
            ),
        ];
        for (pose, field) in cases {
            assert_eq!(
                check_request(&Request::SetBodyPose(pose), &ROBOT),
                out(field)
            );
        }
        let edge = Pose {
            roll_rad: PI,
            pitch_rad: -PI,
            yaw_rad: PI,
            x_m: span,
            y_m: -span,
            z_m: span,
        };
        assert_eq!(check_pose(&edge, &ROBOT), Ok(()));
    }

    #[test]
    fn feet_joints_and_stance_height() {
        let mut feet = [[0.3, 0.2, -0.4]; 4];
        assert_eq!(check_feet(&feet, &ROBOT), Ok(()));
        feet[2][2] = -1e30;
        assert_eq!(check_feet(&feet, &ROBOT), out(Field::Foot(LegId::RL)));
        feet[2][2] = f32::INFINITY;
        assert_eq!(check_feet(&feet, &ROBOT), Err(NackReason::NonFinite));

        let mut q = [0.0f32; 12];
        assert_eq!(check_joints(&q), Ok(()));
        q[7] = 1e38;
        assert_eq!(
            check_joints(&q),
            out(Field::JointAngle {
                leg: LegId::RL,
                joint: Joint::Hip
            })
        );

        let p = |h| PoseConfig {
            stance_height_m: h,
            order: kin_core::RotationOrder::Zyx,
            policy: kin_core::ReachPolicy::Reject,
        };
        assert_eq!(check_pose_config(&p(0.3), &ROBOT), Ok(()));
        assert_eq!(
            check_pose_config(&p(3.4e38), &ROBOT),
            out(Field::StanceHeight)
        );
        assert_eq!(
            check_pose_config(&p(1e-45), &ROBOT),
            out(Field::StanceHeight)
        );
        for bad in [0.0, -0.5, f32::NAN] {
            assert_eq!(
                check_pose_config(&p(bad), &ROBOT),
                Err(NackReason::InvalidArgument)
            );
        }
    }
}
