//! The twin's IMU fed to the device, and the open-loop baselines of the slope, tilting-floor
//! and push scenarios (the twin's Python environment is required, as for `tests/twin.rs`).
//! What is true before the device closes a loop on its sensor: the body goes with the floor,
//! the readings have the body frame's signs, every sample reaches the device at its time.

use quad_device::Config;
use quad_model::Physical;
use quad_twin::imu::{GRAVITY_M_S2, IMU_PERIOD_S};
use quad_twin::link::{BodyState, ImuSampleAt};
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::source::{DeviceFrame, FrameSource, HostDriven, FRAME_S};
use quad_twin::{run, MotionKind, Plan, RunOptions, Summary};

/// At rest, the accelerometer's magnitude lies within this of g, m/s².
const AT_REST_G_TOLERANCE_M_S2: f64 = 0.2;
/// At rest, the gyroscope reads at most this about any axis, rad/s.
const AT_REST_GYRO_MAX_RAD_S: f64 = 0.02;
/// At rest, the accelerometer's tilt (atan2 of its y or −x over its z) lies within this of the
/// body's true roll or pitch, rad (0.5°): the body frame's signs.
const AT_REST_TILT_TOLERANCE_RAD: f64 = 0.5 * core::f64::consts::PI / 180.0;
/// Under the scripted roll sway, the gyroscope's x rate and the true roll's rate correlate at
/// least this much (same sign: rolling to the right, the left side up, reads positive).
const GYRO_ROLL_CORRELATION_MIN: f64 = 0.95;
/// ... and their amplitudes agree within this ratio band.
const GYRO_ROLL_GAIN_BAND: (f64, f64) = (0.9, 1.1);
/// The last second of the stand-up is at rest.
const AT_REST_WINDOW_S: f64 = 1.0;
/// Open loop on a 10° slope or after the floor tilted by 10°, the body's settled roll (or
/// pitch) lies within this of the floor's angle, degrees: the body goes with the floor (the
/// downhill legs give a little: 10.3–11.1° measured, docs/twin.md).
const SLOPE_FOLLOW_TOLERANCE_DEG: f64 = 1.5;
/// ... and the other axis stays within this of level, degrees.
const SLOPE_CROSS_AXIS_MAX_DEG: f64 = 1.0;
/// The floor's angle in these tests, degrees.
const SLOPE_DEG: f32 = 10.0;
/// Open loop, standing, each preset survives this sideways impulse and falls to this one,
/// N·s: about 15 % below and above the largest impulse survived that the `twin_scenarios`
/// example measures (2.88 N·s on seed 000's robot, 15.8 N·s on seed 001's; docs/twin.md).
const PUSH_SURVIVED_FELL_N_S: [(f32, f32); 2] = [(2.45, 3.3), (13.5, 18.2)];
/// After a push it survives, the body comes back within this of level, degrees.
const PUSH_SETTLED_MAX_DEG: f64 = 2.0;

