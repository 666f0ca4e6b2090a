//! # quad-twin — the physics twin, device side
//!
//! Runs the device controller (`quad-device`) frame by frame and couples it to the MuJoCo
//! twin (the `twin/` Python package) across a process boundary ([`link`]): every 20 ms servo
//! frame, the device's twelve pulses and the joint angles they map to through the device's
//! own calibration go to the twin, which holds them for the frame, steps the physics at the
//! model's time step and answers with the body state (an IMU's reading, for a closed loop
//! later). At the end the twin computes the run's metrics ([`Summary`]) and, when asked, its
//! plots and pictures.
//!
//! - [`device`]: the controller on the host (RAM storage, a frame clock, recording outputs).
//! - [`motions`]: the motions of the twin's catalogue, from kin-core's motion laws.
//! - [`source`]: [`source::FrameSource`], where frames come from ([`source::HostDriven`]: a
//!   host sending `SetFeet` every frame) — the one place to change for onboard motions.
//! - [`link`]: the JSON-lines protocol and the twin process.

pub mod device;
pub mod link;
pub mod motions;
pub mod source;

use core::fmt;
use quad_model::{Model, Physical};
use serde::Deserialize;
use source::FrameSource;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use motions::{MotionKind, Plan};

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
    /// Lowest body-centre height over the floor during the motion, m.
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
    /// Files written (summary, plots, pictures).
    #[serde(default)]
    pub files: Vec<PathBuf>,
}

/// How to run the twin.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Where the model, summary, plots and pictures go (none: a temporary directory for the
    /// model and no other file).
    pub out_dir: Option<PathBuf>,
    /// Render a GIF and a strip of frames (needs `out_dir`).
    pub render: bool,
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
}

/// Runs `kind` on the device of `config` with the physical model `physical`: the device is
/// driven as a host would ([`source::HostDriven`]), the twin steps the physics.
///
/// # Errors
/// [`Error`].
pub fn run(
    config: &quad_device::Config,
    physical: &Physical,
    kind: MotionKind,
    options: &RunOptions,
) -> Result<Run, Error> {
    let model = Model::new(config.robot, *physical).map_err(Error::Model)?;
    let plan = Plan::new(kind, config).map_err(Error::Motion)?;
    let device =
        device::SimDevice::start(*config).map_err(|error| Error::Device { frame: 0, error })?;
    let mut source = source::HostDriven::new(plan, device);
    let tmp = tempfile::tempdir().map_err(Error::Io)?;
    let out_dir = options.out_dir.as_deref();
    if let Some(dir) = out_dir {
        std::fs::create_dir_all(dir).map_err(Error::Io)?;
    }
    let model_path = link::model_path(out_dir, tmp.path());
    quad_model::mjcf::write(&model, &model_path).map_err(Error::Model)?;
    let robot_name = quad_model::mjcf::robot_name(&model);
    run_source(
        &mut source,
        &model_path,
        robot_name,
        &plan,
        out_dir,
        options.render,
    )
}

/// The loop on any frame source.
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
    })? {
        link::FromTwin::Ready { .. } => {}
        _ => return Err(Error::Protocol("expected `ready`")),
    }
    let mut feedback = None;
    for k in 0..source.frame_count() {
        let frame = source.next(k, feedback.as_ref())?;
        match twin.exchange(&link::ToTwin::frame(k, &frame))? {
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
    })
}
