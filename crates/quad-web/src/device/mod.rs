//! The device side of the panel: one thread owns the link ([`quad_host::link::open`]) and a
//! [`Session`] on it, carries out the pages' commands one at a time and reads the device's
//! state between them, so that the 3D view always shows the device's **readback**.
//!
//! Every command goes through the library's checks before a byte is sent, the same as the
//! command line's:
//! - a body pose is solved by the host's kin-core and mapped through the device's calibration
//!   ([`quad_host::client::expected`]); a pose the host rejects is refused here and never sent;
//!   the device's answer then passes the readback check of `quadctl stream`
//!   ([`quad_host::client::judge`]);
//! - a calibration is validated ([`Calibration::validate`]) and must map the joint's current
//!   angle within the servo's travel before it is sent, and is read back after
//!   (`quadctl calibrate`'s check).
//!
//! ## Calibration jog
//! The protocol has no raw-pulse request. A jog of ±N µs moves the servo's `center_us` by N
//! through `SetCalibration`: at the same joint angle the pulse then moves by exactly N µs, so
//! the servo turns and the new centre is what "Save" persists. No new wire request is needed.
//!
//! ## Losing the controlling page
//! While the server runs it reads the device's state several times a second, so the device's
//! own link-loss failsafe never fires. When the controlling page goes away, the server applies
//! the same rule the device applies to a silent link ([`quad_protocol::LinkLossAction`] of its
//! configuration): `Disable` switches the outputs off (which cancels a running motion), `Hold`
//! keeps the last pose and stops a running motion cleanly ([`motion::on_control_lost`]).
//!
//! ## Motions and the device's clock
//! Motion requests go through [`motion::request`]; their `MotionAck` carries the engine's state,
//! which the thread also reads between commands (`GetMotion` instead of `GetState`). A
//! simulated or emulated device's clock runs only while its link is read, so the thread idles
//! the link up to the wall clock while it waits for events: its motions run in real time.
//!
//! ## The guided calibration
//! `guide_start` and `guide_key` drive the step machine of `quadctl calibrate guide`
//! ([`quad_host::ops::calibrate::guide`]) on this session: its actions go through the checks
//! above (a calibration is validated and checked against the held angle, then read back) and
//! its test poses through [`motion::request`]; a test pose runs to its end while the state is
//! published every [`GUIDE_POLL`] at the wall clock's pace. The robot is the device's own
//! ([`quad_host::robot_file::device_robot`]). A device refusal becomes the guide's message, not
//! a failed command. When the controlling page goes away, a running guide is aborted (the
//! calibration read at its start restored) before the link-loss rule applies.
//!
//! ## The inertial sensor
//! A device of protocol 2.3 reports its sensor and balance functions (`GetImu`): read at
//! connection and then every [`balance::IMU_PERIOD`] on a schedule of its own, between
//! commands (a stream of commands holds off the state read, not this one). The leveling switch
//! sends `SetBalance` with the device's other settings kept ([`Session::set_balance`]).

use crate::balance::{self, ImuState};
use crate::motion;
use crate::msg::{self, FlagsMsg, LinkMsg, State};
use kin_core::body::Pose;
use kin_core::Robot;
use quad_host::client::{self, expected, judge, AngleCheck, Client, Expected, Outcome};
use quad_host::link::{self, Link};
use quad_host::ops::calibrate::guide::{self, Guide};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    DeviceInfo, DeviceToHost, Flags, ImuReport, LinkLossAction, MotionStage, MotionStatus,
    NackReason, PoseConfig, Ranges, Readback, Request, ServoId,
};
use std::time::Duration;

mod guided;
mod thread;

pub use guided::{GUIDE_MOTION_LIMIT, GUIDE_POLL};
pub use thread::{run, DeviceSetup, Event, Job, Ready};

