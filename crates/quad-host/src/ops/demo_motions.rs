//! The onboard part of `quadctl demo`: the device runs stand-up, seed 001's roll and pitch
//! sways, the yaw turn, a trot with a changing velocity and sit by itself, and the host checks
//! what it reports against its own kin-core.
//!
//! ## Checks
//! At every answer (the device's state asked for every [`POLL_PERIOD`], every velocity command):
//! - the readback's twelve pulses are the calibration's mapping of its twelve angles (0 while
//!   the outputs are off);
//! - while a sway or the yaw turn runs, its angles are the host's own kin-core solution of the
//!   same law at the motion time the device reports (kin-core's `Sway` / `YawTurn` with the
//!   device's stance and rotation order, its body IK), within the angle tolerance (the AVR's
//!   math differs from the host's);
//! - after stand-up, the angles are the host's IK of the nominal stance; after sit, the device's
//!   rest pose;
//! - on the emulator, the pulses on the twelve pins at every servo frame of a sway or the yaw
//!   turn are the calibration's mapping of the host's angles at that frame's motion time (the
//!   last answer's time plus a frame per period since, give or take a frame: the frames are
//!   latched to the PWM periods; these motions move slower than the joint-speed limit, so the
//!   limiter never holds them back), within one 0.5 µs timer tick.
//!
//! Stand-up, the trot, the walk and sit are replayed ([`crate::replay`]): the device reports
//! the run frame from which each velocity command applies and at which the stop took effect
//! (protocol 2.3), and the host recomputes every frame with the device's own engine on its
//! kin-core; every answer's readback is that replay's frame of the answer's stage and frame
//! number (within the angle tolerance) and, on the emulator, every PWM period the pins showed
//! between the answers is a replayed frame, in order (within one 0.5 µs timer tick). The walk's
//! and the trot's readbacks while they run count as angle checks; stand-up and sit count their
//! end pose (the host's stance, the rest pose) as before, and their ramps' frames among the
//! frames replayed.

use crate::client::{self, AngleCheck};
use crate::emu::CYCLES_PER_TICK;
use crate::link::Link;
use crate::ops::onboard::{self, MotionAnswer, Session, VelocityStep, POLL_PERIOD};
use crate::replay::{self, Commands};
use kin_core::body::{BodyConfig, Pose, Solver};
use kin_core::motion::gait::{Pattern, Velocity};
use kin_core::motion::laws::{self, Axis};
use kin_core::motion::Motion as _;
use kin_core::{ReachPolicy, Robot};
use quad_device::engine;
use quad_protocol::servo::Calibration;
use quad_protocol::{Flags, MotionCommand, MotionKind, MotionStage, Readback, Request};
use serde::Serialize;
use std::time::Duration;

/// One servo frame of the device, s.
const FRAME_S: f32 = engine::FRAME_S;

/// The tour's motions and what each does.
pub fn tour(stance_height_m: f32) -> Vec<(&'static str, MotionCommand, Vec<VelocityStep>)> {
    let sway = |axis| MotionCommand::Sway {
        axis,
        amplitude_rad: 0.1,
        period_s: 4.0,
        duration_s: Some(4.0),
    };
    let step = |forward_m_s, yaw_rate_rad_s, duration_s| VelocityStep {
        forward_m_s,
        lateral_m_s: 0.0,
        yaw_rate_rad_s,
        duration_s,
    };
    vec![
        ("stand up", MotionCommand::StandUp, vec![]),
        ("roll sway (seed 001 eq. 6)", sway(Axis::Roll), vec![]),
        ("pitch sway (seed 001 eq. 8)", sway(Axis::Pitch), vec![]),
        (
            "yaw turn (seed 001 eq. 9-11), counter-clockwise",
            MotionCommand::YawTurn {
                yaw_rate_rad_s: 0.1,
                step_period_s: 2.0,
                lift_height_m: 0.05,
                duration_s: Some(4.0),
            },
            vec![],
        ),
        (
            "trot: 3 cm/s, then 6 cm/s turning left, then stop",
            MotionCommand::walk(kin_core::motion::gait::Pattern::Trot, stance_height_m),
            vec![step(0.03, 0.0, 2.0), step(0.06, 0.1, 2.0)],
        ),
        ("sit", MotionCommand::Sit, vec![]),
    ]
}

