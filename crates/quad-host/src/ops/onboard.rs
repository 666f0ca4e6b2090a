//! The motions the device runs by itself (stand-up, sit, rest, the sways, the yaw turn, the foot
//! paths, trot and walk): starting them, following them to their end, and the device's
//! refusals in words. The operations behind `quadctl stand`, `sit`, `rest`, `run` and `drive`.
//!
//! A motion and its parameters are the protocol's one declaration,
//! [`quad_protocol::MotionCommand`], with its named defaults (`MotionCommand::seed001_sway`,
//! `MotionCommand::walk`, ...); the device's engine runs it as it is. Before sending a motion request the host
//! runs the range check the device runs first ([`quad_protocol::range`]): a number outside its
//! field's range is refused here with the device's own reason, [`Error::NotSent`], and nothing
//! is sent; what depends on the robot's reach and travel stays the device's to check. Refused
//! requests change nothing on the device.

use crate::client::{self, Client, ClientConfig, Outcome, Verdict};
use crate::link::{self, Link, Target};
use crate::robot_file;
use quad_protocol::range::{self, ParamRange, Ranges};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    DeviceInfo, DeviceToHost, Flags, ImuReport, MotionCommand, MotionFrames, MotionKind,
    MotionParam, MotionStage, MotionStatus, NackReason, ParamProblem, PreflightFault, Readback,
    Request, RobotDescription, RobotPreset,
};
use serde::Serialize;
use std::time::Duration;

/// How often a running motion is asked for its state while the host waits for its end.
pub const POLL_PERIOD: Duration = Duration::from_millis(100);

/// Why an onboard motion could not be run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The robot is not a preset and the device is older than protocol 2.4 (it cannot tell
    /// which robot it holds beyond its preset).
    #[error(
        "--robot {0}: the device speaks a protocol older than 2.4 and needs a preset robot \
         (shahriar2023, fernando2025): it reports its preset and both sides must run the same \
         geometry"
    )]
    NotAPreset(String),
    /// The robot file was refused (before anything was sent).
    #[error(transparent)]
    Robot(#[from] crate::robot_file::DeviceError),
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// The handshake or the link failed.
    #[error(transparent)]
    Client(#[from] client::Error),
    /// The device refused a request.
    #[error(
        "the device refused {request}: {}{}",
        words(.reason),
        reach_hint(.reason, .shaped_by, &COMMAND_LINE)
    )]
    Refused {
        /// The request.
        request: &'static str,
        /// Why.
        reason: NackReason,
        /// The parameters that set where a started motion's feet go (empty for other
        /// requests): named when the device's start check finds a foot it cannot place.
        shaped_by: &'static [MotionParam],
    },
    /// A number of the request is outside its field's range (`quad_protocol::range`): not
    /// sent; the device refuses it with the same reason.
    #[error(
        "{request} not sent: {}{}; the device refuses it alike",
        words(.reason),
        admissible(.reason, .range)
    )]
    NotSent {
        /// The request.
        request: &'static str,
        /// The reason the device gives to the same request.
        reason: NackReason,
        /// The refused field and its range, when it is one number's.
        range: Option<(MotionParam, ParamRange)>,
    },
    /// The motion stopped early on the device.
    #[error("the motion stopped early on the device: {}", words(.0))]
    Fault(NackReason),
    /// The motion did not end within the time allowed.
    #[error("the motion did not end within {0:?}")]
    NoEnd(Duration),
    /// The device speaks an older minor version than the request needs.
    #[error(
        "{request} needs protocol 2.{minor_needed}; the device speaks {}.{}",
        quad_protocol::version_major(*.device_version),
        quad_protocol::version_minor(*.device_version)
    )]
    TooOld {
        /// The request.
        request: &'static str,
        /// The minor version it needs.
        minor_needed: u8,
        /// The device's version.
        device_version: u16,
    },
    /// A command-line value the device cannot take in this form.
    #[error("--{option} {value}: {problem}")]
    Value {
        /// The option.
        option: &'static str,
        /// The value given.
        value: f64,
        /// What is wrong.
        problem: &'static str,
    },
}

