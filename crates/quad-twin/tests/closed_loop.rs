//! The loop closed in the twin: the device's balance functions on (`RunOptions::balance`,
//! leveling and fall detection with the protocol's defaults), its attitude estimate scored
//! against MuJoCo's true attitude (the twin's Python environment is required, as for
//! `tests/twin.rs`). The figures are in BENCHMARKS.md and docs/twin.md.

use quad_device::Config;
use quad_model::Physical;
use quad_protocol::BalanceConfig;
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::{run, MotionKind, RunOptions, Summary};

/// Leveling on, standing on a 10° slope or after the floor tilted by 10°: the body's settled
/// |roll| and |pitch|, degrees (issue 22's aim; open loop 10.3–11.1°; measured ≤ 0.22°).
const LEVEL_SETTLED_MAX_DEG: f64 = 1.5;
/// ... settled within this of the tilt's end, s (measured 0.44–0.60 s).
const LEVEL_SETTLING_MAX_S: f64 = 1.0;
/// The floor's angle, degrees.
const SLOPE_DEG: f32 = 10.0;
/// The device's attitude estimate during the onboard trot: RMS error of roll and of pitch,
/// degrees (issue 22; measured 0.23° / 0.48° on seed 000's robot, 0.26° / 0.63° on seed
/// 001's).
const TROT_RMS_MAX_DEG: f64 = 1.0;
/// ... largest error of roll or pitch, degrees (issue 22: 3°; measured 1.09° / 1.70°).
const TROT_MAX_ERROR_DEG: f64 = 3.0;

fn balance() -> Option<BalanceConfig> {
    Some(BalanceConfig {
        leveling: true,
        ..BalanceConfig::DEFAULT
    })
}

fn stand(config: &Config, physical: &Physical, scenario: Scenario) -> Summary {
    let options = RunOptions {
        scenario,
        balance: balance(),
        ..RunOptions::default()
    };
    run(config, physical, MotionKind::Stand, &options)
        .unwrap_or_else(|e| panic!("{scenario:?}: {e}"))
        .summary
}

#[test]
fn leveling_holds_the_body_level_on_a_slope_and_after_the_floor_tilts() {
    let cases = [
        (
            "shahriar2023 slope roll",
            Config::shahriar2023(),
            Physical::shahriar2023(),
            Scenario::new(SlopeAxis::Roll, SLOPE_DEG, false, None).unwrap(),
        ),
        (
            "fernando2025 tilt pitch",
            Config::fernando2025(),
            Physical::fernando2025(),
            Scenario::new(SlopeAxis::Pitch, 0.0, true, None).unwrap(),
        ),
    ];
    for (name, config, physical, scenario) in cases {
        let s = stand(&config, &physical, scenario);
        assert!(!s.fell, "{name}: {:?}", s.fall_reason);
        let sc = s.scenario.expect("a scenario run");
        eprintln!("{name}, leveling on: {sc:?}");
        assert!(
            sc.settled_roll_rad.to_degrees().abs() <= LEVEL_SETTLED_MAX_DEG,
            "{name}: {sc:?}"
        );
        assert!(
            sc.settled_pitch_rad.to_degrees().abs() <= LEVEL_SETTLED_MAX_DEG,
            "{name}: {sc:?}"
        );
        if sc.tilt_by_rad.is_some() {
            let t = sc.settling_time_s.expect("settled");
            assert!(t <= LEVEL_SETTLING_MAX_S, "{name}: {sc:?}");
        }
    }
}