/// [`tour`] with a walk (the four-beat gait) before the sit: what `quadctl demo` runs.
pub fn full_tour(stance_height_m: f32) -> Vec<(&'static str, MotionCommand, Vec<VelocityStep>)> {
    let mut legs = tour(stance_height_m);
    let step = |forward_m_s, yaw_rate_rad_s, duration_s| VelocityStep {
        forward_m_s,
        lateral_m_s: 0.0,
        yaw_rate_rad_s,
        duration_s,
    };
    let walk = (
        "walk: 2 cm/s, then 3 cm/s turning right, then stop",
        MotionCommand::walk(Pattern::Walk, stance_height_m),
        vec![step(0.02, 0.0, 2.0), step(0.03, -0.1, 2.0)],
    );
    legs.insert(legs.len() - 1, walk);
    legs
}

/// The checks of one motion of the tour.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Leg {
    /// The motion.
    pub motion: &'static str,
    /// Answers checked.
    pub answers: u64,
    /// Answers whose angles were compared with the host's kin-core.
    pub angles_checked: u64,
    /// Largest |device − host| angle, rad.
    pub max_angle_err_rad: f32,
    /// Pin pulses compared with the host's mapping.
    pub pins_checked: u64,
    /// Frames compared with the host's replay of the motion: answers' readbacks and PWM periods
    /// of the pins (stand-up, the walks and sit).
    pub frames_checked: u64,
    /// Disagreements (readback pulses, angles, pins).
    pub errors: u64,
    /// The first disagreement, described.
    pub first_error: Option<String>,
    /// Motion time the device reported last, s.
    pub motion_s: f32,
}

/// The host's angles of a running sway or yaw turn at motion time `t_s`, for `robot` at the
/// device's stance and rotation order.
fn host_law_angles(
    robot: &Robot,
    request: &MotionCommand,
    stance_height_m: f32,
    order: kin_core::RotationOrder,
    t_s: f32,
) -> Option<[f32; 12]> {
    let stance = robot.stance_feet(stance_height_m);
    let frame = match *request {
        MotionCommand::Sway {
            axis,
            amplitude_rad,
            period_s,
            ..
        } => laws::Sway::new(laws::SwayParams {
            robot: *robot,
            axis,
            amplitude_rad,
            period_s,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            yaw0_rad: 0.0,
            order,
            feet_in_world: stance,
        })
        .ok()?
        .frame::<kin_core::DefaultMath>(t_s)
        .ok()?,
        MotionCommand::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            ..
        } => laws::YawTurn::new(laws::YawTurnParams {
            robot: *robot,
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            yaw0_rad: 0.0,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            order,
            stance_feet: stance,
        })
        .ok()?
        .frame::<kin_core::DefaultMath>(t_s)
        .ok()?,
        _ => return None,
    };
    Solver::new(robot)
        .inverse(
            &frame.pose,
            &BodyConfig::about_centre(order),
            &frame.feet_in_world,
            ReachPolicy::Reject,
        )
        .ok()
        .map(|s| s.flat())
}

/// The pulses of `angles` through `calibration` (`None`: one beyond its travel).
fn pulses(calibration: &[Calibration; 12], angles: &[f32; 12]) -> Option<[u16; 12]> {
    let mut out = [0u16; 12];
    for (i, (c, &a)) in calibration.iter().zip(angles).enumerate() {
        out[i] = c.pulse_half_us(a).ok()?;
    }
    Some(out)
}

struct Checker<'a> {
    leg: Leg,
    calibration: &'a [Calibration; 12],
    tolerance_rad: f32,
}

