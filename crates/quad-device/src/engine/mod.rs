//! The motion engine: the papers' motions, stand-up and sit, run on the device one servo frame
//! at a time, every setpoint through one joint-speed limiter.
//!
//! The engine calls kin-core's motion code — the robot-free laws [`laws::SwayLaw`],
//! [`laws::YawTurnLaw`], [`laws::LegPathsLaw`] over the [`PathKind`](kin_core::motion::path::PathKind) paths (the robot is the
//! device's, in its body solver), and the [`Walker`] stepper — and kin-core's body IK; it holds
//! no law of its own. It is `no_std`, allocation-free and generic over the
//! kin-core [`Math`] backend, so the firmware and the host's simulated link run the same code.
//!
//! ## Frames
//! [`FRAME_MS`] = 20 ms (50 Hz, the servos' PWM period), timed by the device clock: each
//! [`crate::Device::poll`] that finds one or more frame boundaries passed runs one tick. A late
//! tick advances a running motion by the elapsed whole frames (motion time stays real time),
//! while each output still moves by at most one limiter step: a late loop makes the outputs lag
//! for a moment, never jump.
//!
//! ## The limiter
//! One [`Limiter`] between every setpoint and the outputs, whatever its source (`SetBodyPose`,
//! `SetFeet`, `SetJoints`, a motion): at each frame an output moves toward its target by at
//! most `limit · 20 ms` ([`DEFAULT_JOINT_SPEED_LIMIT_RAD_S`] by default; why is documented
//! there). The exception is the frame in which the outputs are enabled: the servos' positions
//! are unknown then, so what is written in that frame is the jump from wherever they are. The
//! device therefore writes direct setpoints at once only within the enabling frame (the servos
//! have not settled on a first pulse yet); later ones become the held target that the outputs
//! approach frame by frame. Stand-up makes that first frame harmless: it enables the outputs at
//! the [rest pose](rest_angles), where a robot lying on the ground already is.
//!
//! The readback reports the held target (the angles the host commanded or the motion's latest
//! setpoint, and their pulses); the outputs converge to it. [`crate::Device::output_angles`]
//! gives the angles on the outputs.
//!
//! ## Motions ([`MotionCommand`], the protocol's request)
//! Every motion begins with a synchronised joint-space ramp ([`Ramp`]) from the outputs to its
//! first setpoint and ends with one to the stance (nominal stance at the configuration's height
//! and rotation order, [`crate::Config::pose_config`]):
//! - [`MotionCommand::StandUp`]: enables the outputs at the rest pose if they are off, then ramps to
//!   the stance. [`MotionCommand::Sit`] ramps to the rest pose and holds it; [`MotionCommand::Rest`] does
//!   the same and then stops the outputs.
//! - [`MotionCommand::Sway`]: seed 001's roll or pitch sway (eq. 6–8), [`MotionCommand::YawTurn`]: its yaw
//!   turn with the crossed pairs (eq. 9–11 as corrected in `docs/papers.md`), with the yaw rate
//!   counter-clockwise positive (REP 103, as in kin-core and the walk's velocity command),
//!   [`MotionCommand::FootPath`]: a seed 000 foot path on one leg or all four under a held body,
//!   [`MotionCommand::StableTurn`]: kin-core's statically stable yaw turn (one leg at a time, the
//!   body shifted into the support triangle first; its cycles end with the body shifted, and
//!   the ramp to the stance brings it back). They
//!   run for their duration rounded up to whole periods, or until [`Engine::stop`]: a stop or
//!   the end takes effect at the next period boundary, where the joints are back at their start.
//! - [`MotionCommand::Walk`]: trot or walk from a velocity command ([`crate::Device::set_velocity`],
//!   counter-clockwise yaw positive), footholds re-planned at every lift-off. A stop, or a
//!   command not refreshed within its timeout, finishes the strides and parks the feet on the
//!   stance ([`Walker::stop`]): never a freeze mid-stride, never a snap.
//!
//! Starting a motion while another runs is refused ([`Error::Busy`]): the running one keeps
//! running. A direct setpoint request cancels a running motion at once (the host takes over; the
//! limiter still bounds every step), as does stopping the outputs.
//!
//! ## Frame numbers
//! [`Status`] reports the frame of the current stage ([`Status::frame`]: the ramp's steps, or
//! the run's frame, `t_s` in frames), the run frame from which the last velocity command
//! applies and the run frame at which a stop took effect (a stop, the walk's velocity timeout
//! or the failsafe's stop; the first of them). With the request they fix every frame of a
//! motion: the host replays them with this engine (protocol 2.3's `MotionFrames`, quad-host's
//! `replay`).
//!
//! ## Start check
//! A request from the wire has passed the protocol's range check already
//! ([`quad_protocol::range`]: every number within its field's range, the same check the host
//! runs before sending). A motion's parameters are then validated by kin-core's constructors
//! (finite, positive, in range; each refusal names its parameter), without their own reach checks (the start check covers
//! them) and without validating the robot again (the device validated it at boot). It runs the motion through the same per-frame code the running motion uses — the
//! motion's frame at a sample time, its body IK (which refuses unreachable feet and joint
//! limits), the servo travel — at a bounded set of samples, plus kin-core's singularity
//! measure on each leg ([`kin_core::leg::Solver::inverse_condition`] against
//! [`SINGULARITY_THRESHOLD`](kin_core::jacobian::SINGULARITY_THRESHOLD)). A refusal ([`Error`]) changes nothing.
//! - The sways, the yaw turn and the foot paths are periodic in their joint angles, so one
//!   period covers the whole motion: [`START_CHECK_SAMPLES`] evenly spaced instants, a
//!   multiple of 4, so that the sways' extremes (T/4, 3T/4) and the yaw turn's apexes and
//!   swing ends (T1/4, T1/2, 3T1/4, T1) are among them. Between the samples (the foot paths'
//!   corners) the run-time IK is the last check.
//! - The walk checks its first frame, then the [`Walker`]'s stride cylinder at its
//!   [`Walker::ENVELOPE_SAMPLES`] points ([`Walker::envelope`], the bound every velocity
//!   command is held to) through the IK and the servo travel; the singularity measure only at
//!   the first frame (the envelope's points cost a body IK each already).
//!
//! Its cost is bounded by the sample count: a law takes [`START_CHECK_SAMPLES`] + 1 body IKs
//! and 4 singularity measures per sample, a walk [`Walker::ENVELOPE_SAMPLES`] + 2 body IKs
//! and 4 singularity measures (`BENCHMARKS.md` has the cycles; they must stay well under the
//! firmware's watchdog, which resets the board). Kin-core's full [`kin_core::preflight::Checker`] (margins, extrema,
//! joint speeds) stays the host's tool. Ramps need no IK: they are straight in joint space
//! between two checked points. Should a run-time IK still fail, the motion stops: the outputs
//! ramp from the last valid setpoint to the stance and [`Status::fault`] tells why.

