//! Regression: the firmware's knee angle where the knee's `atan2` ratio `|cos k / sin k|`
//! lies just below 2⁻⁵ (the arctangent's first table cell boundary).
//!
//! There the asm `atan2_fixed` lost bit 31 of its linear product `d·b` (cell 0's slope `b`
//! is above 2¹⁵), so the device answered a knee 2⁻⁵ rad (1.79°) off the host's. These poses
//! reproduced it from outside (robot shahriar2023, stance 0.40 m, order zyx): one rotated
//! pose, and level poses swept across the two body heights at which a knee's ratio crosses
//! 2⁻⁵ (beyond and short of 90°), in steps far finer than the window of about 1 µm. Every
//! readback must equal the host's kin-core within the AVR tolerance.

use kin_core::body::{self, Pose};
use kin_core::{BodyConfig, LegId, ReachPolicy, Robot, RotationOrder};
use quad_host::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, AVR_ANGLE_TOLERANCE_RAD,
};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::RobotPreset;

/// The stance of the reports, m.
const STANCE_HEIGHT_M: f32 = 0.40;

/// Half-width of each height sweep around its crossing, m.
const SWEEP_HALF_WIDTH_M: f64 = 1.5e-6;

/// Steps of a height sweep on each side.
const SWEEP_STEPS: i32 = 60;

fn connect() -> PoseStream<EmulatorLink> {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(115_200)).unwrap_or_else(|e| panic!("{e}"));
    let setup = StreamSetup {
        robot: Robot::shahriar2023(),
        preset: RobotPreset::Shahriar2023,
        stance_height_m: Some(STANCE_HEIGHT_M),
        order: Some(RotationOrder::Zyx),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    PoseStream::connect(Client::new(link, ClientConfig::emulator()), setup)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn level(z_m: f64) -> Pose {
    Pose {
        z_m: z_m as f32,
        ..Pose::default()
    }
}

/// The host's FL knee angle of a level pose at height offset `z_m`, rad.
fn host_knee_rad(z_m: f64) -> f64 {
    let config = BodyConfig::about_centre(RotationOrder::Zyx);
    let solution = body::Solver::new(&Robot::shahriar2023())
        .inverse_at_stance(&level(z_m), &config, STANCE_HEIGHT_M, ReachPolicy::Reject)
        .expect("the host solves a level pose");
    f64::from(solution.flat()[LegId::FL as usize * 3 + 2])
}

/// The height offset at which the host's FL knee magnitude crosses `target_rad`, by bisection
/// over `[lo, hi]` (the knee's magnitude changes monotonically with the height there).
fn crossing(target_rad: f64, mut lo: f64, mut hi: f64) -> f64 {
    let side = |z: f64| host_knee_rad(z).abs() > target_rad;
    let lo_side = side(lo);
    assert_ne!(
        lo_side,
        side(hi),
        "no crossing of {target_rad} in [{lo}, {hi}]"
    );
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if side(mid) == lo_side {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn assert_answers_as_the_host(stream: &mut PoseStream<EmulatorLink>, pose: &Pose) {
    let result = stream.send(pose).expect("link");
    assert!(
        matches!(result, PoseResult::Acked { .. }),
        "pose {pose:?}: {result:?}"
    );
}

#[test]
fn the_reported_rotated_pose_gets_the_hosts_knee() {
    let mut stream = connect();
    let pose = Pose {
        roll_rad: 0.091744,
        pitch_rad: 0.055462,
        yaw_rad: 0.193938,
        x_m: -0.006470,
        y_m: 0.015902,
        z_m: -0.014557,
    };
    assert_answers_as_the_host(&mut stream, &pose);
    assert_eq!(stream.stats().readback_mismatches, 0);
}

#[test]
fn level_poses_across_both_knee_ratio_crossings_get_the_hosts_knees() {
    let edge = (2.0f64).powi(-5).atan();
    let half_pi = core::f64::consts::FRAC_PI_2;
    // Beyond 90° (the body lower, the knee more bent) and short of it (near the stance).
    let windows = [
        crossing(half_pi + edge, -0.02, -0.005),
        crossing(half_pi - edge, -0.005, 0.01),
    ];
    eprintln!("knee ratio 2^-5 crossings at z = {windows:?} m");
    let mut stream = connect();
    for z0 in windows {
        for i in -SWEEP_STEPS..=SWEEP_STEPS {
            let z = z0 + SWEEP_HALF_WIDTH_M * f64::from(i) / f64::from(SWEEP_STEPS);
            assert_answers_as_the_host(&mut stream, &level(z));
        }
    }
    let stats = stream.stats();
    assert_eq!(stats.readback_mismatches, 0);
    assert_eq!(stats.acked, 2 * (2 * SWEEP_STEPS as u64 + 1));
}
