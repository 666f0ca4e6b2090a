//! Motions sampled into the motion CSV ([`crate::csv::motion`]): the laws of both papers (seed
//! 001's sways and yaw turn, seed 000's foot paths, trot / walk), their parameters and their
//! validation, and [`run`], the operation behind `quadctl motion`.

use crate::csv::motion::{header, push_num, Output};
use crate::ops::defaults;
use crate::plot::{self, JointSeries};
use crate::{csv, robot_file};
use kin_core::motion::gait::{Gait, GaitParams, Pattern, Velocity};
use kin_core::motion::laws::{
    self, Axis, LegPaths, LegPathsParams, StableTurn, StableTurnParams, Sway, SwayParams, YawTurn,
    YawTurnParams,
};
use kin_core::motion::path::{AnyPath, PathKind, Rectangle, Stride};
use kin_core::motion::{self, AnyMotion, Motion};
use kin_core::preflight::{Sweep, MAX_SWEEP_SAMPLES};
use kin_core::{body, DefaultMath, ReachPolicy, Robot, RotationOrder, Vec3};
use std::io::Write;
use std::path::PathBuf;

/// The motion laws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Law {
    /// Seed 001 eq. 6: roll θ(t) = θ0 + A·sin(2πt/T), feet fixed.
    RollSway,
    /// Seed 001 eq. 8: pitch γ(t) = γ0 + A·sin(2πt/T), feet fixed.
    PitchSway,
    /// Yaw ψ(t) = ψ0 + A·sin(2πt/T), feet fixed (seed 000's twisting posture).
    YawSway,
    /// Seed 001 eq. 9–11 (corrected): ψ(t) = ψ0 − ω_z·t, crossed pairs stepping on circles.
    YawTurn,
    /// Seed 000 §3.2: every foot follows a closed path (default its rectangle) under a held body.
    RectPath,
    /// Trot: diagonal pairs in antiphase, duty 0.75, driven by a velocity command.
    Trot,
    /// Walk: one leg at a time (RL, FL, RR, FR), duty 0.75.
    Walk,
    /// A statically stable yaw turn: one leg at a time, the body shifted towards its support
    /// triangle first (kin-core's `StableTurn`).
    StableTurn,
}

impl Law {
    /// Every law, in the order of the command line's help.
    pub const ALL: [Law; 8] = [
        Law::RollSway,
        Law::PitchSway,
        Law::YawSway,
        Law::YawTurn,
        Law::RectPath,
        Law::Trot,
        Law::Walk,
        Law::StableTurn,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Law::RollSway => "roll-sway",
            Law::PitchSway => "pitch-sway",
            Law::YawSway => "yaw-sway",
            Law::YawTurn => "yaw-turn",
            Law::RectPath => "rect-path",
            Law::Trot => "trot",
            Law::Walk => "walk",
            Law::StableTurn => "stable-turn",
        }
    }

    /// One line on the law, with the equation it implements.
    pub fn summary(self) -> &'static str {
        match self {
            Law::RollSway => "Seed 001 eq. 6: roll θ(t) = θ0 + A·sin(2πt/T), feet fixed",
            Law::PitchSway => "Seed 001 eq. 8: pitch γ(t) = γ0 + A·sin(2πt/T), feet fixed",
            Law::YawSway => {
                "Yaw ψ(t) = ψ0 + A·sin(2πt/T), feet fixed (seed 000's twisting posture)"
            }
            Law::YawTurn => {
                "Seed 001 eq. 9–11 (corrected): ψ(t) = ψ0 − ω_z·t, crossed pairs stepping on \
                 circles"
            }
            Law::RectPath => {
                "Seed 000 §3.2: every foot follows a closed path (default its rectangle) under a \
                 held body"
            }
            Law::Trot => {
                "Trot: diagonal pairs in antiphase, duty 0.75, driven by a velocity command"
            }
            Law::Walk => "Walk: one leg at a time (RL, FL, RR, FR), duty 0.75",
            Law::StableTurn => {
                "Statically stable yaw turn: one leg at a time (FL, FR, RR, RL), the body shifted \
                 towards its support triangle first, Δψ per cycle"
            }
        }
    }

    /// The law named `name` ([`Law::name`]).
    pub fn parse(name: &str) -> Option<Law> {
        Law::ALL.into_iter().find(|l| l.name() == name)
    }
}