impl Error {
    /// The reason a refused request got, from the device ([`Error::Refused`]) or from the
    /// host's range check before sending ([`Error::NotSent`]).
    pub fn refusal(&self) -> Option<&NackReason> {
        match self {
            Error::Refused { reason, .. } | Error::NotSent { reason, .. } => Some(reason),
            _ => None,
        }
    }
}

/// The unit of a motion parameter, as its name ends.
fn unit(param: MotionParam) -> &'static str {
    match param {
        MotionParam::AmplitudeRad | MotionParam::YawPerCycleRad => "rad",
        MotionParam::PeriodS
        | MotionParam::DurationS
        | MotionParam::StepPeriodS
        | MotionParam::CycleS => "s",
        MotionParam::YawRateRadS | MotionParam::JointSpeedLimitRadS => "rad/s",
        MotionParam::LiftHeightM
        | MotionParam::StrideM
        | MotionParam::StepHeightM
        | MotionParam::BodyHeightM => "m",
        MotionParam::ForwardMS | MotionParam::LateralMS => "m/s",
        MotionParam::MaxCorrectionRad | MotionParam::FallAngleRad => "rad",
        MotionParam::LevelKiPerS => "1/s",
        _ => "",
    }
}

/// A field's range after the words of its refusal: " [min, max] unit" after "outside its
/// admissible range", else " (admissible: [min, max] unit)"; empty without a range.
fn admissible(reason: &NackReason, range: &Option<(MotionParam, ParamRange)>) -> String {
    let Some((param, r)) = range else {
        return String::new();
    };
    let unit = match unit(*param) {
        "" => String::new(),
        u => format!(" {u}"),
    };
    let interval = format!("[{}, {}]{unit}", r.min, r.max);
    match reason {
        NackReason::InvalidParameter {
            problem: ParamProblem::OutOfRange,
            ..
        } => format!(" {interval}"),
        _ => format!(" (admissible: {interval})"),
    }
}

/// The command-line option of a motion parameter.
pub fn option(param: MotionParam) -> &'static str {
    match param {
        MotionParam::AmplitudeRad => "--amplitude-rad",
        MotionParam::PeriodS => "--period-s",
        MotionParam::DurationS => "--duration-s",
        MotionParam::YawRateRadS => "--yaw-rate-rad-s",
        MotionParam::StepPeriodS => "--step-period-s",
        MotionParam::LiftHeightM => "--lift-height-m",
        MotionParam::StrideM => "--stride-m",
        MotionParam::StepHeightM => "--step-height-m",
        MotionParam::DutyFactor => "--duty-factor",
        MotionParam::CycleS => "--cycle-s",
        MotionParam::Path => "--path (with --stride-m, --step-height-m)",
        MotionParam::BodyHeightM => "--stance-height-m",
        MotionParam::VelocityTimeoutMs => "--velocity-timeout-ms",
        MotionParam::ForwardMS => "--forward-m-s",
        MotionParam::LateralMS => "--lateral-m-s",
        MotionParam::Velocity => "the velocity (--forward-m-s, --lateral-m-s, --yaw-rate-rad-s)",
        MotionParam::JointSpeedLimitRadS => "--joint-speed-limit-rad-s",
        MotionParam::Stance => "the device's stance height",
        MotionParam::ReachRadiusM => "--stance-height-m (it sets the stride's reach)",
        MotionParam::LevelKp => "--kp",
        MotionParam::LevelKiPerS => "--ki-per-s",
        MotionParam::MaxCorrectionRad => "--max-correction-rad",
        MotionParam::FallAngleRad => "--fall-angle-rad",
        MotionParam::YawPerCycleRad => "--yaw-per-cycle-rad",
        MotionParam::ShiftFraction => "--shift-fraction",
        _ => "a parameter",
    }
}

/// The parameters that set where the feet of a started motion go: the device's start check
/// refuses a sample by the leg that cannot reach it, and these are what to change.
pub fn shaping_params(request: &Request) -> &'static [MotionParam] {
    use MotionParam as P;
    match request {
        Request::StartMotion(MotionCommand::Sway { .. }) => &[P::AmplitudeRad],
        Request::StartMotion(MotionCommand::YawTurn { .. }) => {
            &[P::YawRateRadS, P::StepPeriodS, P::LiftHeightM]
        }
        Request::StartMotion(MotionCommand::FootPath { .. }) => &[P::StrideM, P::StepHeightM],
        Request::StartMotion(MotionCommand::Walk { .. }) => &[P::BodyHeightM, P::StepHeightM],
        Request::StartMotion(MotionCommand::StableTurn { .. }) => {
            &[P::YawPerCycleRad, P::ShiftFraction, P::LiftHeightM]
        }
        _ => &[],
    }
}

