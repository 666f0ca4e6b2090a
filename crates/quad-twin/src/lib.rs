//! # quad-twin — the physics twin, device side
//!
//! Runs the device controller (`quad-device`) frame by frame and couples it to the MuJoCo
//! twin (the `twin/` Python package) across a process boundary ([`link`]): every 20 ms servo
//! frame, the device's twelve pulses and the joint angles they map to through the device's
//! own calibration go to the twin, which holds them for the frame, steps the physics at the
//! model's time step and answers with the body state and the frame's IMU samples, which reach
//! the device at their times before its next frame ([`imu`]). At the end the twin computes the
//! run's metrics ([`Summary`]) and, when asked, its plots and pictures.
//!
//! - [`device`]: the controller in this process ([`device::InProcess`], on the shared in-memory
//!   fakes of `quad_device::sim`).
//! - [`motions`]: the motions of the twin's catalogue, from kin-core's motion laws.
//! - [`source`]: [`source::FrameSource`], where frames come from ([`source::HostDriven`]: a
//!   host sending `SetFeet` every frame to the in-process device;
//!   [`emulated::Emulated`]: the firmware ELF in simavr, its pin pulses measured).
//! - [`link`]: the JSON-lines protocol and the twin process.
//! - [`imu`]: the twin's IMU samples on their way to the device ([`imu::TwinImu`], the feed
//!   of the emulated sensor).
//! - [`scenario`]: the floor (level, a slope, tilting) and a push on the body.
//! - [`command`]: `quadctl sim` and `quadctl export` (robot argument to a run or a file).

pub mod command;
pub mod device;
pub mod emulated;
pub mod imu;
pub mod link;
pub mod motions;
pub mod scenario;
pub mod source;

use core::fmt;
use quad_device::Config;
use quad_model::{Model, Physical};
use scenario::Scenario;
use serde::Deserialize;
use source::FrameSource;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use motions::{MotionKind, Plan, TrotShape};

/// Why a twin run failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The physical model was refused.
    Model(quad_model::Error),
    /// The motion was refused (a parameter out of reach) or a sample failed.
    Motion(kin_core::motion::Error),
    /// The device refused frame `frame`.
    Device {
        /// The frame index.
        frame: u32,
        /// What the device said.
        error: device::DeviceError,
    },
    /// The twin's Python environment is missing.
    Venv(quad_model::venv::Missing),
    /// Starting or talking to the twin failed.
    Io(std::io::Error),
    /// A message could not be encoded or an answer decoded.
    Json(serde_json::Error),
    /// The twin answered out of protocol.
    Protocol(&'static str),
    /// The twin reported an error.
    Twin {
        /// The twin's message.
        message: String,
    },
    /// The twin exited with a failure.
    Exit(std::process::ExitStatus),
    /// The emulated firmware or its link failed.
    Emulator(quad_host::client::Error),
    /// The emulated firmware runs another robot or stance than the one asked for.
    FirmwareConfig {
        /// The robot the firmware reports.
        firmware: quad_protocol::RobotPreset,
    },
    /// A servo pin showed no complete pulse within three periods while the outputs were on.
    NoPulse {
        /// The frame index.
        frame: u32,
        /// The servo.
        servo: quad_protocol::ServoId,
    },
    /// The rendered picture could not be copied to its file (nothing is left at its path).
    Picture(quad_model::Error),
    /// The motion has no onboard form (the device's engine does not run it as the plan does).
    NotOnboard {
        /// The motion's name.
        motion: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Model(e) => write!(f, "model: {e}"),
            Error::Motion(e) => write!(f, "motion: {e}"),
            Error::Device { frame, error } => write!(f, "frame {frame}: {error}"),
            Error::Venv(e) => write!(f, "{e}"),
            Error::Io(e) => write!(f, "twin process: {e}"),
            Error::Json(e) => write!(f, "twin protocol: {e}"),
            Error::Protocol(what) => write!(f, "twin protocol: {what}"),
            Error::Twin { message } => write!(f, "twin: {message}"),
            Error::Exit(status) => write!(f, "twin exited with {status}"),
            Error::Emulator(e) => write!(f, "emulated firmware: {e}"),
            Error::FirmwareConfig { firmware } => write!(
                f,
                "the firmware runs robot {} at its default stance; the emulator can only drive \
                 that robot and stance",
                quad_host::names::robot_preset_name(*firmware)
            ),
            Error::NoPulse { frame, servo } => {
                write!(f, "frame {frame}: no pulse on servo {servo}'s pin")
            }
            Error::Picture(e) => write!(f, "picture: {e}"),
            Error::NotOnboard { motion } => write!(
                f,
                "{motion} has no onboard form (the device's stand-up starts from its own rest \
                 pose); run it host-driven"
            ),
        }
    }
}