/// A law's parameters, every one optional: the defaults are the papers' (see `quadctl motion
/// --help`). Units in the names; the body pose's rotation order as kin-core's.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Params {
    /// Robot: a preset name or a TOML robot file ([`robot_file::resolve`]).
    pub robot: String,
    /// Stance height H, m.
    pub stance_height_m: Option<f32>,
    /// Rotation order of the body pose.
    pub rotation_order: Option<RotationOrder>,
    /// Sways: amplitude A, rad.
    pub amplitude_rad: Option<f32>,
    /// Sways: period T, s.
    pub period_s: Option<f32>,
    /// yaw-turn: yaw rate, rad/s (counter-clockwise positive).
    pub yaw_rate_rad_s: Option<f32>,
    /// yaw-turn: step period T1, s.
    pub step_period_s: Option<f32>,
    /// yaw-turn: lift height h_K, m.
    pub lift_height_m: Option<f32>,
    /// rect-path: path shape; trot/walk: swing shape.
    pub path: Option<PathKind>,
    /// rect-path: stride length, m.
    pub stride_m: Option<f32>,
    /// rect-path, trot, walk: swing apex above the ground, m.
    pub step_height_m: Option<f32>,
    /// rect-path, trot, walk: stance fraction of the cycle.
    pub duty_factor: Option<f32>,
    /// rect-path, trot, walk: cycle time, s.
    pub cycle_s: Option<f32>,
    /// trot, walk: forward speed, m/s.
    pub forward_m_s: Option<f32>,
    /// trot, walk: lateral speed (left positive), m/s.
    pub lateral_m_s: Option<f32>,
    /// trot, walk: yaw rate (counter-clockwise positive), rad/s.
    pub yaw_rad_s: Option<f32>,
    /// stable-turn: yaw of one cycle (counter-clockwise positive), rad.
    pub yaw_per_cycle_rad: Option<f32>,
    /// stable-turn: how far the body moves towards the centroid of its support triangle, in
    /// (0, 1].
    pub shift_fraction: Option<f32>,
}

/// Stance heights closer than this are the same stance, m (seed 001's initial pose through
/// forward kinematics against the device's rounded 0.9294 m).
const SAME_STANCE_M: f32 = 1e-4;

/// Errors of the motion operations (`motion`, `check`, `plot`, `accuracy`).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The robot could not be resolved.
    #[error(transparent)]
    Robot(#[from] robot_file::Error),
    /// A law parameter was refused by kin-core (its name mapped to the option).
    #[error("invalid {option}: {source}")]
    Parameter {
        /// The option.
        option: String,
        /// kin-core's error.
        source: motion::Error,
    },
    /// An option that the chosen law (or source) does not use.
    #[error("{option} does not apply to {law}")]
    NotApplicable {
        /// The option.
        option: &'static str,
        /// The law or source.
        law: &'static str,
    },
    /// A CSV could not be read or written.
    #[error(transparent)]
    Csv(#[from] csv::Error),
    /// Drawing failed.
    #[error(transparent)]
    Plot(#[from] plot::Error),
    /// `--duration-s` × `--rate-hz` is more samples than a sweep holds.
    #[error(
        "invalid {option}: {duration_s} s at {rate_hz} Hz is {samples:.3e} samples, at most \
         2^24 = {MAX_SWEEP_SAMPLES}",
        samples = f64::from(*duration_s) * f64::from(*rate_hz)
    )]
    TooManySamples {
        /// The option blamed.
        option: &'static str,
        /// Duration asked, s.
        duration_s: f32,
        /// Rate asked, Hz.
        rate_hz: f32,
    },
    /// A time to draw outside the file's samples.
    #[error("--at-s: {t_s} s is outside the file's samples, from {first_s} s to {last_s} s")]
    TimeOutOfRange {
        /// The time asked, s.
        t_s: f64,
        /// First sample's time, s.
        first_s: f64,
        /// Last sample's time, s.
        last_s: f64,
    },
    /// A time to draw that is not finite.
    #[error("--at-s: {0} is not a finite time")]
    NotFiniteTime(f64),
}

/// The command-line option of a kin-core parameter name.
pub fn option_of(parameter: &str) -> String {
    match parameter {
        "feet_in_world" | "stance_feet" => "--stance-height-m".to_owned(),
        "velocity" => "--forward-m-s/--lateral-m-s/--yaw-rate-rad-s".to_owned(),
        "path" => "--path/--stride-m/--step-height-m/--duty-factor".to_owned(),
        "max_joint_speed_rad_s" => "--max-joint-speed-rad-s".to_owned(),
        other => format!("--{}", other.replace('_', "-")),
    }
}

