//! The balance functions through the device on the in-memory fakes, with synthetic sensor
//! readings pushed as a driver pushes them (`Device::on_imu`, 100 Hz, the device clock
//! advancing between them): the gyro bias at start-up, body leveling on a slope, fall and
//! free-fall detection, the start check, a sensor fault mid-run, no sensor, and the ranges of
//! `SetBalance`.
//!
//! Leveling is checked in the kinematic sense: the robot stands on a floor tilted by the slope,
//! and the reading the device gets is the gravity of that floor's tilt composed with the body's
//! attitude relative to its feet, which the test computes from the outputs by kin-core's
//! forward kinematics. The body is level when the commanded counter-rotation matches the tilt.

mod common;

use common::*;
use kin_core::body::{self, BodyAngles};
use kin_core::motion::laws::Axis;
use kin_core::{BodyConfig, JointAngles, Pose, Vec3};
use quad_device::balance::{BIAS_WINDOW_MS, FREE_FALL_MS};
use quad_device::{ImuFault, ImuReading, ImuSample};
use quad_protocol::{
    BalanceConfig, DeviceToHost, FallKind, FaultAction, Flags, ImuFaultKind, ImuHealth, ImuReport,
    MotionCommand, MotionKind, MotionParam, MotionStage, NackReason, ParamProblem, Request,
    SafeState, PROTOCOL_VERSION,
};

const G: f32 = 9.806_65;

/// A new sequence number for every request (an exact repeat would get the remembered answer).
fn next_seq() -> u16 {
    use std::sync::atomic::{AtomicU16, Ordering};
    static SEQ: AtomicU16 = AtomicU16::new(1);
    SEQ.fetch_add(1, Ordering::Relaxed)
}

/// The tilt the leveling must reach on a 10° slope, degrees (the figure).
const LEVEL_TOLERANCE_DEG: f32 = 1.5;

/// Sample period of the simulated driver, ms (100 Hz).
const SAMPLE_MS: u32 = 10;

/// A gyro bias of the simulated sensor, rad/s (about 1 °/s), which the start-up measures.
const GYRO_BIAS: [f32; 3] = [0.018, -0.012, 0.009];

/// Small deterministic noise (a linear congruential sequence), ±`amp`.
struct Noise(u32);
impl Noise {
    fn next(&mut self, amp: f32) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        ((self.0 >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0) * amp
    }
}

/// A sample of a body whose up vector (the world's up in the body frame) went from `before`
/// to `up` over the last sample period, with bias and noise: the rate is the one that turns
/// the one into the other (`v̇ = v × ω`, so `ω⊥ = −v × v̇`), the specific force gravity's.
fn sample(before: [f32; 3], up: [f32; 3], noise: &mut Noise) -> ImuReading {
    let dt = SAMPLE_MS as f32 * 1e-3;
    let dv: [f32; 3] = core::array::from_fn(|i| (up[i] - before[i]) / dt);
    let v = before;
    let w = [
        -(v[1] * dv[2] - v[2] * dv[1]),
        -(v[2] * dv[0] - v[0] * dv[2]),
        -(v[0] * dv[1] - v[1] * dv[0]),
    ];
    ImuReading::Sample(ImuSample {
        accel_m_s2: up.map(|u| u * G + noise.next(0.05)),
        gyro_rad_s: core::array::from_fn(|i| w[i] + GYRO_BIAS[i] + noise.next(0.002)),
    })
}

/// The world's up in the body frame of roll `r`, pitch `p` (zyx).
fn up_of(r: f32, p: f32) -> [f32; 3] {
    [-p.sin(), r.sin() * p.cos(), r.cos() * p.cos()]
}

/// Roll and pitch of an up vector (zyx).
fn attitude_of(up: [f32; 3]) -> (f32, f32) {
    (
        up[1].atan2(up[2]),
        (-up[0]).atan2((up[1] * up[1] + up[2] * up[2]).sqrt()),
    )
}

