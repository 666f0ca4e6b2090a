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
//! ([`crate::servo::Calibration::validate`]); the other fields of the requests above (sequence
//! numbers, flags, enum indices, `timeout_ms`) admit every value their type can hold.
//!
//! ## Motion fields
//!
//! Every number of [`Request::StartMotion`], [`Request::SetVelocity`],
//! [`Request::SetJointSpeedLimit`] and [`Request::SetBalance`] has a [`ParamRange`] too, checked here before any maths and
//! refused as [`NackReason::InvalidParameter`] naming the [`MotionParam`] and its
//! [`ParamProblem`]:
//!
//! | field | admissible | why |
//! |---|---|---|
//! | sway `amplitude_rad` | [`SWAY_AMPLITUDE_RAD`]: `[−π/2, π/2]` rad | a quarter turn of the body with the feet on the ground is beyond any leg (the start check refuses far less) |
//! | `period_s`, `step_period_s`, `cycle_s` | [`PERIOD_S`]: `[0.1, 60]` s | five 50 Hz servo frames per period at least; slower than a minute is no motion to watch |
//! | `duration_s` (when given) | [`DURATION_S`]: `[0.02, 3600]` s | one servo frame at least; an hour at most, where f32 motion time still resolves 0.24 ms (longer: no duration, then `StopMotion`) |
//! | `yaw_rate_rad_s` (yaw turn, velocity) | [`YAW_RATE_RAD_S`]: `[−π, π]` rad/s | half a turn per second, beyond what a servo-driven quadruped turns |
//! | `forward_m_s`, `lateral_m_s` | [`SPEED_M_S`]: `[−10, 10]` m/s | 36 km/h, many times what a servo-driven quadruped walks; the gait's stride disc bounds the speed by the robot after this check |
//! | `lift_height_m`, `stride_m`, `step_height_m` | `[0,` [`reach_limit_m`]`]` | no foot moves farther than the reach |
//! | walk `body_height_m` | `[`[`MIN_STANCE_HEIGHT_M`]`, reach_limit_m]` | as the stance height |
//! | `duty_factor` | [`DUTY_FACTOR`]: `[0.05, 0.95]` | stance and swing each at least a twentieth of the loop |
//! | stable turn `yaw_per_cycle_rad` | [`YAW_PER_CYCLE_RAD`]: `[−π/2, π/2]` rad | a quarter turn per cycle (kin-core's bound); the reach is the start check's |
//! | stable turn `shift_fraction` | [`SHIFT_FRACTION`]: `[0.05, 1]` | less keeps the centre of mass on the diagonal the lifted leg leaves; more goes past the centroid of the support triangle |
//! | `velocity_timeout_ms` | `[1, 65535]` ms | 0 would stop a walk at once |
//! | `joint_speed_limit_rad_s` | [`JOINT_SPEED_LIMIT_RAD_S`]: `[0.1, π/0.02]` rad/s | a servo's whole travel (π rad) in half a minute at the least; beyond its whole travel in one 20 ms servo frame a limit limits nothing |
//! | balance `level_kp` (2.3) | [`LEVEL_KP`]: `[0, 0.9]` | the body follows the correction within a frame: a gain of 1 or more overshoots every frame |
//! | balance `level_ki_per_s` (2.3) | [`LEVEL_KI_PER_S`]: `[0, 20]` 1/s | a time constant of 2.5 servo frames at the fastest |
//! | balance `max_correction_rad` (2.3) | [`MAX_CORRECTION_RAD`]: `[0, π/4]` rad | as the sway's amplitude; the reach bounds it further at run time |
//! | balance `fall_angle_rad` (2.3) | [`FALL_ANGLE_RAD`]: `[0.17, π]` rad | below 10° a slope or a sway would be a fall; π is upside down |
//!
//! What a value outside gets ([`ParamRange::check`]): NaN or ±∞ is [`ParamProblem::NonFinite`];
//! zero or a negative value (−0 too) of a field that must be positive (periods, durations, the
//! body height, the joint-speed limit, the timeout) is [`ParamProblem::NotPositive`], a
//! negative length [`ParamProblem::Negative`] (−0 is 0); every other finite value outside
//! (a subnormal below a positive minimum, ±1e30, the next float beyond a bound, a duty factor
//! of 0 or 1) is [`ParamProblem::OutOfRange`]. The fields are checked in declaration order; the first one
//! refused is named. The device's motion engine then checks what depends on the robot and on
//! the other fields (reach, the step height below the body, the velocity within the gait's
//! stride disc) and preflights the motion; this check only keeps out values that are no motion
//! at all, so that host and device refuse them alike, before any maths.
//!
//! [`ParamRange::check`] compares the bits, not the floats: exactly the float order on every
//! target, subnormals included, and integer compares rather than a soft-float call per bound
//! on the ATmega2560.