/// Why a command was not carried out.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The host's kin-core and the device's calibration reject the pose: not sent.
    #[error("not sent: the host rejects this pose ({0})")]
    HostRejects(NackReason),
    /// The device answered something the host's check refuses.
    #[error("the device's answer failed the readback check: {0}")]
    Mismatch(client::Mismatch),
    /// The device refused the request.
    #[error("the device refused {request}: {reason}")]
    Refused {
        /// The request.
        request: &'static str,
        /// Why.
        reason: NackReason,
    },
    /// No answer after every retry.
    #[error("no answer from the device after every retry")]
    Lost,
    /// A request of the session failed.
    #[error(transparent)]
    Client(#[from] client::Error),
    /// The link failed.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// A calibration the protocol refuses: not sent.
    #[error("not sent: {servo}: {source}")]
    BadCalibration {
        /// The servo.
        servo: ServoId,
        /// Why.
        source: quad_protocol::servo::Error,
    },
    /// The new calibration would put the joint's current angle beyond the servo's travel: not
    /// sent.
    #[error("not sent: {servo} at its current angle would be driven beyond its travel ({source})")]
    Travel {
        /// The servo.
        servo: ServoId,
        /// Why.
        source: quad_protocol::servo::Error,
    },
    /// The device holds another calibration than the one sent.
    #[error("{0}: the device holds another calibration than the one sent")]
    NotHeld(ServoId),
    /// The save did not clear the device's "unsaved" flag.
    #[error("the device still reports an unsaved calibration after the save")]
    NotSaved,
    /// The device runs another robot than the server was given, or one the server cannot
    /// know.
    #[error(transparent)]
    Robot(#[from] quad_host::robot_file::DeviceRobotError),
    /// The stance height makes the held pose unreachable: nothing sent.
    #[error(
        "not sent: the held pose is unreachable at stance height {stance_height_m} m ({reason})"
    )]
    Stance {
        /// The stance height asked, m.
        stance_height_m: f32,
        /// Why.
        reason: NackReason,
    },
    /// A servo index beyond 11 (the message validation refuses it first).
    #[error("servo index {0} out of range (0..=11)")]
    Servo(u8),
    /// The link is down; the server keeps serving pages.
    #[error("the device link is down")]
    LinkDown,
    /// A motion command out of its range (the protocol's range check): not sent.
    #[error("not sent: {}", motion::words(.reason, .request))]
    Motion {
        /// The request.
        request: Request,
        /// Why.
        reason: NackReason,
    },
    /// The device refused the balance switch (`SetBalance`): nothing changed.
    #[error("the device refused SetBalance: {}", balance::words(.0))]
    BalanceRefused(NackReason),
    /// A balance setting the protocol's range check refuses: not sent.
    #[error("not sent: the balance settings fail the range check ({0})")]
    BalanceRange(NackReason),
    /// The device speaks a protocol older than 2.3: it has no inertial sensor requests.
    #[error(
        "the device speaks protocol {major}.{minor}: the inertial sensor and balance need 2.3"
    )]
    NoBalance {
        /// Its major version.
        major: u8,
        /// Its minor version.
        minor: u8,
    },
    /// The guided calibration could not start.
    #[error("the guided calibration: {0}")]
    Guide(String),
    /// A guide key without a guided calibration.
    #[error("no guided calibration runs: start one first (guide_start)")]
    NoGuide,
    /// A motion the session waited for stopped early on the device.
    #[error("the motion stopped early on the device: {0}")]
    MotionFault(NackReason),
    /// A motion the session waited for did not end in time.
    #[error("the motion did not end within {0:?}")]
    NoEnd(Duration),
    /// The device refused a motion request; a running motion keeps running.
    #[error("the device refused {}: {}", client::request_name(.request), motion::words(.reason, .request))]
    MotionRefused {
        /// The request.
        request: Request,
        /// Why.
        reason: NackReason,
    },
}

impl Error {
    /// The page's field a refusal names, if it names one.
    pub fn field(&self) -> Option<&'static str> {
        match self {
            Error::MotionRefused { reason, request } | Error::Motion { reason, request } => {
                motion::refused_field(reason, request)
            }
            _ => None,
        }
    }
}