impl std::error::Error for Error {}

/// The yaw reached against the yaw commanded.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct YawMetric {
    /// Commanded yaw change over the run, rad.
    pub commanded_rad: f64,
    /// Body yaw change reached, rad (unwrapped).
    pub achieved_rad: f64,
    /// `achieved / commanded`.
    pub ratio: f64,
}

/// The distance and heading reached against the commanded ones.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct TravelMetric {
    /// Commanded horizontal displacement, m.
    pub commanded_m: f64,
    /// Reached horizontal displacement, m.
    pub achieved_m: f64,
    /// Displacement along the commanded direction over the commanded distance.
    pub ratio: f64,
    /// Angle between the reached and commanded displacements, rad.
    pub heading_error_rad: f64,
}

/// Peak and RMS torque of one joint.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct JointTorque {
    /// Joint name (`FL_hip`, …).
    pub name: String,
    /// Peak |torque|, N·m.
    pub peak_nm: f64,
    /// RMS torque, N·m.
    pub rms_nm: f64,
}

/// Torque figures of a run.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct TorqueMetric {
    /// The servo's stall torque, N·m.
    pub stall_nm: f64,
    /// Per joint, canonical order.
    pub joints: Vec<JointTorque>,
    /// The highest peak, N·m.
    pub peak_nm: f64,
    /// The joint with the highest peak.
    pub peak_joint: String,
    /// Fraction of the run's samples in which some servo was at full duty (saturated).
    pub saturated_fraction: f64,
}

/// Foot slip while the motion has the foot on the ground.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct SlipMetric {
    /// Largest horizontal travel of a foot within one stance phase, m.
    pub max_stance_slip_m: f64,
    /// Per leg, m.
    pub per_leg_max_m: [f64; 4],
}

/// Body roll and pitch against the commanded ones.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct TrackingMetric {
    /// RMS of (reached − commanded) roll, rad.
    pub roll_rms_error_rad: f64,
    /// RMS of (reached − commanded) pitch, rad.
    pub pitch_rms_error_rad: f64,
    /// Reached over commanded peak-to-peak amplitude of the swaying axis (1 = tracks).
    pub amplitude_ratio: Option<f64>,
}

/// How one leg stepped (motions that lift feet).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct LegStepping {
    /// How far the foot moved back under the body over its whole commanded stances, along the
    /// commanded sweep, against the commanded sweep (1 = the stride is swept; none without a
    /// whole stance).
    pub stance_sweep_ratio: Option<f64>,
    /// Share of the commanded-stance frames with the foot on the floor.
    pub contact_in_stance: Option<f64>,
    /// Share of the commanded-swing frames with the foot on the floor.
    pub contact_in_swing: Option<f64>,
    /// Mean knee error (reached − target) in stance, rad.
    pub knee_error_in_stance_rad: Option<f64>,
}

/// Why a gait covers less ground than commanded, per leg.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct SteppingMetric {
    /// Per leg, FL, FR, RL, RR.
    pub legs: [LegStepping; 4],
}

/// How the body answered the run's slope, tilting floor or push ([`scenario`]).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct ScenarioMetric {
    /// The slope's axis (`roll`, `pitch`).
    pub axis: scenario::SlopeAxis,
    /// The floor's slope from the start, rad.
    pub slope_rad: f64,
    /// The floor's tilt during the run, rad.
    pub tilt_by_rad: Option<f64>,
    /// The push's impulse, N·s.
    pub push_n_s: Option<f64>,
    /// Start of the tilt or the push, motion clock, s (0 on a fixed slope).
    pub disturbance_start_s: f64,
    /// End of the tilt or the push, s (0 on a fixed slope).
    pub disturbance_end_s: f64,
    /// Largest body |roll| from the disturbance's start, rad.
    pub max_abs_roll_rad: f64,
    /// Largest body |pitch| from the disturbance's start, rad.
    pub max_abs_pitch_rad: f64,
    /// Body roll settled at the run's end (mean of its last 0.5 s), rad.
    pub settled_roll_rad: f64,
    /// Body pitch settled at the run's end, rad.
    pub settled_pitch_rad: f64,
    /// From the disturbance's end until roll and pitch stay within 0.5° of their settled
    /// values, s (none: they never do).
    pub settling_time_s: Option<f64>,
}