impl Checker<'_> {
    fn error(&mut self, what: String) {
        self.leg.errors += 1;
        if self.leg.first_error.is_none() {
            self.leg.first_error = Some(what);
        }
    }

    fn readback(&mut self, rb: &Readback) {
        self.leg.answers += 1;
        let want = if rb.flags.contains(Flags::OUTPUTS_ENABLED) {
            pulses(self.calibration, &rb.angles_rad)
        } else {
            Some([0; 12])
        };
        if want != Some(rb.pulses_half_us) {
            self.error(format!(
                "readback pulses {:?} are not the calibration's mapping of its angles",
                rb.pulses_half_us
            ));
        }
    }

    fn angles(&mut self, got: &[f32; 12], want: &[f32; 12], what: &str) {
        self.leg.angles_checked += 1;
        let err = got
            .iter()
            .zip(want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        self.leg.max_angle_err_rad = self.leg.max_angle_err_rad.max(err);
        if !(err <= self.tolerance_rad) {
            self.error(format!("{what}: angles off the host's by {err} rad"));
        }
    }
}

/// Runs the tour on `session`, checking as the module docs say; `progress` sees each motion's
/// name as it starts.
///
/// # Errors
/// A refusal or a link failure stops the tour.
pub fn run<L: Link>(
    session: &mut Session<L>,
    robot: &Robot,
    check: AngleCheck,
    progress: impl FnMut(&str),
) -> Result<Vec<Leg>, onboard::Error> {
    run_tour(session, robot, check, tour, progress)
}