mod build;
pub mod limiter;
pub mod protocol;

pub use build::{check_travel, rest_angles, solve_frame};
pub use limiter::{
    limit_for_servo, Limiter, Ramp, DEFAULT_JOINT_SPEED_LIMIT_RAD_S, NO_LOAD_SPEED_SHARE,
};

use core::fmt;
use core::marker::PhantomData;
use kin_core::body::{self, BodyConfig};
use kin_core::motion;
use kin_core::motion::gait::Velocity;
use kin_core::motion::laws;
use kin_core::motion::walker::Walker;
use kin_core::preflight::Failure;
use kin_core::{IkError, Math, Robot, RotationOrder};
use quad_protocol::servo::{self, PulseMap};
pub use quad_protocol::DEFAULT_VELOCITY_TIMEOUT_MS;
use quad_protocol::{MotionCommand, MotionKind, MotionStage, ServoId};

/// One servo frame, ms.
pub const FRAME_MS: u32 = 20;

/// One servo frame, s.
pub const FRAME_S: f32 = 0.02;

/// Samples per period of a law's start check (module docs).
pub const START_CHECK_SAMPLES: u16 = 4;

/// Knee fold of the rest pose, rad short of the folded end of the knee's range (kin-core's
/// [`kin_core::robot::REST_KNEE_MARGIN_RAD`], where the rest pose is defined:
/// [`Robot::rest_leg`](kin_core::Robot::rest_leg)).
pub const REST_KNEE_MARGIN_RAD: f32 = kin_core::robot::REST_KNEE_MARGIN_RAD;

