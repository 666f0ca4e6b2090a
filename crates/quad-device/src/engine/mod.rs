//! The motion engine: the papers' motions, stand-up and sit, run on the device one servo frame
//! at a time, every setpoint through one joint-speed limiter.
//!
//! The engine calls kin-core's motion code — the robot-free laws [`laws::SwayLaw`],
//! [`laws::YawTurnLaw`], [`laws::LegPathsLaw`] over the [`PathKind`] paths (the robot is the
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
//! ## Motions ([`Request`])
//! Every motion begins with a synchronised joint-space ramp ([`Ramp`]) from the outputs to its
//! first setpoint and ends with one to the stance (nominal stance at the configuration's height
//! and rotation order, [`crate::Config::pose_config`]):
//! - [`Request::StandUp`]: enables the outputs at the rest pose if they are off, then ramps to
//!   the stance. [`Request::Sit`] ramps to the rest pose and holds it; [`Request::Rest`] does
//!   the same and then stops the outputs.
//! - [`Request::Sway`]: seed 001's roll or pitch sway (eq. 6–8), [`Request::YawTurn`]: its yaw
//!   turn with the crossed pairs (eq. 9–11 as corrected in `docs/papers.md`), with the yaw rate
//!   counter-clockwise positive (REP 103, as in kin-core and the walk's velocity command),
//!   [`Request::FootPath`]: a seed 000 foot path on one leg or all four under a held body. They
//!   run for their duration rounded up to whole periods, or until [`Engine::stop`]: a stop or
//!   the end takes effect at the next period boundary, where the joints are back at their start.
//! - [`Request::Walk`]: trot or walk from a velocity command ([`crate::Device::set_velocity`],
//!   counter-clockwise yaw positive), footholds re-planned at every lift-off. A stop, or a
//!   command not refreshed within its timeout, finishes the strides and parks the feet on the
//!   stance ([`Walker::stop`]): never a freeze mid-stride, never a snap.
//!
//! Starting a motion while another runs is refused ([`Error::Busy`]): the running one keeps
//! running. A direct setpoint request cancels a running motion at once (the host takes over; the
//! limiter still bounds every step), as does stopping the outputs.
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
//! [`SINGULARITY_THRESHOLD`]). A refusal ([`Error`]) changes nothing.
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

pub mod limiter;
pub mod protocol;

pub use limiter::{
    limit_for_servo, Limiter, Ramp, DEFAULT_JOINT_SPEED_LIMIT_RAD_S, NO_LOAD_SPEED_SHARE,
};

use core::fmt;
use core::marker::PhantomData;
use kin_core::body::{self, BodyConfig, BodySolution, Pose};
use kin_core::jacobian::SINGULARITY_THRESHOLD;
use kin_core::motion::gait::{GaitParams, Pattern, Velocity};
use kin_core::motion::laws::{self, Axis};
use kin_core::motion::path::{AnyPath, PathKind, Stride};
use kin_core::motion::walker::{Walker, WalkerParams};
use kin_core::motion::{self, Frame, Param};
use kin_core::preflight::{Failure, FailureKind};
use kin_core::{IkError, Joint, JointAngles, LegId, Math, ReachPolicy, Robot, RotationOrder, Vec3};
use quad_protocol::servo::{self, PulseMap};
use quad_protocol::ServoId;

/// One servo frame, ms.
pub const FRAME_MS: u32 = 20;

/// One servo frame, s.
pub const FRAME_S: f32 = 0.02;

/// Samples per period of a law's start check (module docs).
pub const START_CHECK_SAMPLES: u16 = 4;

/// Default timeout of a walk's velocity command, ms: five missed commands at the 10 Hz a
/// teleoperating host sends.
pub const DEFAULT_VELOCITY_TIMEOUT_MS: u16 = 500;

/// Knee fold of the rest pose, rad short of the folded end of the knee's range.
pub const REST_KNEE_MARGIN_RAD: f32 = 0.2;

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
        }
    }
}

impl core::error::Error for Error {}

impl From<motion::Error> for Error {
    fn from(e: motion::Error) -> Self {
        Error::Parameter(e)
    }
}

