//! `quadctl motion`: sample a motion law (seed 001's sways and yaw turn, seed 000's foot path,
//! trot / walk) into a CSV of joint angles, feet and body pose; optional plot.
//!
//! Also the motion CSV format shared with `check` and `plot`: [`header`], [`MotionCsv`].

use super::pose::Order;
use super::RobotArgs;
use crate::plot::{self, JointSeries};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use kin_core::motion::gait::{Gait, GaitParams, Pattern, Velocity};
use kin_core::motion::laws::{
    self, Axis, LegPaths, LegPathsParams, Sway, SwayParams, YawTurn, YawTurnParams,
};
use kin_core::motion::path::{AnyPath, PathKind, Rectangle, Stride};
use kin_core::motion::{self, AnyMotion, Motion};
use kin_core::preflight::Sweep;
use kin_core::{body, LegId, Pose, ReachPolicy, Robot, RotationOrder, Vec3};
use std::fmt;
use std::io::{self, BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The motion laws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
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
    /// Trot: diagonal pairs in antiphase, duty 0.5, driven by a velocity command.
    Trot,
    /// Walk: one leg at a time (RL, FL, RR, FR), duty 0.75.
    Walk,
}

impl Law {
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
        }
    }
}

/// `--path`: the foot path shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PathArg {
    /// Lift, stride, lower, return (seed 000 Fig. 8).
    Rectangle,
    /// Semicircle of diameter the stride (its height is stride/2).
    Semicircle,
    /// Half ellipse.
    Ellipse,
    /// Cycloid (zero velocity at lift-off and touch-down).
    Cycloid,
    /// Quintic Bézier, C1 with the stance.
    Bezier,
}

impl From<PathArg> for PathKind {
    fn from(p: PathArg) -> PathKind {
        match p {
            PathArg::Rectangle => PathKind::Rectangle,
            PathArg::Semicircle => PathKind::Semicircle,
            PathArg::Ellipse => PathKind::Ellipse,
            PathArg::Cycloid => PathKind::Cycloid,
            PathArg::Bezier => PathKind::Bezier,
        }
    }
}

/// The law and its parameters, shared by `motion` and `check --motion`. Every parameter is
/// optional; the defaults are the papers' (see `quadctl motion --help`).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct LawArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    /// Stance height H (m): feet straight below the hips, H below them. Default: seed 001's
    /// initial pose (φ=120°, α=60°, β=0) through forward kinematics (0.9294 m for
    /// fernando2025); rect-path: 0.2 m (seed 000 Fig. 8).
    #[arg(long, value_name = "M")]
    pub stance_height_m: Option<f32>,
    /// Rotation order of the body pose [default: zxy for the sways and yaw-turn (seed 001),
    /// zyx otherwise].
    #[arg(long, value_enum)]
    pub rotation_order: Option<Order>,
    /// Sways: amplitude A, rad [default: 0.2].
    #[arg(long, value_name = "RAD")]
    pub amplitude_rad: Option<f32>,
    /// Sways: period T, s [default: 20].
    #[arg(long, value_name = "S")]
    pub period_s: Option<f32>,
    /// yaw-turn: ω_z, rad/s; positive turns clockwise seen from above [default: 0.085].
    #[arg(long, value_name = "RAD_S")]
    pub omega_rad_s: Option<f32>,
    /// yaw-turn: step period T1, s [default: 6].
    #[arg(long, value_name = "S")]
    pub step_period_s: Option<f32>,
    /// yaw-turn: lift height h_K, m [default: 0.3].
    #[arg(long, value_name = "M")]
    pub lift_height_m: Option<f32>,
    /// rect-path: path shape [default: rectangle]; trot/walk: swing shape [default: bezier].
    #[arg(long, value_enum)]
    pub path: Option<PathArg>,
    /// rect-path: stride length, m [default: 0.1].
    #[arg(long, value_name = "M")]
    pub stride_m: Option<f32>,
    /// rect-path, trot, walk: swing apex above the ground, m [default: rect-path 0.05,
    /// gaits 0.15·H].
    #[arg(long, value_name = "M")]
    pub step_height_m: Option<f32>,
    /// rect-path, trot, walk: stance fraction of the cycle, in (0, 1) [default: rectangle 1/3
    /// (one speed round the loop), other paths 0.5; trot 0.5, walk 0.75].
    #[arg(long, value_name = "D")]
    pub duty_factor: Option<f32>,
    /// rect-path, trot, walk: cycle time, s [default: rect-path 3, gaits 0.8].
    #[arg(long, value_name = "S")]
    pub cycle_s: Option<f32>,
    /// trot, walk: forward speed, m/s [default: 0].
    #[arg(long, value_name = "M_S")]
    pub forward_m_s: Option<f32>,
    /// trot, walk: lateral speed (left positive), m/s [default: 0].
    #[arg(long, value_name = "M_S")]
    pub lateral_m_s: Option<f32>,
    /// trot, walk: yaw rate (counter-clockwise positive), rad/s [default: 0].
    #[arg(long, value_name = "RAD_S")]
    pub yaw_rad_s: Option<f32>,
}