/// " (the motion's feet are set by …)" after a start check's refusal of a sample, when the
/// motion has such parameters ([`shaping_params`]), named by `naming`.
pub fn reach_hint(reason: &NackReason, shaped_by: &[MotionParam], naming: &Naming) -> String {
    let sample = matches!(
        reason,
        NackReason::Preflight { .. } | NackReason::ServoRange { .. }
    );
    if sample && !shaped_by.is_empty() {
        let names: Vec<&str> = shaped_by.iter().map(|&p| (naming.param)(p)).collect();
        format!(" (the motion's feet are set by {})", names.join(", "))
    } else {
        String::new()
    }
}

/// How a front end names what the device's refusals point at: the place where a motion
/// parameter is set, and what to do first when a request needs a walk or the outputs on.
#[derive(Debug, Clone, Copy)]
pub struct Naming {
    /// Where a motion parameter is set (a command-line option, a form field).
    pub param: fn(MotionParam) -> &'static str,
    /// How a walk is started.
    pub start_walk: &'static str,
    /// How the outputs are switched on by a stand-up.
    pub stand: &'static str,
}

/// The command line's names: options, `quadctl run`, `quadctl stand`.
pub const COMMAND_LINE: Naming = Naming {
    param: option,
    start_walk: "quadctl run trot or walk",
    stand: "quadctl stand",
};

/// A device refusal in words, naming the command-line option of a refused parameter.
pub fn words(reason: &NackReason) -> String {
    words_in(reason, &COMMAND_LINE)
}

/// What is wrong with a refused parameter, in words after its name ("must be > 0").
pub fn problem_words(problem: ParamProblem) -> &'static str {
    match problem {
        ParamProblem::NonFinite => "is not a finite number",
        ParamProblem::NotPositive => "must be > 0",
        ParamProblem::Negative => "must be >= 0",
        ParamProblem::OutOfRange => "is outside its admissible range",
        ParamProblem::BeyondReach => "puts a foot out of reach",
    }
}

/// A device refusal in words, with a front end's names (see [`Naming`]).
pub fn words_in(reason: &NackReason, naming: &Naming) -> String {
    match reason {
        NackReason::InvalidParameter { param, problem } => {
            format!("{} {}", (naming.param)(*param), problem_words(*problem))
        }
        NackReason::Preflight { leg, fault } => {
            let what = match fault {
                PreflightFault::Reach(r) => format!("{leg} cannot reach its foot ({r})"),
                PreflightFault::JointLimit(j) => format!("{leg} {j:?} leaves its joint limits"),
                PreflightFault::Singular => {
                    format!("{leg} comes too close to a singular configuration")
                }
                PreflightFault::NonFinite => format!("a sample of {leg} is not finite"),
                _ => format!("{leg} fails"),
            };
            format!("the motion's preflight fails: {what}; nothing moved")
        }
        NackReason::ServoRange { leg, joint, fault } => {
            format!("{leg} {joint:?} would leave its servo's travel ({fault:?}); nothing moved")
        }
        NackReason::MotionRunning => {
            "a motion is running; it keeps running (stop it first)".to_owned()
        }
        NackReason::NotWalking => format!("no walk is running ({} first)", naming.start_walk),
        NackReason::OutputsDisabled => format!("the outputs are off ({} first)", naming.stand),
        NackReason::NotUpright => {
            "the inertial sensor finds the body tipped (set the robot on its feet); nothing moved"
                .to_owned()
        }
        NackReason::ImuAbsent => "the device has no inertial sensor: leveling is off".to_owned(),
        other => other.to_string(),
    }
}

