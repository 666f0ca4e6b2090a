//! The motions the twin runs, built from kin-core's motion laws for the device's robot and
//! stance, and turned into the requests a host would send the device at every servo frame.
//!
//! Driven by the host, each frame's target is the kin-core motion's frame at that time, sent as
//! `SetFeet` (the feet in the body frame): the device solves the IK and maps the angles to
//! pulses with its own code, exactly as it would for a host. Run onboard ([`Plan::onboard`]),
//! the device's motion engine runs the same kin-core law (or its walker for the trots) by
//! itself.

use core::fmt;
use kin_core::motion::gait::{Gait, GaitParams, Pattern, Velocity};
use kin_core::motion::laws::{
    Axis, StableTurn, StableTurnParams, Sway, SwayParams, YawTurn, YawTurnParams,
};
use kin_core::motion::{AnyMotion, Contact, Frame, Motion};
use kin_core::preflight::{Checker, Extremum, Sweep, DEFAULT_MAX_JOINT_SPEED_RAD_S};
use kin_core::stability::MassModel;
use kin_core::{rotation, BodyConfig, Pose, Robot, RotationOrder};
use quad_device::engine::DEFAULT_VELOCITY_TIMEOUT_MS;
use quad_device::Config;
use quad_protocol::MotionCommand;

/// Rest height of the stand-up, as a fraction of the stance height: low enough to be a
/// crouch, high enough that the body clears the floor on both presets.
pub const REST_HEIGHT_FRACTION: f32 = 0.6;
/// Duration of the stand-up's ramp from rest to stance, s.
pub const STAND_RAMP_S: f32 = 2.0;
/// Time the stance is held after the ramp, s.
pub const STAND_HOLD_S: f32 = 2.0;
/// Seed 001's stance height with its robot (eq. 5), m: the yaw turn's lift is scaled from
/// seed 001's 0.3 m by the robot's stance height over this one.
pub const SEED001_STANCE_HEIGHT_M: f32 = 0.9294;
/// Trot speed as stance heights per second (0.1 m/s for seed 000's robot).
pub const TROT_SPEED_HEIGHTS_PER_S: f32 = 0.25;
/// Gait cycle of the twin's trot, s: kin-core's default.
pub const TROT_CYCLE_S: f32 = GaitParams::DEFAULT_CYCLE_S;
/// Stance fraction of the twin's trot: kin-core's trot's. Each diagonal pair hands the body
/// over to the other while all four feet are down, so no stance leg carries half the body
/// alone for its whole stance. With hobby-class servos, whose position error grows with the
/// load, a 0.5 duty factor lets the two loaded knees sag through the stance and eat the
/// stride; docs/twin.md has the measurements (they set kin-core's default).
pub const TROT_DUTY_FACTOR: f32 = Pattern::Trot.duty_factor();
/// Duration of the trot, s.
pub const TROT_DURATION_S: f32 = 10.0;
/// Yaw-turn duration, in step periods.
pub const YAW_TURN_PERIODS: f32 = 2.0;
/// Step period of the fast yaw turn, s: the gait's default cycle, so that each diagonal pair
/// is in the air for 0.4 s instead of seed 001's 3 s.
pub const FAST_YAW_TURN_PERIOD_S: f32 = 0.8;
/// Step height of the fast yaw turn as a fraction of the stance height (the gait's default).
pub const FAST_YAW_TURN_LIFT_FRACTION: f32 = 0.15;

/// Duration of the statically stable turn, in cycles of [`StableTurnParams::DEFAULT_CYCLE_S`].
pub const STABLE_TURN_CYCLES: f32 = 3.0;

/// The shape of the twin's trot: kin-core's gait parameters that a parameter study varies,
/// relative to the stance height `H` where they scale with the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrotShape {
    /// Gait cycle, s.
    pub cycle_s: f32,
    /// Stance fraction of the cycle, in (0, 1).
    pub duty_factor: f32,
    /// Swing apex above the ground, as a fraction of `H`.
    pub step_height_fraction: f32,
    /// Forward speed, stance heights per second.
    pub speed_heights_per_s: f32,
}

impl TrotShape {
    /// The gait phase the twin's trot starts at, cycles: the start of the first span with all
    /// four feet down (the first pair has just touched down), so that the body has the whole
    /// span to pick up the gait's speed before a pair lifts; 0 (a pair lifts at once) when
    /// there is no such span (duty factor ½ or less).
    pub fn four_feet_start(&self) -> f32 {
        // Pairs at phase offsets 0 and ½ (kin-core's trot): the first pair is in stance from
        // 1 − d, the second until ½.
        let d = self.duty_factor;
        if d > 0.5 {
            1.0 - d
        } else {
            0.0
        }
    }
}