/// Most frames a late tick catches up with in a walk (1 s); beyond that, motion time is lost.
const MAX_CATCH_UP_FRAMES: u32 = 50;

/// Why a motion request was refused, or why a running motion stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is invalid or out of reach; the variant names it.
    Parameter(motion::Error),
    /// A start-check sample fails (reach, joint limit or singularity; module docs).
    Preflight(Failure),
    /// A sample maps outside a servo's calibrated travel.
    ServoRange {
        /// The servo.
        servo: ServoId,
        /// Below min or above max.
        fault: servo::Error,
    },
    /// The motion needs the outputs enabled (stand up first).
    OutputsOff,
    /// Another motion runs; stop it first.
    Busy,
    /// A velocity command arrived while no walk runs.
    NotWalking,
    /// A run-time IK failed (the motion was stopped).
    Ik(IkError),
    /// The inertial sensor finds the body tipped beyond the start limit
    /// ([`crate::balance::START_TILT_MAX_RAD`]): the robot is not on its feet.
    NotUpright,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Parameter(e) => write!(f, "{e}"),
            Error::Preflight(x) => write!(f, "{} at t = {} s: {}", x.leg, x.t_s, x.kind),
            Error::ServoRange { servo, fault } => {
                write!(f, "{servo:?} beyond its calibrated travel ({fault:?})")
            }
            Error::OutputsOff => f.write_str("the outputs are off (stand up first)"),
            Error::Busy => f.write_str("a motion is running (stop it first)"),
            Error::NotWalking => f.write_str("no walk is running"),
            Error::Ik(e) => write!(f, "unreachable setpoint: {e}"),
            Error::NotUpright => f.write_str("the body is not upright"),
        }
    }
}

impl core::error::Error for Error {}

impl From<motion::Error> for Error {
    fn from(e: motion::Error) -> Self {
        Error::Parameter(e)
    }
}

/// What the engine reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    /// The motion running, if any.
    pub kind: Option<MotionKind>,
    /// Its stage; [`MotionStage::Idle`] when none runs.
    pub stage: MotionStage,
    /// Motion time since the run began, s (0 when idle).
    pub t_s: f32,
    /// Phase within the motion's period (the walk's gait phase), in `[0, 1)` (0 when idle).
    pub phase: f32,
    /// Why the last motion stopped early, if it did.
    pub fault: Option<Error>,
    /// Frames of the current stage so far: the ramp's steps in [`MotionStage::Approach`] and
    /// [`MotionStage::Leave`], the run's frame (`t_s` in frames) in [`MotionStage::Run`] and
    /// [`MotionStage::Stopping`]; 0 when idle.
    pub frame: u32,
    /// The run frame from which the last velocity command applies ([`Engine::set_velocity`]);
    /// `None` before the first, and outside a walk.
    pub velocity_frame: Option<u32>,
    /// The run frame at which the stop took effect ([`Engine::stop`], or the walk's velocity
    /// timeout; the first of them); `None` while none did in the run.
    pub stop_frame: Option<u32>,
}

/// Twelve servo calibrations as their pulse maps, canonical order (the device's calibration
/// table, [`crate::store::Table`], validated and precomputed).
pub type PulseMaps = [PulseMap; 12];

/// What the robot and the device are set up with, for starting a motion.
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a, M: Math> {
    /// The robot.
    pub robot: &'a Robot,
    /// The body IK of `robot`: the device's one solver, whose per-leg constants are computed
    /// once, at boot.
    pub solver: &'a body::Solver<M>,
    /// Stance height, m.
    pub stance_height_m: f32,
    /// Rotation order of the poses.
    pub order: RotationOrder,
    /// The servo calibration, each servo's validated and precomputed for mapping angles to
    /// pulses ([`quad_protocol::servo::Calibration::pulse_map`]).
    pub pulse_maps: &'a PulseMaps,
    /// The angles on the outputs; `None` while they are off.
    pub outputs: Option<&'a [f32; 12]>,
    /// The device clock, ms.
    pub now_ms: u32,
}

