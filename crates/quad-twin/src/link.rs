//! The process boundary between the device side (this crate) and the MuJoCo twin
//! (`python -m quadtwin.runner`): JSON lines on the twin's standard input and output, in
//! lock step — one [`ToTwin::Frame`] in, one [`FromTwin::State`] out — so that the state (an
//! IMU's reading) can be handed to the device before its next frame.
//!
//! ```text
//! → {"type":"start", "model":…, "frame_s":0.02, "imu_period_s":0.005, "scenario":…, …}
//!                                                        ← {"type":"ready", "timestep_s":0.001}
//! → {"type":"frame", "k":0, "pulses_half_us":[…], "angles_rad":[…], …}
//!                                                        ← {"type":"state", "t_s":0.02, "quat":[…], "gyro_rad_s":[…],
//!                                                           "imu":[{"t_s":…, "accel_m_s2":[…], "gyro_rad_s":[…], "rpy_rad":[…]}, …], …}
//! → … one frame, one state …
//! → {"type":"end"}                                       ← {"type":"summary", …}
//! ```
//!
//! A twin that fails answers `{"type":"error", "message":…}` and exits non-zero.

use serde::{Deserialize, Serialize};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Stdio};

/// Messages to the twin.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ToTwin<'a> {
    /// Load the model and prepare a run.
    Start {
        /// The MJCF file.
        model: &'a Path,
        /// Robot name (for the summary).
        robot: &'a str,
        /// Motion name (for the summary and the metrics it selects).
        motion: &'a str,
        /// Servo frame period, s.
        frame_s: f32,
        /// Stance height the motion keeps, m.
        stance_height_m: f32,
        /// Time the first frame is held before the motion's clock starts, s (the robot
        /// settles on its feet).
        settle_s: f32,
        /// Directory for the summary, the plots and the pictures (none: no files).
        out_dir: Option<&'a Path>,
        /// Render a GIF and a strip of frames.
        render: bool,
        /// The IMU's sample period, s ([`crate::imu::IMU_PERIOD_S`]).
        imu_period_s: f32,
        /// The floor and the push ([`crate::scenario`]); none: a level floor, no push.
        #[serde(skip_serializing_if = "Option::is_none")]
        scenario: Option<&'a crate::scenario::Scenario>,
    },
    /// One servo frame, held for `frame_s`.
    Frame {
        /// Frame index.
        k: u32,
        /// Start of the frame on the motion's clock, s.
        t_s: f32,
        /// True while the outputs are driven.
        enabled: bool,
        /// The pulses, half-µs.
        pulses_half_us: [u16; 12],
        /// The servo targets: the pulses through the device's calibration, rad.
        angles_rad: [f32; 12],
        /// The commanded body pose `[roll, pitch, yaw, x, y, z]` (rad, m).
        commanded_pose: [f32; 6],
        /// The feet the motion has on the ground.
        stance: [bool; 4],
        /// The device's own estimate of the body's roll, pitch, yaw at the frame's start, rad,
        /// when it reports one (scored against the true attitude in the summary).
        #[serde(skip_serializing_if = "Option::is_none")]
        estimated_rpy_rad: Option<[f32; 3]>,
    },
    /// The run is over: compute the metrics, write the files, answer the summary.
    End,
}

/// The body state after a frame: what an IMU on the body and contact switches would read.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct BodyState {
    /// Simulated time at the end of the frame, s.
    pub t_s: f64,
    /// Body centre in the world (floor at z = 0), m.
    pub pos_m: [f64; 3],
    /// Body orientation, quaternion `[w, x, y, z]`.
    pub quat: [f64; 4],
    /// Roll, pitch, yaw of the body (`zyx` order), rad.
    pub rpy_rad: [f64; 3],
    /// Angular velocity in the body frame (gyroscope), rad/s.
    pub gyro_rad_s: [f64; 3],
    /// Specific force in the body frame (accelerometer), m/s².
    pub accel_m_s2: [f64; 3],
    /// Feet touching the floor.
    pub feet_contact: [bool; 4],
    /// The IMU's samples during the frame, in time order (every `imu_period_s`).
    #[serde(default)]
    pub imu: Vec<ImuSampleAt>,
}