/// The device's attitude estimate against the body's true attitude.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct EstimateMetric {
    /// RMS error of the roll, rad.
    pub roll_rms_error_rad: f64,
    /// RMS error of the pitch, rad.
    pub pitch_rms_error_rad: f64,
    /// Largest roll or pitch error, rad.
    pub max_error_rad: f64,
}

/// The IMU's samples of a run (`trace.npz` keeps them with the true attitude).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct AttitudeMetric {
    /// Samples taken.
    pub imu_samples: u64,
    /// Their rate, Hz.
    pub imu_rate_hz: Option<f64>,
    /// The device's estimate against the true attitude, when the device reports one.
    pub estimate: Option<EstimateMetric>,
}

/// The metrics of one run (the twin's `summary.json`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Summary {
    /// Robot name.
    pub robot: String,
    /// Motion name.
    pub motion: String,
    /// Servo preset.
    pub servo: String,
    /// Simulated motion time, s (after the settling time).
    pub duration_s: f64,
    /// Physics rate, Hz.
    pub physics_hz: f64,
    /// Simulated seconds per wall-clock second of the twin's stepping.
    pub sim_per_wall: f64,
    /// True when the body fell (see `fall_reason`).
    pub fell: bool,
    /// Which threshold the fall crossed, and when.
    pub fall_reason: Option<String>,
    /// Lowest body-centre height over the floor (along its normal, on a slope) during the
    /// motion, m.
    pub min_height_m: f64,
    /// Largest |roll| or |pitch| during the motion, rad.
    pub max_tilt_rad: f64,
    /// For turning motions.
    pub yaw: Option<YawMetric>,
    /// For moving motions.
    pub travel: Option<TravelMetric>,
    /// Slip of the stance feet.
    pub slip: SlipMetric,
    /// Servo torques.
    pub torque: TorqueMetric,
    /// Roll/pitch tracking of the commanded body pose.
    pub tracking: TrackingMetric,
    /// Stance sweep and contact timing, for motions that lift feet.
    #[serde(default)]
    pub stepping: Option<SteppingMetric>,
    /// The answer to the run's slope, tilt or push (none on a level floor without a push).
    #[serde(default)]
    pub scenario: Option<ScenarioMetric>,
    /// The IMU's samples and the device's attitude estimate against the truth.
    #[serde(default)]
    pub attitude: Option<AttitudeMetric>,
    /// Files written (summary, plots, pictures).
    #[serde(default)]
    pub files: Vec<PathBuf>,
}

/// Where the device's frames come from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Driver {
    /// The device controller (`quad-device`) in-process, as behind the simulated link
    /// ([`source::HostDriven`]).
    #[default]
    Device,
    /// The firmware ELF in simavr ([`emulated::Emulated`]; none: built from `firmware-avr/`).
    Emulator {
        /// The ELF.
        elf: Option<PathBuf>,
    },
}

/// How to run the twin.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Where the model, summary, plots and pictures go (none: a temporary directory for the
    /// model and no other file, unless `picture` asks for one).
    pub out_dir: Option<PathBuf>,
    /// Render a GIF and a strip of frames (into `out_dir`).
    pub render: bool,
    /// Also copy the rendered animation to this file (a GIF; the strip of frames, a PNG, when
    /// the name ends in `.png`; its directory made if missing); renders even without `render`
    /// and `out_dir`.
    pub picture: Option<PathBuf>,
    /// Where the frames come from.
    pub driver: Driver,
    /// The device runs the motion itself (its motion engine, started once; a walk's velocity
    /// sent every frame) instead of getting every frame's feet from the host.
    pub onboard: bool,
    /// The floor and a push ([`scenario`]); the default: a level floor, no push.
    pub scenario: Scenario,
    /// The device's balance functions (`SetBalance`, sent once its sensor has a reading: in
    /// process [`device::InProcess::set_balance_when_ready`], emulated
    /// [`emulated::Emulated::set_balance`]). The device then first runs 1.1 s with the robot
    /// still before the run ([`device::REST_BEFORE_RUN_FRAMES`]; its gyro-bias measurement
    /// needs a second of stillness), so that it estimates from the first frame; none: the device's power-on settings (leveling
    /// off, fall detection on). The in-process device's attitude estimate is in every frame;
    /// the emulated firmware's only with balance settings (a `GetImu` every frame).
    pub balance: Option<quad_protocol::BalanceConfig>,
}

