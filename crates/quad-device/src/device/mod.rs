//! The controller: bytes in → requests → IK, joint limits, servo calibration → outputs →
//! answer bytes out.

use crate::balance::{Balance, Event};
use crate::config::{
    preset_of, validate_pose_config, write_default_calibration, Config, ConfigError, ValidConfig,
    UNBOOTED_CALIBRATION,
};
use crate::engine::{self, Engine, Limiter, PulseMaps, Setup, FRAME_MS, FRAME_S, LEVEL_SHARES};
use crate::hal::{Clock, ServoOutputs, Storage};
use crate::imu::{ImuReading, ImuState};
use crate::store::{RobotImage, RobotStore, Store, Table};
use kin_core::body::{self, BodySolution, Pose};
use kin_core::motion::gait::Velocity;
use kin_core::{BodyConfig, DefaultMath, Math, ReachPolicy, Vec3};
use quad_protocol::frame::encoded_len_max;
use quad_protocol::servo::{Calibration, PulseMap};
use quad_protocol::{
    check_request_in, encode_frame_in_pieces, is_compatible, negotiated_minor, Accumulator,
    DeviceInfo, DeviceToHost, Feed, Flags, HostToDevice, LinkLossAction, LinkTimeout,
    MotionCommand, MotionFrames, MotionKind, MotionStatus, NackReason, PoseConfig, Ranges,
    Readback, Request, RobotDescription, ServoId, Setting, DEVICE_TO_HOST_MAX_LEN, MAX_DECODED_LEN,
    PROTOCOL_VERSION,
};
use quad_protocol::{BalanceConfig, FaultAction, ImuReport, SafeState};

mod link;
mod motion;
mod outputs;
mod sensor;
mod stored;

use link::Answered;
pub use link::{encode_answer, feed_request};

/// Receive buffer of the accumulator (decoded bytes), the protocol's `MAX_DECODED_LEN`.
pub const RX_LEN: usize = MAX_DECODED_LEN;

/// The longest answer frame on the wire, bytes: it is encoded into the receive buffer (free
/// once the request is decoded), so it must fit there.
pub const TX_LEN: usize = encoded_len_max(DEVICE_TO_HOST_MAX_LEN);
const _: () = assert!(TX_LEN <= RX_LEN);

/// The shortest time between two nacks of unreadable frames (`BadCrc`, `BadFrame`,
/// `Oversize`), ms: the others in between are only counted (`frames_bad`). Noise rich in `0x00`
/// makes a "frame" every few bytes; answering each would keep the transmitter busy with nacks
/// and delay the answers to the valid frames among them. At 115,200 baud an 8-byte nack per
/// 10 ms takes 7 % of the line.
pub const FRAMING_NACK_INTERVAL_MS: u32 = 10;

/// The joint angles the device holds and the pulses they map to.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Held {
    angles_rad: [f32; 12],
    pulses_half_us: [u16; 12],
}