/// The device's answer to a motion request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionAnswer {
    /// The engine after the request.
    pub status: MotionStatus,
    /// The readback after it.
    pub readback: Readback,
    /// The motion's frame numbers (from a device of protocol 2.3 or later).
    pub frames: Option<MotionFrames>,
}

/// Checks that the device's robot (`device`, with the hash its hello reported) is the one the
/// host plans with (`host`; `None`: the host plans with the device's, nothing to check).
///
/// # Errors
/// [`client::Error::RobotMismatch`] with both names and hashes.
pub fn check_same_robot(
    device: &RobotDescription,
    hello_hash: Option<u32>,
    host: Option<&RobotDescription>,
) -> Result<(), client::Error> {
    let device_hash = hello_hash.unwrap_or_else(|| device.hash());
    let Some(host) = host else {
        return Ok(());
    };
    if host.hash() == device_hash && device.hash() == device_hash {
        return Ok(());
    }
    let name = |d: &RobotDescription| d.name_str().unwrap_or("(unnamed)").to_owned();
    Err(client::Error::RobotMismatch {
        device_name: name(device),
        device_hash,
        host_name: name(host),
        host_hash: host.hash(),
    })
}

/// A session with the device for onboard motions: handshake, robot check, calibration.
pub struct Session<L> {
    client: Client<L>,
    info: DeviceInfo,
    calibration: [Calibration; 12],
    /// The request ranges of the device's robot (`None` for a geometry that is no preset: the
    /// host does not know it, the device alone checks).
    ranges: Option<Ranges>,
    /// The robot the device holds, read at connection from a device of protocol 2.4 or later
    /// ([`Session::connect_robot`]).
    robot: Option<RobotDescription>,
}

impl<L: Link> Session<L> {
    /// Handshake, robot check, calibration read-back.
    ///
    /// # Errors
    /// The handshake's errors, [`client::Error::Robot`] for another robot.
    pub fn connect(client: Client<L>, preset: RobotPreset) -> Result<Session<L>, Error> {
        Session::connect_checking(client, Some(preset))
    }

    /// Handshake and calibration read-back, on whatever robot the device runs (the
    /// operations that plan with the device's own robot: [`crate::robot_file::device_robot`]).
    ///
    /// # Errors
    /// The handshake's errors.
    pub fn connect_to_device(client: Client<L>) -> Result<Session<L>, Error> {
        Session::connect_checking(client, None)
    }

    fn connect_checking(
        mut client: Client<L>,
        preset: Option<RobotPreset>,
    ) -> Result<Session<L>, Error> {
        let info = client.hello()?;
        if let Some(preset) = preset.filter(|p| *p != info.robot) {
            return Err(client::Error::Robot {
                device: info.robot,
                host: preset,
            }
            .into());
        }
        let calibration = client.calibrations()?;
        Ok(Session {
            client,
            info,
            calibration,
            ranges: info.robot.robot().map(|r| Ranges::of(&r)),
            robot: None,
        })
    }

    /// Handshake, the robot the device holds (protocol 2.4: `GetRobot`), checked against the
    /// robot the host plans with when one is given (their hashes,
    /// [`RobotDescription::hash`], must be equal), calibration read-back. With `host: None`
    /// the host plans with the device's own robot ([`Session::robot`]).
    ///
    /// # Errors
    /// The handshake's errors; [`client::Error::RobotMismatch`] naming both robots and their
    /// hashes; [`client::Error::NoRobotRequests`] for a device older than 2.4 (whose robot is
    /// a preset: [`Session::connect`]).
    pub fn connect_robot(
        mut client: Client<L>,
        host: Option<&RobotDescription>,
    ) -> Result<Session<L>, Error> {
        let info = client.hello()?;
        if quad_protocol::version_minor(info.version) < 4 {
            return Err(client::Error::NoRobotRequests {
                device: info.version,
            }
            .into());
        }
        let robot = client.get_robot()?;
        check_same_robot(&robot, info.robot_hash, host)?;
        let calibration = client.calibrations()?;
        Ok(Session {
            client,
            info,
            calibration,
            ranges: Some(Ranges::of(&robot.robot)),
            robot: Some(robot),
        })
    }

    /// The client, the session ended (its link stays up).
    pub fn into_client(self) -> Client<L> {
        self.client
    }

