//! The Motion tab's commands: the onboard motions its buttons start, the velocity its joystick
//! sets, and the one place ([`request`]) that turns them into the device's motion requests
//! (protocol 2.1: `StartMotion`, `StopMotion`, `SetVelocity`), plus the stop a lost page owes
//! ([`on_control_lost`]) and the device's refusals in the page's words ([`words`]).
//!
//! A motion's parameters are the device's to check against the robot (reach, travel, the
//! gait's limits): the page's values go to it as they are, after the message checks of
//! [`MotionCommand::validate`], and its typed refusal comes back naming the page's field.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::LegId;
use quad_device::engine::{self, WalkRequest};
use quad_host::ops::onboard::{self, Naming};
use quad_protocol::{LinkLossAction, MotionParam, MotionStage, MotionStatus, NackReason, Request};
use serde::{Deserialize, Serialize};

/// A motion the device runs by itself, as the page asks it. Durations: `None` runs until
/// stopped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionMsg {
    /// Outputs on at the rest pose, then a ramp to the stance.
    Stand,
    /// A ramp to the rest pose, held.
    Sit,
    /// A ramp to the rest pose, then the outputs off.
    Rest,
    /// Seed 001's sway about `axis`, `angle = A·sin(2πt/T)`, feet fixed.
    Sway {
        /// Roll, pitch or yaw.
        axis: Axis,
        /// Amplitude `A`, rad.
        amplitude_rad: f32,
        /// Period `T`, s.
        period_s: f32,
        /// Duration, s.
        duration_s: Option<f32>,
    },
    /// Seed 001's crossed-pair yaw turn about the body centre.
    YawTurn {
        /// Turn rate, rad/s, counter-clockwise positive.
        yaw_rate_rad_s: f32,
        /// Step period, s.
        step_period_s: f32,
        /// Lift, m.
        lift_height_m: f32,
        /// Duration, s.
        duration_s: Option<f32>,
    },
    /// A seed 000 foot path around the stance point of one leg (`leg` 0..4, FL FR RL RR) or
    /// all four (`leg` absent), body held.
    FootPath {
        /// The path's shape.
        path: PathKind,
        /// One leg, or all four when `None`.
        leg: Option<u8>,
        /// Stride, m.
        stride_m: f32,
        /// Lift, m.
        step_height_m: f32,
        /// Stance fraction of the loop, in (0, 1).
        duty_factor: f32,
        /// One loop, s.
        cycle_s: f32,
        /// Duration, s.
        duration_s: Option<f32>,
    },
    /// Trot or walk, steered by [`crate::msg::ClientMsg::SetVelocity`] (zero at the start).
    Walk {
        /// Trot or walk.
        gait: Pattern,
        /// Hip plane above the ground, m.
        body_height_m: f32,
        /// Swing apex above the ground, m.
        step_height_m: f32,
        /// Gait cycle, s.
        cycle_s: f32,
        /// A velocity not refreshed within this stops the walk, ms (> 0).
        velocity_timeout_ms: u16,
    },
}

/// A body-frame velocity command of a walk.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityMsg {
    /// Forward, m/s.
    pub forward_m_s: f32,
    /// To the left, m/s.
    pub lateral_m_s: f32,
    /// Yaw rate, rad/s, counter-clockwise positive.
    pub yaw_rate_rad_s: f32,
}

/// What the Motion tab asks of the device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionCommand {
    /// Start a motion.
    Start(MotionMsg),
    /// Stop the running motion cleanly.
    Stop,
    /// The running walk's velocity.
    Velocity(VelocityMsg),
}

/// A field of a motion command out of its range.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Invalid {
    /// NaN or infinite.
    #[error("`{0}` must be a finite number")]
    NonFinite(&'static str),
    /// Zero or negative where only a positive value means something.
    #[error("`{name}` must be > 0 (got {value})")]
    NotPositive {
        /// The field.
        name: &'static str,
        /// Its value.
        value: f32,
    },
    /// A duty factor outside (0, 1).
    #[error("`duty_factor` must be in (0, 1) (got {0})")]
    DutyFactor(f32),
    /// A leg index beyond 3.
    #[error("leg index {0} out of range (0..=3)")]
    Leg(u8),
    /// A zero velocity timeout.
    #[error("`velocity_timeout_ms` must be > 0")]
    Timeout,
}

impl Invalid {
    /// The field out of range.
    pub fn field(&self) -> &'static str {
        match *self {
            Invalid::NonFinite(name) | Invalid::NotPositive { name, .. } => name,
            Invalid::DutyFactor(_) => "duty_factor",
            Invalid::Leg(_) => "leg",
            Invalid::Timeout => "velocity_timeout_ms",
        }
    }
}

fn finite(name: &'static str, v: f32) -> Result<(), Invalid> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Invalid::NonFinite(name))
    }
}