/// A motion to start.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Request {
    /// Outputs on at the rest pose (when off), then a ramp to the stance.
    StandUp,
    /// A ramp to the rest pose, held.
    Sit,
    /// A ramp to the rest pose, then the outputs off.
    Rest,
    /// Seed 001's sway (eq. 6–8) about `axis`: `angle = A·sin(2πt/T)`, feet fixed.
    Sway {
        /// Roll (eq. 6), pitch (eq. 8) or yaw.
        axis: Axis,
        /// Amplitude `A`, rad.
        amplitude_rad: f32,
        /// Period `T`, s.
        period_s: f32,
        /// Duration, s (rounded up to whole periods); `None`: until stopped.
        duration_s: Option<f32>,
    },
    /// Seed 001's yaw turn (eq. 9–11, corrected) about the body centre.
    YawTurn {
        /// Turn rate, rad/s, counter-clockwise positive (REP 103).
        yaw_rate_rad_s: f32,
        /// Step period `T1` (both pairs), s.
        step_period_s: f32,
        /// Lift `h_K`, m.
        lift_height_m: f32,
        /// Duration, s (rounded up to whole periods); `None`: until stopped.
        duration_s: Option<f32>,
    },
    /// A seed 000 foot path around the stance point of one leg or all four, body held.
    FootPath {
        /// The path's shape.
        path: PathKind,
        /// The leg; `None`: all four, in phase.
        leg: Option<LegId>,
        /// Stride (length along x), m.
        stride_m: f32,
        /// Lift, m (the semicircle's is half its stride).
        step_height_m: f32,
        /// Stance fraction of the loop, in (0, 1).
        duty_factor: f32,
        /// One loop, s.
        cycle_s: f32,
        /// Duration, s (rounded up to whole loops); `None`: until stopped.
        duration_s: Option<f32>,
    },
    /// Trot or walk from a velocity command (zero at the start).
    Walk(WalkRequest),
}

impl Request {
    /// Seed 000 Fig. 8's rectangle (stride 0.1 m, lift 0.05 m, 3 s per loop, duty 1/3) on
    /// `leg` (or all four) for `duration_s`.
    pub fn seed000_rectangle(leg: Option<LegId>, duration_s: Option<f32>) -> Request {
        let s = motion::path::Rectangle::seed000().stride();
        Request::FootPath {
            path: PathKind::Rectangle,
            leg,
            stride_m: s.length_m(),
            step_height_m: s.height_m(),
            duty_factor: s.duty_factor(),
            cycle_s: 3.0,
            duration_s,
        }
    }

    /// Seed 001's sway about `axis` (A = 0.2 rad, T = 20 s) for `duration_s`.
    pub fn seed001_sway(axis: Axis, duration_s: Option<f32>) -> Request {
        let p = laws::SwayParams::seed001(axis);
        Request::Sway {
            axis,
            amplitude_rad: p.amplitude_rad,
            period_s: p.period_s,
            duration_s,
        }
    }

    /// Seed 001's yaw turn (ω_z = 0.085 rad/s clockwise, T1 = 6 s, h_K = 0.3 m) for
    /// `duration_s`.
    pub fn seed001_yaw_turn(duration_s: Option<f32>) -> Request {
        let p = laws::YawTurnParams::seed001();
        Request::YawTurn {
            yaw_rate_rad_s: p.yaw_rate_rad_s,
            step_period_s: p.step_period_s,
            lift_height_m: p.lift_height_m,
            duration_s,
        }
    }

    /// What kind of motion this is.
    pub const fn kind(&self) -> Kind {
        match self {
            Request::StandUp => Kind::StandUp,
            Request::Sit => Kind::Sit,
            Request::Rest => Kind::Rest,
            Request::Sway { .. } => Kind::Sway,
            Request::YawTurn { .. } => Kind::YawTurn,
            Request::FootPath { .. } => Kind::FootPath,
            Request::Walk(_) => Kind::Walk,
        }
    }
}

