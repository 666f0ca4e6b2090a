//! The firmware's IK end to end (`integration_tests::end_to_end`), the CI's seeded share:
//! random body poses and foot targets over the preset's whole workspace, every rotation order
//! and both reach policies, solved in simavr by the firmware's solver, against the host's
//! `SoftFloat` path (the same verdicts; the bit-identical share reported) and against an f64
//! reference (error ≤ 0.01°, no outlier; the feet within the kernels' accuracy of their f64 targets).
//! `cargo xtask kernel-campaign --poses N` runs more.

use integration_tests::end_to_end::{run, TOLERANCE_RAD};
use integration_tests::kernels::Harness;

/// The bound of the feet's distance from their f64 targets, m, from the firmware kernels'
/// documented errors (kin-core's tests hold them): three joint angles each within 2e-6 rad
/// (`atan2_fixed`) on levers of at most the leg's span (0.6 m), 3.6e-6 m; the body rotation's
/// sines and cosines within 1e-6 on the hips' distance from the centre (0.33 m), 0.3e-6 m per
/// term; rounded up to 5e-6 m.
const FOOT_TOLERANCE_M: f64 = 5e-6;

/// Cases of the CI's share.
const CASES: u64 = 20_000;

#[test]
fn firmware_ik_over_the_workspace_agrees_with_the_host_and_f64() {
    let mut harness = Harness::boot();
    let fig = run(&mut harness, CASES, 0x0e2e_0028, |_| {});
    eprintln!("{fig:#?}");
    eprintln!(
        "bit-identical to the host: {:.4} %; {:.0} cases/s",
        100.0 * fig.bit_identical_share(),
        harness.evaluations_per_s()
    );
    assert_eq!(fig.cases, CASES);
    assert!(fig.solved > CASES / 10, "too few solved: {fig:?}");
    assert!(fig.referenced > CASES / 20, "too few referenced: {fig:?}");
    assert_eq!(fig.verdict_differences, 0, "{:#?}", fig.first_findings);
    assert_eq!(fig.outliers, 0, "{:#?}", fig.first_findings);
    assert!(fig.max_error_rad <= TOLERANCE_RAD);
    // Where the angles are ill-conditioned (a foot near its abduction offset), the feet they
    // put still stand within the kernels' documented accuracy of their targets.
    assert!(fig.max_foot_error_m <= FOOT_TOLERANCE_M, "{fig:?}");
}