/// The device controller, generic over its outputs `O`, clock `C`, calibration storage `S` and
/// kin-core math backend `M`.
///
/// Behaviour (each point is tested):
/// - Outputs are stopped at construction and stay stopped until `SetOutputs { enabled: true }`.
/// - Motion (`SetBodyPose`, `SetFeet`, `SetJoints`) and configuration requests before a
///   successful `Hello` are refused with [`NackReason::HelloRequired`]; `Hello`, `GetState` and
///   `GetCalibration` are always answered.
/// - A motion request is solved completely (IK or joint limits, then the servo mapping of all
///   twelve joints) before anything changes: an unreachable, out-of-limit, out-of-travel or
///   non-finite target is nacked and moves nothing. A valid one replaces the held target at once
///   (no queue) and, while the outputs are enabled, goes to the outputs.
/// - Motion requests are accepted while the outputs are stopped: the target is held (the
///   readback then shows pulses 0) and `SetOutputs { enabled: true }` starts from it. At
///   power-on the held target is the nominal stance (zero body pose), when it maps within the
///   calibration; otherwise enabling is refused with [`NackReason::InvalidArgument`] until a
///   motion request succeeds.
/// - Every pulse written lies within its servo's calibrated `[min_us, max_us]`; a calibration
///   change that would put the held angle outside the new travel is refused.
/// - Every request is range-checked first ([`quad_protocol::check_request`], the host's own
///   check): a finite value outside its field's range is [`NackReason::OutOfRange`]; a motion
///   field (`StartMotion`, `SetVelocity`, `SetJointSpeedLimit`) outside its range is
///   [`NackReason::InvalidParameter`] naming it, before the motion engine does any maths.
/// - Configuration requests are answered with [`DeviceToHost::Configured`], echoing the setting
///   as applied.
/// - The robot (protocol 2.4): at boot the one stored ([`Request::SaveRobot`]) when a valid
///   one is, else the configuration's. [`Request::SetRobot`] is refused while the outputs are
///   on ([`NackReason::OutputsEnabled`]) and when [`quad_protocol::check_robot`]
///   refuses the robot ([`NackReason::BadRobot`]), changing nothing; accepted, it replaces the
///   geometry, ranges, stance height, rotation order and joint-speed limit at once and holds
///   the new stance (with the outputs off). The hello reports its hash to a host of minor 4.
/// - Link loss: when no valid frame arrived for `timeout_ms` (≠ 0), the failsafe holds the
///   pulses or stops the outputs ([`LinkLossAction`]) and sets [`Flags::FAILSAFE_ACTIVE`],
///   latched until an answer that carries a readback has reported it. Stopped outputs stay
///   stopped until the host enables them again.
/// - The protocol minor negotiated at `Hello` (the lower of the host's and this device's) is
///   remembered: a host of minor 0 or 1 is sent nothing of 2.2 — an idle `MotionStatus` is
///   stage `Run` with `t_s` and `phase` 0 rather than [`quad_protocol::MotionStage::Idle`], and
///   [`Flags::WATCHDOG_RESET`] is not sent (it stays latched for a later host of minor 2).
/// - After a watchdog reset ([`Device::note_watchdog_reset`]) the readback carries
///   [`Flags::WATCHDOG_RESET`], latched until an answer with a readback has reported it.
/// - A request received twice in a row as the same frame (a retry) is answered twice with the
///   same answer and acts once ([`Device::receive`]).
/// - Unreadable frames are answered with a nack without a sequence number (`BadCrc`,
///   `BadFrame`, `Oversize`), at most one per [`FRAMING_NACK_INTERVAL_MS`], and change nothing
///   but the frame counters.
/// - Every output passes the one joint-speed limiter of the [`engine`]: from the second servo
///   frame after enabling on, a new target is approached by at most `limit · 20 ms` per frame
///   ([`Device::poll`] runs the frames); within the enabling frame a target is written at once
///   (the servos' positions are unknown until then). The readback reports the held target;
///   [`Device::output_angles`] what is on the outputs.
/// - The motion engine ([`Device::start_motion`]) runs stand-up, sit, rest, the sways, the yaw
///   turn, the foot paths and the walk; a direct setpoint request or stopping the outputs
///   cancels a running motion, a link loss with [`LinkLossAction::Hold`] stops it cleanly.
/// - The inertial sensor's readings ([`Device::on_imu`]) drive the [`balance`](crate::balance)
///   functions: the gyro bias measured in the first still second, the attitude, body leveling
///   while a pose is held or a sway runs (through the body IK and the limiter), fall detection
///   (the outputs to their safe state at the sample that detects it, latched until an explicit
///   motion request), the start check (a motion refused while the body is not upright), and the
///   sensor's faults (leveling off). A host of minor < 3 is sent nothing of 2.3: the start
///   check's refusal reaches it as [`NackReason::Busy`] and [`Flags::FALL_DETECTED`] is not set.
pub struct Device<O, C, S, M: Math = DefaultMath> {
    outputs: O,
    clock: C,
    storage: S,
    config: Config,
    /// The body solver of `config.robot`, built once: its per-leg constants (square roots and
    /// products of the link lengths) would otherwise be computed again for every request.
    solver: body::Solver<M>,
    calibration: Table,
    /// `calibration`, each validated once and precomputed for mapping angles to pulses
    /// (recomputed with every change of `calibration`; [`PulseMap::NONE`] until the boot).
    pulse_maps: PulseMaps,
    /// The request ranges of `config.robot` (recomputed when the robot changes).
    ranges: Ranges,
    store: Store,
    /// The robot held ([`Request::SetRobot`]): its geometry is also `config.robot`, its
    /// stance height and rotation order `config.pose_config`'s defaults.
    robot: RobotDescription,
    /// [`RobotDescription::hash`] of `robot`, reported in the hello.
    robot_hash: u32,
    /// Where the robot is stored.
    robot_store: RobotStore,
    acc: Accumulator<RX_LEN>,
    held: Option<Held>,
    clamped: bool,
    limited: bool,
    outputs_enabled: bool,
    hello_done: bool,
    /// The protocol minor negotiated at the last `Hello` (the lower of the host's and this
    /// device's; 0 before any): nothing newer is sent to the host.
    peer_minor: u8,
    failsafe: bool,
    /// The last reset was the watchdog's ([`Flags::WATCHDOG_RESET`]), not yet reported.
    watchdog_reset: bool,
    failsafe_armed: bool,
    calibration_unsaved: bool,
    calibration_default: bool,
    last_valid_ms: u32,
    /// When the last nack of an unreadable frame was sent (`None`: never).
    last_framing_nack_ms: Option<u32>,
    /// The last request answered over the link and its answer, replayed for an exact repeat
    /// (a retry whose answer was lost): see [`Device::receive`].
    last_answered: Option<Answered>,
    engine: Engine<M>,
    /// The angles on the outputs while they are enabled.
    out_rad: [f32; 12],
    /// When the next servo frame begins, ms (frames timed by the clock), or the PWM period of
    /// the last frame (frames latched to the outputs' periods).
    next_frame: u32,
    /// True until the first frame boundary after enabling.
    enabling_frame: bool,
    /// The inertial sensor's readings ([`Device::on_imu`]).
    imu: ImuState,
    /// The balance functions on those readings.
    balance: Balance<M>,
    /// The body pose held while no motion runs (the leveling's base): `None` after joint or
    /// feet setpoints and at the rest pose.
    base_pose: Option<Pose>,
}

