//! The ATmega2560 firmware's math on the host: the firmware's backend `avr_libc_math::AvrFast`
//! is `kin_core::math::SoftFloat` over avr-libc's `sqrt` (correctly rounded, as libm's `sqrtf`
//! of `SoftFloat`'s default here): the kernels `poly::atan2_fixed` and `poly::sin_cos_fixed`,
//! the bit-pattern comparisons and the legs one after the other, as on the board. The same
//! backend runs here on the same benchmark inputs as
//! `bench_accuracy.rs`, against the generating f64 angles (the hard limit of the firmware:
//! 0.01°) and against the host's default backend (the readback bound between device and host,
//! which the emulator test `tests/tests/avr_firmware.rs` checks on the real firmware).

#[path = "../benches/common/mod.rs"]
mod common;

use kin_core::math::{Fast, SoftFloat};
use kin_core::{body, leg, BodyConfig, ReachPolicy, Robot};

/// The firmware's backend, with libm's square root for avr-libc's.
type AvrKernels = SoftFloat;

/// The firmware's hard limit on the angle error against an f64 reference, rad (0.01°).
const HARD_LIMIT_RAD: f64 = 0.01 * std::f64::consts::PI / 180.0;

/// Bound on |firmware angle − host angle| (`AvrFast` against `DefaultMath`), rad: the
/// fixed-point arctangent's 3.5e-5 plus the rounding of its arguments.
const READBACK_BOUND_RAD: f64 = 5e-5;

#[test]
fn firmware_kernels_on_every_benchmark_leg_target() {
    let robots = common::robots();
    let (mut worst_f64, mut worst_host) = (0.0f64, 0.0f64);
    for t in common::leg_targets() {
        let robot = &robots[t.robot];
        let avr = leg::Solver::<AvrKernels>::with_math(robot)
            .inverse(t.leg, t.foot_in_hip, ReachPolicy::Reject)
            .unwrap_or_else(|e| panic!("{t:?}: {e}"))
            .angles
            .to_array();
        let host = leg::Solver::<Fast>::with_math(robot)
            .inverse(t.leg, t.foot_in_hip, ReachPolicy::Reject)
            .expect("the host solves every benchmark target")
            .angles
            .to_array();
        for j in 0..3 {
            worst_f64 = worst_f64.max((avr[j] as f64 - t.angles_rad[j]).abs());
            worst_host = worst_host.max((avr[j] as f64 - host[j] as f64).abs());
        }
    }
    eprintln!(
        "firmware kernels over {} leg targets: {worst_f64:.2e} rad from the generating f64 \
         angles, {worst_host:.2e} rad from the host",
        common::N_TARGETS
    );
    assert!(worst_f64 <= HARD_LIMIT_RAD, "{worst_f64:e} rad from f64");
    assert!(
        worst_host <= READBACK_BOUND_RAD,
        "{worst_host:e} rad from the host"
    );
}

#[test]
fn firmware_kernels_on_every_benchmark_pose() {
    let robot = Robot::shahriar2023();
    let height_m = common::STANCE_HEIGHT_SHAHRIAR_M;
    let config = BodyConfig::default();
    let mut worst = 0.0f64;
    for pose in common::body_poses() {
        let solve = |avr: bool| {
            if avr {
                body::Solver::<AvrKernels>::with_math(&robot).inverse_at_stance(
                    &pose,
                    &config,
                    height_m,
                    ReachPolicy::Reject,
                )
            } else {
                body::Solver::<Fast>::with_math(&robot).inverse_at_stance(
                    &pose,
                    &config,
                    height_m,
                    ReachPolicy::Reject,
                )
            }
            .unwrap_or_else(|e| panic!("{pose:?}: {e}"))
            .flat()
        };
        for (a, h) in solve(true).iter().zip(solve(false)) {
            worst = worst.max((*a as f64 - h as f64).abs());
        }
    }
    eprintln!(
        "firmware kernels over {} body poses: {worst:.2e} rad from the host",
        common::N_POSES
    );
    assert!(worst <= READBACK_BOUND_RAD, "{worst:e} rad from the host");
}