/// The body's roll and pitch relative to the plane of its feet, from the outputs (kin-core's
/// forward kinematics): the feet's plane normal in the body frame read as an up vector.
fn body_on_feet(dev: &Dev) -> (f32, f32) {
    let q = dev.output_angles().expect("outputs on");
    let angles: BodyAngles =
        core::array::from_fn(|l| JointAngles::new(q[3 * l], q[3 * l + 1], q[3 * l + 2]));
    let f = body::forward(
        &dev.config().robot,
        &Pose::default(),
        &BodyConfig::default(),
        &angles,
    );
    // FL, FR, RL, RR: the diagonals' cross product is the plane's normal.
    let d1: Vec3 = f[0] - f[3];
    let d2: Vec3 = f[1] - f[2];
    let n = d1.cross(d2);
    let n = if n.z < 0.0 { n * -1.0 } else { n };
    let len = (n.x * n.x + n.y * n.y + n.z * n.z).sqrt();
    attitude_of([n.x / len, n.y / len, n.z / len])
}

/// The world's up in the body frame of a body standing on a floor tilted by `slope_roll`,
/// `slope_pitch` (rad), from the outputs: `R_world_body = R_floor · R_body_on_feet`.
fn up_on_slope(dev: &Dev, slope_roll: f32, slope_pitch: f32) -> [f32; 3] {
    let (r, p) = body_on_feet(dev);
    let rot = |r: f32, p: f32| -> [[f32; 3]; 3] {
        let (sr, cr) = r.sin_cos();
        let (sp, cp) = p.sin_cos();
        // Ry(p)·Rx(r)
        [
            [cp, sp * sr, sp * cr],
            [0.0, cr, -sr],
            [-sp, cp * sr, cp * cr],
        ]
    };
    let (a, b) = (rot(slope_roll, slope_pitch), rot(r, p));
    // R = A·B; up in body = Rᵀ·ẑ = the third row of R.
    core::array::from_fn(|j| (0..3).map(|k| a[2][k] * b[k][j]).sum())
}

fn hello(dev: &mut Dev, version: u16) {
    assert!(matches!(
        ask(dev, next_seq(), Request::Hello { version }),
        DeviceToHost::HelloAck { .. }
    ));
}

fn report(dev: &mut Dev) -> ImuReport {
    match ask(dev, next_seq(), Request::GetImu) {
        DeviceToHost::Imu { report, .. } => report,
        other => panic!("not an Imu answer: {other:?}"),
    }
}

/// Runs `ms` of time in 10 ms steps: a sample of `up(dev)` pushed at each, the device polled.
fn run(
    dev: &mut Dev,
    clock: &VirtualClock,
    noise: &mut Noise,
    ms: u32,
    mut up: impl FnMut(&Dev) -> [f32; 3],
) {
    let mut before = up(dev);
    for _ in 0..ms / SAMPLE_MS {
        clock.advance_ms(SAMPLE_MS);
        let u = up(dev);
        dev.on_imu(sample(before, u, noise));
        before = u;
        dev.poll();
    }
}

/// A 2.3 device standing (stand-up finished), its sensor started on level ground.
fn standing() -> (Dev, VirtualClock, Noise) {
    let (mut dev, clock) = clocked_device();
    let mut noise = Noise(7);
    hello(&mut dev, PROTOCOL_VERSION);
    assert_eq!(report(&mut dev).health, ImuHealth::Absent);
    // The still second of the bias measurement, and a little more.
    run(&mut dev, &clock, &mut noise, 200, |_| up_of(0.0, 0.0));
    assert_eq!(report(&mut dev).health, ImuHealth::Starting);
    run(&mut dev, &clock, &mut noise, BIAS_WINDOW_MS, |_| {
        up_of(0.0, 0.0)
    });
    assert_eq!(report(&mut dev).health, ImuHealth::Ok);
    assert!(matches!(
        ask(
            &mut dev,
            next_seq(),
            Request::StartMotion(MotionCommand::StandUp)
        ),
        DeviceToHost::MotionAck { .. }
    ));
    run(&mut dev, &clock, &mut noise, 6000, |_| up_of(0.0, 0.0));
    assert_eq!(
        status(ask(&mut dev, next_seq(), Request::GetMotion)).stage,
        MotionStage::Idle
    );
    (dev, clock, noise)
}

fn set_balance(dev: &mut Dev, config: BalanceConfig) -> DeviceToHost {
    ask(dev, next_seq(), Request::SetBalance(config))
}