/// Parameters of [`Request::Walk`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkRequest {
    /// Trot or walk.
    pub pattern: Pattern,
    /// Body height (hip plane above the ground) while walking, m.
    pub body_height_m: f32,
    /// Swing apex above the ground, m.
    pub step_height_m: f32,
    /// Gait cycle, s.
    pub cycle_s: f32,
    /// The velocity command's timeout, ms (> 0).
    pub velocity_timeout_ms: u16,
}

impl WalkRequest {
    /// `pattern` at `body_height_m` with kin-core's default cycle and step height
    /// ([`kin_core::motion::gait::GaitParams::new`]) and [`DEFAULT_VELOCITY_TIMEOUT_MS`].
    pub fn new(pattern: Pattern, body_height_m: f32) -> WalkRequest {
        WalkRequest {
            pattern,
            body_height_m,
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * body_height_m,
            cycle_s: GaitParams::DEFAULT_CYCLE_S,
            velocity_timeout_ms: DEFAULT_VELOCITY_TIMEOUT_MS,
        }
    }
}

/// The kinds of motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Kind {
    /// [`Request::StandUp`].
    StandUp,
    /// [`Request::Sit`].
    Sit,
    /// [`Request::Rest`].
    Rest,
    /// [`Request::Sway`].
    Sway,
    /// [`Request::YawTurn`].
    YawTurn,
    /// [`Request::FootPath`].
    FootPath,
    /// [`Request::Walk`].
    Walk,
}

/// Where a motion is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Ramping from the outputs to the motion's first setpoint.
    Approach,
    /// Running.
    Run,
    /// Stop requested: running to the end of the period (or of the strides).
    Stopping,
    /// Ramping to the stance (or the rest pose).
    Leave,
}

/// What the engine reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    /// The motion running, if any.
    pub kind: Option<Kind>,
    /// Its stage.
    pub stage: Stage,
    /// Motion time since the run began, s.
    pub t_s: f32,
    /// Phase within the motion's period (the walk's gait phase), in `[0, 1)`.
    pub phase: f32,
    /// Why the last motion stopped early, if it did.
    pub fault: Option<Error>,
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
    /// Stop the outputs after this frame ([`Request::Rest`] ended).
    pub disable_outputs: bool,
}

/// A law's kin-core motion, without the robot (the device's solver holds it).
#[derive(Debug, Clone, Copy, PartialEq)]
enum LawMotion {
    Sway(laws::SwayLaw),
    YawTurn(laws::YawTurnLaw),
    LegPaths(laws::LegPathsLaw),
}

impl LawMotion {
    /// The rotation order of the law's poses.
    fn order(&self) -> RotationOrder {
        match self {
            LawMotion::Sway(m) => m.order,
            LawMotion::YawTurn(m) => m.params().order,
            LawMotion::LegPaths(_) => BodyConfig::default().order,
        }
    }