/// Wraps kin-core's error with the option it names.
pub fn param_err(e: motion::Error) -> Error {
    let name = match e {
        motion::Error::NonFinite(p)
        | motion::Error::NotPositive(p)
        | motion::Error::Negative(p) => Some(p.name()),
        motion::Error::OutOfRange { parameter, .. }
        | motion::Error::BeyondReach { parameter, .. } => Some(parameter.name()),
        _ => None,
    };
    Error::Parameter {
        option: name.map_or_else(|| "--robot".to_owned(), option_of),
        source: e,
    }
}

impl Params {
    /// The first law option given (all but `--robot` and `--rotation-order`), if any.
    pub fn law_option_given(&self) -> Option<&'static str> {
        [
            ("--stance-height-m", self.stance_height_m.is_some()),
            ("--amplitude-rad", self.amplitude_rad.is_some()),
            ("--period-s", self.period_s.is_some()),
            ("--yaw-rate-rad-s", self.yaw_rate_rad_s.is_some()),
            ("--step-period-s", self.step_period_s.is_some()),
            ("--lift-height-m", self.lift_height_m.is_some()),
            ("--path", self.path.is_some()),
            ("--stride-m", self.stride_m.is_some()),
            ("--step-height-m", self.step_height_m.is_some()),
            ("--duty-factor", self.duty_factor.is_some()),
            ("--cycle-s", self.cycle_s.is_some()),
            ("--forward-m-s", self.forward_m_s.is_some()),
            ("--lateral-m-s", self.lateral_m_s.is_some()),
            ("--yaw-rad-s", self.yaw_rad_s.is_some()),
            ("--yaw-per-cycle-rad", self.yaw_per_cycle_rad.is_some()),
            ("--shift-fraction", self.shift_fraction.is_some()),
        ]
        .into_iter()
        .find(|(_, given)| *given)
        .map(|(o, _)| o)
    }

    /// Refuses the options that `law` does not use.
    fn check_applicable(&self, law: Law) -> Result<(), Error> {
        let sway = matches!(law, Law::RollSway | Law::PitchSway | Law::YawSway);
        let gait = matches!(law, Law::Trot | Law::Walk);
        let rect = law == Law::RectPath;
        let stable = law == Law::StableTurn;
        let given: [(&'static str, bool, bool); 15] = [
            ("--amplitude-rad", self.amplitude_rad.is_some(), sway),
            ("--period-s", self.period_s.is_some(), sway),
            (
                "--yaw-rate-rad-s",
                self.yaw_rate_rad_s.is_some(),
                law == Law::YawTurn || gait,
            ),
            (
                "--step-period-s",
                self.step_period_s.is_some(),
                law == Law::YawTurn,
            ),
            (
                "--lift-height-m",
                self.lift_height_m.is_some(),
                law == Law::YawTurn || stable,
            ),
            ("--path", self.path.is_some(), rect || gait),
            ("--stride-m", self.stride_m.is_some(), rect),
            (
                "--step-height-m",
                self.step_height_m.is_some(),
                rect || gait,
            ),
            ("--duty-factor", self.duty_factor.is_some(), rect || gait),
            ("--cycle-s", self.cycle_s.is_some(), rect || gait || stable),
            ("--forward-m-s", self.forward_m_s.is_some(), gait),
            ("--lateral-m-s", self.lateral_m_s.is_some(), gait),
            ("--yaw-rad-s", self.yaw_rad_s.is_some(), gait),
            (
                "--yaw-per-cycle-rad",
                self.yaw_per_cycle_rad.is_some(),
                stable,
            ),
            ("--shift-fraction", self.shift_fraction.is_some(), stable),
        ];
        for (option, present, applies) in given {
            if present && !applies {
                return Err(Error::NotApplicable {
                    option,
                    law: law.name(),
                });
            }
        }
        Ok(())
    }

    /// The device's pose configuration of a preset robot (`quad_device::Config`, what the
    /// firmware and the simulated device run): the one source of a preset's rotation order, so
    /// that a motion's body poses read the same here and on the device. `None` for a robot
    /// file.
    pub fn device_pose_config(&self) -> Option<quad_protocol::PoseConfig> {
        let preset = quad_protocol::RobotPreset::from_name(self.robot.trim())?;
        quad_device::Config::for_preset(preset).map(|c| c.pose_config)
    }

    /// Stance feet (world frame of the nominal pose) and their height.
    fn stance(&self, robot: &Robot, default_height_m: Option<f32>) -> Result<[Vec3; 4], Error> {
        match self.stance_height_m.or(default_height_m) {
            Some(h) => {
                if !h.is_finite() {
                    return Err(param_err(motion::Error::NonFinite(
                        motion::Param::StanceHeightM,
                    )));
                }
                if h <= 0.0 {
                    return Err(param_err(motion::Error::NotPositive(
                        motion::Param::StanceHeightM,
                    )));
                }
                Ok(robot.stance_feet(h))
            }
            None => Ok(self.device_stance(robot)),
        }
    }

    /// The device's stance for a preset ([`defaults::stance_height_m`]: feet straight below
    /// the hips), seed 001's initial stance for a robot file. Where the device's stance is
    /// seed 001's initial pose (fernando2025's 0.9294 m), that pose's own feet (forward
    /// kinematics of eq. 5), which lie there within float rounding.
    fn device_stance(&self, robot: &Robot) -> [Vec3; 4] {
        let seed001 = laws::seed001_stance(robot);
        match defaults::stance_height_m(&self.robot) {
            Some(h) if (seed001[0].z + h).abs() > SAME_STANCE_M => robot.stance_feet(h),
            _ => seed001,
        }
    }

    /// Builds and validates the motion.
    pub fn build(&self, law: Law) -> Result<AnyMotion, Error> {
        self.check_applicable(law)?;
        let robot = robot_file::resolve(&self.robot)?;
        let device_order = self.device_pose_config().map(|c| c.order);
        let order =
            |default: RotationOrder| self.rotation_order.or(device_order).unwrap_or(default);
        Ok(match law {
            Law::RollSway | Law::PitchSway | Law::YawSway => {
                let axis = match law {
                    Law::RollSway => Axis::Roll,
                    Law::PitchSway => Axis::Pitch,
                    _ => Axis::Yaw,
                };
                let mut p = SwayParams::seed001(axis);
                p.robot = robot;
                p.feet_in_world = self.stance(&robot, None)?;
                p.order = order(RotationOrder::Zxy);
                if let Some(a) = self.amplitude_rad {
                    p.amplitude_rad = a;
                }
                if let Some(t) = self.period_s {
                    p.period_s = t;
                }
                AnyMotion::Sway(Sway::new(p).map_err(param_err)?)
            }
            Law::YawTurn => {
                let mut p = YawTurnParams::seed001();
                p.robot = robot;
                p.stance_feet = self.stance(&robot, None)?;
                p.order = order(RotationOrder::Zxy);
                if let Some(v) = self.yaw_rate_rad_s {
                    p.yaw_rate_rad_s = v;
                }
                if let Some(v) = self.step_period_s {
                    p.step_period_s = v;
                }
                if let Some(v) = self.lift_height_m {
                    p.lift_height_m = v;
                }
                AnyMotion::YawTurn(YawTurn::new(p).map_err(param_err)?)
            }
            Law::RectPath => {
                let kind = self.path.unwrap_or(PathKind::Rectangle);
                let seed = Rectangle::seed000().stride();
                let default_duty = if kind == PathKind::Rectangle {
                    seed.duty_factor()
                } else {
                    0.5
                };
                let stride = Stride::new(
                    self.stride_m.unwrap_or(seed.length_m()),
                    self.step_height_m.unwrap_or(seed.height_m()),
                    self.duty_factor.unwrap_or(default_duty),
                )
                .map_err(param_err)?;
                let mut p = LegPathsParams::seed000();
                p.robot = robot;
                p.path = AnyPath::new(kind, stride);
                p.stance_feet = self.stance(&robot, Some(Rectangle::SEED000_STANCE_HEIGHT_M))?;
                if let Some(c) = self.cycle_s {
                    p.cycle_s = c;
                }
                AnyMotion::LegPaths(LegPaths::new(p).map_err(param_err)?)
            }
            Law::Trot | Law::Walk => {
                let pattern = if law == Law::Trot {
                    Pattern::Trot
                } else {
                    Pattern::Walk
                };
                let stance = self.stance(&robot, None)?;
                let h = -stance[0].z;
                let mut p = GaitParams::new(pattern, robot, h);
                p.order = order(RotationOrder::Zyx);
                if let Some(v) = self.cycle_s {
                    p.cycle_s = v;
                }
                if let Some(v) = self.duty_factor {
                    p.duty_factor = v;
                }
                if let Some(v) = self.step_height_m {
                    p.step_height_m = v;
                }
                if let Some(k) = self.path {
                    p.swing = k;
                }
                p.velocity = Velocity {
                    forward_m_s: self.forward_m_s.unwrap_or(0.0),
                    lateral_m_s: self.lateral_m_s.unwrap_or(0.0),
                    yaw_rad_s: self.yaw_rad_s.or(self.yaw_rate_rad_s).unwrap_or(0.0),
                };
                AnyMotion::Gait(Gait::new(p).map_err(param_err)?)
            }
            Law::StableTurn => {
                // A preset's default stance is the device's (the twin's); a robot file's, seed
                // 001's initial pose.
                let device_h = self.device_pose_config().map(|c| c.stance_height_m);
                let stance = self.stance(&robot, device_h)?;
                let h = -stance[0].z;
                let mut p = StableTurnParams::new(robot, h);
                p.stance_feet = stance;
                p.order = order(RotationOrder::Zyx);
                if let Some(v) = self.yaw_per_cycle_rad {
                    p.yaw_per_cycle_rad = v;
                }
                if let Some(v) = self.cycle_s {
                    p.cycle_s = v;
                }
                if let Some(v) = self.lift_height_m {
                    p.lift_height_m = v;
                }
                if let Some(v) = self.shift_fraction {
                    p.shift_fraction = v;
                }
                AnyMotion::StableTurn(StableTurn::new(p).map_err(param_err)?)
            }
        })
    }
}