impl Default for TrotShape {
    /// [`TROT_CYCLE_S`], [`TROT_DUTY_FACTOR`], kin-core's default step height, at
    /// [`TROT_SPEED_HEIGHTS_PER_S`].
    fn default() -> TrotShape {
        TrotShape {
            cycle_s: TROT_CYCLE_S,
            duty_factor: TROT_DUTY_FACTOR,
            step_height_fraction: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION,
            speed_heights_per_s: TROT_SPEED_HEIGHTS_PER_S,
        }
    }
}

/// A motion of the twin's catalogue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotionKind {
    /// Rest crouch → stance in [`STAND_RAMP_S`] (raised cosine), held [`STAND_HOLD_S`].
    Stand,
    /// Seed 001's roll sway (eq. 6: A = 0.2 rad, T = 20 s), one period.
    Roll,
    /// Seed 001's pitch sway (eq. 8), one period.
    Pitch,
    /// Seed 000's roll sweep (±28°, 10 s sine), one period.
    SweepRoll,
    /// Seed 000's pitch sweep (±21°), one period.
    SweepPitch,
    /// Seed 000's yaw sweep (±21°), one period.
    SweepYaw,
    /// Seed 001's crossed-pair yaw turn (eq. 9–11: ω = 0.085 rad/s, T1 = 6 s), two periods.
    YawTurn,
    /// Seed 001's yaw turn at the same turn rate with a step period of
    /// [`FAST_YAW_TURN_PERIOD_S`] (dynamic, trot-like) over the same 12 s.
    YawTurnFast,
    /// A trot forward at [`TROT_SPEED_HEIGHTS_PER_S`], [`TROT_DURATION_S`], shaped by
    /// [`TrotShape::default`].
    Trot,
    /// A turn on the spot with the trot of [`TrotShape::default`] at seed 001's yaw rate
    /// (ω = 0.085 rad/s, clockwise) over the yaw turn's 12 s.
    TrotTurn,
    /// The statically stable yaw turn (kin-core's `StableTurn`, its defaults: one leg at a
    /// time, the body shifted into the support triangle first, 0.2 rad per 20 s cycle),
    /// [`STABLE_TURN_CYCLES`] cycles.
    StableTurn,
}

impl MotionKind {
    /// Every motion.
    pub const ALL: [MotionKind; 11] = [
        MotionKind::Stand,
        MotionKind::Roll,
        MotionKind::Pitch,
        MotionKind::SweepRoll,
        MotionKind::SweepPitch,
        MotionKind::SweepYaw,
        MotionKind::YawTurn,
        MotionKind::YawTurnFast,
        MotionKind::Trot,
        MotionKind::TrotTurn,
        MotionKind::StableTurn,
    ];

    /// Command-line name.
    pub const fn name(self) -> &'static str {
        match self {
            MotionKind::Stand => "stand",
            MotionKind::Roll => "roll",
            MotionKind::Pitch => "pitch",
            MotionKind::SweepRoll => "sweep-roll",
            MotionKind::SweepPitch => "sweep-pitch",
            MotionKind::SweepYaw => "sweep-yaw",
            MotionKind::YawTurn => "yaw-turn",
            MotionKind::YawTurnFast => "yaw-turn-fast",
            MotionKind::Trot => "trot",
            MotionKind::TrotTurn => "trot-turn",
            MotionKind::StableTurn => "stable-turn",
        }
    }

    /// One line for people (`quadctl sim --help`).
    pub const fn summary(self) -> &'static str {
        match self {
            MotionKind::Stand => "Rise from the rest crouch to the stance and hold it",
            MotionKind::Roll => "Seed 001's roll sway (eq. 6), one period",
            MotionKind::Pitch => "Seed 001's pitch sway (eq. 8), one period",
            MotionKind::SweepRoll => "Seed 000's roll sweep (±28°), one period",
            MotionKind::SweepPitch => "Seed 000's pitch sweep (±21°), one period",
            MotionKind::SweepYaw => "Seed 000's yaw sweep (±21°), one period",
            MotionKind::YawTurn => "Seed 001's crossed-pair yaw turn (eq. 9-11, T1 = 6 s)",
            MotionKind::YawTurnFast => "The yaw turn with a trot's step period, same turn rate",
            MotionKind::Trot => "A trot forward, 10 s",
            MotionKind::TrotTurn => "A turn on the spot with the trot, seed 001's turn rate",
            MotionKind::StableTurn => {
                "A statically stable yaw turn: one leg at a time, the body shifted first"
            }
        }
    }

    /// Parses a [`MotionKind::name`].
    pub fn parse(name: &str) -> Option<MotionKind> {
        MotionKind::ALL.into_iter().find(|m| m.name() == name)
    }
}