/// Arguments of `quadctl motion`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Sample a motion law into CSV: t, 12 joint angles, 4 feet, body pose, status",
    long_about = LONG_ABOUT,
    allow_negative_numbers = true
)]
pub struct Args {
    /// The motion law.
    #[arg(value_enum)]
    pub law: Law,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub law_args: LawArgs,
    /// Duration, s (samples at 0, 1/F, …, up to T).
    #[arg(long, value_name = "T")]
    pub duration_s: f32,
    /// Sampling rate, Hz.
    #[arg(long, value_name = "F")]
    pub rate_hz: f32,
    /// Output CSV file (written to a temporary file and renamed when complete); default stdout.
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also draw the joint angles over time (.svg or .png).
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
}

const LONG_ABOUT: &str = "\
Sample a motion law at a fixed rate and write one CSV row per sample.

Laws (defaults are the papers' values; seed 001's laws with --robot fernando2025 reproduce its
Fig. 4-6):
  roll-sway   seed 001 eq. 6: roll(t) = A·sin(2πt/T), feet fixed on the ground (eq. 7)
  pitch-sway  seed 001 eq. 8: pitch(t) = A·sin(2πt/T), feet fixed
  yaw-sway    yaw(t) = A·sin(2πt/T), feet fixed
              (A = 0.2 rad, T = 20 s, body centre fixed, rotation order zxy)
  yaw-turn    seed 001 eq. 9-11, corrected (docs/papers.md): yaw(t) = −ω_z·t; the crossed pairs
              (FL, RR) and (FR, RL) step alternately along the circles of their feet with a
              half-wave sine lift (ω_z = 0.085 rad/s, T1 = 6 s, h_K = 0.3 m)
  rect-path   seed 000 §3.2 Fig. 8: each foot runs a closed path under a held body (rectangle:
              stride 0.1 m, lift 0.05 m at stance height 0.2 m, 3 s per loop)
  trot, walk  gait driven by --forward-m-s, --lateral-m-s, --yaw-rad-s (stance feet fixed in
              the world, Bezier swing by default)

Frames and units: world frame = body frame of the nominal pose (x forward, y left, z up, origin
at the body centre); the ground is z = −H. Metres, radians, seconds.

Output columns: t_s; FL_abduction_rad, FL_hip_rad, FL_knee_rad, then FR, RL, RR likewise (the
canonical convention, all zero = leg straight down); FL_x_m, FL_y_m, FL_z_m, … RR_z_m (feet in
the world frame); roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m (body pose, feed to `quadctl
stream`); status: `ok`, or `<leg>:<reason>` for the first leg that cannot reach (its angle cells
are then all empty).

Bad parameters (negative durations or periods, zero rates, NaN, a step or lift height beyond
reach, options that do not apply to the law) are refused before anything is written, naming the
option; exit status 2. With --output, the file appears only when complete. Exit status 1 when
some samples are unreachable (the file is complete and says which).";

