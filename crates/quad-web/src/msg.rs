//! The WebSocket messages between the page and the server, as serde types (JSON, one object
//! per text message, tagged by `type`), and the validation every message from a page passes
//! before anything is done with it.
//!
//! A page's message is refused — with an [`Error`] sent back to that page and written to the
//! server log, the connection kept open — when it is larger than [`MAX_MESSAGE_BYTES`], not
//! JSON, not one of the [`ClientMsg`] commands (unknown `type`, a missing or unknown field), or
//! carries a value outside its range (a non-finite number, a servo index beyond 11, a jog
//! larger than [`MAX_JOG_US`]). A refused message reaches neither the device thread nor the
//! device.

use crate::balance::ImuState;
use crate::motion::{self, Command, VelocityMsg};
use kin_core::body::Pose;
use kin_core::Robot;
use quad_host::ops::calibrate::guide::{self, Key};
use quad_protocol::servo::Calibration;
use quad_protocol::{MotionCommand, ServoId};
use serde::{Deserialize, Serialize};

/// Largest message a page may send, bytes. The largest command is well under 300 bytes.
pub const MAX_MESSAGE_BYTES: usize = 4096;

/// Largest pulse step of one jog, µs.
pub const MAX_JOG_US: i32 = 100;

/// What a page asks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMsg {
    /// Become the controlling page (refused while another page controls).
    TakeControl,
    /// Stop controlling; the device keeps its state.
    ReleaseControl,
    /// Switch the servo outputs on or off.
    SetOutputs {
        /// True to drive the outputs.
        enabled: bool,
    },
    /// A body pose at the stance; `id` comes back in [`State::pose_id`] once the device holds it.
    SetPose {
        /// The page's number of this pose.
        id: u32,
        /// The pose.
        pose: Pose,
    },
    /// A new stance height, m; the commanded pose is solved again at it.
    SetStanceHeight {
        /// The stance height, m (> 0).
        stance_height_m: f32,
    },
    /// Moves one servo's pulse by `delta_us` at the same joint angle (its calibration's
    /// `center_us`, in RAM).
    Jog {
        /// Servo index in kin-core's canonical order (0..12).
        servo: u8,
        /// Pulse step, µs (|step| ≤ [`MAX_JOG_US`]).
        delta_us: i32,
    },
    /// Sets one servo's `center_us` (in RAM).
    SetCenter {
        /// Servo index (0..12).
        servo: u8,
        /// The pulse at the servo's `zero_rad`, µs.
        center_us: u16,
    },
    /// Sets one servo's direction (in RAM).
    SetDirection {
        /// Servo index (0..12).
        servo: u8,
        /// True when a positive angle needs a shorter pulse.
        reversed: bool,
    },
    /// Persists the twelve calibrations (EEPROM).
    SaveCalibration,
    /// Reads the twelve calibrations back from the device.
    ReadCalibration,
    /// Starts an onboard motion (see [`crate::motion`]).
    StartMotion {
        /// The motion and its parameters: the protocol's request in its text form.
        motion: MotionCommand,
    },
    /// Stops the running motion cleanly.
    StopMotion,
    /// The running walk's velocity (the joystick).
    SetVelocity {
        /// The velocity.
        velocity: VelocityMsg,
    },
    /// Switches the device's leveling on or off (`SetBalance`, its other balance settings
    /// kept; see [`crate::balance`]).
    SetBalance {
        /// True to level the body.
        leveling: bool,
    },
    /// Starts the guided calibration ([`quad_host::ops::calibrate::guide`]) on the device's
    /// own robot: the device moves to the calibration posture. Refused while one runs.
    GuideStart,
    /// A key of the guided calibration, by name: `+ - ] [ n b t r s q` (`y`, `enter`: `n`).
    GuideKey {
        /// The key.
        key: Key,
    },
}

/// Why a page's message was refused before reaching the device thread.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Larger than [`MAX_MESSAGE_BYTES`].
    #[error("message of {len} bytes refused (at most {MAX_MESSAGE_BYTES})")]
    TooLarge {
        /// Its size, bytes.
        len: usize,
    },
    /// A binary WebSocket message (the panel speaks JSON text).
    #[error("binary message refused (the panel speaks JSON text)")]
    Binary,
    /// Not JSON, not a known command, or a field missing, unknown or of the wrong type.
    #[error("malformed message: {0}")]
    Malformed(#[from] serde_json::Error),
    /// A NaN or infinite value (e.g. a JSON number beyond the f32 range).
    #[error("`{0}` must be a finite number")]
    NonFinite(&'static str),
    /// A servo index beyond 11.
    #[error("servo index {0} out of range (0..=11)")]
    Servo(u8),
    /// A jog step beyond [`MAX_JOG_US`].
    #[error("jog of {0} us refused (at most {MAX_JOG_US} us per step)")]
    JogTooLarge(i32),
    /// A stance height that is not positive.
    #[error("stance_height_m must be > 0 (got {0})")]
    StanceHeight(f32),
}

fn finite(name: &'static str, v: f32) -> Result<(), Error> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::NonFinite(name))
    }
}

