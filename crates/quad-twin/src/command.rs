//! The operations behind `quadctl sim` and `quadctl export`: a `--robot` argument (preset, TOML
//! robot file with its `[physical]` table, or URDF) to a run of the twin or to a robot
//! description file.

use crate::{config_for, run, MotionKind, Run, RunOptions};
use core::fmt;
use quad_host::robot_file::{self, Description};
use quad_model::{Model, Physical};
use std::io::Write as _;
use std::path::PathBuf;

/// Why a command failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The robot (preset, file) was refused.
    Robot(robot_file::Error),
    /// The physical model was refused (a servo preset, a value out of range).
    Model(quad_model::Error),
    /// The run failed.
    Run(crate::Error),
    /// Writing the description to stdout failed.
    Stdout(std::io::Error),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Robot(e) => write!(f, "{e}"),
            Error::Model(e) => write!(f, "{e}"),
            Error::Run(e) => write!(f, "{e}"),
            Error::Stdout(e) => write!(f, "stdout: {e}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Robot(e) => Some(e),
            Error::Model(e) => Some(e),
            Error::Run(e) => Some(e),
            Error::Stdout(e) => Some(e),
        }
    }
}

/// The robot of a `--robot` argument with its physical properties, the servo preset `servo`
/// over them, validated.
///
/// # Errors
/// [`Error::Robot`], [`Error::Model`].
pub fn model(robot: &str, servo: Option<&str>) -> Result<Model, Error> {
    let Description { robot, physical } =
        robot_file::resolve_description(robot).map_err(Error::Robot)?;
    let physical: Physical = match servo {
        Some(name) => physical.with_servo(name).map_err(Error::Model)?,
        None => physical,
    };
    Model::new(robot, physical).map_err(Error::Model)
}

/// A `quadctl sim` request.
#[derive(Debug, Clone)]
pub struct Sim {
    /// `--robot`: preset, TOML robot file or URDF.
    pub robot: String,
    /// The motion.
    pub motion: MotionKind,
    /// Another servo preset than the robot's.
    pub servo: Option<String>,
    /// Another stance height than the device's default, m.
    pub stance_height_m: Option<f32>,
    /// Where the frames come from, the files to write.
    pub options: RunOptions,
}

/// Runs a `quadctl sim` request. A robot that is not a preset's geometry runs on the device
/// settings of seed 000's robot (its stance height unless `stance_height_m`).
///
/// # Errors
/// [`Error`].
pub fn sim(request: &Sim) -> Result<Run, Error> {
    let model = model(&request.robot, request.servo.as_deref())?;
    let config = config_for(model.robot(), request.stance_height_m);
    run(&config, model.physical(), request.motion, &request.options).map_err(Error::Run)
}

/// A robot description format of `quadctl export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// MuJoCo's MJCF.
    Mjcf,
    /// URDF (for RViz, PyBullet, …).
    Urdf,
    /// This project's TOML robot file (docs/robots.md), every key explicit.
    Toml,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 3] = [Format::Mjcf, Format::Urdf, Format::Toml];

    /// Command-line name.
    pub const fn name(self) -> &'static str {
        match self {
            Format::Mjcf => "mjcf",
            Format::Urdf => "urdf",
            Format::Toml => "toml",
        }
    }
}

/// Writes the description of `robot` (with the servo preset `servo`) in `format` to `output`
/// (whole or not at all), or to stdout.
///
/// # Errors
/// [`Error`]; nothing is left at `output` on error.
pub fn export(
    robot: &str,
    servo: Option<&str>,
    format: Format,
    output: Option<&PathBuf>,
) -> Result<(), Error> {
    let model = model(robot, servo)?;
    let text = match format {
        Format::Mjcf => quad_model::mjcf::to_string(&model),
        Format::Urdf => quad_model::urdf::to_string(&model).map_err(Error::Model)?,
        Format::Toml => robot_file::to_toml(&Description {
            robot: *model.robot(),
            physical: *model.physical(),
        })
        .map_err(Error::Robot)?,
    };
    match output {
        Some(path) => quad_model::write_atomic(path, text.as_bytes()).map_err(Error::Model),
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())
                .and_then(|()| out.flush())
                .map_err(Error::Stdout)
        }
    }
}