impl fmt::Display for MotionKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a motion asks at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// The body pose the motion commands, world frame.
    pub pose: Pose,
    /// The four feet in the body frame (what `SetFeet` carries), m.
    pub feet_in_body_m: [[f32; 3]; 4],
    /// True for the feet the motion has on the ground.
    pub stance: [bool; 4],
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Script {
    StandUp { rest_m: f32, stance_m: f32 },
    Law(AnyMotion),
}

/// A motion built for one device configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    kind: MotionKind,
    robot: Robot,
    order: RotationOrder,
    stance_height_m: f32,
    duration_s: f32,
    script: Script,
    /// The law's time at the plan's start, s.
    law_start_s: f32,
}

impl Plan {
    /// Builds `kind` for the robot and stance of `config` (the device's own defaults).
    ///
    /// # Errors
    /// kin-core's [`kin_core::motion::Error`] naming the parameter that puts a foot out of
    /// reach (e.g. seed 000's sweeps on a robot they do not fit).
    pub fn new(kind: MotionKind, config: &Config) -> Result<Plan, kin_core::motion::Error> {
        let robot = config.robot;
        let h = config.pose_config.stance_height_m;
        let order = config.pose_config.order;
        let sway = |base: SwayParams| -> Result<(Script, f32), kin_core::motion::Error> {
            let p = SwayParams {
                robot,
                order,
                feet_in_world: robot.stance_feet(h),
                ..base
            };
            Ok((Script::Law(AnyMotion::Sway(Sway::new(p)?)), p.period_s))
        };
        let (script, duration_s) = match kind {
            MotionKind::Stand => (
                Script::StandUp {
                    rest_m: REST_HEIGHT_FRACTION * h,
                    stance_m: h,
                },
                STAND_RAMP_S + STAND_HOLD_S,
            ),
            MotionKind::Roll => sway(SwayParams::seed001(Axis::Roll))?,
            MotionKind::Pitch => sway(SwayParams::seed001(Axis::Pitch))?,
            MotionKind::SweepRoll => sway(SwayParams::seed000(Axis::Roll))?,
            MotionKind::SweepPitch => sway(SwayParams::seed000(Axis::Pitch))?,
            MotionKind::SweepYaw => sway(SwayParams::seed000(Axis::Yaw))?,
            MotionKind::YawTurn => {
                let base = YawTurnParams::seed001();
                let p = YawTurnParams {
                    robot,
                    order,
                    stance_feet: robot.stance_feet(h),
                    lift_height_m: base.lift_height_m * h / SEED001_STANCE_HEIGHT_M,
                    ..base
                };
                (
                    Script::Law(AnyMotion::YawTurn(YawTurn::new(p)?)),
                    YAW_TURN_PERIODS * p.step_period_s,
                )
            }
            MotionKind::YawTurnFast => {
                let base = YawTurnParams::seed001();
                let p = YawTurnParams {
                    robot,
                    order,
                    stance_feet: robot.stance_feet(h),
                    lift_height_m: FAST_YAW_TURN_LIFT_FRACTION * h,
                    step_period_s: FAST_YAW_TURN_PERIOD_S,
                    ..base
                };
                (
                    Script::Law(AnyMotion::YawTurn(YawTurn::new(p)?)),
                    YAW_TURN_PERIODS * base.step_period_s,
                )
            }
            MotionKind::StableTurn => {
                let p = StableTurnParams {
                    order,
                    ..StableTurnParams::new(robot, h)
                };
                (
                    Script::Law(AnyMotion::StableTurn(StableTurn::new(p)?)),
                    STABLE_TURN_CYCLES * p.cycle_s,
                )
            }
            MotionKind::Trot => return Plan::trot(config, TrotShape::default()),
            MotionKind::TrotTurn => {
                let base = YawTurnParams::seed001();
                return Plan::gait(
                    MotionKind::TrotTurn,
                    config,
                    TrotShape::default(),
                    Velocity {
                        // Seed 001's turn rate; both counter-clockwise positive.
                        yaw_rad_s: base.yaw_rate_rad_s,
                        ..Velocity::default()
                    },
                    YAW_TURN_PERIODS * base.step_period_s,
                );
            }
        };
        Ok(Plan {
            kind,
            robot,
            order,
            stance_height_m: h,
            duration_s,
            script,
            law_start_s: 0.0,
        })
    }