/// Time the first frame is held before the motion starts, s: the robot, placed with its feet
/// on the floor, settles under gravity.
pub const SETTLE_S: f32 = 0.5;

/// A finished run: the metrics and the wall time of the whole loop.
#[derive(Debug, Clone)]
pub struct Run {
    /// The twin's metrics.
    pub summary: Summary,
    /// Wall-clock time of the loop (device stepping, pipe, physics), s.
    pub wall_s: f64,
    /// Simulated seconds per wall second of the whole loop.
    pub sim_per_wall: f64,
    /// The commanded motion's minimum static stability margin (m) and its time after the
    /// settling, with the physical model's masses ([`Plan::min_static_margin`] at the servo
    /// frame rate); `None` when no frame's legs all solve.
    pub static_margin: Option<kin_core::preflight::Extremum>,
}

impl fmt::Display for Run {
    /// The run's metrics for people, one aspect a line.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        writeln!(
            f,
            "{} {} ({} servos): fell={} min_height={:.3} m max_tilt={:.3} rad",
            s.robot, s.motion, s.servo, s.fell, s.min_height_m, s.max_tilt_rad
        )?;
        if let Some(reason) = &s.fall_reason {
            writeln!(f, "  fall: {reason}")?;
        }
        if let Some(m) = &self.static_margin {
            writeln!(
                f,
                "  static stability margin (commanded): min {:.4} m at {:.2} s",
                m.value, m.t_s
            )?;
        }
        if let Some(y) = &s.yaw {
            writeln!(
                f,
                "  yaw: commanded {:.3} rad, achieved {:.3} rad, ratio {:.2}",
                y.commanded_rad, y.achieved_rad, y.ratio
            )?;
        }
        if let Some(t) = &s.travel {
            writeln!(
                f,
                "  travel: commanded {:.3} m, achieved {:.3} m, ratio {:.2}, heading error {:.3} rad",
                t.commanded_m, t.achieved_m, t.ratio, t.heading_error_rad
            )?;
        }
        writeln!(
            f,
            "  slip: max {:.4} m per stance {:?}",
            s.slip.max_stance_slip_m, s.slip.per_leg_max_m
        )?;
        writeln!(
            f,
            "  torque: peak {:.3} N·m at {} (stall {:.2}), saturated {:.1} % of steps",
            s.torque.peak_nm,
            s.torque.peak_joint,
            s.torque.stall_nm,
            100.0 * s.torque.saturated_fraction
        )?;
        write!(f, " ")?;
        for j in &s.torque.joints {
            write!(f, " {}={:.2}/{:.2}", j.name, j.peak_nm, j.rms_nm)?;
        }
        writeln!(f)?;
        writeln!(
            f,
            "  tracking: roll rms {:.4} rad, pitch rms {:.4} rad, amplitude ratio {:?}",
            s.tracking.roll_rms_error_rad,
            s.tracking.pitch_rms_error_rad,
            s.tracking.amplitude_ratio
        )?;
        if let Some(st) = &s.stepping {
            let per_leg = |value: fn(&LegStepping) -> Option<f64>| {
                st.legs
                    .iter()
                    .map(|l| value(l).map_or_else(|| "-".to_owned(), |v| format!("{v:.2}")))
                    .collect::<Vec<_>>()
                    .join(" / ")
            };
            writeln!(
                f,
                "  stepping (FL / FR / RL / RR): stance sweep {}, on the floor in swing {}, knee error in stance {} rad",
                per_leg(|l| l.stance_sweep_ratio),
                per_leg(|l| l.contact_in_swing),
                per_leg(|l| l.knee_error_in_stance_rad)
            )?;
        }
        if let Some(sc) = &s.scenario {
            let deg = f64::to_degrees;
            write!(
                f,
                "  scenario: slope {:.1}° {}",
                deg(sc.slope_rad),
                sc.axis.name()
            )?;
            if let Some(tilt) = sc.tilt_by_rad {
                write!(f, ", floor tilting {:+.1}°", deg(tilt))?;
            }
            if let Some(push) = sc.push_n_s {
                write!(f, ", push {push:.2} N·s")?;
            }
            writeln!(
                f,
                " ({:.2}–{:.2} s): body |roll| max {:.2}°, |pitch| max {:.2}°, settled roll {:.2}° pitch {:.2}°, settling time {}",
                sc.disturbance_start_s,
                sc.disturbance_end_s,
                deg(sc.max_abs_roll_rad),
                deg(sc.max_abs_pitch_rad),
                deg(sc.settled_roll_rad),
                deg(sc.settled_pitch_rad),
                sc.settling_time_s
                    .map_or_else(|| "none (not settled)".to_owned(), |t| format!("{t:.2} s"))
            )?;
        }
        if let Some(a) = &s.attitude {
            write!(
                f,
                "  imu: {} samples at {} Hz",
                a.imu_samples,
                a.imu_rate_hz
                    .map_or_else(|| "-".to_owned(), |r| format!("{r:.0}"))
            )?;
            match &a.estimate {
                Some(e) => writeln!(
                    f,
                    "; estimate error roll rms {:.2}°, pitch rms {:.2}°, max {:.2}°",
                    e.roll_rms_error_rad.to_degrees(),
                    e.pitch_rms_error_rad.to_degrees(),
                    e.max_error_rad.to_degrees()
                )?,
                None => writeln!(f)?,
            }
        }
        writeln!(
            f,
            "  speed: physics {:.1} sim s / wall s; whole loop {:.2} sim s / wall s ({:.2} s wall)",
            s.sim_per_wall, self.sim_per_wall, self.wall_s
        )?;
        for file in &s.files {
            writeln!(f, "  wrote {}", file.display())?;
        }
        Ok(())
    }
}

