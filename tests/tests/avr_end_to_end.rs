//! The firmware's IK end to end (`integration_tests::end_to_end`), the CI's seeded share:
//! random body poses and foot targets over the preset's whole workspace, every rotation order
//! and both reach policies, solved in simavr by the firmware's solver, against the host's
//! `SoftFloat` path (the same verdicts; the bit-identical share reported) and against an f64
//! reference (error ≤ 0.01°, no outlier). `cargo xtask kernel-campaign --poses N` runs more.

use integration_tests::end_to_end::{run, TOLERANCE_RAD};
use integration_tests::kernels::Harness;

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
}