use crate::msg::{
    Field, MotionCommand, MotionParam, NackReason, ParamProblem, PoseConfig, Request,
};
use crate::robot::{RobotDescription, RobotField};
use core::f32::consts::{FRAC_PI_2, PI};
use kin_core::body::{self, BodyConfig};
use kin_core::{Joint, LegId, Math, Pose, ReachPolicy, Robot};

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

    /// The range of a motion's lengths (a lift, a stride, a step height), m:
    /// `[0,` [`reach_limit_m`]`]`.
    pub const fn length_m(&self) -> ParamRange {
        ParamRange::non_negative(self.reach_limit_m())
    }

    /// The range of a walk's body height, m: that of the stance height,
    /// `[`[`MIN_STANCE_HEIGHT_M`]`,` [`reach_limit_m`]`]`.
    pub const fn body_height_m(&self) -> ParamRange {
        ParamRange::positive(MIN_STANCE_HEIGHT_M, self.reach_limit_m())
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
/// (in declaration order), [`NackReason::InvalidArgument`] for a stance height that is not
/// positive, or [`NackReason::InvalidParameter`] naming the first motion field refused.
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
        Request::StartMotion(m) => motion_in(m, ranges),
        Request::SetVelocity {
            forward_m_s,
            lateral_m_s,
            yaw_rate_rad_s,
        } => first_invalid(&[
            (MotionParam::ForwardMS, SPEED_M_S, *forward_m_s),
            (MotionParam::LateralMS, SPEED_M_S, *lateral_m_s),
            (MotionParam::YawRateRadS, YAW_RATE_RAD_S, *yaw_rate_rad_s),
        ]),
        Request::SetJointSpeedLimit {
            joint_speed_limit_rad_s,
        } => first_invalid(&[(
            MotionParam::JointSpeedLimitRadS,
            JOINT_SPEED_LIMIT_RAD_S,
            *joint_speed_limit_rad_s,
        )]),
        Request::SetBalance(b) => first_invalid(&[
            (MotionParam::LevelKp, LEVEL_KP, b.level_kp),
            (MotionParam::LevelKiPerS, LEVEL_KI_PER_S, b.level_ki_per_s),
            (
                MotionParam::MaxCorrectionRad,
                MAX_CORRECTION_RAD,
                b.max_correction_rad,
            ),
            (MotionParam::FallAngleRad, FALL_ANGLE_RAD, b.fall_angle_rad),
        ]),
        Request::Hello { .. }
        | Request::GetImu
        | Request::GetState
        | Request::SetOutputs { .. }
        | Request::SetLinkTimeout(_)
        | Request::SetCalibration { .. }
        | Request::GetCalibration { .. }
        | Request::SaveCalibration
        | Request::StopMotion
        | Request::GetMotion
        | Request::GetRobot
        | Request::SaveRobot => Ok(()),
        // Its own check, which needs the IK ([`check_robot`]): the device runs it in the
        // handler, where the solver it builds is kept.
        Request::SetRobot(_) => Ok(()),
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

/// What a finite value below a [`ParamRange`]'s minimum is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Below {
    /// [`ParamProblem::OutOfRange`], whatever its sign (signed fields, the duty factor).
    OutOfRange,
    /// [`ParamProblem::NotPositive`] when zero or negative, else [`ParamProblem::OutOfRange`]
    /// (periods, durations, the body height, the joint-speed limit).
    NotPositive,
    /// [`ParamProblem::Negative`]: the minimum is 0 and −0 is 0 (lengths).
    Negative,
}

/// The admissible values `[min, max]` of a numeric motion field, in the field's unit (see the
/// module docs for each field's), and what a value outside them is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamRange {
    /// The smallest admissible value.
    pub min: f32,
    /// The largest admissible value.
    pub max: f32,
    /// What a value below `min` is.
    pub below: Below,
}