/// Errors of the motion commands.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// `--robot` could not be resolved.
    Robot(crate::robot_file::LoadError),
    /// A law parameter was refused by kin-core (its name mapped to the option).
    Parameter {
        /// The option.
        option: String,
        /// kin-core's error.
        source: motion::Error,
    },
    /// An option that the chosen law does not use.
    NotApplicable {
        /// The option.
        option: &'static str,
        /// The law.
        law: &'static str,
    },
    /// Reading or writing a file failed.
    Io {
        /// What was being done.
        context: String,
        /// The I/O error.
        source: io::Error,
    },
    /// A motion CSV could not be read.
    Csv {
        /// File and line.
        at: String,
        /// What is wrong.
        message: String,
    },
    /// Drawing failed.
    Plot(plot::PlotError),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Robot(e) => write!(f, "{e}"),
            Error::Parameter { option, source } => write!(f, "invalid {option}: {source}"),
            Error::NotApplicable { option, law } => {
                write!(f, "{option} does not apply to {law}")
            }
            Error::Io { context, source } => write!(f, "{context}: {source}"),
            Error::Csv { at, message } => write!(f, "{at}: {message}"),
            Error::Plot(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for Error {}

impl From<plot::PlotError> for Error {
    fn from(e: plot::PlotError) -> Self {
        Error::Plot(e)
    }
}

/// The command-line option of a kin-core parameter name.
pub fn option_of(parameter: &str) -> String {
    match parameter {
        "feet_in_world" | "stance_feet" => "--stance-height-m".to_owned(),
        "velocity" => "--forward-m-s/--lateral-m-s/--yaw-rad-s".to_owned(),
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
        | motion::Error::Negative(p) => Some(p),
        motion::Error::OutOfRange { parameter, .. }
        | motion::Error::BeyondReach { parameter, .. } => Some(parameter),
        _ => None,
    };
    Error::Parameter {
        option: name.map_or_else(|| "--robot".to_owned(), option_of),
        source: e,
    }
}

impl LawArgs {
    /// The first law option given (all but `--robot` and `--rotation-order`), if any.
    pub fn law_option_given(&self) -> Option<&'static str> {
        [
            ("--stance-height-m", self.stance_height_m.is_some()),
            ("--amplitude-rad", self.amplitude_rad.is_some()),
            ("--period-s", self.period_s.is_some()),
            ("--omega-rad-s", self.omega_rad_s.is_some()),
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
        let given: [(&'static str, bool, bool); 13] = [
            ("--amplitude-rad", self.amplitude_rad.is_some(), sway),
            ("--period-s", self.period_s.is_some(), sway),
            (
                "--omega-rad-s",
                self.omega_rad_s.is_some(),
                law == Law::YawTurn,
            ),
            (
                "--step-period-s",
                self.step_period_s.is_some(),
                law == Law::YawTurn,
            ),
            (
                "--lift-height-m",
                self.lift_height_m.is_some(),
                law == Law::YawTurn,
            ),
            ("--path", self.path.is_some(), rect || gait),
            ("--stride-m", self.stride_m.is_some(), rect),
            (
                "--step-height-m",
                self.step_height_m.is_some(),
                rect || gait,
            ),
            ("--duty-factor", self.duty_factor.is_some(), rect || gait),
            ("--cycle-s", self.cycle_s.is_some(), rect || gait),
            ("--forward-m-s", self.forward_m_s.is_some(), gait),
            ("--lateral-m-s", self.lateral_m_s.is_some(), gait),
            ("--yaw-rad-s", self.yaw_rad_s.is_some(), gait),
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

    /// Stance feet (world frame of the nominal pose) and their height.
    fn stance(&self, robot: &Robot, default_height_m: Option<f32>) -> Result<[Vec3; 4], Error> {
        match self.stance_height_m.or(default_height_m) {
            Some(h) => {
                if !h.is_finite() {
                    return Err(param_err(motion::Error::NonFinite("stance_height_m")));
                }
                if h <= 0.0 {
                    return Err(param_err(motion::Error::NotPositive("stance_height_m")));
                }
                Ok(robot.stance_feet(h))
            }
            None => Ok(laws::seed001_stance(robot)),
        }
    }

    /// Builds and validates the motion.
    pub fn build(&self, law: Law) -> Result<AnyMotion, Error> {
        self.check_applicable(law)?;
        let robot = crate::robot_file::resolve(&self.robot.robot).map_err(Error::Robot)?;
        let order = |default: RotationOrder| self.rotation_order.map_or(default, Into::into);
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
                if let Some(v) = self.omega_rad_s {
                    p.omega_rad_s = v;
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
                let kind: PathKind = self.path.map_or(PathKind::Rectangle, Into::into);
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
                    p.swing = k.into();
                }
                p.velocity = Velocity {
                    forward_m_s: self.forward_m_s.unwrap_or(0.0),
                    lateral_m_s: self.lateral_m_s.unwrap_or(0.0),
                    yaw_rad_s: self.yaw_rad_s.unwrap_or(0.0),
                };
                AnyMotion::Gait(Gait::new(p).map_err(param_err)?)
            }
        })
    }
}

/// Validates `--duration-s` and `--rate-hz` into a sweep from t = 0.
pub fn sweep(duration_s: f32, rate_hz: f32) -> Result<Sweep, Error> {
    Sweep::new(0.0, duration_s, rate_hz).map_err(param_err)
}

/// The CSV header of a motion.
pub fn header() -> String {
    let mut cols = vec!["t_s".to_owned()];
    for leg in LegId::ALL {
        for j in ["abduction", "hip", "knee"] {
            cols.push(format!("{leg}_{j}_rad"));
        }
    }
    for leg in LegId::ALL {
        for a in ["x", "y", "z"] {
            cols.push(format!("{leg}_{a}_m"));
        }
    }
    for c in [
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "x_m",
        "y_m",
        "z_m",
        "status",
    ] {
        cols.push(c.to_owned());
    }
    cols.join(",")
}

/// A progress bar on stderr when it is a terminal, hidden otherwise.
pub fn progress(len: u64, what: &str) -> ProgressBar {
    if !io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} samples ({per_sec}, {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

/// Pushes `v` as the shortest decimal that reads back to the same f32 (`ryu`; `-0` as `0`).
fn push_num(line: &mut String, buf: &mut ryu::Buffer, v: f32) {
    if v == 0.0 {
        line.push('0');
    } else {
        line.push_str(buf.format(v));
    }
}

/// Where the rows go: a temporary file renamed on success, or stdout.
struct Sink {
    out: Box<dyn Write>,
    temp: Option<(PathBuf, PathBuf)>,
}

impl Sink {
    fn open(output: Option<&Path>) -> Result<Sink, Error> {
        let Some(path) = output else {
            return Ok(Sink {
                out: Box::new(io::BufWriter::with_capacity(1 << 20, io::stdout())),
                temp: None,
            });
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "motion".to_owned());
        let temp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
        let file = std::fs::File::create(&temp).map_err(|source| Error::Io {
            context: format!("cannot create `{}`", temp.display()),
            source,
        })?;
        Ok(Sink {
            out: Box::new(io::BufWriter::with_capacity(1 << 20, file)),
            temp: Some((temp, path.to_owned())),
        })
    }

    /// Flushes and renames into place.
    fn commit(mut self) -> Result<(), Error> {
        let flushed = self.out.flush();
        let temp = self.temp.take();
        drop(self.out);
        match (flushed, temp) {
            (Ok(()), Some((temp, path))) => std::fs::rename(&temp, &path).map_err(|source| {
                let _ = std::fs::remove_file(&temp);
                Error::Io {
                    context: format!("cannot write `{}`", path.display()),
                    source,
                }
            }),
            (Ok(()), None) => Ok(()),
            (Err(source), temp) => {
                if let Some((temp, _)) = temp {
                    let _ = std::fs::remove_file(temp);
                }
                Err(Error::Io {
                    context: "cannot write the output".to_owned(),
                    source,
                })
            }
        }
    }

    /// Removes the temporary file.
    fn abandon(self) {
        if let Some((temp, _)) = self.temp {
            drop(self.out);
            let _ = std::fs::remove_file(temp);
        }
    }
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
/// `series` is given. `bar` advances per sample.
pub fn write_motion<T: Motion>(
    m: &T,
    sweep: &Sweep,
    law: &str,
    robot: &str,
    out: &mut dyn Write,
    mut series: Option<&mut JointSeries>,
    bar: &ProgressBar,
) -> Result<Written, Error> {
    let io_err = |source| Error::Io {
        context: "cannot write the output".to_owned(),
        source,
    };
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
    let mut line = String::with_capacity(512);
    let (mut ryu32, mut ryu64) = (ryu::Buffer::new(), ryu::Buffer::new());
    let mut w = Written::default();
    for k in 0..n {
        let t64 = f64::from(k) / rate;
        let t = sweep.time_s(k);
        let frame = m.frame(t).map_err(param_err)?;
        let sol = body::Solver::new(m.robot()).inverse(
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
            bar.inc(4096);
        }
        w.samples += 1;
    }
    bar.set_position(u64::from(n));
    Ok(w)
}

/// The exit status of a command that either succeeds ([`super::EXIT_OK`]) or fails: the error
/// on stderr and [`super::EXIT_FATAL`].
pub(super) fn exit_status(result: Result<(), Error>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::from(super::EXIT_OK),
        Err(e) => {
            eprintln!("quadctl: error: {e}");
            ExitCode::from(super::EXIT_FATAL)
        }
    }
}

/// `quadctl motion`.
pub fn run(args: &Args) -> ExitCode {
    match run_inner(args) {
        Ok(w) if w.unreachable == 0 => ExitCode::from(super::EXIT_OK),
        Ok(w) => {
            if let Some((t, e)) = w.first_unreachable {
                eprintln!(
                    "quadctl: {} of {} samples unreachable (first at t = {t} s: {e})",
                    w.unreachable, w.samples
                );
            }
            ExitCode::from(super::EXIT_MALFORMED)
        }
        Err(e) => {
            eprintln!("quadctl: error: {e}");
            ExitCode::from(super::EXIT_FATAL)
        }
    }
}

fn run_inner(args: &Args) -> Result<Written, Error> {
    // Everything is validated before a file is created.
    let m = args.law_args.build(args.law)?;
    let sw = sweep(args.duration_s, args.rate_hz)?;
    if let Some(p) = &args.plot {
        // Refuse a bad plot name before the long part.
        if !matches!(
            p.extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase)
                .as_deref(),
            Some("svg" | "png")
        ) {
            return Err(plot::PlotError::Format(p.display().to_string()).into());
        }
    }
    let mut sink = Sink::open(args.output.as_deref())?;
    let bar = progress(u64::from(sw.samples()), args.law.name());
    let mut series = args.plot.as_ref().map(|_| JointSeries::default());
    let result = write_motion(
        &m,
        &sw,
        args.law.name(),
        &args.law_args.robot.robot,
        &mut sink.out,
        series.as_mut(),
        &bar,
    );
    bar.finish_and_clear();
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
            args.law_args.robot.robot
        );
        plot::joint_angles(path, &title, series)?;
    }
    Ok(written)
}