    /// One period (one loop of the foot paths), s.
    fn period_s(&self) -> f32 {
        match self {
            LawMotion::Sway(m) => m.period_s,
            LawMotion::YawTurn(m) => m.params().step_period_s,
            LawMotion::LegPaths(m) => m.cycle_s,
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
        kind: Kind,
    },
    Law(Law),
    Walk {
        walker: Walker,
        timeout_ms: u16,
        last_command_ms: u32,
    },
}

/// The motion engine (module docs), on kin-core math backend `M`.
///
/// The fields are laid out in declaration order, the small ones first: on the AVR a field
/// within 63 bytes of the engine's address is one load instruction, one beyond costs a pointer
/// adjustment at each access.
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub struct Engine<M> {
    stage: Stage,
    /// Frames run since [`Stage::Run`] began.
    frame: u32,
    limiter: Limiter,
    fault: Option<Error>,
    program: Program,
    ramp: Ramp,
    /// Where the motion ends (stance or rest angles).
    home: [f32; 12],
    _math: PhantomData<fn() -> M>,
}

/// The rest pose of `robot`, order FL, FR, RL, RR: legs folded under the body — abduction 0,
/// knee [`REST_KNEE_MARGIN_RAD`] short of the folded end of its range, hip at minus half the
/// knee, which puts each foot below its hip joint. The body then rests low, on the ground or on
/// its folded legs. Refused when a joint limit excludes it.
#[inline(never)]
pub fn rest_angles(robot: &Robot) -> Result<[f32; 12], Error> {
    let l = &robot.limits;
    let knee = match robot.knee_bend {
        kin_core::KneeBend::Backward => l.min_rad[2] + REST_KNEE_MARGIN_RAD,
        kin_core::KneeBend::Forward => l.max_rad[2] - REST_KNEE_MARGIN_RAD,
    };
    let leg = [0.0, -0.5 * knee, knee];
    for (j, &a) in Joint::ALL.iter().zip(&leg) {
        if !l.admits(*j, a) {
            return Err(Error::Preflight(Failure {
                sample: 0,
                t_s: 0.0,
                leg: LegId::FL,
                kind: FailureKind::Unreachable(kin_core::Unreachable::JointLimit(*j)),
            }));
        }
    }
    let mut out = [0.0; 12];
    for c in out.chunks_exact_mut(3) {
        c.copy_from_slice(&leg);
    }
    Ok(out)
}

/// The body IK of one motion frame (poses in rotation order `order`, about the body centre)
/// through `solver`, the device's one body solver (the one `SetBodyPose` and `SetFeet` use),
/// so the firmware holds one copy of it and computes its constants once.
pub fn solve_frame<M: Math>(
    solver: &body::Solver<M>,
    order: RotationOrder,
    frame: &Frame,
) -> Result<[f32; 12], IkError> {
    // Solved into a solution here, its angles read from it (none returned and then copied).
    let mut solution = BodySolution::default();
    solver.inverse_into(
        &frame.pose,
        &BodyConfig::about_centre(order),
        &frame.feet_in_world,
        ReachPolicy::Reject,
        &mut solution,
    )?;
    Ok(solution.angles_rad)
}

/// Checks that `angles` map within every servo's calibrated travel (`pulse_maps`: each
/// servo's calibration as its [`PulseMap`]).
#[inline(never)]
pub fn check_travel(pulse_maps: &PulseMaps, angles: &[f32; 12]) -> Result<(), Error> {
    for (s, (c, &a)) in ServoId::ALL.iter().zip(pulse_maps.iter().zip(angles)) {
        c.pulse_half_us(a)
            .map_err(|fault| Error::ServoRange { servo: *s, fault })?;
    }
    Ok(())
}

/// The stance angles of a setup: the nominal stance at its height, zero pose.
#[inline(never)]
fn stance_angles<M: Math>(s: &Setup<'_, M>) -> Result<[f32; 12], Error> {
    let frame = Frame {
        pose: Pose::default(),
        feet_in_world: s.robot.stance_feet(s.stance_height_m),
        contact: [motion::Contact::Stance; 4],
    };
    // Matched in place, not `map_err(…)?`: one copy of the angles fewer on the way.
    match solve_frame(s.solver, s.order, &frame) {
        Ok(q) => check_travel(s.pulse_maps, &q).map(|()| q),
        Err(e) => Err(Error::Ik(e)),
    }
}

/// One sample of a start check (module docs): `solved` is what the per-frame path (the
/// frame's body IK, [`solve_frame`]) gave at sample `sample`, time `t_s`; then the servo
/// travel and, when `singularity`, each leg's singularity measure. The sample's setpoint when
/// it passes (borrowed from `solved`: the angles are not copied on the way).
#[inline(never)]
fn check_sample<'r, M: Math>(
    s: &Setup<'_, M>,
    sample: u16,
    t_s: f32,
    solved: &'r Result<[f32; 12], IkError>,
    singularity: bool,
) -> Result<&'r [f32; 12], Error> {
    let failure = |leg, kind| {
        Error::Preflight(Failure {
            sample: u32::from(sample),
            t_s,
            leg,
            kind,
        })
    };
    let q = solved
        .as_ref()
        .map_err(|e| failure(e.leg, FailureKind::Unreachable(e.kind)))?;
    check_travel(s.pulse_maps, q)?;
    if !singularity {
        return Ok(q);
    }
    let solver = s.solver.leg();
    for (&leg, a) in LegId::ALL.iter().zip(q.chunks_exact(3)) {
        let ic = solver.inverse_condition(leg, JointAngles::new(a[0], a[1], a[2]));
        if !(ic >= SINGULARITY_THRESHOLD) {
            return Err(failure(
                leg,
                FailureKind::Singular {
                    inverse_condition: ic,
                },
            ));
        }
    }
    Ok(q)
}