/// Validates `--duration-s` and `--rate-hz` into a sweep from t = 0.
///
/// Too many samples is blamed on the rate when the rate alone is beyond the limit (more than
/// [`MAX_SWEEP_SAMPLES`] per second), on the duration when the duration alone is (more than
/// [`MAX_SWEEP_SAMPLES`] seconds), else on both.
pub fn sweep(duration_s: f32, rate_hz: f32) -> Result<Sweep, Error> {
    Sweep::new(0.0, duration_s, rate_hz).map_err(|e| match e {
        motion::Error::OutOfRange {
            parameter: motion::Param::DurationS,
            ..
        } if duration_s.is_finite() && rate_hz.is_finite() => {
            let max = MAX_SWEEP_SAMPLES as f32;
            let option = if rate_hz > max {
                "--rate-hz"
            } else if duration_s > max {
                "--duration-s"
            } else {
                "--duration-s × --rate-hz"
            };
            Error::TooManySamples {
                option,
                duration_s,
                rate_hz,
            }
        }
        other => param_err(other),
    })
}

/// How far a long operation is, for a progress bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// It starts; this many samples to go.
    Start(u64),
    /// This many samples done.
    Done(u64),
    /// It ended (successfully or not).
    Finished,
}

/// Outcome of a written motion.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Written {
    /// Samples written.
    pub samples: u64,
    /// Samples with an unreachable leg.
    pub unreachable: u64,
    /// The first of them: time and the failing leg's error.
    pub first_unreachable: Option<(f64, kin_core::IkError)>,
}