/// What a tick asks of the device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    /// The new target, if it changed.
    pub target: Option<[f32; 12]>,
    /// Stop the outputs after this frame ([`MotionCommand::Rest`] ended).
    pub disable_outputs: bool,
    /// The leveling correction this frame took, when the tick was given one and the motion
    /// takes it (a sway running).
    pub leveled: Option<Leveled>,
}

/// A body-leveling correction as a frame took it ([`Engine::tick`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leveled {
    /// The roll and pitch the motion itself commands this frame (the level the correction
    /// holds), rad.
    pub intended_rad: [f32; 2],
    /// The correction of roll and pitch applied, rad: the one asked, or the largest share of
    /// it within reach ([`LEVEL_SHARES`]).
    pub applied_rad: [f32; 2],
    /// Less than the correction asked was applied (the robot's reach).
    pub limited: bool,
}

/// The shares of a leveling correction tried in turn through the body IK until one is within
/// reach: the whole, a half, a quarter, none (the motion's own frame, start-checked).
pub const LEVEL_SHARES: [f32; 4] = [1.0, 0.5, 0.25, 0.0];

/// A law's kin-core motion, without the robot (the device's solver holds it).
#[derive(Debug, Clone, Copy, PartialEq)]
enum LawMotion {
    Sway(laws::SwayLaw),
    YawTurn(laws::YawTurnLaw),
    LegPaths(laws::LegPathsLaw),
    StableTurn(laws::StableTurnLaw),
}

impl LawMotion {
    /// The rotation order of the law's poses.
    fn order(&self) -> RotationOrder {
        match self {
            LawMotion::Sway(m) => m.order,
            LawMotion::YawTurn(m) => m.params().order,
            LawMotion::LegPaths(_) => BodyConfig::default().order,
            LawMotion::StableTurn(m) => m.params().order,
        }
    }

    /// One period (one loop of the foot paths), s.
    fn period_s(&self) -> f32 {
        match self {
            LawMotion::Sway(m) => m.period_s,
            LawMotion::YawTurn(m) => m.params().step_period_s,
            LawMotion::LegPaths(m) => m.cycle_s,
            LawMotion::StableTurn(m) => m.params().cycle_s,
        }
    }
}

/// A law motion: the kin-core motion, the legs it moves, when it ends.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Law {
    motion: LawMotion,
    /// Legs that follow the motion; the others stay at their stance point (the foot paths'
    /// only: the other laws move every leg).
    legs: [bool; 4],
    period_s: f32,
    end_frame: Option<u32>,
}

#[derive(Debug, Clone, Copy)]
enum Program {
    Idle,
    /// Stand-up, sit or rest: one ramp.
    Pose {
        kind: MotionKind,
    },
    Law(Law),
    Walk {
        walker: Walker,
        timeout_ms: u16,
        last_command_ms: u32,
    },
}

/// The motion engine (module docs), on kin-core math backend `M`.
#[derive(Debug, Clone, Copy)]
pub struct Engine<M> {
    /// The motion running.
    program: Program,
    /// Where it is ([`MotionStage::Idle`] exactly when the program is idle).
    stage: MotionStage,
    /// Frames run since [`MotionStage::Run`] began.
    frame: u32,
    /// The ramp of the approach and the leave.
    ramp: Ramp,
    /// Where the motion ends (stance or rest angles).
    home: [f32; 12],
    /// The joint-speed limit of the ramps and the outputs.
    limiter: Limiter,
    /// Why the last motion stopped early.
    fault: Option<Error>,
    /// The run frame from which the last velocity command applies.
    velocity_frame: Option<u32>,
    /// The run frame at which the stop took effect.
    stop_frame: Option<u32>,
    _math: PhantomData<fn() -> M>,
}

/// Whole frames from 0 to the first period boundary at or after `t_s`.
fn frames_to_boundary(t_s: f32, period_s: f32) -> u32 {
    let periods = kin_core::math::ceil(t_s / period_s - 1e-4);
    let frames = kin_core::math::ceil(periods * period_s / FRAME_S - 1e-3);
    // NaN and every negative fail the comparison; `+∞` saturates in the cast.
    if frames >= 0.0 {
        frames as u32
    } else {
        u32::MAX
    }
}