impl ParamRange {
    /// `[−max, max]`; a value outside is [`ParamProblem::OutOfRange`].
    pub const fn symmetric(max: f32) -> ParamRange {
        ParamRange {
            min: -max,
            max,
            below: Below::OutOfRange,
        }
    }

    /// `[min, max]` with `min > 0`; zero or a negative value is [`ParamProblem::NotPositive`].
    pub const fn positive(min: f32, max: f32) -> ParamRange {
        ParamRange {
            min,
            max,
            below: Below::NotPositive,
        }
    }

    /// `[0, max]`; a negative value is [`ParamProblem::Negative`].
    pub const fn non_negative(max: f32) -> ParamRange {
        ParamRange {
            min: 0.0,
            max,
            below: Below::Negative,
        }
    }

    /// `[min, max]`; a value outside is [`ParamProblem::OutOfRange`].
    pub const fn interval(min: f32, max: f32) -> ParamRange {
        ParamRange {
            min,
            max,
            below: Below::OutOfRange,
        }
    }

    /// Checks `v` (see the module docs): the comparisons on the bits, the same on every
    /// target.
    ///
    /// # Errors
    /// [`ParamProblem::NonFinite`] for NaN or ±∞; then as [`ParamRange::below`] says for a
    /// value below `min`, [`ParamProblem::OutOfRange`] above `max`.
    pub const fn check(&self, v: f32) -> Result<(), ParamProblem> {
        if !finite(v) {
            return Err(ParamProblem::NonFinite);
        }
        let k = order_key(v);
        if k > order_key(self.max) {
            return Err(ParamProblem::OutOfRange);
        }
        if k >= order_key(self.min) {
            return Ok(());
        }
        Err(match self.below {
            Below::OutOfRange => ParamProblem::OutOfRange,
            Below::NotPositive if k <= 0 => ParamProblem::NotPositive,
            Below::NotPositive => ParamProblem::OutOfRange,
            Below::Negative => ParamProblem::Negative,
        })
    }
}

/// `v` is neither NaN nor ±∞: its exponent bits are not all ones.
const fn finite(v: f32) -> bool {
    v.to_bits() & 0x7f80_0000 != 0x7f80_0000
}

/// An integer that orders finite floats as `<` does, with −0 = +0: the magnitude's bits,
/// negated for a negative value.
const fn order_key(v: f32) -> i32 {
    let magnitude = (v.to_bits() & 0x7fff_ffff) as i32;
    if v.is_sign_negative() {
        -magnitude
    } else {
        magnitude
    }
}

/// A sway's amplitude `A`, rad: `[−π/2, π/2]`. The body turned a quarter turn with its feet
/// on the ground is beyond the reach of any leg (the device's start check then refuses far
/// less); the sign only sets the direction of the first half-period.
pub const SWAY_AMPLITUDE_RAD: ParamRange = ParamRange::symmetric(FRAC_PI_2);

/// A period, s — a sway's `period_s`, a yaw turn's `step_period_s`, a foot path's or a walk's
/// `cycle_s`: `[0.1, 60]`. The device samples motions at 50 Hz: a period of 0.1 s is five
/// servo frames, about the fewest in which its samples still trace the motion (its start
/// check samples four points of a period); a period of more than a minute is a motion too
/// slow to watch (hold a pose instead).
pub const PERIOD_S: ParamRange = ParamRange::positive(0.1, 60.0);

/// A motion's duration, s, when one is given (none: until `StopMotion`): `[0.02, 3600]`. One
/// 20 ms servo frame at least (the device rounds it up to whole periods); an hour at most,
/// where f32 motion time still resolves 0.24 ms.
pub const DURATION_S: ParamRange = ParamRange::positive(0.02, 3600.0);

/// A yaw rate (a yaw turn's, a velocity command's), rad/s, counter-clockwise positive:
/// `[−π, π]`, half a turn per second, beyond what a servo-driven quadruped turns.
pub const YAW_RATE_RAD_S: ParamRange = ParamRange::symmetric(PI);

/// A stable turn's yaw per cycle, rad, counter-clockwise positive: `[−π/2, π/2]`, a quarter
/// turn per cycle (kin-core's own bound).
pub const YAW_PER_CYCLE_RAD: ParamRange = ParamRange::symmetric(FRAC_PI_2);

/// A stable turn's shift towards the centroid of its support triangle: `[0.05, 1]`; less keeps
/// the centre of mass on the diagonal the lifted leg leaves, more goes past the centroid.
pub const SHIFT_FRACTION: ParamRange = ParamRange::positive(0.05, 1.0);