// The dispatcher and the handlers that solve the body IK are `#[inline(never)]` on purpose:
// inlined into one function (as LTO does on the ATmega2560), their locals make one large stack
// frame, beyond the reach of the AVR's frame-pointer displacement: every access then costs a
// pointer adjustment (the flash grew by half), and the LLVM AVR backend miscompiled one such
// access (it saved SREG in r0 while r0 still held a `mul` result: a wrong calibration index).
// Small frames avoid both; `firmware-avr`'s emulator tests scan the ELF for that pattern. The
// figures are in docs/benchmark-journal.md.
impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// Powers the device on: stops the outputs, loads the calibration from `storage` (the
    /// defaults of [`default_calibration`](crate::default_calibration) when none is valid) and holds the nominal stance.
    /// The same as [`Device::stopped`] followed by [`Device::boot`].
    ///
    /// # Errors
    /// [`Config::validate`]'s error.
    pub fn new(config: Config, outputs: O, clock: C, storage: S) -> Result<Self, ConfigError> {
        let mut device = Self::stopped(config, outputs, clock, storage)?;
        device.boot();
        Ok(device)
    }

    /// The first half of [`Device::new`]: validates `config`, stops the outputs and builds the
    /// controller, holding nothing; call [`Device::boot`] next (until then no angle maps
    /// into any servo's calibration). Cheap (no IK, no storage
    /// access), so that the caller can build the controller in its final place and then
    /// [`Device::boot`] it there — the 8 KB of SRAM of the ATmega2560 have no room for a second
    /// copy.
    ///
    /// # Errors
    /// [`Config::validate`]'s error.
    pub fn stopped(config: Config, outputs: O, clock: C, storage: S) -> Result<Self, ConfigError> {
        Ok(Self::stopped_valid(
            ValidConfig::new(config)?,
            outputs,
            clock,
            storage,
        ))
    }

    /// [`Device::stopped`] on a configuration validated already (infallible): a firmware
    /// whose configuration is a constant validates it at compile time
    /// ([`ValidConfig::checked`]) and carries no validation code.
    pub fn stopped_valid(valid: ValidConfig, mut outputs: O, clock: C, storage: S) -> Self {
        let config = *valid.config();
        outputs.set_enabled(false);
        let now = clock.now_ms();
        Device {
            outputs,
            clock,
            storage,
            calibration: UNBOOTED_CALIBRATION,
            pulse_maps: [PulseMap::NONE; 12],
            store: Store::new(config.storage_base),
            robot: config.description(),
            robot_hash: 0,
            robot_store: RobotStore::robot(config.storage_base),
            ranges: *valid.ranges(),
            solver: body::Solver::<M>::with_math(&config.robot),
            config,
            acc: Accumulator::new(),
            held: None,
            clamped: false,
            limited: false,
            outputs_enabled: false,
            hello_done: false,
            peer_minor: 0,
            failsafe: false,
            watchdog_reset: false,
            failsafe_armed: true,
            calibration_unsaved: false,
            calibration_default: true,
            last_valid_ms: now,
            last_framing_nack_ms: None,
            last_answered: None,
            engine: Engine::new(*valid.limiter()),
            out_rad: [0.0; 12],
            next_frame: now,
            enabling_frame: false,
            imu: ImuState::default(),
            balance: Balance::new(),
            base_pose: None,
        }
    }

    /// The second half of [`Device::new`], once, on a controller from [`Device::stopped`]:
    /// loads the calibration from storage (the defaults of [`default_calibration`](crate::default_calibration) when none is
    /// valid) and holds
    /// the nominal stance (zero body pose) when it maps within that calibration.
    pub fn boot(&mut self) {
        self.robot_hash = self.robot.hash();
        self.load_robot();
        self.calibration_default = !self.load_calibration();
        if self.calibration_default {
            // Also over a table that a failing load left half-read.
            write_default_calibration(
                &self.solver,
                &self.config.pose_config,
                &mut self.calibration,
            );
        }
        self.refresh_pulse_maps();
        // The stance may not map within a stored calibration: then nothing is held.
        let _ = self.set_body_pose(&Pose::default());
    }

    /// Records that the last reset was the watchdog's: the readback reports
    /// [`Flags::WATCHDOG_RESET`] to a host of minor 2 or later until an answer carrying the
    /// flags has reported it. Called by a firmware at boot that reads its reset cause; the
    /// outputs stay off as after any reset.
    pub fn note_watchdog_reset(&mut self) {
        self.watchdog_reset = true;
    }

    /// The protocol minor negotiated at the last compatible `Hello` (the lower of the host's and
    /// this device's), 0 before any.
    pub fn peer_minor(&self) -> u8 {
        self.peer_minor
    }

    /// Handles one decoded request (what [`Device::receive`] does for every valid frame) and
    /// returns the answer.
    pub fn handle(&mut self, msg: HostToDevice) -> DeviceToHost {
        self.handle_ref(&msg)
    }

    /// [`Device::handle`] on a borrowed request: [`Device::receive`] hands it the request
    /// where the decoder left it (no copy of the request on the way).
    // Out of line: the receive path's frame stays apart from the dispatcher's (note above).
    #[inline(never)]
    fn handle_ref(&mut self, msg: &HostToDevice) -> DeviceToHost {
        self.last_valid_ms = self.clock.now_ms();
        self.failsafe_armed = true;
        let answer = self.answer(msg);
        // Latched until an answer reports it (only the readback carries the flags).
        if let Some(rb) = answer.readback() {
            self.failsafe = false;
            // Reported only to a host that knows the bit (minor 2 or later).
            if rb.flags.contains(Flags::WATCHDOG_RESET) {
                self.watchdog_reset = false;
            }
        }
        answer
    }

    // Out of line: the dispatcher's frame holds only the request, each handler its own locals.
    #[inline(never)]
    fn answer(&mut self, msg: &HostToDevice) -> DeviceToHost {
        let seq = msg.seq;
        // The host's own check (`Ok` for the requests answered before the handshake).
        let in_range = check_range(&msg.request, &self.ranges);
        let result = match msg.request {
            Request::Hello { version } => {
                return if is_compatible(version) {
                    self.hello_done = true;
                    self.peer_minor = negotiated_minor(version, PROTOCOL_VERSION);
                    DeviceToHost::HelloAck {
                        seq,
                        info: self.info(),
                    }
                } else {
                    nack(
                        Some(seq),
                        NackReason::UnknownVersion {
                            supported: PROTOCOL_VERSION,
                        },
                    )
                };
            }
            Request::GetState => Ok(()),
            Request::GetCalibration { servo } => {
                return DeviceToHost::Calibration {
                    seq,
                    servo,
                    calibration: self.calibration[servo.index()],
                };
            }
            Request::GetRobot => {
                return DeviceToHost::Robot {
                    seq,
                    robot: self.robot,
                };
            }
            _ if !self.hello_done => Err(NackReason::HelloRequired),
            _ if in_range.is_err() => in_range,
            Request::SetBodyPose(pose) => self.set_body_pose(&pose),
            Request::SetFeet { feet_in_body_m } => self.set_feet(&feet_in_body_m),
            Request::SetJoints { angles_rad } => self.set_joints(&angles_rad),
            Request::SetOutputs { enabled } => self.set_outputs(enabled),
            Request::SetLinkTimeout(t) => {
                self.config.link_timeout = t;
                return self.configured(seq, Setting::LinkTimeout(self.config.link_timeout));
            }
            Request::SetCalibration { servo, calibration } => {
                return match self.set_calibration(servo, calibration) {
                    Ok(()) => self.configured(
                        seq,
                        Setting::Calibration {
                            servo,
                            calibration: self.calibration[servo.index()],
                        },
                    ),
                    Err(reason) => nack(Some(seq), reason),
                };
            }
            Request::SaveCalibration => self.save_calibration(),
            Request::SetRobot(robot) => {
                return match self.set_robot(&robot) {
                    Ok(()) => DeviceToHost::Robot {
                        seq,
                        robot: self.robot,
                    },
                    Err(reason) => nack(Some(seq), reason.for_minor(self.peer_minor)),
                };
            }
            Request::SaveRobot => self.save_robot(),
            Request::SetPoseConfig(p) => {
                return match self.set_pose_config(p) {
                    Ok(()) => self.configured(seq, Setting::PoseConfig(self.config.pose_config)),
                    Err(reason) => nack(Some(seq), reason),
                };
            }
            Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s,
            } => self
                .set_joint_speed_limit(joint_speed_limit_rad_s)
                .map_err(NackReason::from),
            Request::StartMotion(m) => {
                let r = self.start_motion(&m);
                return self.motion_answer(seq, r);
            }
            Request::StopMotion => {
                self.stop_motion();
                return self.motion_answer(seq, Ok(()));
            }
            Request::GetMotion => return self.motion_answer(seq, Ok(())),
            Request::SetBalance(config) => {
                return match self.set_balance(config) {
                    Ok(()) => DeviceToHost::Imu {
                        seq,
                        report: self.balance.report(),
                    },
                    Err(reason) => nack(Some(seq), reason),
                };
            }
            Request::GetImu => {
                return DeviceToHost::Imu {
                    seq,
                    report: self.balance.report(),
                };
            }
            Request::SetVelocity {
                forward_m_s,
                lateral_m_s,
                yaw_rate_rad_s,
            } => {
                let r = self.set_velocity(Velocity {
                    forward_m_s,
                    lateral_m_s,
                    yaw_rad_s: yaw_rate_rad_s,
                });
                return self.motion_answer(seq, r);
            }
        };
        match result {
            Ok(()) => DeviceToHost::Ack {
                seq,
                readback: self.readback(),
            },
            Err(reason) => nack(Some(seq), reason),
        }
    }

    /// The answer to a configuration request that was carried out: `setting` as now held.
    fn configured(&self, seq: u16, setting: Setting) -> DeviceToHost {
        DeviceToHost::Configured {
            seq,
            setting,
            readback: self.readback(),
        }
    }

    /// The answer to a motion request: `MotionAck` with the engine's status and the readback,
    /// or the nack of `result`'s error.
    fn motion_answer(&self, seq: u16, result: Result<(), engine::Error>) -> DeviceToHost {
        match result {
            Ok(()) => {
                let status = self.engine.status();
                DeviceToHost::MotionAck {
                    seq,
                    status: MotionStatus::from(status).for_minor(self.peer_minor),
                    readback: self.readback(),
                    // Since 2.3: to an older host, no byte of it.
                    frames: (self.peer_minor >= 3).then(|| MotionFrames::from(status)),
                }
            }
            Err(e) => nack(Some(seq), NackReason::from(e).for_minor(self.peer_minor)),
        }
    }

    /// What `HelloAck` reports (the robot's hash to a host of minor 4 or later only).
    pub fn info(&self) -> DeviceInfo {
        DeviceInfo {
            version: PROTOCOL_VERSION,
            firmware: self.config.firmware,
            robot: self.config.preset,
            max_frame_len: RX_LEN as u16,
            pose_config: self.config.pose_config,
            link_timeout: self.config.link_timeout,
            robot_hash: (self.peer_minor >= 4).then_some(self.robot_hash),
        }
    }

    /// The state an `Ack` reports: held angles (zeros when nothing is held), the pulses on the
    /// outputs (zeros while stopped), flags and frame counters.
    pub fn readback(&self) -> Readback {
        let flags = Flags::EMPTY
            .with(Flags::CLAMPED, self.clamped)
            .with(Flags::LIMITED, self.limited)
            .with(Flags::OUTPUTS_ENABLED, self.outputs_enabled)
            .with(Flags::FAILSAFE_ACTIVE, self.failsafe)
            .with(Flags::CALIBRATION_UNSAVED, self.calibration_unsaved)
            .with(Flags::CALIBRATION_DEFAULT, self.calibration_default)
            .with(
                Flags::WATCHDOG_RESET,
                self.watchdog_reset && self.peer_minor >= 2,
            )
            .with(
                Flags::FALL_DETECTED,
                self.balance.fall().is_some() && self.peer_minor >= 3,
            );
        let (frames_ok, frames_bad) = (self.acc.frames_ok(), self.acc.frames_bad());
        // One arm per case, so that each array is written once, in place (zeroed first and
        // then copied over from the held target, they were written twice).
        match &self.held {
            Some(h) if self.outputs_enabled => Readback {
                angles_rad: h.angles_rad,
                pulses_half_us: h.pulses_half_us,
                flags,
                frames_ok,
                frames_bad,
            },
            Some(h) => Readback {
                angles_rad: h.angles_rad,
                pulses_half_us: [0; 12],
                flags,
                frames_ok,
                frames_bad,
            },
            None => Readback {
                angles_rad: [0.0; 12],
                pulses_half_us: [0; 12],
                flags,
                frames_ok,
                frames_bad,
            },
        }
    }

    /// The twelve calibrations in RAM.
    pub fn calibration(&self) -> &Table {
        &self.calibration
    }

    /// The current configuration (pose configuration and link timeout as last set).
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// True while the outputs are driven.
    pub fn outputs_enabled(&self) -> bool {
        self.outputs_enabled
    }

    /// The outputs.
    pub fn outputs(&self) -> &O {
        &self.outputs
    }

    /// The storage.
    pub fn storage(&self) -> &S {
        &self.storage
    }

    /// The clock.
    pub fn clock(&self) -> &C {
        &self.clock
    }

    /// Takes the device apart (e.g. to "power it on" again from the same storage in a test).
    pub fn into_parts(self) -> (O, C, S) {
        (self.outputs, self.clock, self.storage)
    }
}

/// [`check_request_in`] for [`Device::answer`].
// Out of line: inlined, its copies of the request's values enlarge the dispatcher's frame.
#[inline(never)]
fn check_range(request: &Request, ranges: &Ranges) -> Result<(), NackReason> {
    check_request_in(request, ranges)
}

const fn nack(seq: Option<u16>, reason: NackReason) -> DeviceToHost {
    DeviceToHost::Nack { seq, reason }
}