impl<M: Math> Engine<M> {
    /// An idle engine whose ramps and outputs move at `limiter`'s speed.
    pub const fn new(limiter: Limiter) -> Self {
        Engine {
            program: Program::Idle,
            stage: MotionStage::Idle,
            ramp: Ramp::idle(),
            home: [0.0; 12],
            frame: 0,
            fault: None,
            velocity_frame: None,
            stop_frame: None,
            limiter,
            _math: PhantomData,
        }
    }

    /// The one joint-speed limiter of the device.
    pub const fn limiter(&self) -> &Limiter {
        &self.limiter
    }

    /// Sets the joint-speed limit, rad/s; ramps built from now on use it (as does every output
    /// step).
    ///
    /// # Errors
    /// [`Limiter::new`]'s, naming `joint_speed_limit_rad_s`; nothing changes then.
    pub fn set_joint_speed_limit(&mut self, rad_s: f32) -> Result<(), Error> {
        self.limiter = Limiter::new(rad_s)?;
        Ok(())
    }

    /// True while a motion runs.
    pub fn is_active(&self) -> bool {
        // A pattern, not `!=`: comparing whole programs would compare every walker field.
        !matches!(self.program, Program::Idle)
    }

    /// Validates and start-checks `request` against `setup` and, when it passes, starts it: the
    /// first tick begins the ramp from `setup.outputs` (for [`MotionCommand::StandUp`] with the
    /// outputs off, from the rest pose at which the device enables them; its returned angles).
    /// A refusal changes nothing.
    ///
    /// # Errors
    /// See [`Error`].
    pub fn start(
        &mut self,
        request: &MotionCommand,
        setup: &Setup<'_, M>,
    ) -> Result<[f32; 12], Error> {
        if self.is_active() {
            return Err(Error::Busy);
        }
        let (first, home, start) = match request {
            MotionCommand::StandUp | MotionCommand::Sit | MotionCommand::Rest => {
                let stand_up = matches!(request, MotionCommand::StandUp);
                // Sit and rest ramp from the outputs, which must be on; stand-up enables them at
                // the rest pose when they are off.
                let out = match setup.outputs {
                    Some(o) => Some(*o),
                    None if stand_up => None,
                    None => return Err(Error::OutputsOff),
                };
                let rest = rest_angles(setup.robot)?;
                check_travel(setup.pulse_maps, &rest)?;
                let target = if stand_up {
                    build::stance_angles::<M>(setup)?
                } else {
                    rest
                };
                self.program = Program::Pose {
                    kind: match request {
                        MotionCommand::StandUp => MotionKind::StandUp,
                        MotionCommand::Sit => MotionKind::Sit,
                        _ => MotionKind::Rest,
                    },
                };
                (target, target, out.unwrap_or(rest))
            }
            _ => {
                let out = *setup.outputs.ok_or(Error::OutputsOff)?;
                let home = build::stance_angles::<M>(setup)?;
                let first = match request {
                    MotionCommand::Walk { .. } => Self::walk(request, setup, &mut self.program)?,
                    _ => Self::law(request, setup, &mut self.program)?,
                };
                (first, home, out)
            }
        };
        self.stage = MotionStage::Approach;
        self.ramp.restart(&start, &first, &self.limiter);
        self.home = home;
        self.frame = 0;
        self.fault = None;
        self.velocity_frame = None;
        self.stop_frame = None;
        Ok(start)
    }

    /// Sets a walk's velocity command at `now_ms`.
    ///
    /// # Errors
    /// [`Error::NotWalking`] outside a running walk (or once it stops); the walker's
    /// [`Walker::check_velocity`] error naming the component.
    pub fn set_velocity(&mut self, v: Velocity, now_ms: u32) -> Result<(), Error> {
        match &mut self.program {
            Program::Walk {
                walker,
                last_command_ms,
                ..
            } if !walker.is_stopping() && self.stage != MotionStage::Leave => {
                walker.set_velocity::<M>(v)?;
                *last_command_ms = now_ms;
                // The next tick's first step is the first with `v` (frame 0 before the run).
                self.velocity_frame = Some(self.frame);
                Ok(())
            }
            _ => Err(Error::NotWalking),
        }
    }