    /// The trot of the catalogue ([`MotionKind::Trot`]) with another shape: a parameter
    /// study's entry point.
    ///
    /// # Errors
    /// kin-core's [`kin_core::motion::Error`] naming the gait parameter it refuses.
    pub fn trot(config: &Config, shape: TrotShape) -> Result<Plan, kin_core::motion::Error> {
        let velocity = Velocity {
            forward_m_s: shape.speed_heights_per_s * config.pose_config.stance_height_m,
            ..Velocity::default()
        };
        Plan::gait(MotionKind::Trot, config, shape, velocity, TROT_DURATION_S)
    }

    /// The trot turning on the spot ([`MotionKind::TrotTurn`]) with another shape (its
    /// speed is not used).
    ///
    /// # Errors
    /// kin-core's [`kin_core::motion::Error`] naming the gait parameter it refuses.
    pub fn trot_turn(config: &Config, shape: TrotShape) -> Result<Plan, kin_core::motion::Error> {
        let mut plan = Plan::new(MotionKind::TrotTurn, config)?;
        if let Script::Law(AnyMotion::Gait(g)) = plan.script {
            let v = g.params().velocity;
            plan = Plan::gait(MotionKind::TrotTurn, config, shape, v, plan.duration_s)?;
        }
        Ok(plan)
    }

    fn gait(
        kind: MotionKind,
        config: &Config,
        shape: TrotShape,
        velocity: Velocity,
        duration_s: f32,
    ) -> Result<Plan, kin_core::motion::Error> {
        let robot = config.robot;
        let h = config.pose_config.stance_height_m;
        let mut p = GaitParams::new(Pattern::Trot, robot, h);
        p.order = config.pose_config.order;
        p.cycle_s = shape.cycle_s;
        p.duty_factor = shape.duty_factor;
        p.step_height_m = shape.step_height_fraction * h;
        p.velocity = velocity;
        Ok(Plan {
            kind,
            robot,
            order: p.order,
            stance_height_m: h,
            duration_s,
            script: Script::Law(AnyMotion::Gait(Gait::new(p)?)),
            law_start_s: shape.four_feet_start() * shape.cycle_s,
        })
    }

    /// True when the plan holds the device's nominal stance at `t_s` (a stand-up's hold: the
    /// body level at the stance height, the feet at the stance): a host may then hold the
    /// pose on the device (`SetBodyPose` with the zero pose) instead of sending the feet every
    /// frame, which lets the device's leveling correct it.
    pub fn holds_stance(&self, t_s: f32) -> bool {
        matches!(self.script, Script::StandUp { .. }) && t_s >= STAND_RAMP_S
    }

    /// The plan as the device's motion engine runs it: the `StartMotion` command with the
    /// plan's parameters and, for the trots, the velocity to keep commanding. `None` for the
    /// stand-up, whose crouch-to-stance ramp the device does from its own rest pose instead.
    /// The trots' walker takes its duty factor from the gait pattern, not from the plan's
    /// shape.
    pub fn onboard(&self) -> Option<(MotionCommand, Option<Velocity>)> {
        let duration_s = Some(self.duration_s);
        let command = match self.script {
            Script::StandUp { .. } => return None,
            Script::Law(AnyMotion::Sway(m)) => {
                let p = m.params();
                MotionCommand::Sway {
                    axis: p.axis,
                    amplitude_rad: p.amplitude_rad,
                    period_s: p.period_s,
                    duration_s,
                }
            }
            Script::Law(AnyMotion::YawTurn(m)) => {
                let p = m.params();
                MotionCommand::YawTurn {
                    yaw_rate_rad_s: p.yaw_rate_rad_s,
                    step_period_s: p.step_period_s,
                    lift_height_m: p.lift_height_m,
                    duration_s,
                }
            }
            Script::Law(AnyMotion::StableTurn(m)) => {
                let p = m.params();
                MotionCommand::StableTurn {
                    yaw_per_cycle_rad: p.yaw_per_cycle_rad,
                    cycle_s: p.cycle_s,
                    lift_height_m: p.lift_height_m,
                    shift_fraction: p.shift_fraction,
                    duration_s,
                }
            }
            Script::Law(AnyMotion::Gait(g)) => {
                let p = g.params();
                // The catalogue's gaits are trots (`Plan::gait`).
                let command = MotionCommand::Walk {
                    gait: Pattern::Trot,
                    body_height_m: self.stance_height_m,
                    step_height_m: p.step_height_m,
                    cycle_s: p.cycle_s,
                    velocity_timeout_ms: DEFAULT_VELOCITY_TIMEOUT_MS,
                };
                return Some((command, Some(p.velocity)));
            }
            Script::Law(_) => return None,
        };
        Some((command, None))
    }