/// The servo of a page's index.
///
/// # Errors
/// [`Error::Servo`] beyond 11.
pub fn servo(index: u8) -> Result<ServoId, Error> {
    ServoId::from_index(usize::from(index)).ok_or(Error::Servo(index))
}

impl ClientMsg {
    /// Reads and validates one text message of a page.
    ///
    /// # Errors
    /// See [`Error`].
    pub fn parse(text: &str) -> Result<ClientMsg, Error> {
        if text.len() > MAX_MESSAGE_BYTES {
            return Err(Error::TooLarge { len: text.len() });
        }
        let msg: ClientMsg = serde_json::from_str(text)?;
        msg.validate()?;
        Ok(msg)
    }

    /// Range checks of the fields (serde only checks the types).
    ///
    /// # Errors
    /// See [`Error`].
    pub fn validate(&self) -> Result<(), Error> {
        match *self {
            ClientMsg::SetPose { pose, .. } => {
                finite("roll_rad", pose.roll_rad)?;
                finite("pitch_rad", pose.pitch_rad)?;
                finite("yaw_rad", pose.yaw_rad)?;
                finite("x_m", pose.x_m)?;
                finite("y_m", pose.y_m)?;
                finite("z_m", pose.z_m)
            }
            ClientMsg::SetStanceHeight { stance_height_m } => {
                finite("stance_height_m", stance_height_m)?;
                if stance_height_m > 0.0 {
                    Ok(())
                } else {
                    Err(Error::StanceHeight(stance_height_m))
                }
            }
            ClientMsg::Jog { servo: s, delta_us } => {
                servo(s)?;
                if delta_us.abs() <= MAX_JOG_US {
                    Ok(())
                } else {
                    Err(Error::JogTooLarge(delta_us))
                }
            }
            ClientMsg::SetCenter { servo: s, .. } | ClientMsg::SetDirection { servo: s, .. } => {
                servo(s).map(|_| ())
            }
            // A motion's numbers pass the protocol's range check for the device's robot
            // (`motion::request`).
            ClientMsg::TakeControl
            | ClientMsg::ReleaseControl
            | ClientMsg::SetOutputs { .. }
            | ClientMsg::SaveCalibration
            | ClientMsg::ReadCalibration
            | ClientMsg::StartMotion { .. }
            | ClientMsg::StopMotion
            | ClientMsg::SetVelocity { .. }
            | ClientMsg::SetBalance { .. }
            | ClientMsg::GuideStart
            | ClientMsg::GuideKey { .. } => Ok(()),
        }
    }

    /// The Motion tab's command this message carries, if it is one.
    pub fn motion(&self) -> Option<Command> {
        match *self {
            ClientMsg::StartMotion { motion } => Some(Command::Start(motion)),
            ClientMsg::StopMotion => Some(Command::Stop),
            ClientMsg::SetVelocity { velocity } => Some(Command::Velocity(velocity)),
            _ => None,
        }
    }
}

/// The device's status bits, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct FlagsMsg {
    /// The servo outputs are driven.
    pub outputs_enabled: bool,
    /// The link-loss failsafe has acted.
    pub failsafe_active: bool,
    /// The device's last reset was its watchdog's (reported once, protocol 2.2).
    pub watchdog_reset: bool,
    /// A calibration in RAM differs from the stored one.
    pub calibration_unsaved: bool,
    /// No stored calibration was found at power-on.
    pub calibration_default: bool,
    /// A joint or servo limit acted on the last target.
    pub limited: bool,
    /// The last target was clamped.
    pub clamped: bool,
    /// A fall was detected and the outputs went to their safe state: latched until an
    /// explicit motion request (protocol 2.3).
    pub fall_detected: bool,
}