/// A session with the device: what the server knows of it and the requests the panel makes.
pub struct Session<L> {
    client: Client<L>,
    robot: Robot,
    /// Its name: the description's, or the preset's.
    robot_name: String,
    /// The protocol's ranges of `robot`.
    ranges: Ranges,
    info: DeviceInfo,
    pose_config: PoseConfig,
    calibration: [Calibration; 12],
    check: AngleCheck,
    readback: Readback,
    motion: MotionStatus,
    /// The device speaks protocol 2.1 or later: it has the motion requests.
    motions: bool,
    /// The device speaks protocol 2.3 or later: it has the inertial sensor's requests.
    balance: bool,
    /// Its last `Imu` report.
    imu: Option<ImuReport>,
    /// Attempts of the last exchange.
    attempts: u32,
    /// The link's clock when the session connected.
    link_epoch: Duration,
    pose: Option<(Pose, u32)>,
    poses_sent: u64,
    link: LinkMsg,
    /// The guided calibration, once a page started one.
    guide: Option<Guide>,
}

impl<L: Link> Session<L> {
    /// Handshake, robot check, calibration read, current state. Nothing moves: the outputs
    /// stay as they are (off at power-on).
    ///
    /// # Errors
    /// The handshake's errors, or [`Error::Robot`].
    pub fn connect(
        mut client: Client<L>,
        robot: Option<Robot>,
        check: AngleCheck,
    ) -> Result<Session<L>, Error> {
        let info = client.hello()?;
        // The device's own robot: the description a device of protocol 2.4 holds, else its
        // preset; a robot the server was given must be that one.
        let held = if quad_protocol::version_minor(info.version) >= 4 {
            Some(client.get_robot()?)
        } else {
            None
        };
        let robot = quad_host::robot_file::device_robot(&info, held.as_ref(), robot.as_ref())?;
        let robot_name = match &held {
            Some(h) => h.name_str().unwrap_or("custom").to_owned(),
            None => quad_host::names::robot_preset_name(info.robot).to_owned(),
        };
        let calibration = client.calibrations()?;
        let readback = client.ack(Request::GetState)?;
        let motions = quad_protocol::version_minor(info.version) >= 1;
        let balance = quad_protocol::version_minor(info.version) >= 3;
        let link_epoch = client.link().now();
        let mut session = Session {
            link_epoch,
            motion: MotionStatus {
                kind: None,
                stage: MotionStage::Idle,
                t_s: 0.0,
                phase: 0.0,
                fault: None,
            },
            motions,
            balance,
            imu: None,
            attempts: 0,
            client,
            ranges: Ranges::of(&robot),
            robot,
            robot_name,
            info,
            pose_config: info.pose_config,
            calibration,
            check,
            readback,
            pose: None,
            poses_sent: 0,
            link: LinkMsg::default(),
            guide: None,
        };
        session.read_imu()?;
        Ok(session)
    }

    /// The device's `HelloAck`.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The robot the device runs, which the session plans and checks with.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// Its name: the description's (protocol 2.4), or the preset's.
    pub fn robot_name(&self) -> &str {
        &self.robot_name
    }

    /// The last readback.
    pub fn readback(&self) -> &Readback {
        &self.readback
    }

    /// Link time since the session connected.
    pub fn link_elapsed(&self) -> Duration {
        self.client.link().now().saturating_sub(self.link_epoch)
    }

    /// Lets `d` of link time pass with nothing sent: a simulated or emulated device's clock
    /// runs only while its link is read, and its motions with it; a serial link just waits.
    ///
    /// # Errors
    /// Link failures.
    pub fn idle(&mut self, d: Duration) -> Result<(), Error> {
        let until = self.client.link().now() + d;
        self.client.idle_until(until).map_err(Error::Link)
    }