fn leveling_on() -> BalanceConfig {
    BalanceConfig {
        leveling: true,
        ..BalanceConfig::DEFAULT
    }
}

#[test]
fn the_gyro_bias_is_measured_in_the_first_still_second() {
    let (mut dev, _, _) = standing();
    let r = report(&mut dev);
    // Level and still: the estimate is level within noise (the bias of about 1 °/s would
    // have tilted an uncorrected gyro by degrees over the six seconds).
    assert!(r.roll_rad.abs() < 0.2f32.to_radians(), "{r:?}");
    assert!(r.pitch_rad.abs() < 0.2f32.to_radians(), "{r:?}");
    assert!(r.samples > 700, "{r:?}");
}

#[test]
fn leveling_corrects_a_ten_degree_slope() {
    for (slope_roll, slope_pitch) in [(10f32.to_radians(), 0.0), (0.0, 10f32.to_radians())] {
        let (mut dev, clock, mut noise) = standing();
        // Leveling off: the body tilts with the floor.
        run(&mut dev, &clock, &mut noise, 2000, |d| {
            up_on_slope(d, slope_roll, slope_pitch)
        });
        let (r, p) = attitude_of(up_on_slope(&dev, slope_roll, slope_pitch));
        assert!((r - slope_roll).abs() < 0.5f32.to_radians(), "{r} {p}");
        assert!((p - slope_pitch).abs() < 0.5f32.to_radians(), "{r} {p}");
        // Leveling on: level within the tolerance after 2 s (and stays there).
        assert!(matches!(
            set_balance(&mut dev, leveling_on()),
            DeviceToHost::Imu { .. }
        ));
        run(&mut dev, &clock, &mut noise, 2000, |d| {
            up_on_slope(d, slope_roll, slope_pitch)
        });
        let mut worst = 0.0f32;
        for _ in 0..100 {
            run(&mut dev, &clock, &mut noise, 20, |d| {
                up_on_slope(d, slope_roll, slope_pitch)
            });
            let (r, p) = attitude_of(up_on_slope(&dev, slope_roll, slope_pitch));
            worst = worst.max(r.abs()).max(p.abs());
        }
        println!(
            "slope roll {:.1}° pitch {:.1}°: body tilt with leveling, worst over 2 s after 2 s: \
             {:.3}°",
            slope_roll.to_degrees(),
            slope_pitch.to_degrees(),
            worst.to_degrees()
        );
        assert!(
            worst.to_degrees() <= LEVEL_TOLERANCE_DEG,
            "slope ({slope_roll}, {slope_pitch}): body tilt {}°",
            worst.to_degrees()
        );
        // The commanded counter-rotation matches the measured tilt of the floor.
        let rep = report(&mut dev);
        assert!(rep.leveling_active && !rep.correction_limited, "{rep:?}");
        let (cr, cp) = (rep.correction_roll_rad, rep.correction_pitch_rad);
        assert!(
            (cr + slope_roll).abs().to_degrees() <= LEVEL_TOLERANCE_DEG,
            "{rep:?}"
        );
        assert!(
            (cp + slope_pitch).abs().to_degrees() <= LEVEL_TOLERANCE_DEG,
            "{rep:?}"
        );
        let (br, bp) = body_on_feet(&dev);
        assert!((br - cr).abs() < 0.2f32.to_radians() && (bp - cp).abs() < 0.2f32.to_radians());
        // Leveling off again: back to the pose on the slope, through the limiter.
        let off = BalanceConfig::DEFAULT;
        assert!(matches!(
            set_balance(&mut dev, off),
            DeviceToHost::Imu { .. }
        ));
        run(&mut dev, &clock, &mut noise, 1000, |d| {
            up_on_slope(d, slope_roll, slope_pitch)
        });
        let (br, bp) = body_on_feet(&dev);
        assert!(br.abs() < 1e-3 && bp.abs() < 1e-3, "{br} {bp}");
    }
}