    /// Stops the running motion cleanly: a law at its next period boundary, a walk once its
    /// strides are finished, then a ramp to the stance. A ramp of stand-up, sit or rest runs to
    /// its end.
    pub fn stop(&mut self) {
        match &mut self.program {
            Program::Law(law)
                if self.stage == MotionStage::Run || self.stage == MotionStage::Approach =>
            {
                let t = self.frame as f32 * FRAME_S;
                let end = frames_to_boundary(t, law.period_s);
                law.end_frame = Some(law.end_frame.map_or(end, |e| e.min(end)));
            }
            Program::Walk { walker, .. } => walker.stop(),
            _ => return,
        }
        if self.stage == MotionStage::Run {
            self.stop_frame = Some(self.frame);
        }
        // One tail for both programs: one ramp call site, not two.
        if self.stage == MotionStage::Approach {
            // Not started: ramp back from where the ramp is.
            let from = self.ramp.point();
            self.leave(&from);
        } else if self.stage == MotionStage::Run {
            self.stage = MotionStage::Stopping;
        }
    }

    /// Ends the motion at once (the outputs stopped, or a direct setpoint took over).
    pub fn cancel(&mut self) {
        self.program = Program::Idle;
        self.stage = MotionStage::Idle;
    }

    fn leave(&mut self, from: &[f32; 12]) {
        self.stage = MotionStage::Leave;
        self.ramp.restart(from, &self.home, &self.limiter);
    }

    /// The status.
    pub fn status(&self) -> Status {
        let t_s = self.frame as f32 * FRAME_S;
        let (kind, phase) = match &self.program {
            // Idle: no stage, time or phase of a motion gone by (only its fault, if any).
            Program::Idle => {
                return Status {
                    kind: None,
                    stage: MotionStage::Idle,
                    t_s: 0.0,
                    phase: 0.0,
                    fault: self.fault,
                    frame: 0,
                    velocity_frame: None,
                    stop_frame: None,
                };
            }
            Program::Pose { kind } => (Some(*kind), 0.0),
            Program::Law(law) => (Some(law.motion_kind()), motion_phase(t_s, law.period_s)),
            Program::Walk { walker, .. } => (Some(MotionKind::Walk), walker.phase()),
        };
        let frame = match self.stage {
            MotionStage::Approach | MotionStage::Leave => self.ramp.steps_done(),
            _ => self.frame,
        };
        Status {
            kind,
            stage: self.stage,
            t_s,
            phase,
            fault: self.fault,
            frame,
            velocity_frame: self.velocity_frame,
            stop_frame: self.stop_frame,
        }
    }

    /// True while the running motion takes a leveling correction: a sway, running or
    /// stopping at the end of its period (not its ramps).
    pub fn levels(&self) -> bool {
        matches!(
            (&self.program, self.stage),
            (
                Program::Law(Law {
                    motion: LawMotion::Sway(_),
                    ..
                }),
                MotionStage::Run | MotionStage::Stopping
            )
        )
    }