    /// One request through [`Client::exchange`] with `check`, timed and counted.
    fn exchange(
        &mut self,
        request: Request,
        check: impl FnMut(&DeviceToHost) -> client::Verdict,
    ) -> Result<DeviceToHost, Error> {
        let t0 = self.client.link().now();
        let ex = self.client.exchange(request, check)?;
        self.attempts = ex.attempts;
        let rtt_ms = (self.client.link().now() - t0).as_secs_f64() * 1e3;
        self.link.rtt_ms = rtt_ms;
        self.link.rtt_max_ms = self.link.rtt_max_ms.max(rtt_ms);
        match ex.outcome {
            Outcome::Accepted(DeviceToHost::Nack { reason, .. }) => {
                self.link.nacked += 1;
                Err(Error::Refused {
                    request: client::request_name(&request),
                    reason,
                })
            }
            Outcome::Accepted(answer) => {
                self.link.acked += 1;
                if let Some(readback) = answer.readback() {
                    self.readback = *readback;
                }
                Ok(answer)
            }
            Outcome::Rejected(answer) => Err(Error::Mismatch(client::Mismatch::Unexpected(answer))),
            Outcome::Lost => {
                self.link.lost += 1;
                Err(Error::Lost)
            }
        }
    }

    /// A request answered by an ack, or a configuration request answered by a `Configured`
    /// echoing exactly the setting sent (as [`Client::ack`]).
    fn ack(&mut self, request: Request) -> Result<Readback, Error> {
        let sent = quad_protocol::Setting::of_request(&request);
        match self.exchange(request, |_| client::Verdict::Accept)? {
            DeviceToHost::Ack { readback, .. } => Ok(readback),
            DeviceToHost::Configured {
                setting, readback, ..
            } if Some(setting) == sent => Ok(readback),
            other => Err(Error::Client(client::Error::Unexpected {
                request: client::request_name(&request),
                answer: Box::new(other),
            })),
        }
    }

    /// Reads the device's state: its motion engine's with the readback (`GetMotion`) when it
    /// has one, else the readback (`GetState`).
    ///
    /// # Errors
    /// Link failures, no answer.
    pub fn poll(&mut self) -> Result<(), Error> {
        if self.motions {
            self.motion(Request::GetMotion)
        } else {
            self.ack(Request::GetState).map(|_| ())
        }
    }

    /// Reads the device's inertial sensor and balance functions (`GetImu`) when it has them
    /// (protocol 2.3); nothing is sent to an older device.
    ///
    /// # Errors
    /// Link failures, no answer, an unexpected answer.
    pub fn read_imu(&mut self) -> Result<(), Error> {
        if self.balance {
            self.imu_request(Request::GetImu)?;
        }
        Ok(())
    }

    /// The last `Imu` report, if the device has sent one.
    pub fn imu(&self) -> Option<&ImuReport> {
        self.imu.as_ref()
    }

    /// Switches the device's leveling on or off, its other balance settings kept as it last
    /// reported them (read first when none was read yet).
    ///
    /// # Errors
    /// [`Error::NoBalance`] for a device older than 2.3 and [`Error::BalanceRange`] (nothing
    /// sent), [`Error::BalanceRefused`] with the device's reason (no sensor, a sensor fault),
    /// link failures.
    pub fn set_balance(&mut self, leveling: bool) -> Result<(), Error> {
        if !self.balance {
            return Err(Error::NoBalance {
                major: quad_protocol::version_major(self.info.version),
                minor: quad_protocol::version_minor(self.info.version),
            });
        }
        let current = match self.imu {
            Some(r) => r.config,
            None => self.imu_request(Request::GetImu)?.config,
        };
        let request =
            balance::request(&current, leveling, &self.ranges).map_err(Error::BalanceRange)?;
        match self.imu_request(request) {
            Err(Error::Refused { reason, .. }) => {
                // The refusal changed nothing; the report shows the settings in force.
                self.imu_request(Request::GetImu)?;
                Err(Error::BalanceRefused(reason))
            }
            other => other.map(|_| ()),
        }
    }