#[test]
fn the_devices_estimate_follows_the_true_attitude_during_the_onboard_trot() {
    let options = RunOptions {
        onboard: true,
        balance: balance(),
        ..RunOptions::default()
    };
    let robots = [
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
    for (name, config, physical) in robots {
        let s = run(&config, &physical, MotionKind::Trot, &options)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .summary;
        assert!(!s.fell, "{name}: {:?}", s.fall_reason);
        let e = s
            .attitude
            .and_then(|a| a.estimate)
            .expect("the device's estimate");
        eprintln!("{name} onboard trot: {e:?}");
        assert!(
            e.roll_rms_error_rad.to_degrees() <= TROT_RMS_MAX_DEG,
            "{name}: {e:?}"
        );
        assert!(
            e.pitch_rms_error_rad.to_degrees() <= TROT_RMS_MAX_DEG,
            "{name}: {e:?}"
        );
        assert!(
            e.max_error_rad.to_degrees() <= TROT_MAX_ERROR_DEG,
            "{name}: {e:?}"
        );
    }
}

/// A fall: the true |roll| or |pitch| past the fall angle → the device latches the fall on a
/// sample at most this later, s (issue 22: 100 ms; measured: on the crossing's own sample, on
/// seed 000's robot, with the leveling's rate term and without).
const FALL_DETECTED_WITHIN_S: f64 = 0.1;
/// ... and at most this earlier, s: one IMU sample period (5 ms). The device can only latch on
/// its estimate, which may lead the true tilt by its error (issue 22 bounds it by 3°); at the
/// crossing the body turns about 2° per sample (measured 58.6° → 60.5°), so an estimate
/// within that error can pass 60° one sample before the truth, not two. A latch earlier than
/// that would be a fall declared with the body short of the fall angle by more than the
/// estimate may err (the twin compares both on the same samples, so it sees each sample).
const FALL_LATCHED_EARLY_MAX_S: f64 = 0.005;
/// ... and its outputs are off (safe state `Off`) at most one servo frame after that sample, s.
const OUTPUTS_SAFE_WITHIN_S: f64 = 0.02;
/// The push that tips seed 000's robot over standing, N·s (about three times the largest it
/// survives).
const TIPPING_PUSH_N_S: f32 = 9.0;

/// Per frame: the samples before it (`t_s`, true max tilt), the device's fall flag, its
/// outputs on, the frame's start on the twin's clock, the time of the sample at which the
/// device latched the fall (on the latching frame only).
type Recorded = (Vec<(f64, f64)>, bool, bool, Option<f64>, Option<f64>);

struct Recorder {
    inner: quad_twin::source::HostDriven,
    frames: Vec<Recorded>,
}

impl quad_twin::source::FrameSource for Recorder {
    fn frame_count(&self) -> u32 {
        self.inner.frame_count()
    }

    fn next(
        &mut self,
        k: u32,
        feedback: Option<&quad_twin::link::BodyState>,
    ) -> Result<quad_twin::source::DeviceFrame, quad_twin::Error> {
        let frame = self.inner.next(k, feedback)?;
        let samples = feedback.map_or_else(Vec::new, |s| {
            s.imu
                .iter()
                .map(|i| (i.t_s, i.rpy_rad[0].abs().max(i.rpy_rad[1].abs())))
                .collect()
        });
        self.frames.push((
            samples,
            frame.fall_detected,
            frame.enabled,
            feedback.map(|s| s.t_s),
            frame.fall_latched_t_s,
        ));
        Ok(frame)
    }
}

#[test]
fn a_fall_is_caught_within_100_ms_and_the_outputs_are_off_within_a_frame() {
    let physical = Physical::shahriar2023();
    let config = Config {
        joint_speed_limit_rad_s: quad_device::engine::limit_for_servo(
            physical.servo.no_load_speed_rad_s,
        ),
        ..Config::shahriar2023()
    };
    let scenario = Scenario::new(SlopeAxis::Roll, 0.0, false, Some(TIPPING_PUSH_N_S)).unwrap();
    let plan = quad_twin::Plan::new(MotionKind::Stand, &config)
        .unwrap()
        .lasting_at_least(scenario.min_duration_s().unwrap());
    let mut device = quad_twin::device::InProcess::start(config).unwrap();
    device
        .rest_before_run(
            quad_device::ImuSample {
                accel_m_s2: [0.0, 0.0, quad_twin::imu::GRAVITY_M_S2],
                gyro_rad_s: [0.0; 3],
            },
            quad_twin::device::REST_BEFORE_RUN_FRAMES,
        )
        .unwrap();
    device.set_balance_when_ready(BalanceConfig {
        leveling: true,
        safe_state: quad_protocol::SafeState::Off,
        ..BalanceConfig::DEFAULT
    });
    let mut recorder = Recorder {
        inner: quad_twin::source::HostDriven::new(plan, device).hold_pose(),
        frames: Vec::new(),
    };
    let model = quad_model::Model::new(config.robot, physical).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.xml");
    quad_model::mjcf::write(&model, &path).unwrap();
    let run = quad_twin::run_source_in(
        &mut recorder,
        &path,
        quad_model::mjcf::robot_name(&model),
        &plan,
        None,
        false,
        &scenario,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(run.summary.fell, "the push tips the robot over");
    let crossed = recorder
        .frames
        .iter()
        .flat_map(|f| f.0.iter())
        .find(|&&(_, tilt)| tilt > std::f64::consts::FRAC_PI_3)
        .map(|&(t, _)| t)
        .expect("the true tilt passes 60°");
    let (samples, _, _, _, latched) = recorder
        .frames
        .iter()
        .find(|f| f.1)
        .expect("the device latches the fall");
    let latched = latched.expect("the fall latched on one of the frame's samples");
    let first = samples.first().expect("samples").0;
    let last = samples.last().expect("samples").0;
    let all: Vec<(f64, f64)> = recorder
        .frames
        .iter()
        .flat_map(|f| f.0.iter().copied())
        .collect();
    let at_latch = all
        .iter()
        .position(|s| s.0 == latched)
        .expect("the latching sample among the frame's");
    let tilt_at_latch = all[at_latch].1;
    let tilt_before = all[at_latch.saturating_sub(1)].1;
    let off = recorder
        .frames
        .iter()
        .find(|f| !f.2)
        .and_then(|f| f.3)
        .expect("the outputs go off");
    eprintln!(
        "fall: true tilt past 60° at {crossed:.4} s, latched on the sample at {latched:.4} s \
         (true tilt {:.2}°, {:.2}° on the sample before; the frame's samples {first:.3}–{last:.3} s), \
         outputs off from {off:.3} s",
        tilt_at_latch.to_degrees(),
        tilt_before.to_degrees()
    );
    assert!(
        latched - crossed <= FALL_DETECTED_WITHIN_S,
        "latched {:.1} ms after the crossing",
        1e3 * (latched - crossed)
    );
    assert!(
        latched >= crossed - FALL_LATCHED_EARLY_MAX_S,
        "latched {:.1} ms before the true crossing",
        1e3 * (crossed - latched)
    );
    assert!(off - latched <= OUTPUTS_SAFE_WITHIN_S && off >= last);
}