fn positive(name: &'static str, v: f32) -> Result<(), Invalid> {
    finite(name, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(Invalid::NotPositive { name, value: v })
    }
}

fn duration(d: Option<f32>) -> Result<(), Invalid> {
    d.map_or(Ok(()), |d| positive("duration_s", d))
}

impl MotionCommand {
    /// Range checks a page's command before it reaches the device thread (what the device
    /// checks against the robot — reach, travel, the gait's limits — it checks itself).
    ///
    /// # Errors
    /// The first field out of range.
    pub fn validate(&self) -> Result<(), Invalid> {
        match *self {
            MotionCommand::Stop => Ok(()),
            MotionCommand::Velocity(v) => {
                finite("forward_m_s", v.forward_m_s)?;
                finite("lateral_m_s", v.lateral_m_s)?;
                finite("yaw_rate_rad_s", v.yaw_rate_rad_s)
            }
            MotionCommand::Start(m) => match m {
                MotionMsg::Stand | MotionMsg::Sit | MotionMsg::Rest => Ok(()),
                MotionMsg::Sway {
                    amplitude_rad,
                    period_s,
                    duration_s,
                    ..
                } => {
                    finite("amplitude_rad", amplitude_rad)?;
                    positive("period_s", period_s)?;
                    duration(duration_s)
                }
                MotionMsg::YawTurn {
                    yaw_rate_rad_s,
                    step_period_s,
                    lift_height_m,
                    duration_s,
                } => {
                    finite("yaw_rate_rad_s", yaw_rate_rad_s)?;
                    positive("step_period_s", step_period_s)?;
                    positive("lift_height_m", lift_height_m)?;
                    duration(duration_s)
                }
                MotionMsg::FootPath {
                    leg,
                    stride_m,
                    step_height_m,
                    duty_factor,
                    cycle_s,
                    duration_s,
                    ..
                } => {
                    if let Some(l) = leg.filter(|&l| l > 3) {
                        return Err(Invalid::Leg(l));
                    }
                    positive("stride_m", stride_m)?;
                    positive("step_height_m", step_height_m)?;
                    finite("duty_factor", duty_factor)?;
                    if !(duty_factor > 0.0 && duty_factor < 1.0) {
                        return Err(Invalid::DutyFactor(duty_factor));
                    }
                    positive("cycle_s", cycle_s)?;
                    duration(duration_s)
                }
                MotionMsg::Walk {
                    body_height_m,
                    step_height_m,
                    cycle_s,
                    velocity_timeout_ms,
                    ..
                } => {
                    positive("body_height_m", body_height_m)?;
                    positive("step_height_m", step_height_m)?;
                    positive("cycle_s", cycle_s)?;
                    if velocity_timeout_ms == 0 {
                        return Err(Invalid::Timeout);
                    }
                    Ok(())
                }
            },
        }
    }
}

/// The device's motion of a page's: the engine's request, which the host's onboard
/// operations send as well ([`quad_protocol::MotionCommand`]'s one conversion from it).
///
/// # Errors
/// [`Invalid::Leg`] for a foot path's leg index beyond 3.
pub fn engine_request(m: &MotionMsg) -> Result<engine::Request, Invalid> {
    Ok(match *m {
        MotionMsg::Stand => engine::Request::StandUp,
        MotionMsg::Sit => engine::Request::Sit,
        MotionMsg::Rest => engine::Request::Rest,
        MotionMsg::Sway {
            axis,
            amplitude_rad,
            period_s,
            duration_s,
        } => engine::Request::Sway {
            axis,
            amplitude_rad,
            period_s,
            duration_s,
        },
        MotionMsg::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            duration_s,
        } => engine::Request::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            duration_s,
        },
        MotionMsg::FootPath {
            path,
            leg,
            stride_m,
            step_height_m,
            duty_factor,
            cycle_s,
            duration_s,
        } => engine::Request::FootPath {
            path,
            leg: match leg {
                None => None,
                Some(l) => Some(*LegId::ALL.get(usize::from(l)).ok_or(Invalid::Leg(l))?),
            },
            stride_m,
            step_height_m,
            duty_factor,
            cycle_s,
            duration_s,
        },
        MotionMsg::Walk {
            gait,
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
        } => engine::Request::Walk(WalkRequest {
            pattern: gait,
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
        }),
    })
}

/// The device request that carries `cmd`.
///
/// # Errors
/// `cmd`'s first field out of range ([`MotionCommand::validate`]): nothing to send.
pub fn request(cmd: &MotionCommand) -> Result<Request, Invalid> {
    cmd.validate()?;
    Ok(match cmd {
        MotionCommand::Start(m) => {
            Request::StartMotion(quad_protocol::MotionCommand::from(&engine_request(m)?))
        }
        MotionCommand::Stop => Request::StopMotion,
        MotionCommand::Velocity(v) => Request::SetVelocity {
            forward_m_s: v.forward_m_s,
            lateral_m_s: v.lateral_m_s,
            yaw_rate_rad_s: v.yaw_rate_rad_s,
        },
    })
}