/// The kin-core motion of a law request, written into `motion` (its parameters checked, not
/// its reach: the start check does that).
///
/// The laws carry no robot (the device's solver holds it): one builder for the three, each
/// law's variant set first and its stance feet then written where they stay.
#[inline(never)]
fn law_motion<M: Math>(
    request: &Request,
    s: &Setup<'_, M>,
    motion: &mut LawMotion,
) -> Result<(), Error> {
    let h = s.stance_height_m;
    match *request {
        Request::Sway {
            axis,
            amplitude_rad,
            period_s,
            ..
        } => {
            *motion = LawMotion::Sway(laws::SwayLaw {
                axis,
                amplitude_rad,
                period_s,
                roll0_rad: 0.0,
                pitch0_rad: 0.0,
                yaw0_rad: 0.0,
                order: s.order,
                feet_in_world: [Vec3::ZERO; 4],
            });
            if let LawMotion::Sway(m) = motion {
                m.feet_in_world = s.robot.stance_feet(h);
                m.check()?;
            }
        }
        Request::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            ..
        } => {
            *motion = LawMotion::YawTurn(laws::YawTurnLaw::without_reach_check::<M>(
                laws::YawTurnLawParams {
                    yaw_rate_rad_s,
                    step_period_s,
                    lift_height_m,
                    yaw0_rad: 0.0,
                    roll0_rad: 0.0,
                    pitch0_rad: 0.0,
                    order: s.order,
                    stance_feet: s.robot.stance_feet(h),
                },
            )?);
        }
        Request::FootPath {
            path,
            stride_m,
            step_height_m,
            duty_factor,
            cycle_s,
            ..
        } => {
            let stride = Stride::new(stride_m, step_height_m, duty_factor)?;
            *motion = LawMotion::LegPaths(laws::LegPathsLaw {
                path: AnyPath::new(path, stride),
                cycle_s,
                phase_offsets: [0.0; 4],
                stance_feet: [Vec3::ZERO; 4],
            });
            if let LawMotion::LegPaths(m) = motion {
                m.stance_feet = s.robot.stance_feet(h);
                m.check()?;
            }
        }
        _ => return Err(Error::Busy),
    }
    Ok(())
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

/// `Some(d)` checked finite and > 0.
fn duration(d: Option<f32>) -> Result<Option<f32>, Error> {
    match d {
        None => Ok(None),
        Some(d) if !d.is_finite() => Err(motion::Error::NonFinite(Param::DurationS).into()),
        Some(d) if !(d > 0.0) => Err(motion::Error::NotPositive(Param::DurationS).into()),
        Some(d) => Ok(Some(d)),
    }
}