    /// `GetImu` or `SetBalance`, answered by an `Imu` report that is kept.
    fn imu_request(&mut self, request: Request) -> Result<ImuReport, Error> {
        match self.exchange(request, |_| client::Verdict::Accept)? {
            DeviceToHost::Imu { report, .. } => {
                self.imu = Some(report);
                Ok(report)
            }
            other => Err(Error::Client(client::Error::Unexpected {
                request: client::request_name(&request),
                answer: Box::new(other),
            })),
        }
    }

    /// Sends `pose` (page id `id`) when the host's kin-core and calibration accept it; the
    /// answer must pass the readback check.
    ///
    /// # Errors
    /// [`Error::HostRejects`] (nothing sent), [`Error::Refused`], [`Error::Mismatch`],
    /// [`Error::Lost`], link failures.
    pub fn set_pose(&mut self, pose: Pose, id: u32) -> Result<(), Error> {
        let angles = match expected(&self.robot, &self.pose_config, &self.calibration, &pose) {
            Expected::Angles(angles) => angles,
            Expected::Nack(reason) => return Err(Error::HostRejects(reason)),
        };
        let (check, calibration) = (self.check, self.calibration);
        self.poses_sent += 1;
        let answer = self.exchange(Request::SetBodyPose(pose), |a| {
            judge(check, &calibration, a, &Expected::Angles(angles))
        });
        match answer {
            Ok(_) => {
                self.pose = Some((pose, id));
                Ok(())
            }
            Err(Error::Mismatch(client::Mismatch::Unexpected(DeviceToHost::Ack {
                readback,
                ..
            }))) => Err(Error::Mismatch(
                client::check_readback(check, &calibration, &readback, &angles)
                    .err()
                    .unwrap_or(client::Mismatch::Unexpected(DeviceToHost::Ack {
                        seq: 0,
                        readback,
                    })),
            )),
            Err(e) => Err(e),
        }
    }

    /// A new stance height; the held pose (or the neutral one) is solved and sent again at it.
    ///
    /// # Errors
    /// [`Error::Stance`] when the held pose is unreachable there (nothing sent), the device's
    /// refusal, link failures.
    pub fn set_stance_height(&mut self, stance_height_m: f32) -> Result<(), Error> {
        let config = PoseConfig {
            stance_height_m,
            ..self.pose_config
        };
        quad_protocol::range::check_pose_config(&config, &self.robot).map_err(|reason| {
            Error::Stance {
                stance_height_m,
                reason,
            }
        })?;
        let (pose, id) = self.pose.unwrap_or((Pose::rotation(0.0, 0.0, 0.0), 0));
        if let Expected::Nack(reason) = expected(&self.robot, &config, &self.calibration, &pose) {
            return Err(Error::Stance {
                stance_height_m,
                reason,
            });
        }
        self.ack(Request::SetPoseConfig(config))?;
        self.pose_config = config;
        self.set_pose(pose, id)
    }

    /// Switches the outputs on or off.
    ///
    /// # Errors
    /// The device's refusal, link failures.
    pub fn set_outputs(&mut self, enabled: bool) -> Result<(), Error> {
        self.ack(Request::SetOutputs { enabled }).map(|_| ())
    }

    /// Replaces one servo's calibration in RAM after the checks of the module docs, and reads
    /// it back.
    ///
    /// # Errors
    /// [`Error::BadCalibration`], [`Error::Travel`] (nothing sent), the device's refusal,
    /// [`Error::NotHeld`], link failures.
    pub fn set_calibration(&mut self, servo: ServoId, c: Calibration) -> Result<(), Error> {
        c.validate()
            .map_err(|source| Error::BadCalibration { servo, source })?;
        c.pulse_half_us(self.readback.angles_rad[servo.index()])
            .map_err(|source| Error::Travel { servo, source })?;
        self.ack(Request::SetCalibration {
            servo,
            calibration: c,
        })?;
        let held = match self.exchange(Request::GetCalibration { servo }, |_| {
            client::Verdict::Accept
        })? {
            DeviceToHost::Calibration {
                servo: s,
                calibration,
                ..
            } if s == servo => calibration,
            other => {
                return Err(Error::Client(client::Error::Unexpected {
                    request: "GetCalibration",
                    answer: Box::new(other),
                }))
            }
        };
        self.calibration[servo.index()] = held;
        if held != c {
            return Err(Error::NotHeld(servo));
        }
        self.poll()
    }