/// One row of a motion CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionRow {
    /// 1-based line number.
    pub line: usize,
    /// Time, s.
    pub t_s: f64,
    /// The twelve angles, `None` when the row's status is not `ok`.
    pub angles: Option<[f32; 12]>,
    /// Feet in the world frame, when the file has them.
    pub feet: Option<[Vec3; 4]>,
    /// Body pose, when the file has it.
    pub pose: Option<Pose>,
    /// The status cell.
    pub status: String,
}

/// Reader of motion CSVs (the format [`header`] describes; extra columns are ignored, the feet
/// and pose columns are optional).
pub struct MotionCsv {
    /// The rotation order named by a `rotation_order=` token in a comment line before the
    /// header (as `quadctl motion` writes it), if any.
    pub rotation_order: Option<RotationOrder>,
    name: String,
    reader: Box<dyn BufRead>,
    line: usize,
    t: usize,
    angles: [usize; 12],
    feet: Option<[usize; 12]>,
    pose: Option<[usize; 6]>,
    status: usize,
    buf: String,
}

impl MotionCsv {
    /// Opens `path` (`-` for stdin) and reads its header.
    pub fn open(path: &Path) -> Result<MotionCsv, Error> {
        let input = crate::csv_io::Input::open(path).map_err(|e| Error::Csv {
            at: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_input(input)
    }

    /// Reads the header of `input`.
    pub fn from_input(input: crate::csv_io::Input) -> Result<MotionCsv, Error> {
        let crate::csv_io::Input { name, mut reader } = input;
        let mut buf = String::new();
        let mut line = 0;
        let mut rotation_order = None;
        let header = loop {
            buf.clear();
            let n = reader.read_line(&mut buf).map_err(|source| Error::Io {
                context: format!("cannot read `{name}`"),
                source,
            })?;
            if n == 0 {
                return Err(Error::Csv {
                    at: name,
                    message: "empty file: expected a header starting with t_s".to_owned(),
                });
            }
            line += 1;
            let t = buf.trim();
            if let Some(comment) = t.strip_prefix('#') {
                for token in comment.split_whitespace() {
                    if let Some(o) = token.strip_prefix("rotation_order=") {
                        rotation_order = RotationOrder::parse(o);
                    }
                }
            } else if !t.is_empty() {
                break t.to_owned();
            }
        };
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let at = |c: &str| cols.iter().position(|x| x.eq_ignore_ascii_case(c));
        let need = |c: &str| {
            at(c).ok_or_else(|| Error::Csv {
                at: format!("{name}:{line}"),
                message: format!(
                    "header has no `{c}` column (expected the `quadctl motion` format)"
                ),
            })
        };
        let t = need("t_s")?;
        let mut angles = [0usize; 12];
        for leg in LegId::ALL {
            for (j, jn) in ["abduction", "hip", "knee"].iter().enumerate() {
                angles[3 * leg.index() + j] = need(&format!("{leg}_{jn}_rad"))?;
            }
        }
        let status = need("status")?;
        let mut feet = Some([0usize; 12]);
        for leg in LegId::ALL {
            for (a, an) in ["x", "y", "z"].iter().enumerate() {
                match (at(&format!("{leg}_{an}_m")), feet.as_mut()) {
                    (Some(i), Some(f)) => f[3 * leg.index() + a] = i,
                    _ => feet = None,
                }
            }
        }
        let mut pose = Some([0usize; 6]);
        for (i, c) in ["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"]
            .iter()
            .enumerate()
        {
            match (at(c), pose.as_mut()) {
                (Some(k), Some(p)) => p[i] = k,
                _ => pose = None,
            }
        }
        Ok(MotionCsv {
            rotation_order,
            name,
            reader,
            line,
            t,
            angles,
            feet,
            pose,
            status,
            buf,
        })
    }

    /// The next row, `None` at the end.
    pub fn next_row(&mut self) -> Result<Option<MotionRow>, Error> {
        loop {
            self.buf.clear();
            let n = self
                .reader
                .read_line(&mut self.buf)
                .map_err(|source| Error::Io {
                    context: format!("cannot read `{}`", self.name),
                    source,
                })?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            let text = self.buf.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = text.split(',').map(str::trim).collect();
            let at = format!("{}:{}", self.name, self.line);
            let get = |i: usize| -> Result<&str, Error> {
                fields.get(i).copied().ok_or_else(|| Error::Csv {
                    at: at.clone(),
                    message: format!("expected at least {} fields, found {}", i + 1, fields.len()),
                })
            };
            let num = |i: usize| -> Result<f32, Error> {
                let s = get(i)?;
                s.parse::<f32>().map_err(|_| Error::Csv {
                    at: at.clone(),
                    message: format!("field {}: `{s}` is not a number", i + 1),
                })
            };
            let status = get(self.status)?.to_owned();
            let t_s: f64 = get(self.t)?.parse().map_err(|_| Error::Csv {
                at: at.clone(),
                message: format!("field {}: t_s is not a number", self.t + 1),
            })?;
            let angles = if status == "ok" {
                let mut a = [0.0f32; 12];
                for (slot, &i) in a.iter_mut().zip(&self.angles) {
                    *slot = num(i)?;
                }
                Some(a)
            } else {
                None
            };
            let feet = match self.feet {
                Some(idx) => {
                    let mut f = [Vec3::ZERO; 4];
                    for (l, foot) in f.iter_mut().enumerate() {
                        *foot =
                            Vec3::new(num(idx[3 * l])?, num(idx[3 * l + 1])?, num(idx[3 * l + 2])?);
                    }
                    Some(f)
                }
                None => None,
            };
            let pose = match self.pose {
                Some(idx) => {
                    let mut v = [0.0f32; 6];
                    for (slot, &i) in v.iter_mut().zip(&idx) {
                        *slot = num(i)?;
                    }
                    Some(Pose::from_array(v))
                }
                None => None,
            };
            return Ok(Some(MotionRow {
                line: self.line,
                t_s,
                angles,
                feet,
                pose,
                status,
            }));
        }
    }
}