fn presets() -> [(&'static str, Config, Physical); 2] {
    [
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
    ]
}

/// A source that keeps the twin's IMU samples as they pass to the device.
struct Recording {
    inner: HostDriven,
    samples: Vec<ImuSampleAt>,
    states: u32,
}

impl FrameSource for Recording {
    fn frame_count(&self) -> u32 {
        self.inner.frame_count()
    }

    fn next(
        &mut self,
        k: u32,
        feedback: Option<&BodyState>,
    ) -> Result<DeviceFrame, quad_twin::Error> {
        if let Some(state) = feedback {
            self.samples.extend_from_slice(&state.imu);
            self.states += 1;
        }
        self.inner.next(k, feedback)
    }
}

/// Runs `kind` host-driven on a level floor and returns the samples the device received, the
/// motion's start on the twin's clock, and the source (its device).
fn recorded(config: &Config, physical: &Physical, kind: MotionKind) -> (Recording, f64) {
    let model = quad_model::Model::new(config.robot, *physical).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.xml");
    quad_model::mjcf::write(&model, &path).unwrap();
    let plan = Plan::new(kind, config).unwrap();
    let device = quad_twin::device::InProcess::start(*config).unwrap();
    let mut source = Recording {
        inner: HostDriven::new(plan, device),
        samples: Vec::new(),
        states: 0,
    };
    quad_twin::run_source(
        &mut source,
        &path,
        quad_model::mjcf::robot_name(&model),
        &plan,
        None,
        false,
    )
    .unwrap_or_else(|e| panic!("{kind}: {e}"));
    (source, f64::from(quad_twin::SETTLE_S))
}

#[test]
fn at_rest_the_imu_reads_gravity_upwards_and_every_sample_reaches_the_device() {
    for (name, config, physical) in presets() {
        let (source, t0) = recorded(&config, &physical, MotionKind::Stand);
        let per_frame = (FRAME_S / IMU_PERIOD_S).round() as usize;
        // Every frame's samples, the last frame's excepted (the run ends before the device
        // would take them), reached the device through `Device::on_imu`.
        assert_eq!(source.samples.len(), per_frame * source.states as usize);
        assert_eq!(
            source.inner.device().imu().samples as usize,
            source.samples.len(),
            "{name}"
        );
        // Evenly spaced in time.
        for pair in source.samples.windows(2) {
            let dt = pair[1].t_s - pair[0].t_s;
            assert!((dt - f64::from(IMU_PERIOD_S)).abs() < 1e-6, "{name}: {dt}");
        }
        let end = source.samples.last().unwrap().t_s;
        let at_rest: Vec<_> = source
            .samples
            .iter()
            .filter(|s| s.t_s >= end - AT_REST_WINDOW_S && s.t_s > t0)
            .collect();
        assert!(at_rest.len() > 100, "{name}");
        for s in at_rest {
            let a = s.accel_m_s2;
            let g = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            assert!(
                (g - f64::from(GRAVITY_M_S2)).abs() < AT_REST_G_TOLERANCE_M_S2,
                "{name}: {s:?}"
            );
            assert!(
                s.gyro_rad_s
                    .iter()
                    .all(|w| w.abs() < AT_REST_GYRO_MAX_RAD_S),
                "{name}: {s:?}"
            );
            let (roll, pitch) = (s.rpy_rad[0], s.rpy_rad[1]);
            assert!(
                (a[1].atan2(a[2]) - roll).abs() < AT_REST_TILT_TOLERANCE_RAD,
                "{name}: {s:?}"
            );
            assert!(
                ((-a[0]).atan2(a[2]) - pitch).abs() < AT_REST_TILT_TOLERANCE_RAD,
                "{name}: {s:?}"
            );
        }
        // The device's last reading is the last sample it was given.
        let last = source.inner.device().imu().last.unwrap();
        assert_eq!(last, source.samples.last().unwrap().sample(), "{name}");
    }
}

#[test]
fn under_a_scripted_roll_the_gyroscope_reads_the_roll_rate_with_its_sign() {
    let (_, config, physical) = &presets()[0];
    let (source, t0) = recorded(config, physical, MotionKind::Roll);
    let s: Vec<_> = source.samples.iter().filter(|s| s.t_s > t0).collect();
    // The true roll's rate by central differences against the gyroscope's x rate (the roll
    // sway keeps pitch and yaw near zero, so the body rate about x is the roll rate).
    let mut rate = Vec::new();
    let mut gyro = Vec::new();
    for w in s.windows(3) {
        rate.push((w[2].rpy_rad[0] - w[0].rpy_rad[0]) / (w[2].t_s - w[0].t_s));
        gyro.push(w[1].gyro_rad_s[0]);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mr, mg) = (mean(&rate), mean(&gyro));
    let cov: f64 = rate
        .iter()
        .zip(&gyro)
        .map(|(r, g)| (r - mr) * (g - mg))
        .sum();
    let var_r: f64 = rate.iter().map(|r| (r - mr).powi(2)).sum();
    let var_g: f64 = gyro.iter().map(|g| (g - mg).powi(2)).sum();
    let correlation = cov / (var_r * var_g).sqrt();
    assert!(correlation > GYRO_ROLL_CORRELATION_MIN, "{correlation}");
    let gain = cov / var_r;
    assert!(
        gain > GYRO_ROLL_GAIN_BAND.0 && gain < GYRO_ROLL_GAIN_BAND.1,
        "{gain}"
    );
}

fn scenario_run(config: &Config, physical: &Physical, scenario: Scenario) -> Summary {
    let options = RunOptions {
        scenario,
        ..RunOptions::default()
    };
    run(config, physical, MotionKind::Stand, &options)
        .unwrap_or_else(|e| panic!("{scenario:?}: {e}"))
        .summary
}

/// The run did not fall and its body settled at the floor's angle about `axis`, level about
/// the other.
fn assert_goes_with_the_floor(name: &str, axis: SlopeAxis, s: &Summary) {
    assert!(!s.fell, "{name}: {:?}", s.fall_reason);
    let sc = s.scenario.expect("a scenario run");
    let (along, across) = match axis {
        SlopeAxis::Roll => (sc.settled_roll_rad, sc.settled_pitch_rad),
        SlopeAxis::Pitch => (sc.settled_pitch_rad, sc.settled_roll_rad),
    };
    assert!(
        (along.to_degrees() - f64::from(SLOPE_DEG)).abs() < SLOPE_FOLLOW_TOLERANCE_DEG,
        "{name} {axis:?}: {sc:?}"
    );
    assert!(
        across.to_degrees().abs() < SLOPE_CROSS_AXIS_MAX_DEG,
        "{name} {axis:?}: {sc:?}"
    );
}

#[test]
fn open_loop_the_body_goes_with_a_slope_and_a_tilting_floor() {
    // Seed 001's robot on a roll slope is the next test: it tips over.
    for (name, config, physical) in presets() {
        let axes: &[SlopeAxis] = match name {
            "shahriar2023" => &SlopeAxis::ALL,
            _ => &[SlopeAxis::Pitch],
        };
        for &axis in axes {
            let slope = Scenario::new(axis, SLOPE_DEG, false, None).unwrap();
            assert_goes_with_the_floor(name, axis, &scenario_run(&config, &physical, slope));
            let tilt = Scenario::new(axis, 0.0, true, None).unwrap();
            let s = scenario_run(&config, &physical, tilt);
            assert_goes_with_the_floor(name, axis, &s);
            assert!(
                s.scenario.unwrap().settling_time_s.is_some(),
                "{name}: {s:?}"
            );
        }
    }
}

#[test]
fn open_loop_seed_001s_robot_tips_over_on_a_10_degree_roll_slope_and_a_tilting_floor() {
    // The finding docs/twin.md reports: tall (0.93 m stance) on a 0.5 m track, its downhill
    // abduction servos loaded, the body rolls past the slope and over, from the rest crouch
    // (slope) and from the stance (tilt).
    let (name, config, physical) = &presets()[1];
    for tilt in [false, true] {
        let slope = if tilt { 0.0 } else { SLOPE_DEG };
        let scenario = Scenario::new(SlopeAxis::Roll, slope, tilt, None).unwrap();
        let s = scenario_run(config, physical, scenario);
        assert!(s.fell, "{name} tilt={tilt}: {:?}", s.scenario);
    }
}

#[test]
fn open_loop_standing_survives_a_small_sideways_push_and_falls_to_a_large_one() {
    for ((name, config, physical), (survived, fell)) in
        presets().into_iter().zip(PUSH_SURVIVED_FELL_N_S)
    {
        let small = Scenario::new(SlopeAxis::Roll, 0.0, false, Some(survived)).unwrap();
        let s = scenario_run(&config, &physical, small);
        assert!(!s.fell, "{name} {survived} N·s: {:?}", s.fall_reason);
        let sc = s.scenario.unwrap();
        assert!(
            sc.settled_roll_rad.to_degrees().abs() < PUSH_SETTLED_MAX_DEG,
            "{name}: {sc:?}"
        );
        let large = Scenario::new(SlopeAxis::Roll, 0.0, false, Some(fell)).unwrap();
        let s = scenario_run(&config, &physical, large);
        assert!(s.fell, "{name} {fell} N·s: {:?}", s.scenario);
    }
}