    /// Moves one servo's pulse by `delta_us` at the same angle (see the module docs).
    ///
    /// # Errors
    /// As [`Session::set_calibration`]; a centre beyond 0..=65535 µs is
    /// [`Error::BadCalibration`].
    pub fn jog(&mut self, servo: ServoId, delta_us: i32) -> Result<(), Error> {
        let c = self.calibration[servo.index()];
        let center_us = i32::from(c.center_us) + delta_us;
        let center_us = u16::try_from(center_us).map_err(|_| Error::BadCalibration {
            servo,
            source: quad_protocol::servo::Error::CenterOutOfBounds,
        })?;
        self.set_calibration(servo, Calibration { center_us, ..c })
    }

    /// Sets one servo's centre pulse.
    ///
    /// # Errors
    /// As [`Session::set_calibration`].
    pub fn set_center(&mut self, servo: ServoId, center_us: u16) -> Result<(), Error> {
        let c = self.calibration[servo.index()];
        self.set_calibration(servo, Calibration { center_us, ..c })
    }

    /// Sets one servo's direction.
    ///
    /// # Errors
    /// As [`Session::set_calibration`].
    pub fn set_direction(&mut self, servo: ServoId, reversed: bool) -> Result<(), Error> {
        let c = self.calibration[servo.index()];
        self.set_calibration(servo, Calibration { reversed, ..c })
    }

    /// Persists the twelve calibrations and checks the device's "unsaved" flag cleared.
    ///
    /// # Errors
    /// The device's refusal (storage), [`Error::NotSaved`], link failures.
    pub fn save_calibration(&mut self) -> Result<(), Error> {
        let rb = self.ack(Request::SaveCalibration)?;
        if rb.flags.contains(Flags::CALIBRATION_UNSAVED) {
            return Err(Error::NotSaved);
        }
        Ok(())
    }

    /// Reads the twelve calibrations back from the device.
    ///
    /// # Errors
    /// Link failures, no answer.
    pub fn read_calibration(&mut self) -> Result<(), Error> {
        self.calibration = self.client.calibrations()?;
        Ok(())
    }

    /// The controlling page went away: the device's link-loss rule (see the module docs).
    ///
    /// # Errors
    /// Link failures, no answer.
    pub fn control_lost(&mut self) -> Result<(), Error> {
        if self.guide.as_ref().is_some_and(|g| !g.step().is_done()) {
            self.guide_command(
                &msg::ClientMsg::GuideKey {
                    key: guide::Key::Abort,
                },
                &|_| {},
            )?;
        }
        if let Some(stop) = motion::on_control_lost(self.info.link_timeout.action) {
            if self.motions {
                self.motion(stop)?;
            }
        }
        match self.info.link_timeout.action {
            LinkLossAction::Disable => self.set_outputs(false),
            LinkLossAction::Hold => Ok(()),
        }
    }

    /// Sends a motion request (`StartMotion`, `StopMotion`, `GetMotion`, `SetVelocity`) and
    /// keeps the engine's state of its `MotionAck`; a refusal is [`Error::MotionRefused`].
    fn motion(&mut self, request: Request) -> Result<(), Error> {
        match self.exchange(request, |_| client::Verdict::Accept) {
            Ok(DeviceToHost::MotionAck { status, .. }) => {
                self.motion = status;
                Ok(())
            }
            Ok(other) => Err(Error::Client(client::Error::Unexpected {
                request: client::request_name(&request),
                answer: Box::new(other),
            })),
            // A start whose first answer was lost: its retry finds it running.
            Err(Error::Refused {
                reason: NackReason::MotionRunning,
                ..
            }) if self.attempts > 1 && matches!(request, Request::StartMotion(_)) => {
                self.motion(Request::GetMotion)
            }
            Err(Error::Refused { reason, .. }) => Err(Error::MotionRefused { request, reason }),
            Err(e) => Err(e),
        }
    }