#[test]
fn a_correction_beyond_the_bound_is_limited_and_reported() {
    let (mut dev, clock, mut noise) = standing();
    let config = BalanceConfig {
        max_correction_rad: 5f32.to_radians(),
        ..leveling_on()
    };
    set_balance(&mut dev, config);
    let slope = 10f32.to_radians();
    run(&mut dev, &clock, &mut noise, 3000, |d| {
        up_on_slope(d, slope, 0.0)
    });
    let rep = report(&mut dev);
    assert!(rep.correction_limited, "{rep:?}");
    assert!(
        (rep.correction_roll_rad + 5f32.to_radians()).abs() < 1e-4,
        "{rep:?}"
    );
    let (r, _) = body_on_feet(&dev);
    assert!(r.is_finite() && (r + 5f32.to_radians()).abs() < 0.2f32.to_radians());
}

/// Tips the standing robot about its roll axis at `rate` rad/s until `until_rad` and returns
/// the time (ms from the start of the tip) at which the outputs were found in their safe
/// state, with the time the true roll crossed 60°.
fn tip(dev: &mut Dev, clock: &VirtualClock, noise: &mut Noise, rate: f32) -> (u32, u32) {
    let mut roll = 0.0f32;
    let (mut crossed, mut safe) = (None, None);
    let rest = quad_device::engine::rest_angles(&dev.config().robot).unwrap();
    for k in 1..=200u32 {
        clock.advance_ms(SAMPLE_MS);
        roll += rate * SAMPLE_MS as f32 * 1e-3;
        let reading = ImuReading::Sample(ImuSample {
            accel_m_s2: up_of(roll, 0.0).map(|u| u * G + noise.next(0.05)),
            gyro_rad_s: [rate + GYRO_BIAS[0], GYRO_BIAS[1], GYRO_BIAS[2]],
        });
        dev.on_imu(reading);
        if crossed.is_none() && roll > 60f32.to_radians() {
            crossed = Some(k * SAMPLE_MS);
        }
        let in_safe_state = match dev.output_angles() {
            None => true,
            Some(_) => dev.motion_status().kind.is_none() && held_is(dev, &rest),
        };
        if safe.is_none() && in_safe_state {
            safe = Some(k * SAMPLE_MS);
        }
        dev.poll();
    }
    (crossed.unwrap(), safe.expect("no safe state"))
}

fn held_is(dev: &mut Dev, angles: &[f32; 12]) -> bool {
    // The readback reports the held target.
    match ask(dev, next_seq(), Request::GetState) {
        DeviceToHost::Ack { readback, .. } => readback
            .angles_rad
            .iter()
            .zip(angles)
            .all(|(a, b)| (a - b).abs() < 1e-6),
        _ => false,
    }
}

#[test]
fn a_fall_at_sixty_degrees_stops_within_a_frame_and_is_latched() {
    for safe_state in [SafeState::Off, SafeState::Rest] {
        let (mut dev, clock, mut noise) = standing();
        let config = BalanceConfig {
            safe_state,
            ..BalanceConfig::DEFAULT
        };
        set_balance(&mut dev, config);
        // A sway runs when the robot tips over (1 rad/s).
        let sway = MotionCommand::seed001_sway(Axis::Roll, None);
        assert!(matches!(
            ask(&mut dev, next_seq(), Request::StartMotion(sway)),
            DeviceToHost::MotionAck { .. }
        ));
        let (crossed, safe) = tip(&mut dev, &clock, &mut noise, 1.0);
        assert!(
            safe >= crossed && safe - crossed <= quad_device::engine::FRAME_MS,
            "{safe_state:?}: crossed at {crossed} ms, safe at {safe} ms"
        );
        match safe_state {
            SafeState::Off => assert!(dev.output_angles().is_none()),
            SafeState::Rest => assert!(dev.output_angles().is_some()),
        }
        // Latched: reported, and still so once level again; the flag goes to a 2.3 host.
        // Set back on its feet (the estimate follows within a few seconds).
        run(&mut dev, &clock, &mut noise, 6000, |_| up_of(0.0, 0.0));
        let rep = report(&mut dev);
        assert_eq!(rep.fall, Some(FallKind::Tilt), "{rep:?}");
        let state = ask(&mut dev, next_seq(), Request::GetState);
        assert!(state
            .readback()
            .unwrap()
            .flags
            .contains(Flags::FALL_DETECTED));
        assert_eq!(dev.motion_status().kind, None);
        // An explicit request clears it: stand up again.
        assert!(matches!(
            ask(
                &mut dev,
                next_seq(),
                Request::StartMotion(MotionCommand::StandUp)
            ),
            DeviceToHost::MotionAck { .. }
        ));
        assert_eq!(report(&mut dev).fall, None);
        let state = ask(&mut dev, next_seq(), Request::GetState);
        assert!(!state
            .readback()
            .unwrap()
            .flags
            .contains(Flags::FALL_DETECTED));
    }
}