/// A velocity command's forward or lateral speed, m/s: `[−10, 10]` (36 km/h, many times what
/// a servo-driven quadruped walks). What a robot's gait can take is narrower and the device's
/// walker checks it after this check (the footholds within its stride disc).
pub const SPEED_M_S: ParamRange = ParamRange::symmetric(10.0);

/// A foot path's duty factor (the stance fraction of its loop): `[0.05, 0.95]`, stance and
/// swing each at least a twentieth of the loop (the gait's own bound is the open `(0, 1)`).
pub const DUTY_FACTOR: ParamRange = ParamRange::interval(0.05, 0.95);

/// One 50 Hz servo frame, s: the step of the device's joint-speed limiter.
const SERVO_FRAME_S: f32 = 0.02;

/// The joint-speed limit of every output, rad/s: `[0.1, π / 0.02]`.
///
/// The minimum moves a servo in useful time: its whole travel (π rad) in 31 s, a stand-up
/// (about 1.5 rad at the knee) in 15 s, 2 mrad per 20 ms frame — far above the resolution of
/// an f32 angle (2.4e-7 rad near π), so that every frame moves the outputs. A limit of 1e-45
/// rad/s would be "finite and > 0" and yet move no output ever: it rounds to a step of 0. The
/// maximum is a servo's whole travel in one 20 ms frame (157 rad/s): a higher limit limits
/// nothing, and none is needed (the fastest hobby servos turn 20–30 rad/s unloaded).
pub const JOINT_SPEED_LIMIT_RAD_S: ParamRange = ParamRange::positive(0.1, PI / SERVO_FRAME_S);

/// The leveling's proportional gain (`BalanceConfig::level_kp`), rad per rad: `[0, 0.9]`. The
/// body follows a correction within a servo frame or two, so the loop's plant is nearly a unit
/// gain with a delay: a proportional gain of 1 or more would overshoot every frame.
pub const LEVEL_KP: ParamRange = ParamRange::non_negative(0.9);

/// The leveling's integral gain (`BalanceConfig::level_ki_per_s`), 1/s: `[0, 20]`, a time
/// constant of 50 ms (2.5 servo frames) at the fastest; faster would oscillate against the
/// joint-speed limiter and the estimator's own lag.
pub const LEVEL_KI_PER_S: ParamRange = ParamRange::non_negative(20.0);

/// The largest leveling correction (`BalanceConfig::max_correction_rad`), rad: `[0, π/4]`. A
/// quarter turn of the body with its feet on the ground is beyond any leg (as the sway's
/// amplitude); the robot's reach bounds the correction further at run time (reported).
pub const MAX_CORRECTION_RAD: ParamRange = ParamRange::non_negative(core::f32::consts::FRAC_PI_4);

/// The fall angle (`BalanceConfig::fall_angle_rad`), rad: `[0.17, π]` (10° to upside down).
/// Below 10° a slope or a sway would count as a fall; at π only an upside-down roll reaches it
/// (free fall is detected by the acceleration).
pub const FALL_ANGLE_RAD: ParamRange = ParamRange::positive(0.17, PI);

/// The admissible range of `param` for a robot of `ranges` (see the module docs); `None` for
/// the parameters that are no single number (the path, the velocity as a whole, the stance)
/// and for the walk's `velocity_timeout_ms`, an integer (`[1, 65535]` ms).
pub fn param_range(param: MotionParam, ranges: &Ranges) -> Option<ParamRange> {
    use MotionParam as P;
    Some(match param {
        P::AmplitudeRad => SWAY_AMPLITUDE_RAD,
        P::PeriodS | P::StepPeriodS | P::CycleS => PERIOD_S,
        P::DurationS => DURATION_S,
        P::YawRateRadS => YAW_RATE_RAD_S,
        P::LiftHeightM | P::StrideM | P::StepHeightM => ranges.length_m(),
        P::DutyFactor => DUTY_FACTOR,
        P::BodyHeightM => ranges.body_height_m(),
        P::ForwardMS | P::LateralMS => SPEED_M_S,
        P::JointSpeedLimitRadS => JOINT_SPEED_LIMIT_RAD_S,
        P::LevelKp => LEVEL_KP,
        P::LevelKiPerS => LEVEL_KI_PER_S,
        P::MaxCorrectionRad => MAX_CORRECTION_RAD,
        P::FallAngleRad => FALL_ANGLE_RAD,
        P::YawPerCycleRad => YAW_PER_CYCLE_RAD,
        P::ShiftFraction => SHIFT_FRACTION,
        _ => return None,
    })
}