    /// The robot the device holds, when read at connection ([`Session::connect_robot`]).
    pub fn robot(&self) -> Option<&RobotDescription> {
        self.robot.as_ref()
    }

    /// The range check the device runs first ([`quad_protocol::range::check_request`]), on
    /// the host before sending.
    ///
    /// # Errors
    /// [`Error::NotSent`] with the reason the device gives.
    pub fn check(&self, request: &Request) -> Result<(), Error> {
        let Some(ranges) = &self.ranges else {
            return Ok(());
        };
        range::check_request_in(request, ranges).map_err(|reason| Error::NotSent {
            request: client::request_name(request),
            reason,
            range: match reason {
                NackReason::InvalidParameter { param, .. } => {
                    range::param_range(param, ranges).map(|r| (param, r))
                }
                _ => None,
            },
        })
    }

    /// The device's `HelloAck`.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The calibration read at connection.
    pub fn calibration(&self) -> &[Calibration; 12] {
        &self.calibration
    }

    /// The client.
    pub fn client_mut(&mut self) -> &mut Client<L> {
        &mut self.client
    }

    /// The link's clock.
    pub fn now(&self) -> Duration {
        self.client.link().now()
    }

    /// A motion request (`StartMotion`, `StopMotion`, `GetMotion`, `SetVelocity`), sent once
    /// the host's range check ([`Session::check`]) passes it.
    ///
    /// # Errors
    /// [`Error::NotSent`] (nothing sent), [`Error::Refused`] with the device's reason, or the
    /// link's errors.
    pub fn motion(&mut self, request: Request) -> Result<MotionAnswer, Error> {
        self.check(&request)?;
        let name = client::request_name(&request);
        let retries = self.client.config().retries;
        let exchange = self
            .client
            .exchange_with(request, retries, |_| Verdict::Accept)
            .map_err(client::Error::from)?;
        match exchange.outcome {
            Outcome::Accepted(DeviceToHost::MotionAck {
                status,
                readback,
                frames,
                ..
            }) => Ok(MotionAnswer {
                status,
                readback,
                frames,
            }),
            // A start whose first answer was lost: its retry finds it running.
            Outcome::Accepted(DeviceToHost::Nack {
                reason: NackReason::MotionRunning,
                ..
            }) if exchange.attempts > 1 && matches!(request, Request::StartMotion(_)) => {
                self.motion(Request::GetMotion)
            }
            Outcome::Accepted(DeviceToHost::Nack { reason, .. }) => Err(Error::Refused {
                request: name,
                reason,
                shaped_by: shaping_params(&request),
            }),
            Outcome::Accepted(other) | Outcome::Rejected(other) => Err(client::Error::Unexpected {
                request: name,
                answer: Box::new(other),
            }
            .into()),
            Outcome::Lost => Err(client::Error::NoAnswer { request: name }.into()),
        }
    }

    /// A request of the inertial sensor and the balance functions (`SetBalance`, `GetImu`;
    /// protocol 2.3), sent once the host's range check passes it.
    ///
    /// # Errors
    /// [`Error::TooOld`] for a device of an older minor (nothing sent), [`Error::NotSent`],
    /// [`Error::Refused`] with the device's reason, or the link's errors.
    pub fn imu(&mut self, request: Request) -> Result<ImuReport, Error> {
        let name = client::request_name(&request);
        if quad_protocol::version_minor(self.info.version) < 3 {
            return Err(Error::TooOld {
                request: name,
                minor_needed: 3,
                device_version: self.info.version,
            });
        }
        self.check(&request)?;
        let retries = self.client.config().retries;
        let exchange = self
            .client
            .exchange_with(request, retries, |_| Verdict::Accept)
            .map_err(client::Error::from)?;
        match exchange.outcome {
            Outcome::Accepted(DeviceToHost::Imu { report, .. }) => Ok(report),
            Outcome::Accepted(DeviceToHost::Nack { reason, .. }) => Err(Error::Refused {
                request: name,
                reason,
                shaped_by: &[],
            }),
            Outcome::Accepted(other) | Outcome::Rejected(other) => Err(client::Error::Unexpected {
                request: name,
                answer: Box::new(other),
            }
            .into()),
            Outcome::Lost => Err(client::Error::NoAnswer { request: name }.into()),
        }
    }