#[test]
fn free_fall_is_detected() {
    let (mut dev, clock, mut noise) = standing();
    let mut detected_after = None;
    for k in 1..=20u32 {
        clock.advance_ms(SAMPLE_MS);
        dev.on_imu(ImuReading::Sample(ImuSample {
            accel_m_s2: [noise.next(0.3), noise.next(0.3), 0.5 + noise.next(0.3)],
            gyro_rad_s: GYRO_BIAS,
        }));
        if detected_after.is_none() && dev.output_angles().is_none()
            || report(&mut dev).fall.is_some()
        {
            detected_after.get_or_insert(k * SAMPLE_MS);
        }
        dev.poll();
    }
    let t = detected_after.expect("free fall not detected");
    // The first sample of the fall starts the timer; detected FREE_FALL_MS later.
    assert!(
        (FREE_FALL_MS..=FREE_FALL_MS + SAMPLE_MS).contains(&t),
        "{t} ms"
    );
    assert_eq!(report(&mut dev).fall, Some(FallKind::FreeFall));
    // A trot's bounce (40 ms of low force) is none.
    let (mut dev, clock, mut noise) = standing();
    for k in 0..40u32 {
        clock.advance_ms(SAMPLE_MS);
        let low = k % 10 < 4;
        let z = if low { 0.5 } else { G };
        dev.on_imu(ImuReading::Sample(ImuSample {
            accel_m_s2: [noise.next(0.1), noise.next(0.1), z],
            gyro_rad_s: GYRO_BIAS,
        }));
        dev.poll();
    }
    assert_eq!(report(&mut dev).fall, None);
}

#[test]
fn a_motion_is_refused_while_the_robot_is_tipped() {
    let (mut dev, clock) = clocked_device();
    let mut noise = Noise(3);
    hello(&mut dev, PROTOCOL_VERSION);
    // Lying on its side (80° of roll), the sensor started there; outputs off.
    run(&mut dev, &clock, &mut noise, 1500, |_| {
        up_of(80f32.to_radians(), 0.0)
    });
    assert_eq!(report(&mut dev).health, ImuHealth::Ok);
    let refused = ask(
        &mut dev,
        next_seq(),
        Request::StartMotion(MotionCommand::StandUp),
    );
    assert!(
        matches!(
            refused,
            DeviceToHost::Nack {
                reason: NackReason::NotUpright,
                ..
            }
        ),
        "{refused:?}"
    );
    assert!(dev.output_angles().is_none());
    // A 2.2 host, which does not know the reason, is told the device is busy.
    hello(&mut dev, 0x0202);
    let refused = ask(
        &mut dev,
        next_seq(),
        Request::StartMotion(MotionCommand::StandUp),
    );
    assert!(
        matches!(
            refused,
            DeviceToHost::Nack {
                reason: NackReason::Busy,
                ..
            }
        ),
        "{refused:?}"
    );
    // During the bias measurement the accelerometer alone is checked.
    let (mut dev, clock) = clocked_device();
    hello(&mut dev, PROTOCOL_VERSION);
    run(&mut dev, &clock, &mut noise, 100, |_| up_of(0.0, 2.5));
    assert_eq!(report(&mut dev).health, ImuHealth::Starting);
    assert!(matches!(
        ask(
            &mut dev,
            next_seq(),
            Request::StartMotion(MotionCommand::StandUp)
        ),
        DeviceToHost::Nack {
            reason: NackReason::NotUpright,
            ..
        }
    ));
    // Upright on a 20° slope: it starts.
    let (mut dev, clock) = clocked_device();
    hello(&mut dev, PROTOCOL_VERSION);
    run(&mut dev, &clock, &mut noise, 1500, |_| {
        up_of(20f32.to_radians(), 0.0)
    });
    assert!(matches!(
        ask(
            &mut dev,
            next_seq(),
            Request::StartMotion(MotionCommand::StandUp)
        ),
        DeviceToHost::MotionAck { .. }
    ));
}

