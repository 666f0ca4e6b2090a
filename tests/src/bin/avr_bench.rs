//! `cargo xtask avr-bench`: the firmware's IK benchmark in simavr (see
//! `integration_tests::avr_bench`). Prints a table per backend, then the JSON figures as the
//! last line of stdout.

use integration_tests::avr_bench;

fn main() {
    let report = avr_bench::run();
    println!(
        "{:<38} {:>9} {:>10} {:>10} {:>11} {:>12} {:>14}",
        "backend (ELF)", "leg max", "leg mean", "body max", "body mean", "err max °", "vs host rad"
    );
    for b in &report.backends {
        println!(
            "{:<38} {:>9} {:>10.0} {:>10} {:>11.0} {:>12.2e} {:>14.2e}",
            b.name,
            b.leg_max_cycles,
            b.leg_mean_cycles,
            b.body_max_cycles,
            b.body_mean_cycles,
            b.max_angle_err_deg,
            b.max_diff_to_host_libm_rad
        );
    }
    println!(
        "{:<16} {:>16} {:>18}",
        "primitive", "bench.elf", "bench-libm.elf"
    );
    for (name, avr, libm) in &report.primitives {
        let libm = libm.map_or_else(|| "-".to_string(), |c| format!("{c:.0}"));
        println!("{name:<16} {avr:>16.0} {libm:>18}");
    }
    println!(
        "{:<20} {:>14} {:>15} {:>16}",
        "onboard motion", "frame max", "frame mean", "share of 20 ms"
    );
    for m in &report.motions {
        println!(
            "{:<20} {:>14} {:>15.0} {:>15.1}%",
            m.name,
            m.max_cycles,
            m.mean_cycles,
            100.0 * m.max_cycles as f64 / avr_bench::SERVO_FRAME_CYCLES as f64
        );
    }
    println!(
        "targets: {} body poses + {} leg targets (seed {:#x}); cycles at 16 MHz; solvers built once at boot, as the firmware builds its own, except where marked; bench.elf stack {} B",
        avr_bench::N_TARGETS,
        avr_bench::N_TARGETS,
        avr_bench::SEED,
        report.bench_stack_bytes
    );
    println!(
        "{}",
        serde_json::to_string(&report.summary).expect("serialisable figures")
    );
}