    /// The state (`GetState`): the readback.
    ///
    /// # Errors
    /// The link's errors, or an unexpected answer.
    pub fn state(&mut self) -> Result<Readback, Error> {
        let name = "GetState";
        let retries = self.client.config().retries;
        let exchange = self
            .client
            .exchange_with(Request::GetState, retries, |_| Verdict::Accept)
            .map_err(client::Error::from)?;
        match exchange.outcome {
            Outcome::Accepted(DeviceToHost::Ack { readback, .. }) => Ok(readback),
            Outcome::Accepted(other) | Outcome::Rejected(other) => Err(client::Error::Unexpected {
                request: name,
                answer: Box::new(other),
            }
            .into()),
            Outcome::Lost => Err(client::Error::NoAnswer { request: name }.into()),
        }
    }

    /// Starts `request` on the device.
    ///
    /// # Errors
    /// As [`Session::motion`].
    pub fn start(&mut self, request: &MotionCommand) -> Result<MotionAnswer, Error> {
        self.motion(Request::StartMotion(*request))
    }

    /// The engine's state.
    ///
    /// # Errors
    /// As [`Session::motion`].
    pub fn get(&mut self) -> Result<MotionAnswer, Error> {
        self.motion(Request::GetMotion)
    }

    /// Asks for the state every [`POLL_PERIOD`] until no motion runs, at most `limit`;
    /// `each` sees every answer.
    ///
    /// # Errors
    /// [`Error::Fault`] when the motion stopped early, [`Error::NoEnd`], the link's errors.
    pub fn wait_idle(
        &mut self,
        limit: Duration,
        mut each: impl FnMut(&MotionAnswer),
    ) -> Result<MotionAnswer, Error> {
        let until = self.now() + limit;
        loop {
            let answer = self.get()?;
            each(&answer);
            if answer.status.kind.is_none() {
                if let Some(fault) = answer.status.fault {
                    return Err(Error::Fault(fault));
                }
                return Ok(answer);
            }
            let now = self.now();
            if now >= until {
                return Err(Error::NoEnd(limit));
            }
            self.client
                .idle_until(now + POLL_PERIOD)
                .map_err(client::Error::from)?;
        }
    }

    /// Stands up when the outputs are off (the motions need them on); returns whether it did.
    ///
    /// # Errors
    /// As [`Session::wait_idle`].
    pub fn stand_if_off(&mut self, limit: Duration) -> Result<bool, Error> {
        let now = self.get()?;
        if now.readback.flags.contains(Flags::OUTPUTS_ENABLED) {
            return Ok(false);
        }
        self.start(&MotionCommand::StandUp)?;
        self.wait_idle(limit, |_| {})?;
        Ok(true)
    }
}

/// Opens `target` and connects a [`Session`] for `robot`: a preset, a TOML or a URDF robot
/// file ([`robot_file::device_description`]). A device of protocol 2.4 or later must hold
/// that robot (the hashes are compared, [`Session::connect_robot`]); an older device must run
/// the preset named ([`Session::connect`]).
///
/// # Errors
/// [`Error::Robot`] for a robot file refused (before the link is opened),
/// [`Error::NotAPreset`] for a robot file and a device older than 2.4,
/// [`client::Error::RobotMismatch`] for a device holding another robot, the link's and the
/// handshake's errors.
pub fn open(robot: &str, target: &Target, retries: u32) -> Result<Session<Box<dyn Link>>, Error> {
    let wanted = robot_file::device_description(robot)?;
    let link = link::open(target)?;
    let mut client = Client::new(link, ClientConfig::for_target(target, retries));
    let info = client.hello()?;
    if quad_protocol::version_minor(info.version) >= 4 {
        return Session::connect_robot(client, Some(&wanted));
    }
    let preset =
        RobotPreset::from_name(robot.trim()).ok_or_else(|| Error::NotAPreset(robot.to_owned()))?;
    Session::connect(client, preset)
}