impl<M: Math> Engine<M> {
    /// An idle engine whose ramps and outputs move at `limiter`'s speed.
    pub const fn new(limiter: Limiter) -> Self {
        Engine {
            program: Program::Idle,
            stage: Stage::Run,
            ramp: Ramp::idle(),
            home: [0.0; 12],
            frame: 0,
            fault: None,
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
    /// first tick begins the ramp from `setup.outputs` (for [`Request::StandUp`] with the
    /// outputs off, from the rest pose at which the device enables them; its returned angles).
    /// A refusal changes nothing.
    ///
    /// # Errors
    /// See [`Error`].
    ///
    /// Out of line, as are the law and walk builders, which write the program in place once
    /// every check passed: a program is a few hundred bytes, and each copy of it on the way
    /// would be a stack frame beyond the AVR's 63-byte displacement.
    #[inline(never)]
    pub fn start(&mut self, request: &Request, setup: &Setup<'_, M>) -> Result<[f32; 12], Error> {
        if self.is_active() {
            return Err(Error::Busy);
        }
        let kind = request.kind();
        let (first, home, start) = match request {
            Request::StandUp | Request::Sit | Request::Rest => {
                // Sit and rest ramp from the outputs, which must be on; stand-up enables them at
                // the rest pose when they are off.
                let out = match setup.outputs {
                    Some(o) => Some(*o),
                    None if kind == Kind::StandUp => None,
                    None => return Err(Error::OutputsOff),
                };
                let rest = rest_angles(setup.robot)?;
                check_travel(setup.pulse_maps, &rest)?;
                let target = if kind == Kind::StandUp {
                    stance_angles::<M>(setup)?
                } else {
                    rest
                };
                self.program = Program::Pose { kind };
                (target, target, out.unwrap_or(rest))
            }
            _ => {
                let out = *setup.outputs.ok_or(Error::OutputsOff)?;
                let home = stance_angles::<M>(setup)?;
                let first = match request {
                    Request::Walk(w) => Self::walk(w, setup, &mut self.program)?,
                    _ => Self::law(request, setup, &mut self.program)?,
                };
                (first, home, out)
            }
        };
        self.stage = Stage::Approach;
        self.ramp.restart(&start, &first, &self.limiter);
        self.home = home;
        self.frame = 0;
        self.fault = None;
        Ok(start)
    }

    /// Builds a law motion into `program` and runs its start check there; a refusal leaves
    /// `program` idle. Its first setpoint.
    ///
    /// Built first, checked after, each out of line: the check's deep calls (the body IK)
    /// then start from a small stack frame, not from one that holds the builder's copies of
    /// the motion's parameters.
    #[inline(never)]
    fn law(request: &Request, s: &Setup<'_, M>, program: &mut Program) -> Result<[f32; 12], Error> {
        let checked = match Self::build_law(request, s, program) {
            Ok(()) => match program {
                Program::Law(law) => Self::check_law(law, s),
                _ => Err(Error::Busy),
            },
            Err(e) => Err(e),
        };
        if checked.is_err() {
            *program = Program::Idle;
        }
        checked
    }

    #[inline(never)]
    fn build_law(request: &Request, s: &Setup<'_, M>, program: &mut Program) -> Result<(), Error> {
        let (legs, d) = match *request {
            Request::Sway { duration_s, .. } | Request::YawTurn { duration_s, .. } => {
                ([true; 4], duration_s)
            }
            Request::FootPath {
                leg, duration_s, ..
            } => (
                match leg {
                    None => [true; 4],
                    Some(l) => LegId::ALL.map(|x| x == l),
                },
                duration_s,
            ),
            _ => return Err(Error::Busy),
        };
        let d = duration(d)?;
        // The law written where it stays (its motion a placeholder until built there), then
        // the fields that follow from its motion.
        *program = Program::Law(Law {
            motion: LawMotion::Sway(laws::SwayLaw {
                axis: Axis::Roll,
                amplitude_rad: 0.0,
                period_s: 1.0,
                roll0_rad: 0.0,
                pitch0_rad: 0.0,
                yaw0_rad: 0.0,
                order: s.order,
                feet_in_world: [Vec3::ZERO; 4],
            }),
            legs,
            period_s: 1.0,
            end_frame: None,
        });
        if let Program::Law(law) = program {
            law_motion::<M>(request, s, &mut law.motion)?;
            let period_s = law.motion.period_s();
            law.period_s = period_s;
            law.end_frame = d.map(|d| frames_to_boundary(d, period_s).max(1));
        }
        Ok(())
    }

    #[inline(never)]
    fn check_law(law: &Law, s: &Setup<'_, M>) -> Result<[f32; 12], Error> {
        let n = START_CHECK_SAMPLES;
        let mut first = [0.0; 12];
        for k in 0..n {
            let t = law.period_s * f32::from(k) / f32::from(n);
            let solved = Self::law_setpoint(law, t, s.solver);
            let q = check_sample::<M>(s, k, t, &solved, true)?;
            if k == 0 {
                first = *q;
            }
        }
        Ok(first)
    }

    /// Builds a walk into `program` and runs its start check there (as [`Engine::law`]); a
    /// refusal leaves `program` idle. Its first setpoint.
    #[inline(never)]
    fn walk(w: &WalkRequest, s: &Setup<'_, M>, program: &mut Program) -> Result<[f32; 12], Error> {
        Self::build_walk(w, s, program)?;
        let checked = match program {
            Program::Walk { walker, .. } => Self::check_walk(walker, s),
            _ => Err(Error::Busy),
        };
        if checked.is_err() {
            *program = Program::Idle;
        }
        checked
    }

    #[inline(never)]
    fn build_walk(w: &WalkRequest, s: &Setup<'_, M>, program: &mut Program) -> Result<(), Error> {
        if w.velocity_timeout_ms == 0 {
            return Err(motion::Error::NotPositive(Param::VelocityTimeoutMs).into());
        }
        let mut p = WalkerParams::new(w.pattern, w.body_height_m);
        p.step_height_m = w.step_height_m;
        p.cycle_s = w.cycle_s;
        p.order = s.order;
        let p = p.checked()?;
        // The device validated its robot at boot.
        let stance = s.robot.stance_feet(w.body_height_m);
        *program = Program::Walk {
            walker: Walker::standing(p, &stance),
            timeout_ms: w.velocity_timeout_ms,
            last_command_ms: s.now_ms,
        };
        Ok(())
    }

    #[inline(never)]
    fn check_walk(walker: &Walker, s: &Setup<'_, M>) -> Result<[f32; 12], Error> {
        let order = walker.params().order;
        let solved = Self::walk_setpoint(s.solver, order, &walker.feet());
        let first = *check_sample::<M>(s, 0, 0.0, &solved, true)?;
        for k in 0..Walker::ENVELOPE_SAMPLES {
            let solved = Self::walk_setpoint(s.solver, order, &walker.envelope(k));
            // Sample 0 is the first frame; the envelope's points follow, without the
            // singularity measure (see the module docs).
            check_sample::<M>(s, k as u16 + 1, 0.0, &solved, false)?;
        }
        Ok(first)
    }

    /// The law's frame at `t_s`, written into `frame`: the motion's frame with the legs it
    /// does not move at their stance points.
    ///
    /// Out of line, the frame in the caller's storage: the laws' frame code then reaches it
    /// through a pointer, not through a stack frame beyond the AVR's 63-byte displacement.
    #[inline(never)]
    fn law_frame(law: &Law, t_s: f32, frame: &mut Frame) -> Result<(), motion::Error> {
        match &law.motion {
            LawMotion::Sway(m) => m.frame_into::<M>(t_s, frame),
            LawMotion::YawTurn(m) => m.frame_into::<M>(t_s, frame),
            LawMotion::LegPaths(m) => {
                m.frame_into::<M>(t_s, frame)?;
                let stance = &m.stance_feet;
                for (i, moves) in law.legs.iter().enumerate() {
                    if !moves {
                        frame.feet_in_world[i] = stance[i];
                        frame.contact[i] = motion::Contact::Stance;
                    }
                }
                Ok(())
            }
        }
    }

    /// The law's joint setpoint at `t_s`: its frame through the body IK.
    #[inline(never)]
    fn law_setpoint(law: &Law, t_s: f32, solver: &body::Solver<M>) -> Result<[f32; 12], IkError> {
        let mut frame = Frame::ZERO;
        Self::law_frame(law, t_s, &mut frame).map_err(|_| IkError {
            leg: LegId::FL,
            kind: kin_core::Unreachable::NonFinite,
        })?;
        solve_frame(solver, law.motion.order(), &frame)
    }

    /// The walk's joint setpoint with its feet at `feet` (body frame, the body at the zero pose;
    /// the contacts do not enter the IK), through `solver`.
    #[inline(never)]
    fn walk_setpoint(
        solver: &body::Solver<M>,
        order: RotationOrder,
        feet: &[Vec3; 4],
    ) -> Result<[f32; 12], IkError> {
        let frame = Frame {
            pose: Pose::default(),
            feet_in_world: *feet,
            contact: [motion::Contact::Stance; 4],
        };
        solve_frame(solver, order, &frame)
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
            } if !walker.is_stopping() && self.stage != Stage::Leave => {
                walker.set_velocity::<M>(v)?;
                *last_command_ms = now_ms;
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
            Program::Law(law) if self.stage == Stage::Run || self.stage == Stage::Approach => {
                let t = self.frame as f32 * FRAME_S;
                let end = frames_to_boundary(t, law.period_s);
                law.end_frame = Some(law.end_frame.map_or(end, |e| e.min(end)));
            }
            Program::Walk { walker, .. } => walker.stop(),
            _ => return,
        }
        // One tail for both programs: one ramp call site, not two.
        if self.stage == Stage::Approach {
            // Not started: ramp back from where the ramp is.
            let from = self.ramp.point();
            self.leave(&from);
        } else if self.stage == Stage::Run {
            self.stage = Stage::Stopping;
        }
    }

    /// Ends the motion at once (the outputs stopped, or a direct setpoint took over).
    pub fn cancel(&mut self) {
        self.program = Program::Idle;
        self.stage = Stage::Run;
    }

    fn leave(&mut self, from: &[f32; 12]) {
        self.stage = Stage::Leave;
        self.ramp.restart(from, &self.home, &self.limiter);
    }

    /// The status.
    pub fn status(&self) -> Status {
        let t_s = self.frame as f32 * FRAME_S;
        let (kind, phase) = match &self.program {
            Program::Idle => (None, 0.0),
            Program::Pose { kind } => (Some(*kind), 0.0),
            Program::Law(law) => (Some(law.motion_kind()), motion_phase(t_s, law.period_s)),
            Program::Walk { walker, .. } => (Some(Kind::Walk), walker.phase()),
        };
        Status {
            kind,
            stage: self.stage,
            t_s,
            phase,
            fault: self.fault,
        }
    }

    /// One tick after `frames` (≥ 1) frame boundaries, at `now_ms`, with the outputs at `out`,
    /// the motion's frames solved by `solver` (the [`Setup::solver`] it started with): the new
    /// target, if any.
    ///
    /// Out of line, as are the law's frame and setpoint and the walker's steps: each keeps its
    /// own small stack frame (see `Device`'s notes on AVR stack frames).
    #[inline(never)]
    pub fn tick(
        &mut self,
        frames: u32,
        now_ms: u32,
        out: &[f32; 12],
        solver: &body::Solver<M>,
    ) -> Tick {
        let mut tick = Tick {
            target: None,
            disable_outputs: false,
        };
        match self.stage {
            Stage::Approach | Stage::Leave => {
                if !self.ramp.finished() {
                    tick.target = Some(self.ramp.advance());
                    return tick;
                }
                // The ramp is at its end: wait for the outputs (the limiter) to get there.
                if out != self.ramp.to() {
                    return tick;
                }
                if self.stage == Stage::Leave || matches!(self.program, Program::Pose { .. }) {
                    tick.disable_outputs =
                        matches!(self.program, Program::Pose { kind: Kind::Rest });
                    self.cancel();
                    return tick;
                }
                self.stage = Stage::Run;
                self.frame = 0;
                if let Program::Walk {
                    last_command_ms, ..
                } = &mut self.program
                {
                    *last_command_ms = now_ms;
                }
                tick
            }
            Stage::Run | Stage::Stopping => {
                // Borrowed, not copied: a walker is a few hundred bytes of stack.
                let (result, ended) = match &mut self.program {
                    Program::Law(law) => {
                        let mut frame = self.frame.saturating_add(frames);
                        let end = law.end_frame.filter(|&e| frame >= e);
                        if let Some(e) = end {
                            frame = e;
                        }
                        self.frame = frame;
                        let q = Self::law_setpoint(law, frame as f32 * FRAME_S, solver);
                        (q, end.is_some())
                    }
                    Program::Walk {
                        walker,
                        timeout_ms,
                        last_command_ms,
                    } => {
                        if now_ms.wrapping_sub(*last_command_ms) > u32::from(*timeout_ms) {
                            walker.stop();
                            self.stage = Stage::Stopping;
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
    fn motion_kind(&self) -> Kind {
        match self.motion {
            LawMotion::Sway(_) => Kind::Sway,
            LawMotion::YawTurn(_) => Kind::YawTurn,
            LawMotion::LegPaths(_) => Kind::FootPath,
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