/// The first of `fields` (parameter, range, value) whose value its range refuses. One loop
/// for every motion request: on the ATmega2560 each unrolled check is its own code.
#[inline(never)]
fn first_invalid(fields: &[(MotionParam, ParamRange, f32)]) -> Result<(), NackReason> {
    for &(param, range, v) in fields {
        if let Err(problem) = range.check(v) {
            return Err(NackReason::InvalidParameter { param, problem });
        }
    }
    Ok(())
}

/// A motion's duration, when given.
fn duration(duration_s: Option<f32>) -> Result<(), NackReason> {
    match duration_s {
        Some(d) => first_invalid(&[(MotionParam::DurationS, DURATION_S, d)]),
        None => Ok(()),
    }
}

/// A motion command's numbers (see the module docs), in declaration order.
///
/// # Errors
/// As [`check_request`].
pub fn check_motion(m: &MotionCommand, robot: &Robot) -> Result<(), NackReason> {
    motion_in(m, &Ranges::of(robot))
}

fn motion_in(m: &MotionCommand, ranges: &Ranges) -> Result<(), NackReason> {
    use MotionParam as P;
    let length = ranges.length_m();
    match *m {
        MotionCommand::StandUp | MotionCommand::Sit | MotionCommand::Rest => Ok(()),
        MotionCommand::Sway {
            amplitude_rad,
            period_s,
            duration_s,
            ..
        } => {
            first_invalid(&[
                (P::AmplitudeRad, SWAY_AMPLITUDE_RAD, amplitude_rad),
                (P::PeriodS, PERIOD_S, period_s),
            ])?;
            duration(duration_s)
        }
        MotionCommand::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            duration_s,
        } => {
            first_invalid(&[
                (P::YawRateRadS, YAW_RATE_RAD_S, yaw_rate_rad_s),
                (P::StepPeriodS, PERIOD_S, step_period_s),
                (P::LiftHeightM, length, lift_height_m),
            ])?;
            duration(duration_s)
        }
        MotionCommand::FootPath {
            stride_m,
            step_height_m,
            duty_factor,
            cycle_s,
            duration_s,
            ..
        } => {
            first_invalid(&[
                (P::StrideM, length, stride_m),
                (P::StepHeightM, length, step_height_m),
                (P::DutyFactor, DUTY_FACTOR, duty_factor),
                (P::CycleS, PERIOD_S, cycle_s),
            ])?;
            duration(duration_s)
        }
        MotionCommand::Walk {
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
            ..
        } => {
            first_invalid(&[
                (P::BodyHeightM, ranges.body_height_m(), body_height_m),
                (P::StepHeightM, length, step_height_m),
                (P::CycleS, PERIOD_S, cycle_s),
            ])?;
            if velocity_timeout_ms == 0 {
                return Err(NackReason::InvalidParameter {
                    param: P::VelocityTimeoutMs,
                    problem: ParamProblem::NotPositive,
                });
            }
            Ok(())
        }
        MotionCommand::StableTurn {
            yaw_per_cycle_rad,
            cycle_s,
            lift_height_m,
            shift_fraction,
            duration_s,
        } => {
            first_invalid(&[
                (P::YawPerCycleRad, YAW_PER_CYCLE_RAD, yaw_per_cycle_rad),
                (P::CycleS, PERIOD_S, cycle_s),
                (P::LiftHeightM, length, lift_height_m),
                (P::ShiftFraction, SHIFT_FRACTION, shift_fraction),
            ])?;
            duration(duration_s)
        }
    }
}

/// A femur's or a tibia's length, m: `[0.01, 2]`. Below a centimetre no servo moves a link;
/// beyond 2 m (four times the longest link of the presets) no servo-driven quadruped, and the
/// f32 IK's resolution (about 0.2 µm at 2 m) stays far below any servo's.
pub const LINK_LENGTH_M: ParamRange = ParamRange::positive(0.01, 2.0);

/// A leg's offsets `d_lat_m`, `d_ax_m`, m: `[0, 1]` (half the longest link).
pub const LEG_OFFSET_M: ParamRange = ParamRange::non_negative(1.0);

