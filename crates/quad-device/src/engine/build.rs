//! Building a motion from its request and checking it before it starts (the start check of
//! the [module docs](super)), and the per-frame setpoints a running motion takes.

use super::{
    frames_to_boundary, Engine, Error, Law, LawMotion, Program, PulseMaps, Setup,
    START_CHECK_SAMPLES,
};
use kin_core::body::{self, BodyConfig, BodySolution, Pose};
use kin_core::jacobian::SINGULARITY_THRESHOLD;
use kin_core::motion::laws;
use kin_core::motion::path::{AnyPath, Stride};
use kin_core::motion::walker::{Walker, WalkerParams};
use kin_core::motion::{self, Frame, Param};
use kin_core::preflight::{Failure, FailureKind};
use kin_core::{IkError, JointAngles, LegId, Math, ReachPolicy, Robot, RotationOrder, Vec3};
use quad_protocol::{LegSet, MotionCommand, ServoId};

/// The rest pose of `robot`, order FL, FR, RL, RR: legs folded under the body — abduction 0,
/// knee [`REST_KNEE_MARGIN_RAD`](super::REST_KNEE_MARGIN_RAD) short of the folded end of its range, hip at minus half the
/// knee, which puts each foot below its hip joint. The body then rests low, on the ground or on
/// its folded legs. Refused when a joint limit excludes it.
pub fn rest_angles(robot: &Robot) -> Result<[f32; 12], Error> {
    let rest = robot.rest_leg();
    if let Some(j) = robot.limits.first_violation(rest) {
        return Err(Error::Preflight(Failure {
            sample: 0,
            t_s: 0.0,
            leg: LegId::FL,
            kind: FailureKind::Unreachable(kin_core::Unreachable::JointLimit(j)),
        }));
    }
    let leg = rest.to_array();
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
/// servo's calibration as its [`PulseMap`](quad_protocol::servo::PulseMap)).
pub fn check_travel(pulse_maps: &PulseMaps, angles: &[f32; 12]) -> Result<(), Error> {
    for (s, (c, &a)) in ServoId::ALL.iter().zip(pulse_maps.iter().zip(angles)) {
        c.pulse_half_us(a)
            .map_err(|fault| Error::ServoRange { servo: *s, fault })?;
    }
    Ok(())
}

/// The stance angles of a setup: the nominal stance at its height, zero pose.
pub(super) fn stance_angles<M: Math>(s: &Setup<'_, M>) -> Result<[f32; 12], Error> {
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

/// The kin-core motion of a law request, its parameters checked (not its reach: the start
/// check does that). The laws carry no robot (the device's solver holds it), only its stance.
fn law_motion<M: Math>(request: &MotionCommand, s: &Setup<'_, M>) -> Result<LawMotion, Error> {
    let stance_feet = s.robot.stance_feet(s.stance_height_m);
    match *request {
        MotionCommand::Sway {
            axis,
            amplitude_rad,
            period_s,
            ..
        } => {
            let law = laws::SwayLaw {
                axis,
                amplitude_rad,
                period_s,
                roll0_rad: 0.0,
                pitch0_rad: 0.0,
                yaw0_rad: 0.0,
                order: s.order,
                feet_in_world: stance_feet,
            };
            law.check()?;
            Ok(LawMotion::Sway(law))
        }
        MotionCommand::YawTurn {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            ..
        } => Ok(LawMotion::YawTurn(laws::YawTurnLaw::without_reach_check::<
            M,
        >(laws::YawTurnLawParams {
            yaw_rate_rad_s,
            step_period_s,
            lift_height_m,
            yaw0_rad: 0.0,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            order: s.order,
            stance_feet,
        })?)),
        MotionCommand::StableTurn {
            yaw_per_cycle_rad,
            cycle_s,
            lift_height_m,
            shift_fraction,
            ..
        } => Ok(LawMotion::StableTurn(
            laws::StableTurnLaw::without_reach_check::<M>(laws::StableTurnLawParams {
                yaw_per_cycle_rad,
                cycle_s,
                lift_height_m,
                shift_fraction,
                order: s.order,
                stance_feet,
            })?,
        )),
        MotionCommand::FootPath {
            path,
            stride_m,
            step_height_m,
            duty_factor,
            cycle_s,
            ..
        } => {
            let law = laws::LegPathsLaw {
                path: AnyPath::new(path, Stride::new(stride_m, step_height_m, duty_factor)?),
                cycle_s,
                phase_offsets: [0.0; 4],
                stance_feet,
            };
            law.check()?;
            Ok(LawMotion::LegPaths(law))
        }
        _ => Err(Error::Busy),
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
    /// Builds a law motion and runs its start check; when it passes, the law goes into
    /// `program` (a refusal leaves `program` as it was). Its first setpoint.
    pub(super) fn law(
        request: &MotionCommand,
        s: &Setup<'_, M>,
        program: &mut Program,
    ) -> Result<[f32; 12], Error> {
        let law = Self::build_law(request, s)?;
        let first = Self::check_law(&law, s)?;
        *program = Program::Law(law);
        Ok(first)
    }

    fn build_law(request: &MotionCommand, s: &Setup<'_, M>) -> Result<Law, Error> {
        let (legs, duration_s) = match *request {
            MotionCommand::Sway { duration_s, .. }
            | MotionCommand::YawTurn { duration_s, .. }
            | MotionCommand::StableTurn { duration_s, .. } => ([true; 4], duration_s),
            MotionCommand::FootPath {
                legs, duration_s, ..
            } => (
                match legs {
                    LegSet::All => [true; 4],
                    LegSet::One(l) => LegId::ALL.map(|x| x == l),
                },
                duration_s,
            ),
            _ => return Err(Error::Busy),
        };
        let duration_s = duration(duration_s)?;
        let motion = law_motion::<M>(request, s)?;
        let period_s = motion.period_s();
        Ok(Law {
            motion,
            legs,
            period_s,
            end_frame: duration_s.map(|d| frames_to_boundary(d, period_s).max(1)),
        })
    }

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

    /// Builds a walk into `program` and runs its start check there; a refusal leaves
    /// `program` idle. Its first setpoint.
    pub(super) fn walk(
        request: &MotionCommand,
        s: &Setup<'_, M>,
        program: &mut Program,
    ) -> Result<[f32; 12], Error> {
        Self::build_walk(request, s, program)?;
        let checked = match program {
            Program::Walk { walker, .. } => Self::check_walk(walker, s),
            _ => Err(Error::Busy),
        };
        if checked.is_err() {
            *program = Program::Idle;
        }
        checked
    }

    /// Writes the walk of `request` into `program` (a walker is a few hundred bytes: built
    /// where it stays).
    fn build_walk(
        request: &MotionCommand,
        s: &Setup<'_, M>,
        program: &mut Program,
    ) -> Result<(), Error> {
        let MotionCommand::Walk {
            gait,
            body_height_m,
            step_height_m,
            cycle_s,
            velocity_timeout_ms,
        } = *request
        else {
            return Err(Error::Busy);
        };
        if velocity_timeout_ms == 0 {
            return Err(motion::Error::NotPositive(Param::VelocityTimeoutMs).into());
        }
        let mut p = WalkerParams::new(gait, body_height_m);
        p.step_height_m = step_height_m;
        p.cycle_s = cycle_s;
        p.order = s.order;
        let p = p.checked()?;
        // The device validated its robot at boot.
        let stance = s.robot.stance_feet(body_height_m);
        *program = Program::Walk {
            walker: Walker::standing(p, &stance),
            timeout_ms: velocity_timeout_ms,
            last_command_ms: s.now_ms,
        };
        Ok(())
    }

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
    fn law_frame(law: &Law, t_s: f32, frame: &mut Frame) -> Result<(), motion::Error> {
        match &law.motion {
            LawMotion::Sway(m) => m.frame_into::<M>(t_s, frame),
            LawMotion::YawTurn(m) => m.frame_into::<M>(t_s, frame),
            LawMotion::StableTurn(m) => m.frame_into::<M>(t_s, frame),
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
    pub(super) fn law_setpoint(
        law: &Law,
        t_s: f32,
        solver: &body::Solver<M>,
    ) -> Result<[f32; 12], IkError> {
        let mut frame = Frame::ZERO;
        Self::law_frame(law, t_s, &mut frame).map_err(|_| IkError {
            leg: LegId::FL,
            kind: kin_core::Unreachable::NonFinite,
        })?;
        solve_frame(solver, law.motion.order(), &frame)
    }

    /// The law's joint setpoint at `t_s` with `correction` (roll, pitch, rad) added to its body
    /// pose, or the largest of [`LEVEL_SHARES`](super::LEVEL_SHARES) of it within reach; what
    /// was applied (`None` when even the frame without correction fails: its error).
    pub(super) fn law_setpoint_leveled(
        law: &Law,
        t_s: f32,
        solver: &body::Solver<M>,
        correction: [f32; 2],
    ) -> (Result<[f32; 12], IkError>, Option<super::Leveled>) {
        let mut frame = Frame::ZERO;
        if Self::law_frame(law, t_s, &mut frame).is_err() {
            let e = IkError {
                leg: LegId::FL,
                kind: kin_core::Unreachable::NonFinite,
            };
            return (Err(e), None);
        }
        let intended_rad = [frame.pose.roll_rad, frame.pose.pitch_rad];
        let order = law.motion.order();
        let mut last = None;
        for share in super::LEVEL_SHARES {
            let applied_rad = [correction[0] * share, correction[1] * share];
            frame.pose.roll_rad = intended_rad[0] + applied_rad[0];
            frame.pose.pitch_rad = intended_rad[1] + applied_rad[1];
            match solve_frame(solver, order, &frame) {
                Ok(q) => {
                    let leveled = super::Leveled {
                        intended_rad,
                        applied_rad,
                        limited: share < 1.0 && (correction[0] != 0.0 || correction[1] != 0.0),
                    };
                    return (Ok(q), Some(leveled));
                }
                Err(e) => last = Some(e),
            }
        }
        // `LEVEL_SHARES` is not empty: `last` holds the failure of the uncorrected frame.
        (
            Err(last.unwrap_or(IkError {
                leg: LegId::FL,
                kind: kin_core::Unreachable::NonFinite,
            })),
            None,
        )
    }

    /// The walk's joint setpoint with its feet at `feet` (body frame, the body at the zero pose;
    /// the contacts do not enter the IK), through `solver`.
    pub(super) fn walk_setpoint(
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
}
