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
        for (m, c) in self.pulse_maps.iter_mut().zip(&self.calibration) {
            // Each calibration was validated when it was loaded, and the defaults are valid:
            // no map is left at `PulseMap::NONE`.
            if let Ok(map) = c.pulse_map() {
                *m = map;
            }
        }
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

    /// Loads the calibration from storage (true when a valid one was found).
    fn load_calibration(&mut self) -> bool {
        self.store.load(&mut self.storage, &mut self.calibration)
    }

    /// Adopts the robot stored (since protocol 2.4) when the storage holds a valid one that
    /// passes [`quad_protocol::check_robot`]; else the configuration's robot stays.
    // Out of line: the image and the check's solver stay out of `boot`'s frame.
    #[inline(never)]
    fn load_robot(&mut self) {
        let mut image = RobotImage([0; RobotDescription::WIRE_LEN]);
        if !self.robot_store.load(&mut self.storage, &mut image) {
            return;
        }
        let Some(robot) = image.robot() else {
            return;
        };
        if let Ok(solver) = quad_protocol::check_robot::<M>(&robot) {
            self.adopt_robot(&robot, solver);
        }
    }

    /// Makes `robot` (checked, with its body solver) the one held: the IK's geometry, the
    /// request ranges, the stance height and rotation order of body poses, the joint-speed
    /// limit, the preset and the hash the hello reports.
    fn adopt_robot(&mut self, robot: &RobotDescription, solver: body::Solver<M>) {
        self.config.robot = robot.robot;
        self.config.pose_config.stance_height_m = robot.stance_height_m;
        self.config.pose_config.order = robot.order;
        self.config.joint_speed_limit_rad_s = robot.joint_speed_limit_rad_s;
        self.config.preset = preset_of(robot);
        self.ranges = Ranges::of(&robot.robot);
        self.solver = solver;
        // Within the range `check_robot` admits, which the limiter accepts.
        let _ = self
            .engine
            .set_joint_speed_limit(robot.joint_speed_limit_rad_s);
        self.robot = *robot;
        self.robot_hash = robot.hash();
    }

    /// `SetRobot` (since protocol 2.4): refused while the outputs are on (a geometry change
    /// must never move powered servos: with the outputs off no motion runs either), checked
    /// ([`quad_protocol::check_robot`]) before anything changes. Then the robot is adopted
    /// ([`Device::adopt_robot`]); a default calibration (none stored, none changed since) is
    /// recomputed for the new stance; the new stance is held when it maps within the
    /// calibration (else nothing is held, and enabling is refused until a setpoint maps).
    // Out of line: the check's solver stays out of the dispatcher's frame.
    #[inline(never)]
    fn set_robot(&mut self, robot: &RobotDescription) -> Result<(), NackReason> {
        if self.outputs_enabled {
            return Err(NackReason::OutputsEnabled);
        }
        let solver = quad_protocol::check_robot::<M>(robot)?;
        self.adopt_robot(robot, solver);
        if self.calibration_default && !self.calibration_unsaved {
            write_default_calibration(
                &self.solver,
                &self.config.pose_config,
                &mut self.calibration,
            );
            for (m, c) in self.pulse_maps.iter_mut().zip(&self.calibration) {
                if let Ok(map) = c.pulse_map() {
                    *m = map;
                }
            }
        }
        self.held = None;
        self.base_pose = None;
        let _ = self.set_body_pose(&Pose::default());
        Ok(())
    }

    /// `SaveRobot` (since protocol 2.4): the robot held to the storage's inactive bank.
    fn save_robot(&mut self) -> Result<(), NackReason> {
        self.robot_store
            .save(&mut self.storage, &RobotImage::of(&self.robot))
            .map_err(|_| NackReason::Storage)
    }

    /// The robot held (what `GetRobot` answers).
    pub fn robot(&self) -> &RobotDescription {
        &self.robot
    }

    /// Feeds received bytes (any chunking) and sends one answer frame through `tx` for every
    /// frame that ends in them, in order (nacks of unreadable frames rate-limited, see
    /// [`FRAMING_NACK_INTERVAL_MS`]). Each answer frame reaches `tx` in consecutive pieces
    /// ([`encode_frame_in_pieces`]): its first bytes as soon as they are final, so that a
    /// transmitter starts while the rest is encoded; one frame's pieces all come before the
    /// next frame's.
    ///
    /// Every request is safe to retry: an exact repeat of the last request answered here (the
    /// same `seq` and the same frame CRC, so the same bytes) is answered with the same answer
    /// again and does not act again — a `StartMotion` resent because its `MotionAck` was lost
    /// gets that `MotionAck`, not `MotionRunning`. A repeated `seq` with other bytes is a new
    /// request. ([`Device::handle`], which sees no frame, always acts.)
    pub fn receive(&mut self, mut bytes: &[u8], mut tx: impl FnMut(&[u8])) {
        while let Some(remaining) = self.receive_one(bytes, &mut tx) {
            bytes = remaining;
        }
    }

    /// The answer to replay when the request `seq` of a frame whose CRC is `crc` is an exact
    /// repeat of the last request answered (a retry whose answer was lost), `None` for a new
    /// request. A repeat feeds the link timer as any frame does.
    fn repeated(&mut self, seq: u16, crc: Option<u16>) -> Option<DeviceToHost> {
        let last = self.last_answered.as_ref()?;
        if last.seq != seq || Some(last.crc) != crc {
            return None;
        }
        self.last_valid_ms = self.clock.now_ms();
        self.failsafe_armed = true;
        Some(last.answer)
    }

    /// Remembers `answer` to the request `seq` of a frame whose CRC is `crc`, for
    /// [`Device::repeated`]; unless it is a `Busy` nack, which asks for the same request again
    /// once the device is free.
    fn remember(&mut self, seq: u16, crc: Option<u16>, answer: &DeviceToHost) {
        let busy = matches!(
            answer,
            DeviceToHost::Nack {
                reason: NackReason::Busy,
                ..
            }
        );
        self.last_answered = crc.filter(|_| !busy).map(|crc| Answered {
            seq,
            crc,
            answer: *answer,
        });
    }

    /// Consumes `bytes` up to the end of the first frame in them, handles it and sends its
    /// answer through `tx` (encoded in the accumulator's buffer, free between frames): the
    /// bytes left, `None` when no frame ended in `bytes`. Not generic over the caller's
    /// closure, so that the firmware has one instance of it.
    fn receive_one<'a>(&mut self, bytes: &'a [u8], tx: &mut dyn FnMut(&[u8])) -> Option<&'a [u8]> {
        // The request is read where the decoder put it (bound by reference, not moved out).
        let (reason, remaining) = match &feed_request(&mut self.acc, bytes) {
            Feed::NeedMore => return None,
            Feed::Frame { msg, remaining } => {
                let (seq, crc) = (msg.seq, self.acc.frame_crc());
                if let Some(answer) = self.repeated(seq, crc) {
                    self.encode(&answer, tx);
                    return Some(remaining);
                }
                let answer = self.handle_ref(msg);
                self.encode(&answer, tx);
                // Remembered once the answer's first bytes are on their way.
                self.remember(seq, crc, &answer);
                return Some(remaining);
            }
            Feed::BadCrc { remaining } => (NackReason::BadCrc, *remaining),
            Feed::BadFrame { remaining, .. } => (NackReason::BadFrame, *remaining),
            Feed::Oversize { remaining } => (NackReason::Oversize, *remaining),
        };
        let now = self.clock.now_ms();
        let due = self
            .last_framing_nack_ms
            .is_none_or(|t| now.wrapping_sub(t) >= FRAMING_NACK_INTERVAL_MS);
        if due {
            self.last_framing_nack_ms = Some(now);
            self.encode(&nack(None, reason), tx);
        }
        Some(remaining)
    }

    /// Encodes `answer` into the accumulator's buffer (free between frames) and sends it
    /// through `tx`, in pieces; nothing is sent when it cannot be encoded.
    fn encode(&mut self, answer: &DeviceToHost, tx: &mut dyn FnMut(&[u8])) {
        // The buffer holds the largest answer (`TX_LEN`); a failure would only drop this answer.
        if let Some(buf) = self.acc.scratch() {
            encode_answer(answer, buf, tx);
        }
    }

    /// Takes one reading of the inertial sensor (or the fault that kept the driver from reading
    /// one), pushed by the target's driver at its rate (the device clock times it); see
    /// [`crate::imu`] and [`crate::balance`]. A fall detected here stops the motion and puts
    /// the outputs in their safe state at once.
    pub fn on_imu(&mut self, reading: ImuReading) {
        self.imu.push(reading);
        let now = self.clock.now_ms();
        match self.balance.push(reading, now, self.outputs_enabled) {
            Event::None => {}
            Event::Fall(_) => self.enter_safe_state(),
            Event::Fault => {
                if self.balance.config().on_fault == FaultAction::Stop {
                    self.engine.stop();
                }
            }
        }
    }

    /// The balance functions' report (what `GetImu` answers).
    pub fn imu_report(&self) -> ImuReport {
        self.balance.report()
    }

    /// Configures the balance functions (`SetBalance`).
    ///
    /// # Errors
    /// [`NackReason::ImuAbsent`] or [`NackReason::ImuFault`] for leveling without a working
    /// sensor.
    pub fn set_balance(&mut self, config: BalanceConfig) -> Result<(), NackReason> {
        self.balance.configure(config)
    }

    /// A fall: the motion ends and the outputs go to the safe state.
    fn enter_safe_state(&mut self) {
        self.engine.cancel();
        self.base_pose = None;
        if self.balance.config().safe_state == SafeState::Rest {
            let rest = engine::rest_angles(&self.config.robot);
            if let Ok(()) = rest.and_then(|r| self.hold_motion_target(r)) {
                return;
            }
        }
        self.stop_outputs();
    }

    /// Holds `pose` with the leveling correction `c` (roll, pitch) added, or the largest of
    /// [`LEVEL_SHARES`] of it within reach: the set point, the correction applied and whether
    /// it was limited; `None` when not even the pose itself maps.
    // Out of line: the body solve's locals stay out of the frame tick's stack frame.
    #[inline(never)]
    fn level_pose(&mut self, pose: &Pose, c: [f32; 2]) -> Option<([f32; 2], [f32; 2], bool)> {
        let pc = self.config.pose_config;
        let intended = [pose.roll_rad, pose.pitch_rad];
        for share in LEVEL_SHARES {
            let applied = [c[0] * share, c[1] * share];
            let leveled = Pose {
                roll_rad: pose.roll_rad + applied[0],
                pitch_rad: pose.pitch_rad + applied[1],
                ..*pose
            };
            let mut solution = BodySolution::default();
            let solved = self.solver.inverse_at_stance_into(
                &leveled,
                &BodyConfig::about_centre(pc.order),
                pc.stance_height_m,
                ReachPolicy::Reject,
                &mut solution,
            );
            if solved.is_ok() && self.hold_angles(&solution.angles_rad).is_ok() {
                let limited = share < 1.0 && (c[0] != 0.0 || c[1] != 0.0);
                return Some((intended, applied, limited));
            }
        }
        None
    }

    /// Makes `angles_rad` the held target when all twelve map through the calibration, the
    /// flags and the engine untouched (the leveling's re-solve of the held pose).
    fn hold_angles(&mut self, angles_rad: &[f32; 12]) -> Result<(), ()> {
        let mut pulses_half_us = [0u16; 12];
        for (i, p) in pulses_half_us.iter_mut().enumerate() {
            *p = self.pulse_maps[i]
                .pulse_half_us(angles_rad[i])
                .map_err(|_| ())?;
        }
        self.held = Some(Held {
            angles_rad: *angles_rad,
            pulses_half_us,
        });
        Ok(())
    }

    /// What the controller knows of its inertial sensor.
    pub fn imu(&self) -> &ImuState {
        &self.imu
    }

    /// Runs the link-loss failsafe and, at each servo frame boundary, the motion engine and the
    /// joint-speed limiter; call it from the main loop (at least every 20 ms).
    pub fn poll(&mut self) {
        self.failsafe_check();
        self.frame_tick();
    }

    fn failsafe_check(&mut self) {
        let LinkTimeout { timeout_ms, action } = self.config.link_timeout;
        if timeout_ms == 0 || !self.failsafe_armed {
            return;
        }
        let silent_ms = self.clock.now_ms().wrapping_sub(self.last_valid_ms);
        if silent_ms < u32::from(timeout_ms) {
            return;
        }
        self.failsafe = true;
        self.failsafe_armed = false;
        if action == LinkLossAction::Disable {
            self.stop_outputs();
        } else {
            // Holding a motion mid-stride would freeze it: it ends cleanly instead.
            self.engine.stop();
        }
    }

    /// One servo frame, when a frame boundary has passed: the engine's new target, then one
    /// limiter step of the outputs toward the held target. The boundaries are the outputs' PWM
    /// periods when they count them ([`ServoOutputs::periods_begun`]), else the clock's 20 ms.
    fn frame_tick(&mut self) {
        if !self.outputs_enabled {
            return;
        }
        let now = self.clock.now_ms();
        let frames = match self.outputs.periods_begun() {
            // Latched to the PWM periods: one frame per period at most, and none while the last
            // write waits for a period to show it.
            Some(period) => {
                let frames = period.wrapping_sub(self.next_frame);
                if frames == 0 || self.outputs.write_pending() {
                    return;
                }
                self.next_frame = period;
                frames
            }
            None => {
                let late_ms = now.wrapping_sub(self.next_frame);
                if late_ms > i32::MAX as u32 {
                    return; // Before the boundary.
                }
                let frames = 1 + late_ms / FRAME_MS;
                self.next_frame = self.next_frame.wrapping_add(frames * FRAME_MS);
                frames
            }
        };
        self.enabling_frame = false;
        let mut disable = false;
        // The leveling: its correction for this frame, taken by a sway or by the held pose.
        let had_correction = self.balance.correction_rad() != [0.0; 2];
        let correction = self.balance.level(frames as f32 * FRAME_S);
        let mut applied = None;
        if self.engine.is_active() {
            let kind = self.engine.status().kind;
            let levels = correction.filter(|_| self.engine.levels());
            let tick = self
                .engine
                .tick(frames, now, &self.out_rad, &self.solver, levels);
            if let Some(l) = tick.leveled {
                applied = Some((l.intended_rad, l.applied_rad, l.limited));
            }
            if let Some(q) = tick.target {
                if let Err(e) = self.hold_motion_target(q) {
                    self.engine.fail(e, &self.out_rad);
                }
            }
            disable = tick.disable_outputs;
            if !self.engine.is_active() {
                // Ended: at the stance, or at the rest pose after sit and rest.
                self.base_pose = match kind {
                    Some(MotionKind::Sit | MotionKind::Rest) => None,
                    _ => Some(Pose::default()),
                };
            }
        } else if let Some(pose) = self.base_pose {
            match correction {
                Some(c) => applied = self.level_pose(&pose, c),
                // Leveling just ended: the pose without its correction, once.
                None if had_correction => {
                    self.level_pose(&pose, [0.0; 2]);
                }
                None => {}
            }
        }
        self.balance
            .applied(applied, correction.unwrap_or([0.0; 2]));
        if let Some(held) = &self.held {
            if self
                .engine
                .limiter()
                .step(&mut self.out_rad, &held.angles_rad)
            {
                self.write_out();
            }
        }
        if disable {
            self.stop_outputs();
        }
    }

    /// Makes a motion setpoint the held target, after mapping it through the calibration.
    fn hold_motion_target(&mut self, angles_rad: [f32; 12]) -> Result<(), engine::Error> {
        let mut pulses_half_us = [0u16; 12];
        // `ServoId::ALL` is in index order: the position is the index, no bounds checks.
        for (i, s) in ServoId::ALL.into_iter().enumerate() {
            pulses_half_us[i] = self.pulse_maps[i]
                .pulse_half_us(angles_rad[i])
                .map_err(|fault| engine::Error::ServoRange { servo: s, fault })?;
        }
        self.held = Some(Held {
            angles_rad,
            pulses_half_us,
        });
        self.clamped = false;
        self.limited = false;
        Ok(())
    }

    /// Starts a motion of the engine (see [`engine`]): validated and start-checked first, refused
    /// with nothing changed. [`MotionCommand::StandUp`] with the outputs off holds the rest
    /// pose and enables the outputs at it.
    ///
    /// # Errors
    /// [`engine::Error`].
    pub fn start_motion(&mut self, request: &MotionCommand) -> Result<(), engine::Error> {
        self.balance.start_check(self.imu.last.as_ref())?;
        let setup = Setup {
            robot: &self.config.robot,
            solver: &self.solver,
            stance_height_m: self.config.pose_config.stance_height_m,
            order: self.config.pose_config.order,
            pulse_maps: &self.pulse_maps,
            outputs: if self.outputs_enabled {
                Some(&self.out_rad)
            } else {
                None
            },
            now_ms: self.clock.now_ms(),
        };
        let start = self.engine.start(request, &setup)?;
        if !self.outputs_enabled {
            let enabled = self.hold_motion_target(start).and_then(|()| {
                self.set_outputs(true)
                    .map_err(|_| engine::Error::OutputsOff)
            });
            if let Err(e) = enabled {
                self.engine.cancel();
                return Err(e);
            }
        }
        self.balance.clear_fall();
        Ok(())
    }

    /// Stops the running motion cleanly ([`Engine::stop`]).
    pub fn stop_motion(&mut self) {
        self.engine.stop();
    }

    /// Sets the running walk's velocity command (body frame; yaw counter-clockwise positive);
    /// it must be refreshed within the walk's timeout.
    ///
    /// # Errors
    /// [`engine::Error::NotWalking`], or the component beyond the gait's reach.
    pub fn set_velocity(&mut self, velocity: Velocity) -> Result<(), engine::Error> {
        let now = self.clock.now_ms();
        self.engine.set_velocity(velocity, now)
    }

    /// Sets the joint-speed limit of every output, rad/s (finite, > 0).
    ///
    /// # Errors
    /// [`engine::Error::Parameter`] naming `joint_speed_limit_rad_s`.
    pub fn set_joint_speed_limit(&mut self, rad_s: f32) -> Result<(), engine::Error> {
        self.engine.set_joint_speed_limit(rad_s)
    }

    /// The motion engine's status.
    pub fn motion_status(&self) -> engine::Status {
        self.engine.status()
    }

    /// The limiter in effect.
    pub fn limiter(&self) -> &Limiter {
        self.engine.limiter()
    }

    /// The angles on the outputs (`None` while they are stopped).
    pub fn output_angles(&self) -> Option<&[f32; 12]> {
        if self.outputs_enabled {
            Some(&self.out_rad)
        } else {
            None
        }
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

    /// `SetBodyPose`: the pose at the stance of the pose configuration's height, about the body
    /// centre in its rotation order.
    // Out of line: the body solve's locals stay out of the dispatcher's stack frame.
    #[inline(never)]
    fn set_body_pose(&mut self, pose: &Pose) -> Result<(), NackReason> {
        let c = &self.config.pose_config;
        // Solved into this frame's solution and read there (no solution returned through
        // memory, no flattened copy of its angles).
        let mut solution = BodySolution::default();
        self.solver.inverse_at_stance_into(
            pose,
            &BodyConfig::about_centre(c.order),
            c.stance_height_m,
            c.policy,
            &mut solution,
        )?;
        self.apply_solution(&solution)?;
        self.base_pose = Some(*pose);
        Ok(())
    }

    /// `SetFeet`: the feet in the body frame at the zero pose.
    // Out of line: the body solve's locals stay out of the dispatcher's stack frame.
    #[inline(never)]
    fn set_feet(&mut self, feet: &[[f32; 3]; 4]) -> Result<(), NackReason> {
        let feet = feet.map(|[x, y, z]| Vec3::new(x, y, z));
        // Through the general solve at the zero pose (the body frame is the world frame):
        // its one out-of-line copy, not a second for the feet in the body frame.
        let pc = &self.config.pose_config;
        let mut solution = BodySolution::default();
        self.solver.inverse_into(
            &Pose::default(),
            &BodyConfig::about_centre(pc.order),
            &feet,
            pc.policy,
            &mut solution,
        )?;
        self.apply_solution(&solution)?;
        self.base_pose = None;
        Ok(())
    }

    /// Applies a body solve's angles, read where the solve left them (no copy).
    fn apply_solution(&mut self, solution: &BodySolution) -> Result<(), NackReason> {
        let angles = &solution.angles_rad;
        let clamped = solution.any_clamped();
        // A clamp to the joint limits puts the angle exactly on a bound.
        let limits = &self.config.robot.limits;
        let limited = clamped
            && ServoId::ALL.iter().zip(angles).any(|(s, &a)| {
                let j = s.joint as usize;
                a == limits.min_rad[j] || a == limits.max_rad[j]
            });
        self.apply(angles, clamped, limited)
    }

    /// `SetJoints`, on angles the range check has found finite (`check_request`).
    fn set_joints(&mut self, angles: &[f32; 12]) -> Result<(), NackReason> {
        for (s, &a) in ServoId::ALL.iter().zip(angles) {
            if !self.config.robot.limits.admits(s.joint, a) {
                return Err(NackReason::JointLimit {
                    leg: s.leg,
                    joint: s.joint,
                });
            }
        }
        self.apply(angles, false, false)?;
        self.base_pose = None;
        Ok(())
    }

    /// Maps all twelve angles through the calibration; commits and drives only when all map.
    fn apply(
        &mut self,
        angles_rad: &[f32; 12],
        clamped: bool,
        limited: bool,
    ) -> Result<(), NackReason> {
        let mut pulses_half_us = [0u16; 12];
        // By reference: `into_iter` would copy the servo table into this frame first.
        for (i, s) in ServoId::ALL.iter().enumerate() {
            let a = angles_rad[i];
            if !a.is_finite() {
                return Err(NackReason::NonFinite);
            }
            pulses_half_us[i] =
                self.pulse_maps[i]
                    .pulse_half_us(a)
                    .map_err(|fault| NackReason::ServoRange {
                        leg: s.leg,
                        joint: s.joint,
                        fault,
                    })?;
        }
        // In place: each array is copied once, into the held target (built on the stack and
        // then moved into place, it was copied twice).
        match &mut self.held {
            Some(held) => {
                held.angles_rad = *angles_rad;
                held.pulses_half_us = pulses_half_us;
            }
            None => {
                self.held = Some(Held {
                    angles_rad: *angles_rad,
                    pulses_half_us,
                })
            }
        }
        self.clamped = clamped;
        self.limited = limited;
        // A direct setpoint takes over from a running motion (and is an explicit request after
        // a fall).
        self.engine.cancel();
        self.balance.clear_fall();
        if self.outputs_enabled && self.in_enabling_frame() {
            self.out_rad = *angles_rad;
            self.write_out();
        }
        Ok(())
    }

    /// True while no frame boundary has passed since the outputs were enabled: the enabling
    /// frame, whose target is written at once. Ended here as well as by the frame that follows
    /// it: that frame may not run before the next target comes (it waits while a write is
    /// pending, and a host that sends a target early in every period keeps one pending at each
    /// poll), and every target would then be written at once.
    fn in_enabling_frame(&mut self) -> bool {
        if self.enabling_frame {
            let boundary_passed = match self.outputs.periods_begun() {
                Some(period) => period != self.next_frame,
                None => self.clock.now_ms().wrapping_sub(self.next_frame) <= i32::MAX as u32,
            };
            if boundary_passed {
                self.enabling_frame = false;
            }
        }
        self.enabling_frame
    }

    /// Writes the output angles through the calibration; stops the outputs instead if one maps
    /// outside its travel (unreachable by construction: the outputs lie between admitted
    /// targets).
    fn write_out(&mut self) -> bool {
        let mut pulses = [0u16; 12];
        for (p, (c, &a)) in pulses
            .iter_mut()
            .zip(self.pulse_maps.iter().zip(&self.out_rad))
        {
            match c.pulse_half_us(a) {
                Ok(v) => *p = v,
                Err(_) => {
                    self.stop_outputs();
                    return false;
                }
            }
        }
        self.outputs.set_pulses(&pulses);
        true
    }

    fn stop_outputs(&mut self) {
        self.outputs.set_enabled(false);
        self.outputs_enabled = false;
        self.engine.cancel();
    }

    fn set_outputs(&mut self, enabled: bool) -> Result<(), NackReason> {
        if !enabled {
            self.stop_outputs();
            return Ok(());
        }
        if !self.outputs_enabled {
            // The enabling frame: the held target is written as it is (module docs).
            let Some(held) = &self.held else {
                self.stop_outputs();
                return Err(NackReason::InvalidArgument);
            };
            self.out_rad = held.angles_rad;
            self.enabling_frame = true;
            self.next_frame = match self.outputs.periods_begun() {
                Some(period) => period,
                None => self.clock.now_ms().wrapping_add(FRAME_MS),
            };
        }
        if !self.write_out() {
            return Err(NackReason::InvalidArgument);
        }
        if !self.outputs_enabled {
            self.outputs.set_enabled(true);
            self.outputs_enabled = true;
        }
        self.balance.clear_fall();
        Ok(())
    }

    fn set_calibration(&mut self, servo: ServoId, c: Calibration) -> Result<(), NackReason> {
        let map = c.pulse_map().map_err(NackReason::BadCalibration)?;
        let i = servo.index();
        // Both checks before anything changes: a refusal leaves the held pulses as they were.
        let held_pulse = match &self.held {
            Some(held) => Some(map.pulse_half_us(held.angles_rad[i]).map_err(|fault| {
                NackReason::ServoRange {
                    leg: servo.leg,
                    joint: servo.joint,
                    fault,
                }
            })?),
            None => None,
        };
        if self.outputs_enabled {
            // The outputs may still be on their way to the held angle.
            map.pulse_half_us(self.out_rad[i])
                .map_err(|fault| NackReason::ServoRange {
                    leg: servo.leg,
                    joint: servo.joint,
                    fault,
                })?;
        }
        if let (Some(held), Some(pulse)) = (&mut self.held, held_pulse) {
            held.pulses_half_us[i] = pulse;
        }
        if self.calibration[i] != c {
            self.calibration[i] = c;
            self.pulse_maps[i] = map;
            self.calibration_unsaved = true;
        }
        if self.outputs_enabled {
            self.write_out();
        }
        Ok(())
    }

    fn save_calibration(&mut self) -> Result<(), NackReason> {
        self.store
            .save(&mut self.storage, &self.calibration)
            .map_err(|_| NackReason::Storage)?;
        self.calibration_unsaved = false;
        self.calibration_default = false;
        Ok(())
    }

    fn set_pose_config(&mut self, p: PoseConfig) -> Result<(), NackReason> {
        validate_pose_config(&p).map_err(|_| NackReason::InvalidArgument)?;
        self.config.pose_config = p;
        Ok(())
    }
}