/// The request that stops a running motion when the controlling page goes away, as the
/// device's own link-loss rule stops it: with [`LinkLossAction::Hold`] a running motion ends
/// cleanly (`StopMotion`: the end of its period or strides, then a ramp to the stance); with
/// [`LinkLossAction::Disable`] nothing here, the outputs going off cancels it.
pub fn on_control_lost(action: LinkLossAction) -> Option<Request> {
    match action {
        LinkLossAction::Hold => Some(Request::StopMotion),
        LinkLossAction::Disable => None,
    }
}

/// The page's field of a motion parameter (the field of its `start_motion` and
/// `set_velocity` messages; the form shows it in degrees or millimetres where its unit says
/// so).
pub fn field(param: MotionParam) -> &'static str {
    match param {
        MotionParam::AmplitudeRad => "amplitude_rad",
        MotionParam::PeriodS => "period_s",
        MotionParam::DurationS => "duration_s",
        MotionParam::YawRateRadS => "yaw_rate_rad_s",
        MotionParam::StepPeriodS => "step_period_s",
        MotionParam::LiftHeightM => "lift_height_m",
        MotionParam::StrideM => "stride_m",
        MotionParam::StepHeightM => "step_height_m",
        MotionParam::DutyFactor => "duty_factor",
        MotionParam::CycleS => "cycle_s",
        MotionParam::Path => "path (with stride_m, step_height_m)",
        MotionParam::BodyHeightM => "body_height_m",
        MotionParam::VelocityTimeoutMs => "velocity_timeout_ms",
        MotionParam::ForwardMS => "forward_m_s",
        MotionParam::LateralMS => "lateral_m_s",
        MotionParam::Velocity => "the velocity (forward_m_s, lateral_m_s, yaw_rate_rad_s)",
        MotionParam::JointSpeedLimitRadS => "joint_speed_limit_rad_s",
        MotionParam::Stance => "the device's stance height",
        MotionParam::ReachRadiusM => "body_height_m (it sets the stride's reach)",
        _ => "a parameter",
    }
}

/// The page's names for the device's refusals ([`onboard::words_in`]).
pub const PANEL: Naming = Naming {
    param: field,
    start_walk: "start a trot / walk",
    stand: "start stand",
};

/// A device refusal in the page's words: the host's sentences ([`onboard::words_in`]) with
/// the page's field names, and for a refused sample of a started motion the fields that set
/// its feet.
pub fn words(reason: &NackReason, request: &Request) -> String {
    format!(
        "{}{}",
        onboard::words_in(reason, &PANEL),
        onboard::reach_hint(reason, onboard::shaping_params(request), &PANEL)
    )
}

/// The page's field a refusal of `request` names, when it names one: the refused parameter,
/// or for a refused sample of a started motion the first field that sets its feet.
pub fn refused_field(reason: &NackReason, request: &Request) -> Option<&'static str> {
    match reason {
        NackReason::InvalidParameter { param, .. } => Some(field(*param)),
        NackReason::Preflight { .. } | NackReason::ServoRange { .. } => {
            onboard::shaping_params(request).first().map(|&p| field(p))
        }
        _ => None,
    }
}

/// The motion engine's state for the pages.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionState {
    /// The motion running (`stand_up`, `sit`, `rest`, `sway`, `yaw_turn`, `foot_path`,
    /// `walk`); `None` when idle.
    pub kind: Option<&'static str>,
    /// Its stage: `approach`, `run`, `stopping`, `leave` (`run` when idle).
    pub stage: &'static str,
    /// Motion time since the run began, s.
    pub t_s: f32,
    /// Phase within the motion's period (the walk's gait phase), in `[0, 1)`.
    pub phase: f32,
    /// Why the last motion stopped early, in words, if it did.
    pub fault: Option<String>,
}

impl Default for MotionState {
    fn default() -> MotionState {
        MotionState {
            kind: None,
            stage: "run",
            t_s: 0.0,
            phase: 0.0,
            fault: None,
        }
    }
}

impl From<&MotionStatus> for MotionState {
    fn from(s: &MotionStatus) -> MotionState {
        MotionState {
            kind: s.kind.map(onboard::kind_name),
            stage: match s.stage {
                MotionStage::Approach => "approach",
                MotionStage::Run => "run",
                MotionStage::Stopping => "stopping",
                MotionStage::Leave => "leave",
            },
            t_s: s.t_s,
            phase: s.phase,
            fault: s.fault.map(|f| onboard::words_in(&f, &PANEL)),
        }
    }
}