impl From<quad_protocol::Flags> for FlagsMsg {
    fn from(f: quad_protocol::Flags) -> FlagsMsg {
        use quad_protocol::Flags as F;
        FlagsMsg {
            outputs_enabled: f.contains(F::OUTPUTS_ENABLED),
            failsafe_active: f.contains(F::FAILSAFE_ACTIVE),
            watchdog_reset: f.contains(F::WATCHDOG_RESET),
            calibration_unsaved: f.contains(F::CALIBRATION_UNSAVED),
            calibration_default: f.contains(F::CALIBRATION_DEFAULT),
            limited: f.contains(F::LIMITED),
            clamped: f.contains(F::CLAMPED),
            fall_detected: f.contains(F::FALL_DETECTED),
        }
    }
}

/// Link health: the client's counters and the round-trip times.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LinkMsg {
    /// Requests answered and accepted.
    pub acked: u64,
    /// Requests the device refused (nacks with a sequence number).
    pub nacked: u64,
    /// Requests without an answer after every retry.
    pub lost: u64,
    /// Request frames sent, retries included.
    pub frames_sent: u64,
    /// Resends.
    pub retries: u64,
    /// Attempts that timed out.
    pub timeouts: u64,
    /// Received frames that did not decode.
    pub bad_frames: u64,
    /// Round-trip time of the last request on the link's clock, ms.
    pub rtt_ms: f64,
    /// Largest round-trip time so far, ms.
    pub rtt_max_ms: f64,
    /// Frames the device received with a good CRC (its counter).
    pub device_frames_ok: u32,
    /// Frames the device dropped (its counter).
    pub device_frames_bad: u32,
}

/// The device as the server last read it, sent to every page on each change.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct State {
    /// Server time of this state, ms since the server started.
    pub t_ms: f64,
    /// The device's twelve joint angles (readback), rad, canonical order.
    pub angles_rad: [f32; 12],
    /// The twelve pulses on the outputs (readback), µs; 0 = off.
    pub pulses_us: [f32; 12],
    /// Status bits.
    pub flags: FlagsMsg,
    /// Link health.
    pub link: LinkMsg,
    /// The body pose the device holds (the last one it acked), if any.
    pub pose: Option<Pose>,
    /// The page's id of that pose.
    pub pose_id: u32,
    /// Stance height in force, m.
    pub stance_height_m: f32,
    /// The twelve calibrations as last read from the device.
    pub calibration: [Calibration; 12],
    /// Body poses the server sent to the device (every one passed the host's check first).
    pub poses_sent: u64,
    /// The id of the controlling page, if any.
    pub controller: Option<u64>,
    /// Pages connected.
    pub pages: u32,
    /// The device link is up (false after a link failure; the server keeps serving the page).
    pub link_up: bool,
    /// The device's motion engine, from its last `MotionAck`.
    pub motion: motion::MotionState,
    /// The device's inertial sensor and balance functions, from its last `Imu` report (read
    /// every [`crate::balance::IMU_PERIOD`]); `None` for a device older than protocol 2.3,
    /// or before the first report.
    pub imu: Option<ImuState>,
    /// The guided calibration, since a page started it (its last state stays after the end).
    pub guide: Option<guide::View>,
}

/// What the server tells a page.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMsg {
    /// First message on a connection: who the page is and what it talks to.
    Welcome {
        /// This page's id (compare with [`State::controller`]).
        page_id: u64,
        /// The robot.
        robot: Robot,
        /// Its name (a preset or `custom`).
        robot_name: String,
        /// Index of the device's rotation order in kin-core's `RotationOrder::ALL`.
        rotation_order: u8,
        /// Servo names, canonical order (`FL_abduction`, …).
        servos: Vec<String>,
        /// What the device does when its link is lost, and so what the server does when the
        /// controlling page goes away: `hold` or `disable`.
        link_loss_action: &'static str,
        /// The device: `sim`, `emulator` or `serial`.
        target: &'static str,
    },
    /// The device's state.
    State(Box<State>),
    /// A command was carried out.
    Done {
        /// Which (the `type` of the command).
        command: &'static str,
    },
    /// A message was refused or a command failed; nothing moved.
    Error {
        /// What went wrong.
        message: String,
        /// The field of the command the refusal names, if it names one (a motion parameter).
        #[serde(skip_serializing_if = "Option::is_none")]
        field: Option<&'static str>,
    },
}