    /// One tick after `frames` (≥ 1) frame boundaries, at `now_ms`, with the outputs at `out`,
    /// the motion's frames solved by `solver` (the [`Setup::solver`] it started with): the new
    /// target, if any. `correction` (roll, pitch, rad) is added to a sway's body pose
    /// ([`Engine::levels`]) before its IK, or the largest share of it that is within reach
    /// ([`LEVEL_SHARES`]); [`Tick::leveled`] tells what was applied.
    pub fn tick(
        &mut self,
        frames: u32,
        now_ms: u32,
        out: &[f32; 12],
        solver: &body::Solver<M>,
        correction: Option<[f32; 2]>,
    ) -> Tick {
        let mut tick = Tick {
            target: None,
            disable_outputs: false,
            leveled: None,
        };
        match self.stage {
            MotionStage::Idle => tick,
            MotionStage::Approach | MotionStage::Leave => {
                if !self.ramp.finished() {
                    tick.target = Some(self.ramp.advance());
                    return tick;
                }
                // The ramp is at its end: wait for the outputs (the limiter) to get there.
                if out != self.ramp.to() {
                    return tick;
                }
                if self.stage == MotionStage::Leave || matches!(self.program, Program::Pose { .. })
                {
                    tick.disable_outputs = matches!(
                        self.program,
                        Program::Pose {
                            kind: MotionKind::Rest
                        }
                    );
                    self.cancel();
                    return tick;
                }
                self.stage = MotionStage::Run;
                self.frame = 0;
                if let Program::Walk {
                    last_command_ms, ..
                } = &mut self.program
                {
                    *last_command_ms = now_ms;
                }
                tick
            }
            MotionStage::Run | MotionStage::Stopping => {
                // Borrowed, not copied: a walker is a few hundred bytes of stack.
                let (result, ended) = match &mut self.program {
                    Program::Law(law) => {
                        let mut frame = self.frame.saturating_add(frames);
                        let end = law.end_frame.filter(|&e| frame >= e);
                        if let Some(e) = end {
                            frame = e;
                        }
                        self.frame = frame;
                        let t_s = frame as f32 * FRAME_S;
                        let q = match (&law.motion, correction) {
                            (LawMotion::Sway(_), Some(c)) => {
                                let (q, leveled) = Self::law_setpoint_leveled(law, t_s, solver, c);
                                tick.leveled = leveled;
                                q
                            }
                            _ => Self::law_setpoint(law, t_s, solver),
                        };
                        (q, end.is_some())
                    }
                    Program::Walk {
                        walker,
                        timeout_ms,
                        last_command_ms,
                    } => {
                        if now_ms.wrapping_sub(*last_command_ms) > u32::from(*timeout_ms) {
                            walker.stop();
                            if self.stage == MotionStage::Run {
                                self.stop_frame = Some(self.frame);
                            }
                            self.stage = MotionStage::Stopping;
                        }
                        for _ in 0..frames.min(MAX_CATCH_UP_FRAMES) {
                            // FRAME_S > 0: the step cannot fail.
                            let _ = walker.step::<M>(FRAME_S);
                        }
                        self.frame = self.frame.saturating_add(frames);
                        (
                            Self::walk_setpoint(solver, walker.params().order, &walker.feet()),
                            walker.is_stopped(),
                        )
                    }
                    _ => {
                        self.cancel();
                        return tick;
                    }
                };
                if let (true, Ok(q)) = (ended, result) {
                    self.leave(&q);
                }
                match result {
                    Ok(q) => tick.target = Some(q),
                    Err(e) => self.fail(Error::Ik(e), out),
                }
                tick
            }
        }
    }

    /// Stops the motion after a run-time failure: a ramp from `from` to the stance.
    pub fn fail(&mut self, e: Error, from: &[f32; 12]) {
        self.fault = Some(e);
        if self.is_active() {
            self.leave(from);
        }
    }
}

impl Law {
    fn motion_kind(&self) -> MotionKind {
        match self.motion {
            LawMotion::Sway(_) => MotionKind::Sway,
            LawMotion::YawTurn(_) => MotionKind::YawTurn,
            LawMotion::LegPaths(_) => MotionKind::FootPath,
            LawMotion::StableTurn(_) => MotionKind::StableTurn,
        }
    }
}

/// `t/T` wrapped into `[0, 1)`.
fn motion_phase(t_s: f32, period_s: f32) -> f32 {
    let x = t_s / period_s;
    let r = x - kin_core::math::floor(x);
    if (0.0..1.0).contains(&r) {
        r
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::{frames_to_boundary, FRAME_S};

    #[test]
    fn frames_to_boundary_is_max_unless_finite_and_non_negative() {
        let reference = |t_s: f32, period_s: f32| {
            let periods = kin_core::math::ceil(t_s / period_s - 1e-4);
            let frames = kin_core::math::ceil(periods * period_s / FRAME_S - 1e-3);
            if frames.is_finite() && frames >= 0.0 {
                frames as u32
            } else {
                u32::MAX
            }
        };
        let values = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -1.0,
            -0.0,
            0.0,
            0.013,
            0.5,
            2.0,
            1e30,
        ];
        for t in values {
            for p in values {
                assert_eq!(frames_to_boundary(t, p), reference(t, p), "{t} {p}");
            }
        }
    }
}