/// The body's length and width (between the hip mounts), m: `[0, 4]`, four times the largest
/// preset's length.
pub const BODY_SIZE_M: ParamRange = ParamRange::non_negative(4.0);

/// One bound of a joint limit, rad: `[−π, π]` (the IK's angles are in this interval).
pub const JOINT_LIMIT_RAD: ParamRange = ParamRange::symmetric(PI);

/// Checks a robot description (since 2.4) — the one check of [`Request::SetRobot`] that the
/// host runs before sending and the device before anything changes — and returns its body
/// solver, built for the stance check (the device keeps it). In this order:
///
/// | field | admissible |
/// |---|---|
/// | name | printable ASCII, 1‥16 bytes, zero-padded ([`RobotDescription::name_len`]) |
/// | `femur_m`, `tibia_m` | [`LINK_LENGTH_M`]: `[0.01, 2]` m |
/// | `d_lat_m`, `d_ax_m` | [`LEG_OFFSET_M`]: `[0, 1]` m |
/// | `body_length_m`, `body_width_m` | [`BODY_SIZE_M`]: `[0, 4]` m |
/// | joint limits (abduction, hip, knee) | each bound in [`JOINT_LIMIT_RAD`] `[−π, π]`, min ≤ max |
/// | `stance_height_m` | `[`[`MIN_STANCE_HEIGHT_M`]`,` [`reach_limit_m`]`]` |
/// | `joint_speed_limit_rad_s` | [`JOINT_SPEED_LIMIT_RAD_S`] |
/// | the rest pose ([`Robot::rest_leg`]) | within the joint limits (the device's sit, rest and safe state go there) |
/// | the stance | every leg reaches its stance foot at the zero body pose within its joint limits (the device holds the stance at power-on) |
///
/// The stance check solves the body IK with the math backend `M`: the device's own backend
/// there, the host's here (they agree to a few ulp; a stance that close to the edge of the
/// reach is refused by the start checks of every motion anyway).
///
/// # Errors
/// [`NackReason::BadRobot`] naming the first field refused.
pub fn check_robot<M: Math>(d: &RobotDescription) -> Result<body::Solver<M>, NackReason> {
    let bad = |field| Err(NackReason::BadRobot(field));
    if d.name_len().is_none() {
        return bad(RobotField::Name);
    }
    let r = &d.robot;
    let lengths = [
        (RobotField::FemurM, LINK_LENGTH_M, r.leg.femur_m),
        (RobotField::TibiaM, LINK_LENGTH_M, r.leg.tibia_m),
        (RobotField::DLatM, LEG_OFFSET_M, r.leg.d_lat_m),
        (RobotField::DAxM, LEG_OFFSET_M, r.leg.d_ax_m),
        (RobotField::BodyLengthM, BODY_SIZE_M, r.body_length_m),
        (RobotField::BodyWidthM, BODY_SIZE_M, r.body_width_m),
    ];
    for (field, range, v) in lengths {
        if range.check(v).is_err() {
            return bad(field);
        }
    }
    for (j, joint) in Joint::ALL.iter().enumerate() {
        let (lo, hi) = (r.limits.min_rad[j], r.limits.max_rad[j]);
        // Both finite after the range checks: the float comparison is the order.
        if JOINT_LIMIT_RAD.check(lo).is_err() || JOINT_LIMIT_RAD.check(hi).is_err() || lo > hi {
            return bad(RobotField::Limit(*joint));
        }
    }
    let stance = ParamRange::positive(MIN_STANCE_HEIGHT_M, reach_limit_m(r));
    if stance.check(d.stance_height_m).is_err() {
        return bad(RobotField::StanceHeightM);
    }
    if JOINT_SPEED_LIMIT_RAD_S
        .check(d.joint_speed_limit_rad_s)
        .is_err()
    {
        return bad(RobotField::JointSpeedLimitRadS);
    }
    if let Some(j) = r.limits.first_violation(r.rest_leg()) {
        return bad(RobotField::RestPose(j));
    }
    let solver = body::Solver::<M>::with_math(r);
    match solver.inverse_at_stance(
        &Pose::default(),
        &BodyConfig::about_centre(d.order),
        d.stance_height_m,
        ReachPolicy::Reject,
    ) {
        Ok(_) => Ok(solver),
        Err(e) => bad(RobotField::Stance(e.leg)),
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