/// Runs `kind` on the device of `config` with the physical model `physical`: the device (or
/// the firmware in simavr, [`RunOptions::driver`]) is driven as a host would, the twin steps
/// the physics.
///
/// # Errors
/// [`Error`].
pub fn run(
    config: &quad_device::Config,
    physical: &Physical,
    kind: MotionKind,
    options: &RunOptions,
) -> Result<Run, Error> {
    let plan = Plan::new(kind, config).map_err(Error::Motion)?;
    run_plan(config, physical, &plan, options)
}

/// [`run`] with a plan built by the caller (e.g. [`Plan::trot`] with another shape).
///
/// # Errors
/// [`Error`].
pub fn run_plan(
    config: &quad_device::Config,
    physical: &Physical,
    plan: &Plan,
    options: &RunOptions,
) -> Result<Run, Error> {
    let model = Model::new(config.robot, *physical).map_err(Error::Model)?;
    // The device's joint-speed limiter set for the twin's servos, by the rule of its default
    // (half the no-load speed): the default is for MG996R-class servos, and a faster servo
    // would otherwise be held back to their speed.
    let config = &quad_device::Config {
        joint_speed_limit_rad_s: quad_device::engine::limit_for_servo(
            physical.servo.no_load_speed_rad_s,
        ),
        ..*config
    };
    let plan = match options.scenario.min_duration_s() {
        Some(d) => plan.lasting_at_least(d),
        None => *plan,
    };
    let static_margin = plan
        .min_static_margin(&physical.mass_model(), source::FRAME_S)
        .map_err(Error::Motion)?;
    let mut source: Box<dyn FrameSource> = match &options.driver {
        Driver::Device => {
            let mut device = device::InProcess::start(*config)
                .map_err(|error| Error::Device { frame: 0, error })?;
            if let Some(balance) = options.balance {
                device
                    .rest_before_run(
                        quad_device::ImuSample {
                            accel_m_s2: options.scenario.at_rest_accel_m_s2(imu::GRAVITY_M_S2),
                            gyro_rad_s: [0.0; 3],
                        },
                        device::REST_BEFORE_RUN_FRAMES,
                    )
                    .map_err(|error| Error::Device { frame: 0, error })?;
                device.set_balance_when_ready(balance);
            }
            if options.onboard {
                Box::new(source::Onboard::new(plan, device).ok_or(Error::NotOnboard {
                    motion: plan.kind().name(),
                })?)
            } else {
                let source = source::HostDriven::new(plan, device);
                Box::new(match options.balance {
                    Some(b) if b.leveling => source.hold_pose(),
                    _ => source,
                })
            }
        }
        Driver::Emulator { elf } => {
            let mut emulated = emulated::Emulated::boot_on(
                plan,
                config,
                elf.as_deref(),
                options.onboard,
                &options.scenario,
            )?;
            if let Some(balance) = options.balance {
                emulated.set_balance(balance)?;
            }
            Box::new(emulated)
        }
    };
    let tmp = tempfile::tempdir().map_err(Error::Io)?;
    let out_dir = match (&options.out_dir, &options.picture) {
        (Some(dir), _) => Some(dir.as_path()),
        (None, Some(_)) => Some(tmp.path()),
        (None, None) => None,
    };
    if let Some(dir) = out_dir {
        std::fs::create_dir_all(dir).map_err(Error::Io)?;
    }
    let model_path = link::model_path(out_dir, tmp.path());
    quad_model::mjcf::write(&model, &model_path).map_err(Error::Model)?;
    let robot_name = quad_model::mjcf::robot_name(&model);
    let mut run = run_source_in(
        source.as_mut(),
        &model_path,
        robot_name,
        &plan,
        out_dir,
        options.render || options.picture.is_some(),
        &options.scenario,
    )?;
    run.static_margin = static_margin;
    if let (Some(picture), Some(dir)) = (&options.picture, out_dir) {
        let strip = picture
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        let rendered = dir.join(if strip { "strip.png" } else { "motion.gif" });
        let bytes = std::fs::read(&rendered).map_err(Error::Io)?;
        // The picture's directory is made as `out_dir` is (`--render target/twin/run.gif`).
        if let Some(parent) = picture.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(Error::Io)?;
        }
        quad_model::write_atomic(picture, &bytes).map_err(Error::Picture)?;
        if options.out_dir.is_none() {
            run.summary.files.clear();
        }
        run.summary.files.push(picture.clone());
    }
    Ok(run)
}

