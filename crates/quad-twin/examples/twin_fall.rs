//! A fall caught: each preset standing with its balance functions on (leveling, fall detection
//! at 60°, the outputs switched off as the safe state) is pushed sideways hard enough to tip
//! it over; the run records the body's true attitude at every IMU sample and, every frame,
//! whether the device reports the fall and drives its outputs:
//!
//! ```sh
//! cargo run --release -p quad-twin --example twin_fall
//! ```
//!
//! Printed: when the true |roll| or |pitch| first exceeds 60° (the twin's clock), the sample
//! at which the device latched the fall (`DeviceFrame::fall_latched_t_s`), and the frame
//! boundary from which the outputs are off (one servo frame or less after the detection).

use quad_device::Config;
use quad_model::Physical;
use quad_protocol::{BalanceConfig, SafeState};
use quad_twin::device::{InProcess, REST_BEFORE_RUN_FRAMES};
use quad_twin::link::BodyState;
use quad_twin::motions::Plan;
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::source::{DeviceFrame, FrameSource, HostDriven};
use quad_twin::MotionKind;
use std::process::ExitCode;

/// The fall angle of the balance settings (the protocol's default), rad.
const FALL_ANGLE_RAD: f64 = std::f64::consts::FRAC_PI_3;

/// The push that tips each preset over, N·s (about three times the largest one it survives).
const PUSHES_N_S: [f32; 2] = [9.0, 48.0];

/// One frame as recorded: the samples the device took before it (`t_s`, true max tilt),
/// the time of the sample at which the device latched the fall (on the latching frame), whether
/// its outputs are on, and the frame's start on the twin's clock (the end of the previous
/// frame).
type Recorded = (Vec<(f64, f64)>, Option<f64>, bool, Option<f64>);

/// The frames of a run and the samples before each.
struct Recorder {
    inner: HostDriven,
    /// Per frame `k`.
    frames: Vec<Recorded>,
}

impl FrameSource for Recorder {
    fn frame_count(&self) -> u32 {
        self.inner.frame_count()
    }

    fn next(
        &mut self,
        k: u32,
        feedback: Option<&BodyState>,
    ) -> Result<DeviceFrame, quad_twin::Error> {
        let frame = self.inner.next(k, feedback)?;
        let samples = feedback.map_or_else(Vec::new, |s| {
            s.imu
                .iter()
                .map(|i| (i.t_s, i.rpy_rad[0].abs().max(i.rpy_rad[1].abs())))
                .collect()
        });
        self.frames.push((
            samples,
            frame.fall_latched_t_s,
            frame.enabled,
            feedback.map(|s| s.t_s),
        ));
        Ok(frame)
    }
}

fn main() -> ExitCode {
    let presets = [
        (
            "shahriar2023",
            Config::shahriar2023(),
            Physical::shahriar2023(),
        ),
        (
            "fernando2025",
            Config::fernando2025(),
            Physical::fernando2025(),
        ),
    ];
    for ((name, config, physical), push) in presets.into_iter().zip(PUSHES_N_S) {
        if let Err(e) = fall(name, &config, &physical, push) {
            eprintln!("twin_fall: {name}: {e}");
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}

fn fall(name: &str, config: &Config, physical: &Physical, push_n_s: f32) -> Result<(), String> {
    let scenario =
        Scenario::new(SlopeAxis::Roll, 0.0, false, Some(push_n_s)).map_err(|e| e.to_string())?;
    // As `quad_twin::run_plan` builds an in-process run with balance settings.
    let config = Config {
        joint_speed_limit_rad_s: quad_device::engine::limit_for_servo(
            physical.servo.no_load_speed_rad_s,
        ),
        ..*config
    };
    let plan = Plan::new(MotionKind::Stand, &config).map_err(|e| e.to_string())?;
    let plan = match scenario.min_duration_s() {
        Some(d) => plan.lasting_at_least(d),
        None => plan,
    };
    let mut device = InProcess::start(config).map_err(|e| e.to_string())?;
    device
        .rest_before_run(
            quad_device::ImuSample {
                accel_m_s2: [0.0, 0.0, quad_twin::imu::GRAVITY_M_S2],
                gyro_rad_s: [0.0; 3],
            },
            REST_BEFORE_RUN_FRAMES,
        )
        .map_err(|e| e.to_string())?;
    device.set_balance_when_ready(BalanceConfig {
        leveling: true,
        safe_state: SafeState::Off,
        ..BalanceConfig::DEFAULT
    });
    let mut recorder = Recorder {
        inner: HostDriven::new(plan, device).hold_pose(),
        frames: Vec::new(),
    };
    let model = quad_model::Model::new(config.robot, *physical).map_err(|e| e.to_string())?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let path = dir.path().join("model.xml");
    quad_model::mjcf::write(&model, &path).map_err(|e| e.to_string())?;
    let robot_name = quad_model::mjcf::robot_name(&model);
    let run = quad_twin::run_source_in(
        &mut recorder,
        &path,
        robot_name,
        &plan,
        None,
        false,
        &scenario,
    )
    .map_err(|e| e.to_string())?;
    let crossed = recorder
        .frames
        .iter()
        .flat_map(|f| f.0.iter())
        .find(|&&(_, tilt)| tilt > FALL_ANGLE_RAD)
        .map(|&(t, _)| t);
    let detected = recorder.frames.iter().find_map(|f| f.1);
    let off = recorder.frames.iter().find(|f| !f.2);
    let ms = |t: f64| format!("{:.1} ms", 1e3 * t);
    match (crossed, detected, off) {
        (Some(t_c), Some(t_latch), Some((.., Some(t_off)))) => {
            println!(
                "{name:13} push {push_n_s:.1} N·s (fell={}): true tilt past 60° at {t_c:.3} s; fall latched on the sample at {t_latch:.3} s ({} after the crossing); outputs off from {t_off:.3} s ({} after the crossing, {} after the detection)",
                run.summary.fell,
                ms(t_latch - t_c),
                ms(t_off - t_c),
                ms(t_off - t_latch),
            );
            Ok(())
        }
        other => Err(format!(
            "no fall caught: crossed {:?}, detected {}, outputs off {}",
            other.0,
            other.1.is_some(),
            other.2.is_some()
        )),
    }
}
