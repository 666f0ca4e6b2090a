//! The firmware's IK in simavr against the cycle figures it is held to: the leg IK within
//! 8,000 cycles (0.5 ms at 16 MHz) on every one of the benchmark's 50 leg targets, and the
//! body pose within 32,000 cycles on its 50 poses, both on the firmware's backend
//! ([`FIRMWARE_BACKEND`], its solver built once as the firmware builds its own) and as
//! accurate as `cargo xtask avr-bench` requires. Simulated
//! cycles are deterministic: a change that makes the IK slower fails here, not only in the
//! benchmark's report.
//!
//! The firmware is built once per test process (`quad_host::emu::build`); the test fails —
//! never skips — when it cannot be built.

use integration_tests::avr_bench::{self, measure_backend, BenchFirmware, FIRMWARE_BACKEND};
use quad_host::emu::build;

/// The leg IK's figure, cycles (worst of the 50 leg targets).
const LEG_IK_MAX_CYCLES: u64 = 8_000;

/// The body pose's figure, cycles (worst of the 50 poses; 2 ms at 16 MHz, 0.5 ms per leg).
/// Measured 31,894 (BENCHMARKS.md).
const BODY_POSE_MAX_CYCLES: u64 = 32_000;

/// The angle error against the f64 reference allowed on the firmware's backend, degrees.
const MAX_ANGLE_ERR_DEG: f64 = 0.01;

#[test]
fn leg_ik_and_body_pose_stay_within_their_cycle_figures() {
    let elf = build::firmware_elf(build::BENCH).unwrap_or_else(|e| panic!("{e}"));
    let mut fw = BenchFirmware::boot(&elf);
    let figures = measure_backend(
        &mut fw,
        FIRMWARE_BACKEND,
        "bench.elf",
        &avr_bench::targets(),
    );
    println!(
        "{}: leg IK max {} cycles, body pose max {} cycles, max angle error {:.2e}°",
        figures.name, figures.leg_max_cycles, figures.body_max_cycles, figures.max_angle_err_deg
    );
    assert!(
        figures.leg_max_cycles <= LEG_IK_MAX_CYCLES,
        "leg IK {} cycles > {LEG_IK_MAX_CYCLES}",
        figures.leg_max_cycles
    );
    assert!(
        figures.body_max_cycles <= BODY_POSE_MAX_CYCLES,
        "body pose {} cycles > {BODY_POSE_MAX_CYCLES}",
        figures.body_max_cycles
    );
    assert!(
        figures.max_angle_err_deg <= MAX_ANGLE_ERR_DEG,
        "max angle error {:.2e}° > {MAX_ANGLE_ERR_DEG}°",
        figures.max_angle_err_deg
    );
}