/// The device configuration of `robot`: its preset's when it is a preset's geometry, else
/// seed 000's robot's device settings on this geometry (reported as a custom robot);
/// `stance_height_m` overrides the stance.
pub fn config_for(robot: &kin_core::Robot, stance_height_m: Option<f32>) -> Config {
    let mut config = [Config::shahriar2023(), Config::fernando2025()]
        .into_iter()
        .find(|c| c.robot == *robot)
        .unwrap_or(Config {
            preset: quad_protocol::RobotPreset::Custom,
            robot: *robot,
            ..Config::shahriar2023()
        });
    if let Some(h) = stance_height_m {
        config.pose_config.stance_height_m = h;
    }
    config
}

/// The loop on any frame source, on a level floor without a push.
///
/// # Errors
/// [`Error`].
pub fn run_source(
    source: &mut dyn FrameSource,
    model_path: &Path,
    robot_name: &str,
    plan: &Plan,
    out_dir: Option<&Path>,
    render: bool,
) -> Result<Run, Error> {
    run_source_in(
        source,
        model_path,
        robot_name,
        plan,
        out_dir,
        render,
        &Scenario::default(),
    )
}

/// The loop on any frame source, in `scenario`'s world (its floor and push; the plan should
/// last [`Scenario::min_duration_s`]).
///
/// # Errors
/// [`Error`].
pub fn run_source_in(
    source: &mut dyn FrameSource,
    model_path: &Path,
    robot_name: &str,
    plan: &Plan,
    out_dir: Option<&Path>,
    render: bool,
    scenario: &Scenario,
) -> Result<Run, Error> {
    let started = Instant::now();
    let mut twin = link::Twin::spawn(&quad_model::venv::workspace_root())?;
    match twin.exchange(&link::ToTwin::Start {
        model: model_path,
        robot: robot_name,
        motion: plan.kind().name(),
        frame_s: source::FRAME_S,
        stance_height_m: plan.stance_height_m(),
        settle_s: SETTLE_S,
        out_dir,
        render: render && out_dir.is_some(),
        imu_period_s: imu::IMU_PERIOD_S,
        scenario: (!scenario.is_plain()).then_some(scenario),
    })? {
        link::FromTwin::Ready { .. } => {}
        _ => return Err(Error::Protocol("expected `ready`")),
    }
    let mut feedback = None;
    for k in 0..source.frame_count() {
        let frame = source.next(k, feedback.as_ref())?;
        match twin.exchange(&frame.to_twin(k))? {
            link::FromTwin::State(state) => feedback = Some(state),
            _ => return Err(Error::Protocol("expected `state`")),
        }
    }
    let loop_s = started.elapsed().as_secs_f64();
    let summary = match twin.exchange(&link::ToTwin::End)? {
        link::FromTwin::Summary(s) => *s,
        _ => return Err(Error::Protocol("expected `summary`")),
    };
    twin.finish()?;
    let simulated = f64::from(SETTLE_S) + summary.duration_s;
    Ok(Run {
        sim_per_wall: simulated / loop_s,
        wall_s: loop_s,
        summary,
        // The caller that knows the masses fills it in (`run_plan`).
        static_margin: None,
    })
}