impl ClientMsg {
    /// The `type` of this command, for [`ServerMsg::Done`] and the log.
    pub fn name(&self) -> &'static str {
        match self {
            ClientMsg::TakeControl => "take_control",
            ClientMsg::ReleaseControl => "release_control",
            ClientMsg::SetOutputs { .. } => "set_outputs",
            ClientMsg::SetPose { .. } => "set_pose",
            ClientMsg::SetStanceHeight { .. } => "set_stance_height",
            ClientMsg::Jog { .. } => "jog",
            ClientMsg::SetCenter { .. } => "set_center",
            ClientMsg::SetDirection { .. } => "set_direction",
            ClientMsg::SaveCalibration => "save_calibration",
            ClientMsg::ReadCalibration => "read_calibration",
            ClientMsg::StartMotion { .. } => "start_motion",
            ClientMsg::StopMotion => "stop_motion",
            ClientMsg::SetVelocity { .. } => "set_velocity",
            ClientMsg::SetBalance { .. } => "set_balance",
            ClientMsg::GuideStart => "guide_start",
            ClientMsg::GuideKey { .. } => "guide_key",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_parse() {
        let m = ClientMsg::parse(
            r#"{"type":"set_pose","id":3,"pose":{"roll_rad":0.1,"pitch_rad":0,"yaw_rad":0,"x_m":0,"y_m":0,"z_m":0.01}}"#,
        )
        .unwrap();
        assert!(matches!(m, ClientMsg::SetPose { id: 3, .. }));
        assert_eq!(
            ClientMsg::parse(r#"{"type":"jog","servo":4,"delta_us":-10}"#).unwrap(),
            ClientMsg::Jog {
                servo: 4,
                delta_us: -10
            }
        );
    }

    #[test]
    fn motion_commands_parse_and_are_range_checked() {
        use crate::motion;
        use kin_core::motion::laws::Axis;
        use quad_protocol::{MotionParam as P, NackReason, ParamProblem, Ranges};
        let m = ClientMsg::parse(
            r#"{"type":"start_motion","motion":{"sway":{"axis":"roll","amplitude_rad":0.1,"period_s":2,"duration_s":null}}}"#,
        )
        .unwrap();
        assert_eq!(
            m,
            ClientMsg::StartMotion {
                motion: MotionCommand::Sway {
                    axis: Axis::Roll,
                    amplitude_rad: 0.1,
                    period_s: 2.0,
                    duration_s: None
                }
            }
        );
        assert_eq!(m.name(), "start_motion");
        assert_eq!(
            ClientMsg::parse(r#"{"type":"start_motion","motion":"stand_up"}"#).unwrap(),
            ClientMsg::StartMotion {
                motion: MotionCommand::StandUp
            }
        );
        assert_eq!(
            ClientMsg::parse(r#"{"type":"stop_motion"}"#).unwrap(),
            ClientMsg::StopMotion
        );
        let v = ClientMsg::parse(
            r#"{"type":"set_velocity","velocity":{"forward_m_s":0.1,"lateral_m_s":0,"yaw_rate_rad_s":-0.2}}"#,
        )
        .unwrap();
        assert!(matches!(v, ClientMsg::SetVelocity { .. }));
        // The protocol's range check, the one the host and the device run.
        let ranges = Ranges::of(&Robot::shahriar2023());
        for (text, param, problem) in [
            (
                r#"{"type":"start_motion","motion":{"sway":{"axis":"roll","amplitude_rad":0.1,"period_s":0,"duration_s":null}}}"#,
                P::PeriodS,
                ParamProblem::NotPositive,
            ),
            (
                r#"{"type":"start_motion","motion":{"foot_path":{"path":"bezier","legs":"all","stride_m":0.05,"step_height_m":0.03,"duty_factor":1,"cycle_s":1,"duration_s":null}}}"#,
                P::DutyFactor,
                ParamProblem::OutOfRange,
            ),
            (
                r#"{"type":"set_velocity","velocity":{"forward_m_s":1e39,"lateral_m_s":0,"yaw_rate_rad_s":0}}"#,
                P::ForwardMS,
                ParamProblem::NonFinite,
            ),
            (
                r#"{"type":"start_motion","motion":{"walk":{"gait":"trot","body_height_m":0.4,"step_height_m":0.05,"cycle_s":0.8,"velocity_timeout_ms":0}}}"#,
                P::VelocityTimeoutMs,
                ParamProblem::NotPositive,
            ),
        ] {
            let cmd = ClientMsg::parse(text).unwrap().motion().unwrap();
            match motion::request(&cmd, &ranges) {
                Err((_, reason)) => assert_eq!(
                    reason,
                    NackReason::InvalidParameter { param, problem },
                    "{text}"
                ),
                other => panic!("{text}: {other:?}"),
            }
        }
        // A leg the protocol does not have, and the old capitalised spellings, are not read.
        for text in [
            r#"{"type":"start_motion","motion":{"foot_path":{"path":"bezier","legs":{"one":"XX"},"stride_m":0.05,"step_height_m":0.03,"duty_factor":0.5,"cycle_s":1,"duration_s":null}}}"#,
            r#"{"type":"start_motion","motion":{"sway":{"axis":"Roll","amplitude_rad":0.1,"period_s":2,"duration_s":null}}}"#,
        ] {
            assert!(
                matches!(ClientMsg::parse(text), Err(Error::Malformed(_))),
                "{text}"
            );
        }
        let e = ClientMsg::parse(r#"{"type":"start_motion","motion":"dance"}"#).unwrap_err();
        assert!(e.to_string().contains("unknown variant `dance`"), "{e}");
    }

    #[test]
    fn the_balance_switch_parses_and_the_state_carries_the_sensor() {
        let m = ClientMsg::parse(r#"{"type":"set_balance","leveling":true}"#).unwrap();
        assert_eq!(m, ClientMsg::SetBalance { leveling: true });
        assert_eq!(m.name(), "set_balance");
        assert_eq!(m.motion(), None);
        for bad in [
            r#"{"type":"set_balance"}"#,
            r#"{"type":"set_balance","leveling":1}"#,
            r#"{"type":"set_balance","leveling":true,"kp":0.3}"#,
        ] {
            assert!(
                matches!(ClientMsg::parse(bad), Err(Error::Malformed(_))),
                "{bad}"
            );
        }
        // The fall flag by name, the report under `imu`.
        let flags = FlagsMsg::from(quad_protocol::Flags(quad_protocol::Flags::FALL_DETECTED));
        assert!(flags.fall_detected && !flags.outputs_enabled);
        let report = quad_protocol::ImuReport {
            health: quad_protocol::ImuHealth::Starting,
            roll_rad: 0.0,
            pitch_rad: 0.0,
            correction_roll_rad: 0.0,
            correction_pitch_rad: 0.0,
            leveling_active: false,
            correction_limited: false,
            fall: None,
            samples: 7,
            config: quad_protocol::BalanceConfig::DEFAULT,
        };
        let imu = crate::balance::ImuState::from(&report);
        let v = serde_json::to_value(imu).unwrap();
        assert_eq!(v["health"], "starting");
        assert_eq!(v["leveling"], false);
        assert_eq!(v["fall"], serde_json::Value::Null);
    }

    #[test]
    fn the_guide_messages_parse_with_the_keys_by_name() {
        assert_eq!(
            ClientMsg::parse(r#"{"type":"guide_start"}"#).unwrap(),
            ClientMsg::GuideStart
        );
        let m = ClientMsg::parse(r#"{"type":"guide_key","key":"]"}"#).unwrap();
        assert_eq!(m, ClientMsg::GuideKey { key: Key::CoarseUp });
        assert_eq!(m.name(), "guide_key");
        let e = ClientMsg::parse(r#"{"type":"guide_key","key":"fine_up"}"#).unwrap_err();
        assert!(e.to_string().contains("no key of the guide"), "{e}");
        assert!(ClientMsg::parse(r#"{"type":"guide_key"}"#).is_err());
    }

    #[test]
    fn bad_messages_are_refused() {
        let long = format!(r#"{{"type":"take_control","pad":"{}"}}"#, "x".repeat(5000));
        assert!(matches!(
            ClientMsg::parse(&long),
            Err(Error::TooLarge { .. })
        ));
        assert!(matches!(ClientMsg::parse("{"), Err(Error::Malformed(_))));
        let e = ClientMsg::parse(r#"{"type":"fly"}"#).unwrap_err();
        assert!(e.to_string().contains("unknown variant `fly`"), "{e}");
        assert!(matches!(
            ClientMsg::parse(r#"{"type":"set_outputs","enabled":true,"extra":1}"#),
            Err(Error::Malformed(_))
        ));
        // 1e39 is beyond f32: serde makes it infinite, the validation refuses it.
        assert!(matches!(
            ClientMsg::parse(
                r#"{"type":"set_pose","id":1,"pose":{"roll_rad":1e39,"pitch_rad":0,"yaw_rad":0,"x_m":0,"y_m":0,"z_m":0}}"#
            ),
            Err(Error::NonFinite("roll_rad"))
        ));
        assert!(matches!(
            ClientMsg::parse(r#"{"type":"jog","servo":12,"delta_us":1}"#),
            Err(Error::Servo(12))
        ));
        assert!(matches!(
            ClientMsg::parse(r#"{"type":"jog","servo":0,"delta_us":1000}"#),
            Err(Error::JogTooLarge(1000))
        ));
        assert!(matches!(
            ClientMsg::parse(r#"{"type":"set_stance_height","stance_height_m":-1}"#),
            Err(Error::StanceHeight(_))
        ));
    }
}