    /// The motion engine's state, as last reported.
    pub fn motion_status(&self) -> &MotionStatus {
        &self.motion
    }

    /// Starts, stops or steers a motion ([`motion::request`]). A started motion replaces the
    /// held body pose: the state reports none until the next pose.
    ///
    /// # Errors
    /// [`Error::Motion`] (nothing sent), [`Error::MotionRefused`], link failures.
    pub fn motion_command(&mut self, cmd: &motion::Command) -> Result<(), Error> {
        let request = motion::request(cmd, &self.ranges)
            .map_err(|(request, reason)| Error::Motion { request, reason })?;
        self.motion(request)?;
        if matches!(cmd, motion::Command::Start(_)) {
            self.pose = None;
        }
        Ok(())
    }

    /// Holds twelve joint angles (`SetJoints`); the held body pose is gone.
    ///
    /// # Errors
    /// The device's refusal, link failures.
    pub fn set_joints(&mut self, angles_rad: [f32; 12]) -> Result<(), Error> {
        self.ack(Request::SetJoints { angles_rad })?;
        self.pose = None;
        Ok(())
    }

    /// The state for the pages.
    pub fn state(&self, t_ms: f64) -> State {
        let c = self.client.counters();
        let rb = &self.readback;
        State {
            t_ms,
            angles_rad: rb.angles_rad,
            pulses_us: rb.pulses_half_us.map(|p| f32::from(p) * 0.5),
            flags: FlagsMsg::from(rb.flags),
            link: LinkMsg {
                frames_sent: c.frames_sent,
                retries: c.retries,
                timeouts: c.timeouts,
                bad_frames: c.bad_frames,
                device_frames_ok: rb.frames_ok,
                device_frames_bad: rb.frames_bad,
                ..self.link
            },
            pose: self.pose.map(|(p, _)| p),
            pose_id: self.pose.map_or(0, |(_, id)| id),
            stance_height_m: self.pose_config.stance_height_m,
            calibration: self.calibration,
            poses_sent: self.poses_sent,
            controller: None,
            pages: 0,
            link_up: true,
            motion: motion::MotionState::from(&self.motion),
            imu: self.imu.as_ref().map(ImuState::from),
            guide: self.guide.as_ref().map(Guide::view),
        }
    }

    /// Carries out one page command (control commands are the server's, not the device's).
    ///
    /// # Errors
    /// The command's.
    pub fn command(&mut self, cmd: &msg::ClientMsg) -> Result<(), Error> {
        use msg::ClientMsg as M;
        let servo = |i: u8| msg::servo(i).map_err(|_| Error::Servo(i));
        match *cmd {
            M::SetOutputs { enabled } => self.set_outputs(enabled),
            M::SetPose { id, pose } => self.set_pose(pose, id),
            M::SetStanceHeight { stance_height_m } => self.set_stance_height(stance_height_m),
            M::Jog { servo: s, delta_us } => self.jog(servo(s)?, delta_us),
            M::SetCenter {
                servo: s,
                center_us,
            } => self.set_center(servo(s)?, center_us),
            M::SetDirection { servo: s, reversed } => self.set_direction(servo(s)?, reversed),
            M::SaveCalibration => self.save_calibration(),
            M::ReadCalibration => self.read_calibration(),
            M::StartMotion { .. } | M::StopMotion | M::SetVelocity { .. } => match cmd.motion() {
                Some(m) => self.motion_command(&m),
                None => Ok(()),
            },
            M::SetBalance { leveling } => self.set_balance(leveling),
            M::GuideStart | M::GuideKey { .. } => self.guide_command(cmd, &|_| {}),
            M::TakeControl | M::ReleaseControl => Ok(()),
        }
    }
}