/// [`open`] without a robot: the host plans with the robot the device holds (protocol 2.4,
/// [`Session::connect_robot`]).
///
/// # Errors
/// [`client::Error::NoRobotRequests`] for a device older than 2.4, the link's and the
/// handshake's errors.
pub fn open_device_robot(target: &Target, retries: u32) -> Result<Session<Box<dyn Link>>, Error> {
    let link = link::open(target)?;
    Session::connect_robot(
        Client::new(link, ClientConfig::for_target(target, retries)),
        None,
    )
}

/// What a finished onboard motion reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    /// The motion, as the device names it.
    pub motion: &'static str,
    /// True when the device stood up first (its outputs were off).
    pub stood_up_first: bool,
    /// The longest motion time the device reported: the time of the motion's run stage, s
    /// (0 for a stand-up, sit or rest, which are ramps only: see `elapsed_s`).
    pub motion_s: f32,
    /// State requests while waiting.
    pub polls: u64,
    /// Velocity commands sent (walks).
    pub velocity_commands: u64,
    /// Link time from the start request to the end, s.
    pub elapsed_s: f64,
    /// True when the outputs are on at the end.
    pub outputs_enabled: bool,
}

/// The name of a motion kind in summaries.
pub fn kind_name(kind: MotionKind) -> &'static str {
    match kind {
        MotionKind::StandUp => "stand_up",
        MotionKind::Sit => "sit",
        MotionKind::Rest => "rest",
        MotionKind::Sway => "sway",
        MotionKind::YawTurn => "yaw_turn",
        MotionKind::FootPath => "foot_path",
        MotionKind::Walk => "walk",
        MotionKind::StableTurn => "stable_turn",
    }
}

/// A velocity command held for a time during a walk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityStep {
    /// Forward speed, m/s.
    pub forward_m_s: f32,
    /// Lateral speed (left positive), m/s.
    pub lateral_m_s: f32,
    /// Yaw rate, rad/s, counter-clockwise positive.
    pub yaw_rate_rad_s: f32,
    /// How long, s.
    pub duration_s: f32,
}

/// The velocity command of `step`.
pub fn velocity_request(step: &VelocityStep) -> Request {
    Request::SetVelocity {
        forward_m_s: step.forward_m_s,
        lateral_m_s: step.lateral_m_s,
        yaw_rate_rad_s: step.yaw_rate_rad_s,
    }
}

/// Runs `request` to its end: stands up first when the outputs are off (unless the request
/// is a posture; a sit or rest with the outputs off has nothing to do and returns at once),
/// starts it, sends the `walk` velocity steps at [`POLL_PERIOD`] (for a walk,
/// then stops it), and waits until the device is idle. `each` sees every answer.
///
/// # Errors
/// See [`Error`]; a refusal leaves the device as it was (apart from a stand-up first; a
/// request or velocity outside the protocol's ranges is refused before it).
pub fn run<L: Link>(
    session: &mut Session<L>,
    request: &MotionCommand,
    walk: &[VelocityStep],
    limit: Duration,
    mut each: impl FnMut(&MotionAnswer),
) -> Result<Summary, Error> {
    // The range check of the motion and of its velocity commands before anything moves (a
    // stand-up first included).
    session.check(&Request::StartMotion(*request))?;
    for step in walk {
        session.check(&velocity_request(step))?;
    }
    let posture = matches!(
        request,
        MotionCommand::StandUp | MotionCommand::Sit | MotionCommand::Rest
    );
    let stood_up_first = !posture && session.stand_if_off(limit)?;
    if posture && !matches!(request, MotionCommand::StandUp) {
        let now = session.get()?;
        if !now.readback.flags.contains(Flags::OUTPUTS_ENABLED) {
            return Ok(Summary {
                motion: "none",
                stood_up_first: false,
                motion_s: 0.0,
                polls: 1,
                velocity_commands: 0,
                elapsed_s: 0.0,
                outputs_enabled: false,
            });
        }
    }
    let start = session.now();
    let first = session.start(request)?;
    // The motion's time is read while it runs: an idle device reports `t_s` 0 (protocol 2.2,
    // and a 2.2 device to older hosts), not the time of the motion that ended.
    let mut motion_s = 0.0f32;
    let mut each = |a: &MotionAnswer| {
        motion_s = motion_s.max(a.status.t_s);
        each(a);
    };
    each(&first);
    let mut polls = 0u64;
    let mut velocity_commands = 0u64;
    if matches!(request, MotionCommand::Walk { .. }) {
        for step in walk {
            let until = session.now() + Duration::from_secs_f32(step.duration_s);
            loop {
                let sent = session.motion(velocity_request(step));
                let answer = match sent {
                    Ok(a) => a,
                    Err(e) => {
                        // A refused velocity: the walk ends as a stop ends it, then the refusal.
                        session.motion(Request::StopMotion)?;
                        session.wait_idle(limit, |_| {})?;
                        return Err(e);
                    }
                };
                velocity_commands += 1;
                each(&answer);
                let now = session.now();
                if now >= until {
                    break;
                }
                session
                    .client
                    .idle_until((now + POLL_PERIOD).min(until))
                    .map_err(client::Error::from)?;
            }
        }
        each(&session.motion(Request::StopMotion)?);
    }
    let last = session.wait_idle(limit, |a| {
        polls += 1;
        each(a);
    })?;
    Ok(Summary {
        motion: first.status.kind.map_or("none", kind_name),
        stood_up_first,
        motion_s,
        polls,
        velocity_commands,
        elapsed_s: (session.now() - start).as_secs_f64(),
        outputs_enabled: last.readback.flags.contains(Flags::OUTPUTS_ENABLED),
    })
}

