//! The Motion tab's commands: the onboard motions its buttons start, the velocity its joystick
//! sets, and the one place ([`request`]) that turns them into the device's motion requests
//! (protocol 2.1: `StartMotion`, `StopMotion`, `SetVelocity`), plus the stop a lost page owes
//! ([`on_control_lost`]) and the device's refusals in the page's words ([`words`]).
//!
//! A motion is the protocol's [`MotionCommand`] itself, read from the page's JSON in its text
//! form (`quad_protocol::wire`: `"stand_up"`, `{"sway": {"axis": "roll", ...}}`). Its numbers
//! pass the protocol's range check ([`quad_protocol::range`], the one the host and the device
//! run) before anything is sent, and a refusal, there or by the device, comes back in the
//! page's words naming the page's field ([`words`], [`refused_field`]).

use quad_host::ops::onboard::{self, Naming};
use quad_protocol::{
    LinkLossAction, MotionCommand, MotionParam, MotionStage, MotionStatus, NackReason, Ranges,
    Request,
};
use serde::{Deserialize, Serialize};

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
pub enum Command {
    /// Start a motion.
    Start(MotionCommand),
    /// Stop the running motion cleanly.
    Stop,
    /// The running walk's velocity.
    Velocity(VelocityMsg),
}

/// The device request that carries `cmd`, range checked for the robot of `ranges`.
///
/// # Errors
/// The protocol's range check's refusal ([`quad_protocol::range::check_request_in`]) with the
/// request it refused: nothing to send.
pub fn request(cmd: &Command, ranges: &Ranges) -> Result<Request, (Request, NackReason)> {
    let request = match cmd {
        Command::Start(m) => Request::StartMotion(*m),
        Command::Stop => Request::StopMotion,
        Command::Velocity(v) => Request::SetVelocity {
            forward_m_s: v.forward_m_s,
            lateral_m_s: v.lateral_m_s,
            yaw_rate_rad_s: v.yaw_rate_rad_s,
        },
    };
    match quad_protocol::check_request_in(&request, ranges) {
        Ok(()) => Ok(request),
        Err(reason) => Err((request, reason)),
    }
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
        MotionParam::YawPerCycleRad => "yaw_per_cycle_rad",
        MotionParam::ShiftFraction => "shift_fraction",
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
    let said = match reason {
        // The page quotes its fields, as in its other refusals.
        NackReason::InvalidParameter { param, problem } => {
            format!("`{}` {}", field(*param), onboard::problem_words(*problem))
        }
        _ => onboard::words_in(reason, &PANEL),
    };
    format!(
        "{}{}",
        said,
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
    /// Its stage: `approach`, `run`, `stopping`, `leave`, `idle` (no motion runs; a device of
    /// protocol 2.1 or older reports `run` then).
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
            stage: "idle",
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
                MotionStage::Idle => "idle",
            },
            t_s: s.t_s,
            phase: s.phase,
            fault: s.fault.map(|f| onboard::words_in(&f, &PANEL)),
        }
    }
}

#[cfg(test)]
mod tests {
    use kin_core::motion::gait::Pattern;
    use kin_core::motion::laws::Axis;
    use kin_core::LegId;
    use quad_protocol::{LegSet, MotionCommand};

    #[test]
    fn every_motion_reads_back_from_its_snake_case_json() {
        let motions = [
            MotionCommand::StandUp,
            MotionCommand::Sit,
            MotionCommand::Rest,
            MotionCommand::seed001_sway(Axis::Pitch, Some(20.0)),
            MotionCommand::seed001_yaw_turn(None),
            MotionCommand::seed000_rectangle(LegSet::One(LegId::RL), Some(3.0)),
            MotionCommand::seed000_rectangle(LegSet::All, None),
            MotionCommand::walk(Pattern::Walk, 0.3),
        ];
        for m in motions {
            let text = serde_json::to_string(&m).unwrap();
            assert_eq!(
                serde_json::from_str::<MotionCommand>(&text).unwrap(),
                m,
                "{text}"
            );
        }
        assert_eq!(
            serde_json::to_string(&MotionCommand::StandUp).unwrap(),
            r#""stand_up""#
        );
        assert_eq!(
            serde_json::to_string(&MotionCommand::seed000_rectangle(
                LegSet::One(LegId::FL),
                None
            ))
            .unwrap(),
            r#"{"foot_path":{"path":"rectangle","legs":{"one":"FL"},"stride_m":0.1,"step_height_m":0.05,"duty_factor":0.33333334,"cycle_s":3.0,"duration_s":null}}"#
        );
    }
}
