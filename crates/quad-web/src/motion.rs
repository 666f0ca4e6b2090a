//! The Motion tab's commands: the onboard motions its buttons start, the velocity its joystick
//! sets, and the one place ([`request`]) that turns them into device requests.
//!
//! The device protocol of this build has no motion requests: [`request`] answers
//! [`Unsupported`] for every command, the device thread reports it to the page as an error
//! ("not sent"), and nothing is sent. The page, its messages, their validation and the server's
//! path to the device are complete; carrying motions is [`request`]'s job alone (one `match`
//! arm per [`MotionMsg`] onto the protocol's motion requests, the device thread sends what it
//! returns like any other request and reports the device's nack), plus [`on_control_lost`]
//! for the stop a lost page owes.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use quad_protocol::Request;
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
                MotionMsg::Stand | MotionMsg::Sit => Ok(()),
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

/// The device protocol of this build cannot carry the command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("not sent: the device protocol of this build has no motion requests")]
pub struct Unsupported;

/// The device request that carries `cmd` (validated).
///
/// # Errors
/// [`Unsupported`] for every command: the protocol has no motion requests yet.
pub fn request(cmd: &MotionCommand) -> Result<Request, Unsupported> {
    match cmd {
        MotionCommand::Start(_) | MotionCommand::Stop | MotionCommand::Velocity(_) => {
            Err(Unsupported)
        }
    }
}

/// The request that stops a running motion when the controlling page goes away, before the
/// device's link-loss rule is applied; `None` while the protocol has no motion requests.
pub fn on_control_lost() -> Option<Request> {
    None
}