/// The device's receive path: the protocol's frame decoder (postcard) on the accumulator.
pub fn feed_request<'a>(acc: &mut Accumulator<RX_LEN>, bytes: &'a [u8]) -> Feed<'a, HostToDevice> {
    acc.feed::<HostToDevice>(bytes)
}

/// The device's answer encoder: [`encode_frame_in_pieces`] (postcard) of `answer` into `out`,
/// handed to `tx` in pieces as they are final; the frame's length, 0 (and nothing sent) when
/// it does not fit.
pub fn encode_answer(answer: &DeviceToHost, out: &mut [u8], tx: &mut dyn FnMut(&[u8])) -> usize {
    encode_frame_in_pieces(answer, out, tx).unwrap_or(0)
}

/// [`check_request_in`] for [`Device::answer`].
// Out of line: inlined, its copies of the request's values enlarge the dispatcher's frame.
#[inline(never)]
fn check_range(request: &Request, ranges: &Ranges) -> Result<(), NackReason> {
    check_request_in(request, ranges)
}

/// A request answered over the link: its sequence number, its frame's CRC, the answer.
#[derive(Debug, Clone, Copy)]
struct Answered {
    seq: u16,
    crc: u16,
    answer: DeviceToHost,
}

const fn nack(seq: Option<u16>, reason: NackReason) -> DeviceToHost {
    DeviceToHost::Nack { seq, reason }
}