/// Samples `m` over `sweep` into `out` as CSV, after a `# quadctl motion …` comment line
/// naming `law`, `robot` and the rotation order; keeps a decimated series for plotting when
/// `series` is given. `progress` is told the samples done, every 4096 and at the end.
///
/// # Errors
/// [`Error::Csv`] when writing fails, [`Error::Parameter`] when the motion refuses a time.
pub fn write_motion<T: Motion>(
    m: &T,
    sweep: &Sweep,
    law: &str,
    robot: &str,
    out: &mut dyn Write,
    mut series: Option<&mut JointSeries>,
    progress: &mut dyn FnMut(u64),
) -> Result<Written, Error> {
    let io_err = |source| Error::Csv(csv::Error::Write { path: None, source });
    writeln!(
        out,
        "# quadctl motion {law} robot={robot} rotation_order={} duration_s={} rate_hz={}",
        m.body_config().order,
        sweep.duration_s(),
        sweep.rate_hz()
    )
    .map_err(io_err)?;
    writeln!(out, "{}", header()).map_err(io_err)?;
    let n = sweep.samples();
    let keep_every = (n as usize).div_ceil(plot::MAX_POINTS).max(1) as u32;
    let rate = f64::from(sweep.rate_hz());
    let config = m.body_config();
    let solver = body::Solver::new(m.robot());
    let mut line = String::with_capacity(512);
    let (mut ryu32, mut ryu64) = (ryu::Buffer::new(), ryu::Buffer::new());
    let mut w = Written::default();
    for k in 0..n {
        let t64 = f64::from(k) / rate;
        let t = sweep.time_s(k);
        let frame = m.frame::<DefaultMath>(t).map_err(param_err)?;
        let sol = solver.inverse(
            &frame.pose,
            &config,
            &frame.feet_in_world,
            ReachPolicy::Reject,
        );
        line.clear();
        line.push_str(ryu64.format(t64));
        match &sol {
            Ok(s) => {
                for a in s.flat() {
                    line.push(',');
                    push_num(&mut line, &mut ryu32, a);
                }
            }
            Err(e) => {
                line.push_str(",,,,,,,,,,,,");
                w.unreachable += 1;
                w.first_unreachable.get_or_insert((t64, *e));
            }
        }
        for f in frame.feet_in_world {
            for v in f.to_array() {
                line.push(',');
                push_num(&mut line, &mut ryu32, v);
            }
        }
        for v in frame.pose.to_array() {
            line.push(',');
            push_num(&mut line, &mut ryu32, v);
        }
        line.push(',');
        match &sol {
            Ok(_) => line.push_str("ok"),
            Err(e) => {
                line.push_str(e.leg.name());
                line.push(':');
                line.push_str(e.kind.code());
            }
        }
        line.push('\n');
        out.write_all(line.as_bytes()).map_err(io_err)?;
        if let Some(s) = series.as_deref_mut() {
            if k % keep_every == 0 || k + 1 == n {
                s.push(t64, sol.as_ref().ok().map(|s| s.flat()));
            }
        }
        if k % 4096 == 4095 {
            progress(u64::from(k) + 1);
        }
        w.samples += 1;
    }
    progress(u64::from(n));
    Ok(w)
}