#[test]
fn a_nak_mid_run_switches_leveling_off_without_a_step_above_the_limiter() {
    for on_fault in [FaultAction::OpenLoop, FaultAction::Stop] {
        let (mut dev, clock, mut noise) = standing();
        let slope = 8f32.to_radians();
        set_balance(
            &mut dev,
            BalanceConfig {
                on_fault,
                ..leveling_on()
            },
        );
        let sway = MotionCommand::Sway {
            axis: Axis::Roll,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: None,
        };
        assert!(matches!(
            ask(&mut dev, next_seq(), Request::StartMotion(sway)),
            DeviceToHost::MotionAck { .. }
        ));
        // The world sees the floor's slope and the body's sway on it.
        run(&mut dev, &clock, &mut noise, 4000, |d| {
            up_on_slope(d, slope, 0.0)
        });
        let rep = report(&mut dev);
        assert!(rep.leveling_active, "{rep:?}");
        assert!(rep.correction_roll_rad < -4f32.to_radians(), "{rep:?}");
        // The sensor stops answering: the outputs never step by more than the limiter's step.
        let step = dev.limiter().max_step_rad();
        let mut last = *dev.output_angles().unwrap();
        for _ in 0..100 {
            clock.advance_ms(SAMPLE_MS);
            dev.on_imu(ImuReading::Fault(ImuFault::Nak));
            dev.poll();
            let now = *dev.output_angles().unwrap();
            for (a, b) in now.iter().zip(&last) {
                assert!(
                    (a - b).abs() <= step * 1.0001,
                    "step {} > {step}",
                    (a - b).abs()
                );
            }
            last = now;
        }
        let rep = report(&mut dev);
        assert_eq!(rep.health, ImuHealth::Fault(ImuFaultKind::Nak), "{rep:?}");
        assert!(!rep.config.leveling && !rep.leveling_active, "{rep:?}");
        assert_eq!(rep.correction_roll_rad, 0.0);
        let st = dev.motion_status();
        match on_fault {
            FaultAction::OpenLoop => {
                assert_eq!(
                    (st.kind, st.stage),
                    (Some(MotionKind::Sway), MotionStage::Run)
                )
            }
            FaultAction::Stop => assert_ne!(st.stage, MotionStage::Run, "{st:?}"),
        }
        // Leveling cannot be switched on again while the sensor fails.
        assert!(matches!(
            set_balance(&mut dev, leveling_on()),
            DeviceToHost::Nack {
                reason: NackReason::ImuFault(ImuFaultKind::Nak),
                ..
            }
        ));
    }
}

#[test]
fn without_a_sensor_leveling_is_refused_and_motions_run_open_loop() {
    let (mut dev, clock) = clocked_device();
    hello(&mut dev, PROTOCOL_VERSION);
    dev.on_imu(ImuReading::Fault(ImuFault::Absent));
    let r = report(&mut dev);
    assert_eq!(r.health, ImuHealth::Absent);
    assert!(matches!(
        set_balance(&mut dev, leveling_on()),
        DeviceToHost::Nack {
            reason: NackReason::ImuAbsent,
            ..
        }
    ));
    assert!(!report(&mut dev).config.leveling);
    // The other settings are taken.
    let config = BalanceConfig {
        safe_state: SafeState::Off,
        ..BalanceConfig::DEFAULT
    };
    assert!(matches!(
        set_balance(&mut dev, config),
        DeviceToHost::Imu { report, .. } if report.config == config
    ));
    assert!(matches!(
        ask(
            &mut dev,
            next_seq(),
            Request::StartMotion(MotionCommand::StandUp)
        ),
        DeviceToHost::MotionAck { .. }
    ));
    frames(&mut dev, &clock, 300);
    let sway = MotionCommand::seed001_sway(Axis::Pitch, Some(20.0));
    assert!(matches!(
        ask(&mut dev, next_seq(), Request::StartMotion(sway)),
        DeviceToHost::MotionAck { .. }
    ));
}