/// Whether the device is ramping (approach or leave) rather than running the motion.
pub fn ramping(status: &MotionStatus) -> bool {
    matches!(status.stage, MotionStage::Approach | MotionStage::Leave)
}

/// A refusal (the device's, or the host's range check's) as the teleop's answer; any other
/// error as it is.
fn refused(e: Error) -> Result<crate::ops::drive::Answer<MotionAnswer>, Error> {
    match e.refusal() {
        Some(reason) => Ok(crate::ops::drive::Answer::Refused(words(reason))),
        None => Err(e),
    }
}

/// The teleop's device end ([`crate::ops::drive::Walker`]) on a [`Session`]: a trot or walk
/// at a body height, velocity commands, stop and sit.
pub struct SessionWalker<'a, L> {
    /// The session.
    pub session: &'a mut Session<L>,
    /// Trot or walk.
    pub pattern: kin_core::motion::gait::Pattern,
    /// How long a stop or a sit may take, link time.
    pub limit: Duration,
}

impl<L: Link> crate::ops::drive::Walker for SessionWalker<'_, L> {
    type State = MotionAnswer;
    type Error = Error;

    fn start(
        &mut self,
        body_height_m: f32,
    ) -> Result<crate::ops::drive::Answer<MotionAnswer>, Error> {
        use crate::ops::drive::Answer;
        self.session.stand_if_off(self.limit)?;
        let request = MotionCommand::walk(self.pattern, body_height_m);
        match self.session.start(&request) {
            Ok(a) => Ok(Answer::Accepted(a)),
            Err(e) => refused(e),
        }
    }

    fn velocity(
        &mut self,
        c: &crate::ops::drive::Command,
    ) -> Result<crate::ops::drive::Answer<MotionAnswer>, Error> {
        use crate::ops::drive::Answer;
        match self.session.motion(Request::SetVelocity {
            forward_m_s: c.forward_m_s,
            lateral_m_s: c.lateral_m_s,
            yaw_rate_rad_s: c.yaw_rate_rad_s,
        }) {
            Ok(a) => Ok(Answer::Accepted(a)),
            Err(e) => refused(e),
        }
    }

    fn stop(&mut self) -> Result<(), Error> {
        self.session.motion(Request::StopMotion)?;
        self.session.wait_idle(self.limit, |_| {})?;
        Ok(())
    }

    fn sit(&mut self) -> Result<(), Error> {
        self.stop()?;
        self.session.start(&MotionCommand::Sit)?;
        self.session.wait_idle(self.limit, |_| {})?;
        Ok(())
    }

    fn now(&self) -> Duration {
        self.session.now()
    }

    fn idle_until(&mut self, deadline: Duration) -> Result<(), Error> {
        self.session
            .client
            .idle_until(deadline)
            .map_err(|e| Error::Client(e.into()))
    }
}