/// Runs the motions `tour` gives for the device's stance height, as [`run`] does.
///
/// # Errors
/// As [`run`].
pub fn run_tour<L: Link>(
    session: &mut Session<L>,
    robot: &Robot,
    check: AngleCheck,
    tour: impl FnOnce(f32) -> Vec<(&'static str, MotionCommand, Vec<VelocityStep>)>,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Leg>, onboard::Error> {
    let tolerance_rad = match check {
        AngleCheck::Exact => 0.0,
        AngleCheck::Within(t) => t,
    };
    let info = *session.info();
    let (h, order) = (info.pose_config.stance_height_m, info.pose_config.order);
    let calibration = *session.calibration();
    let mut legs = Vec::new();
    for (name, request, walk) in tour(h) {
        progress(name);
        let mut c = Checker {
            leg: Leg {
                motion: name,
                answers: 0,
                angles_checked: 0,
                max_angle_err_rad: 0.0,
                pins_checked: 0,
                frames_checked: 0,
                errors: 0,
                first_error: None,
                motion_s: 0.0,
            },
            calibration: &calibration,
            tolerance_rad,
        };
        let is_law = matches!(
            request,
            MotionCommand::Sway { .. } | MotionCommand::YawTurn { .. }
        );
        if is_law {
            c.leg.motion_s = law_run(session, &mut c, robot, &request, h, order)?;
        } else {
            c.leg.motion_s = replayed_run(session, &mut c, robot, &request, &walk)?;
        }
        let last = session.get()?;
        c.readback(&last.readback);
        match request {
            MotionCommand::StandUp => {
                let stance = Solver::new(robot)
                    .inverse_at_stance(
                        &Pose::default(),
                        &BodyConfig::about_centre(order),
                        h,
                        ReachPolicy::Reject,
                    )
                    .map(|s| s.flat());
                match stance {
                    Ok(want) => c.angles(&last.readback.angles_rad, &want, "the stance"),
                    Err(e) => c.error(format!("the host cannot solve the stance: {e}")),
                }
            }
            MotionCommand::Sit => match engine::rest_angles(robot) {
                Ok(want) => c.angles(&last.readback.angles_rad, &want, "the rest pose"),
                Err(e) => c.error(format!("the host has no rest pose: {e:?}")),
            },
            _ => {}
        }
        legs.push(c.leg);
    }
    Ok(legs)
}

/// Longest a motion may take, link time.
const WAIT: Duration = Duration::from_secs(120);

/// A pin's pulse may differ from the host's by one timer tick.
const PIN_TOLERANCE: u64 = CYCLES_PER_TICK;

/// The pins of every PWM period until `deadline` on the emulator (appended to `pins`); on
/// another link, the time passes.
fn capture<L: Link>(
    session: &mut Session<L>,
    pins: &mut Vec<[Option<crate::emu::Pulse>; 12]>,
    deadline: Duration,
) -> Result<(), onboard::Error> {
    if let Some(emu) = session.client_mut().link_mut().emulator() {
        while emu.now() < deadline {
            pins.push(
                emu.next_pulses()
                    .map_err(|e| onboard::Error::Client(e.into()))?,
            );
        }
        return Ok(());
    }
    session
        .client_mut()
        .idle_until(deadline)
        .map_err(|e| onboard::Error::Client(e.into()))
}

/// The longest the joint-speed limiter takes to bring an output onto its target: half a turn
/// at the device's default limit (3 rad/s), with a frame to spare.
const SETTLE_BOUND: Duration = Duration::from_millis(1_070);

/// Waits until the outputs show `pulses_half_us` (the held target): on the emulator until one
/// PWM period shows them on all twelve pins (or [`SETTLE_BOUND`] passed: an error), elsewhere
/// for [`SETTLE_BOUND`] (the outputs cannot be seen).
fn settle<L: Link>(
    session: &mut Session<L>,
    pulses_half_us: &[u16; 12],
) -> Result<(), onboard::Error> {
    let until = session.now() + SETTLE_BOUND;
    if let Some(emu) = session.client_mut().link_mut().emulator() {
        while emu.now() < until {
            let period = emu
                .next_pulses()
                .map_err(|e| onboard::Error::Client(e.into()))?;
            let settled = period.iter().zip(pulses_half_us).all(|(p, &w)| {
                p.is_some_and(|p| p.width_could_be(u64::from(w) * CYCLES_PER_TICK, PIN_TOLERANCE))
            });
            if settled {
                return Ok(());
            }
        }
        return Err(onboard::Error::NoEnd(SETTLE_BOUND));
    }
    session
        .client_mut()
        .idle_until(until)
        .map_err(|e| onboard::Error::Client(e.into()))
}

/// The run frame an answer reports (its time in frames), in `Run` and `Stopping`.
fn run_frame(a: &MotionAnswer) -> Option<u32> {
    matches!(a.status.stage, MotionStage::Run | MotionStage::Stopping)
        .then(|| (a.status.t_s / FRAME_S).round() as u32)
}

/// Runs stand-up, sit or a walk (with its velocity `walk` steps at [`POLL_PERIOD`], then a
/// stop) to its end, recording every answer and, on the emulator, the pins of every period
/// between them; then replays the motion from what the device reported and checks every
/// readback and pin period against it (module docs). Returns the last motion time.
fn replayed_run<L: Link>(
    session: &mut Session<L>,
    c: &mut Checker<'_>,
    robot: &Robot,
    request: &MotionCommand,
    walk: &[VelocityStep],
) -> Result<f32, onboard::Error> {
    session.check(&Request::StartMotion(*request))?;
    for step in walk {
        session.check(&onboard::velocity_request(step))?;
    }
    let is_walk = matches!(request, MotionCommand::Walk { .. });
    if is_walk {
        session.stand_if_off(WAIT)?;
    }
    let mut before = session.get()?;
    let on = before.readback.flags.contains(Flags::OUTPUTS_ENABLED);
    if on {
        // The replay starts from the held target; the outputs may still be on their way
        // there under the limiter (a stream of poses outruns it).
        settle(session, &before.readback.pulses_half_us)?;
        before = session.get()?;
    }
    c.readback(&before.readback);
    if !on && !matches!(request, MotionCommand::StandUp) {
        // A sit with the outputs off has nothing to do.
        return Ok(0.0);
    }
    let mut answers: Vec<MotionAnswer> = Vec::new();
    let mut velocities: Vec<(u32, Velocity)> = Vec::new();
    let mut pins = Vec::new();
    let first = session.start(request)?;
    answers.push(first);
    for step in walk {
        let until = session.now() + Duration::from_secs_f32(step.duration_s);
        loop {
            let now = session.now();
            capture(session, &mut pins, (now + POLL_PERIOD).min(until))?;
            let a = session.motion(onboard::velocity_request(step))?;
            // In the approach a velocity applies from the run's first step.
            velocities.push((
                run_frame(&a).unwrap_or(0),
                Velocity {
                    forward_m_s: step.forward_m_s,
                    lateral_m_s: step.lateral_m_s,
                    yaw_rad_s: step.yaw_rate_rad_s,
                },
            ));
            answers.push(a);
            if session.now() >= until {
                break;
            }
        }
    }
    if is_walk {
        answers.push(session.motion(Request::StopMotion)?);
    }
    let until = session.now() + WAIT;
    loop {
        let now = session.now();
        capture(session, &mut pins, now + POLL_PERIOD)?;
        let a = session.get()?;
        answers.push(a);
        if a.status.kind.is_none() {
            if let Some(fault) = a.status.fault {
                return Err(onboard::Error::Fault(fault));
            }
            break;
        }
        if session.now() >= until {
            return Err(onboard::Error::NoEnd(WAIT));
        }
    }
    let mut motion_s = 0.0f32;
    for a in &answers {
        c.readback(&a.readback);
        motion_s = motion_s.max(a.status.t_s);
    }
    // The stop frame, from the first answer that reports it (unwrapped at its run frame).
    let stop_frame = answers.iter().find_map(|a| {
        let stop = a.frames?.stop_frame?;
        Some(run_frame(a).map_or(u32::from(stop), |now| replay::unwrap_frame(stop, now)))
    });
    let info = *session.info();
    let config = replay::Config {
        robot: *robot,
        calibration: *c.calibration,
        stance_height_m: info.pose_config.stance_height_m,
        order: info.pose_config.order,
        // The device's own robot's limit when the session read it (protocol 2.4).
        joint_speed_limit_rad_s: session
            .robot()
            .map_or(engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S, |r| {
                r.joint_speed_limit_rad_s
            }),
    };
    let commands = Commands {
        request: *request,
        outputs_rad: on.then_some(before.readback.angles_rad),
        velocities,
        stop_frame,
    };
    let replayed = match replay::replay(&config, &commands) {
        Ok(r) => r,
        Err(e) => {
            c.error(format!("{}: {e}", c.leg.motion));
            return Ok(motion_s);
        }
    };
    check_against_replay(c, &replayed, &answers, &pins, is_walk);
    Ok(motion_s)
}

/// Every answer's readback (those of the motion: with frame numbers, not idle) and every pin
/// period against `replayed`.
fn check_against_replay(
    c: &mut Checker<'_>,
    replayed: &replay::Replay,
    answers: &[MotionAnswer],
    pins: &[[Option<crate::emu::Pulse>; 12]],
    is_walk: bool,
) {
    for (i, a) in answers.iter().enumerate() {
        if a.status.kind.is_none() {
            continue;
        }
        let Some(frames) = a.frames else {
            c.error(format!(
                "{}: the device reports no frame numbers (protocol 2.3)",
                c.leg.motion
            ));
            return;
        };
        let label = replay::label(&a.status, &frames);
        match replayed.check_readback(i, label, &a.readback, c.tolerance_rad) {
            Ok(err) => {
                c.leg.frames_checked += 1;
                if is_walk && run_frame(a).is_some() {
                    c.leg.angles_checked += 1;
                    c.leg.max_angle_err_rad = c.leg.max_angle_err_rad.max(err);
                }
            }
            Err(m) => c.error(format!("{}: {m}", c.leg.motion)),
        }
    }
    if pins.is_empty() {
        return;
    }
    match replayed.check_pins(pins, PIN_TOLERANCE) {
        Ok(_) => {
            c.leg.pins_checked += 12 * pins.len() as u64;
            c.leg.frames_checked += pins.len() as u64;
        }
        Err(m) => c.error(format!("{}: {m}", c.leg.motion)),
    }
}

/// Runs a sway or the yaw turn, asking for the state every [`POLL_PERIOD`]: each answer's
/// angles against the host's kin-core, and on the emulator the pins of every servo frame.
/// Returns the last motion time.
fn law_run<L: Link>(
    session: &mut Session<L>,
    c: &mut Checker<'_>,
    robot: &Robot,
    request: &MotionCommand,
    h: f32,
    order: kin_core::RotationOrder,
) -> Result<f32, onboard::Error> {
    session.stand_if_off(WAIT)?;
    let first = session.start(request)?;
    c.readback(&first.readback);
    let until = session.now() + WAIT;
    let end_s = law_end_s(request);
    let mut motion_s = 0.0f32;
    loop {
        let a = session.get()?;
        let poll_end = session.now() + POLL_PERIOD;
        c.readback(&a.readback);
        motion_s = motion_s.max(a.status.t_s);
        let running = matches!(a.status.kind, Some(MotionKind::Sway | MotionKind::YawTurn))
            && a.status.stage == MotionStage::Run;
        if running {
            let t = a.status.t_s;
            if let Some(want) = host_law_angles(robot, request, h, order, t) {
                c.angles(&a.readback.angles_rad, &want, c.leg.motion);
            }
            let calibration = *c.calibration;
            if let Some(emu) = session.client_mut().link_mut().emulator() {
                // Every servo frame until the next question: frame `j` after the answer shows
                // the target of the motion time `t + j·FRAME_S`, give or take a frame (the
                // frames are latched to the PWM periods; the answer may come before or after
                // a frame's write).
                let mut j = 0u32;
                loop {
                    let pins = emu
                        .next_pulses()
                        .map_err(|e| onboard::Error::Client(e.into()))?;
                    let base = t + j as f32 * FRAME_S;
                    // Near its end the motion leaves for the stance: not the law any more.
                    if end_s.is_none_or(|end| base + 3.0 * FRAME_S < end) {
                        let candidates: Vec<[u16; 12]> = (-1..=2)
                            .filter_map(|k| {
                                let at = base + k as f32 * FRAME_S;
                                host_law_angles(robot, request, h, order, at)
                                    .and_then(|q| pulses(&calibration, &q))
                            })
                            .collect();
                        check_law_pins(c, &pins, &candidates, base);
                    }
                    j += 1;
                    if emu.now() >= poll_end {
                        break;
                    }
                }
            }
        }
        if a.status.kind.is_none() {
            if let Some(fault) = a.status.fault {
                return Err(onboard::Error::Fault(fault));
            }
            return Ok(motion_s);
        }
        let now = session.now();
        if now >= until {
            return Err(onboard::Error::NoEnd(WAIT));
        }
        if now < poll_end {
            session
                .client_mut()
                .idle_until(poll_end)
                .map_err(client::Error::from)?;
        }
    }
}

/// The motion time at which a law request with a duration ends (its duration rounded up to
/// whole periods, as the device runs it), s.
fn law_end_s(request: &MotionCommand) -> Option<f32> {
    let (duration_s, period_s) = match *request {
        MotionCommand::Sway {
            duration_s,
            period_s,
            ..
        } => (duration_s?, period_s),
        MotionCommand::YawTurn {
            duration_s,
            step_period_s,
            ..
        } => (duration_s?, step_period_s),
        _ => return None,
    };
    Some((duration_s / period_s - 1e-4).ceil() * period_s)
}

/// One frame's twelve pins against the host's pulses at the candidate motion times.
fn check_law_pins(
    c: &mut Checker<'_>,
    pins: &[Option<crate::emu::Pulse>; 12],
    candidates: &[[u16; 12]],
    t: f32,
) {
    for (i, p) in pins.iter().enumerate() {
        c.leg.pins_checked += 1;
        let fits = p.is_some_and(|p| {
            candidates
                .iter()
                .any(|w| p.width_could_be(u64::from(w[i]) * CYCLES_PER_TICK, PIN_TOLERANCE))
        });
        if !fits {
            c.error(format!(
                "{}: channel {i} at {t:.2} s: pulse {:?} µs, host {:?} µs",
                c.leg.motion,
                p.map(|p| p.high_us()),
                candidates
                    .iter()
                    .map(|w| f64::from(w[i]) / 2.0)
                    .collect::<Vec<_>>()
            ));
        }
    }
}