#[test]
fn balance_fields_out_of_range_are_refused_naming_the_field() {
    let (mut dev, _) = clocked_device();
    hello(&mut dev, PROTOCOL_VERSION);
    let d = BalanceConfig::DEFAULT;
    let cases = [
        (
            BalanceConfig { level_kp: 1.5, ..d },
            MotionParam::LevelKp,
            ParamProblem::OutOfRange,
        ),
        (
            BalanceConfig {
                level_ki_per_s: f32::NAN,
                ..d
            },
            MotionParam::LevelKiPerS,
            ParamProblem::NonFinite,
        ),
        (
            BalanceConfig {
                max_correction_rad: -0.1,
                ..d
            },
            MotionParam::MaxCorrectionRad,
            ParamProblem::Negative,
        ),
        (
            BalanceConfig {
                fall_angle_rad: 0.0,
                ..d
            },
            MotionParam::FallAngleRad,
            ParamProblem::NotPositive,
        ),
        (
            BalanceConfig {
                fall_angle_rad: 4.0,
                ..d
            },
            MotionParam::FallAngleRad,
            ParamProblem::OutOfRange,
        ),
    ];
    for (seq, (config, param, problem)) in cases.into_iter().enumerate() {
        let seq = seq as u16 + 1;
        let answer = ask(&mut dev, seq, Request::SetBalance(config));
        assert_eq!(
            answer,
            DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::InvalidParameter { param, problem }
            }
        );
    }
    // Nothing changed.
    assert_eq!(report(&mut dev).config, d);
}

#[test]
fn a_fast_tip_on_a_held_pose_is_met_by_the_rate_term_and_a_sway_is_not() {
    use quad_device::balance::{Balance, RATE_DEAD_BAND_RAD_S, RATE_GAIN_S, RATE_HELD_FRAMES};
    let reading = |gyro_x: f32| {
        ImuReading::Sample(ImuSample {
            accel_m_s2: [0.0, 0.0, G],
            gyro_rad_s: [gyro_x, 0.0, 0.0],
        })
    };
    let mut b = Balance::<kin_core::DefaultMath>::new();
    let mut now = 0;
    for _ in 0..=(BIAS_WINDOW_MS / SAMPLE_MS) {
        b.push(reading(0.0), now, true);
        now += SAMPLE_MS;
    }
    b.configure(leveling_on()).unwrap();
    // One frame of the leveling: the set point `intended` held or moved.
    let mut frame = |b: &mut Balance<kin_core::DefaultMath>, gyro_x: f32, intended: f32| {
        b.push(reading(gyro_x), now, true);
        now += 20;
        let c = b.level(0.02).expect("leveling runs");
        b.applied(Some(([intended, 0.0], c, false)), c);
        c
    };
    // A held pose, still: nothing to correct.
    for _ in 0..=RATE_HELD_FRAMES {
        frame(&mut b, 0.0, 0.0);
    }
    let c = frame(&mut b, 0.0, 0.0);
    assert!(c[0].abs() < 0.01, "{c:?}");
    // Tipping toward +y (roll falling) at 0.5 rad/s: the rate term lengthens the legs it
    // stands on (a positive roll correction).
    let c = frame(&mut b, -0.5, 0.0);
    let expected = RATE_GAIN_S * (0.5 - RATE_DEAD_BAND_RAD_S);
    assert!((c[0] - expected).abs() < 0.01, "{c:?} against {expected}");
    // Within the dead band: nothing.
    let c = frame(&mut b, -0.9 * RATE_DEAD_BAND_RAD_S, 0.0);
    assert!(c[0].abs() < 0.01, "{c:?}");
    // A sway: the set point moves every frame and the body follows it a frame later; its
    // rate is the body's, no rate term (which would be 0.16 rad here).
    for k in 1..20 {
        let gyro_x = if k > 1 { 0.5 } else { 0.0 };
        let c = frame(&mut b, gyro_x, 0.01 * k as f32);
        assert!(c[0].abs() < 0.05, "frame {k}: {c:?}");
    }
}
