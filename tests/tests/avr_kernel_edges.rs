//! Every AVR kernel against its twin, bit for bit, at the edges of its input space and on
//! random inputs (the CI's seeded share; `cargo xtask kernel-campaign` runs the long one):
//! the firmware's arctangent and sine/cosine against kin-core's portable kernels on the host,
//! the portable kernels compiled for the AVR against the same, and the firmware's float
//! primitives (`__addsf3`, `__subsf3`, `__mulsf3`, `sqrt`) against avr-libc's own routines.
//! The classes are `integration_tests::kernel_edges`'; the harness streams the arguments
//! through the kernel from the emulated chip's memory (`integration_tests::kernels`).
//!
//! A finding prints the arguments and both results in hex. The firmware is built once per
//! test process; the test fails, never skips, when it cannot be built.

use integration_tests::kernel_edges::{classes, plan};
use integration_tests::kernels::{run_plan, Harness, Kernel};

/// Evaluations per firmware kernel in CI (the floor: 10⁶).
const CI_EVALUATIONS: u64 = 1_000_000;

/// Evaluations per portable kernel compiled for the AVR (the firmware runs the asm forms;
/// these check that the host's twin is the AVR's portable kernel too).
const CI_PORTABLE_EVALUATIONS: u64 = 100_000;

/// The seed of the CI's share.
const SEED: u64 = 0x0ed6_e5ca_5e00_0028;

fn check(kernel: Kernel, evaluations: u64) {
    let classes = classes(kernel);
    let share = plan(&classes, evaluations, SEED ^ kernel as u64);
    let mut harness = Harness::boot();
    let report = run_plan(&mut harness, kernel, &classes, &share, |_| {});
    for (class, n, bad) in &report.classes {
        eprintln!(
            "{}: {class}: {n} evaluations, {bad} mismatches",
            report.kernel
        );
    }
    eprintln!(
        "{}: {} evaluations, {} mismatches, {:.0} evaluations/s",
        report.kernel, report.evaluations, report.mismatches, report.evaluations_per_s
    );
    assert!(report.evaluations >= evaluations, "{report:?}");
    assert_eq!(
        report.mismatches,
        0,
        "{} differs from its twin:\n{}",
        report.kernel,
        report.first_findings.join("\n")
    );
}

#[test]
fn atan2_fixed_asm_is_its_twin_at_every_edge() {
    check(Kernel::Atan2Fixed, CI_EVALUATIONS);
}

#[test]
fn sin_cos_fixed_asm_is_its_twin_at_every_edge() {
    check(Kernel::SinCosFixed, CI_EVALUATIONS);
}

#[test]
fn portable_kernels_on_the_avr_are_the_hosts() {
    check(Kernel::Atan2FixedPortable, CI_PORTABLE_EVALUATIONS);
    check(Kernel::SinCosFixedPortable, CI_PORTABLE_EVALUATIONS);
}

#[test]
fn add_is_avr_libcs_at_every_edge() {
    check(Kernel::Add, CI_EVALUATIONS);
}

#[test]
fn sub_is_avr_libcs_at_every_edge() {
    check(Kernel::Sub, CI_EVALUATIONS);
}

#[test]
fn mul_is_avr_libcs_at_every_edge() {
    check(Kernel::Mul, CI_EVALUATIONS);
}

#[test]
fn sqrt_is_avr_libcs_at_every_edge() {
    check(Kernel::Sqrt, CI_EVALUATIONS);
}