/// The minimum static stability margin of `law` over `duration_s` at `rate_hz` (m, and when),
/// with the robot's masses (a preset's physical preset, a robot file's `[physical]` table);
/// `None` when no sample's four legs solve. See `kin_core::stability`.
///
/// # Errors
/// Bad parameters, the robot, a bad sweep.
pub fn static_margin(
    params: &Params,
    law: Law,
    duration_s: f32,
    rate_hz: f32,
) -> Result<Option<kin_core::preflight::Extremum>, Error> {
    let m = params.build(law)?;
    let sw = sweep(duration_s, rate_hz)?;
    let mass = robot_file::resolve_description(&params.robot)?
        .physical
        .mass_model();
    let report = kin_core::preflight::check_with_mass(
        &m,
        &sw,
        [kin_core::preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3],
        &mass,
    )
    .map_err(param_err)?;
    Ok(report.static_margin_m)
}

/// What [`run`] is asked to write.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The law.
    pub law: Law,
    /// Its parameters.
    pub params: Params,
    /// Duration, s (samples at 0, 1/F, …, up to T).
    pub duration_s: f32,
    /// Sampling rate, Hz.
    pub rate_hz: f32,
    /// Output CSV file (a temporary file renamed when complete); `None`: stdout.
    pub output: Option<PathBuf>,
    /// Joint-angle plot (.svg or .png).
    pub plot: Option<PathBuf>,
}

/// Samples a law into a motion CSV (and a plot): everything is validated before a file is
/// created, and the output file appears only when complete. `progress` follows the sampling.
///
/// # Errors
/// Bad parameters, the robot, writing the CSV, drawing the plot.
pub fn run(args: &Request, progress: &mut dyn FnMut(Progress)) -> Result<Written, Error> {
    let m = args.params.build(args.law)?;
    let sw = sweep(args.duration_s, args.rate_hz)?;
    if let Some(p) = &args.plot {
        // Refuse a bad plot name or a missing directory before the long part and before the
        // CSV is written.
        plot::check_output(p)?;
    }
    let mut sink = Output::open(args.output.as_deref())?;
    progress(Progress::Start(u64::from(sw.samples())));
    let mut series = args.plot.as_ref().map(|_| JointSeries::default());
    let result = write_motion(
        &m,
        &sw,
        args.law.name(),
        &args.params.robot,
        &mut sink.out,
        series.as_mut(),
        &mut |done| progress(Progress::Done(done)),
    );
    progress(Progress::Finished);
    let written = match result {
        Ok(w) => w,
        Err(e) => {
            sink.abandon();
            return Err(e);
        }
    };
    sink.commit()?;
    if let (Some(path), Some(series)) = (&args.plot, &series) {
        let title = format!(
            "quadctl motion {} — joint angles ({})",
            args.law.name(),
            args.params.robot
        );
        plot::joint_angles(path, &title, series)?;
    }
    Ok(written)
}