    /// The plan run for at least `duration_s` (a longer run than the motion's own: a stand-up
    /// holds its stance, a law runs on), to watch the answer to a disturbance.
    pub fn lasting_at_least(self, duration_s: f32) -> Plan {
        Plan {
            duration_s: self.duration_s.max(duration_s),
            ..self
        }
    }

    /// The motion.
    pub const fn kind(&self) -> MotionKind {
        self.kind
    }

    /// Duration, s.
    pub const fn duration_s(&self) -> f32 {
        self.duration_s
    }

    /// The stance height the motion keeps (the stand-up's final height), m.
    pub const fn stance_height_m(&self) -> f32 {
        self.stance_height_m
    }

    /// What the motion asks at `t_s`.
    ///
    /// # Errors
    /// kin-core's error for a non-finite time.
    pub fn target(&self, t_s: f32) -> Result<Target, kin_core::motion::Error> {
        let Frame {
            pose,
            feet_in_world,
            contact,
        } = self.frame(t_s)?;
        let r = rotation::matrix::<kin_core::DefaultMath>(
            self.order,
            pose.roll_rad,
            pose.pitch_rad,
            pose.yaw_rad,
        );
        let t = pose.translation();
        Ok(Target {
            pose,
            feet_in_body_m: feet_in_world.map(|p| r.transpose_mul_vec(p - t).to_array()),
            stance: contact.map(|c| c == Contact::Stance),
        })
    }

    /// The minimum static stability margin of the commanded motion (m, and the plan's time of
    /// it), sampled every `frame_s` over the plan with the masses `mass`
    /// ([`kin_core::stability`]); `None` when no sample's four legs solve.
    ///
    /// # Errors
    /// kin-core's error for invalid masses or a non-finite time step.
    pub fn min_static_margin(
        &self,
        mass: &MassModel,
        frame_s: f32,
    ) -> Result<Option<Extremum>, kin_core::motion::Error> {
        let sweep = Sweep::new(0.0, self.duration_s, 1.0 / frame_s)?;
        let mut checker = Checker::new(
            &self.robot,
            BodyConfig::about_centre(self.order),
            [DEFAULT_MAX_JOINT_SPEED_RAD_S; 3],
        )?
        .with_mass(mass)?;
        for k in 0..sweep.samples() {
            let t = sweep.time_s(k);
            let _ = checker.push_frame(t, &self.frame(t)?);
        }
        Ok(checker.finish().static_margin_m)
    }

    /// The commanded body pose, feet in the world and contacts at `t_s`.
    fn frame(&self, t_s: f32) -> Result<Frame, kin_core::motion::Error> {
        let (pose, feet_in_world, contact) = match self.script {
            Script::StandUp { rest_m, stance_m } => {
                let u = (t_s / STAND_RAMP_S).clamp(0.0, 1.0);
                // Raised cosine: zero speed at both ends of the ramp.
                let s = 0.5 - 0.5 * (core::f32::consts::PI * u).cos();
                let h = rest_m + (stance_m - rest_m) * s;
                // The feet stay on the ground at −stance (the world's floor); the body rises.
                let pose = Pose {
                    z_m: h - stance_m,
                    ..Pose::default()
                };
                (pose, self.robot.stance_feet(stance_m), [Contact::Stance; 4])
            }
            Script::Law(m) => {
                let f = m.frame::<kin_core::DefaultMath>(t_s + self.law_start_s)?;
                (f.pose, f.feet_in_world, f.contact)
            }
        };
        Ok(Frame {
            pose,
            feet_in_world,
            contact,
        })
    }
}