/// One IMU sample of the twin: MuJoCo's accelerometer and gyroscope on the body's `imu` site
/// (kin-core's body frame: x forward, y left, z up) and the body's true attitude, all at one
/// simulated time.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct ImuSampleAt {
    /// Simulated time of the sample, s (the clock of [`BodyState::t_s`]).
    pub t_s: f64,
    /// Specific force, m/s² (level and still: `(0, 0, +g)`).
    pub accel_m_s2: [f64; 3],
    /// Angular rate about the body axes, rad/s.
    pub gyro_rad_s: [f64; 3],
    /// The body's true roll, pitch, yaw (`zyx` order), rad.
    pub rpy_rad: [f64; 3],
}

impl ImuSampleAt {
    /// The reading as the device takes it.
    pub fn sample(&self) -> quad_device::ImuSample {
        // The device's maths is f32; the twin's f64 values round to the nearest.
        quad_device::ImuSample {
            accel_m_s2: self.accel_m_s2.map(|v| v as f32),
            gyro_rad_s: self.gyro_rad_s.map(|v| v as f32),
        }
    }
}

/// Messages from the twin.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum FromTwin {
    /// The model is loaded.
    Ready {
        /// The physics time step, s.
        timestep_s: f64,
    },
    /// The state after a frame.
    State(BodyState),
    /// The run's metrics.
    Summary(Box<crate::Summary>),
    /// The twin failed.
    Error {
        /// Its message.
        message: String,
    },
}

/// A running twin process.
pub struct Twin {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    line: String,
}

impl Twin {
    /// Starts `python -m quadtwin.runner` in the project's twin environment.
    ///
    /// # Errors
    /// [`crate::Error::Venv`] when the environment is missing, [`crate::Error::Io`] when the
    /// process cannot start.
    pub fn spawn(root: &Path) -> Result<Twin, crate::Error> {
        let mut cmd =
            quad_model::venv::python_module(root, "runner").map_err(crate::Error::Venv)?;
        let mut child = cmd
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(crate::Error::Io)?;
        let stdin = child
            .stdin
            .take()
            .ok_or(crate::Error::Protocol("no stdin"))?;
        let stdout = child
            .stdout
            .take()
            .ok_or(crate::Error::Protocol("no stdout"))?;
        Ok(Twin {
            child,
            stdin,
            stdout: BufReader::new(stdout),
            line: String::new(),
        })
    }

    /// Sends one message and reads the answer.
    ///
    /// # Errors
    /// [`crate::Error`] on I/O, malformed answers, or the twin's own error.
    pub fn exchange(&mut self, msg: &ToTwin<'_>) -> Result<FromTwin, crate::Error> {
        let mut text = serde_json::to_string(msg).map_err(crate::Error::Json)?;
        text.push('\n');
        self.stdin
            .write_all(text.as_bytes())
            .and_then(|()| self.stdin.flush())
            .map_err(crate::Error::Io)?;
        self.line.clear();
        let n = self
            .stdout
            .read_line(&mut self.line)
            .map_err(crate::Error::Io)?;
        if n == 0 {
            return Err(crate::Error::Protocol(
                "the twin closed its output (see its messages above)",
            ));
        }
        match serde_json::from_str(&self.line).map_err(crate::Error::Json)? {
            FromTwin::Error { message } => Err(crate::Error::Twin { message }),
            answer => Ok(answer),
        }
    }

    /// Waits for the process to exit.
    ///
    /// # Errors
    /// [`crate::Error::Exit`] on a non-zero exit.
    pub fn finish(mut self) -> Result<(), crate::Error> {
        drop(self.stdin);
        let status = self.child.wait().map_err(crate::Error::Io)?;
        if status.success() {
            Ok(())
        } else {
            Err(crate::Error::Exit(status))
        }
    }
}

/// Where a run writes: `out_dir` when given.
pub(crate) fn model_path(out_dir: Option<&Path>, tmp: &Path) -> PathBuf {
    out_dir.unwrap_or(tmp).join("model.xml")
}
