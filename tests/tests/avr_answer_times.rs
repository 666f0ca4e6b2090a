//! Every kind of request's answer time on the firmware in simavr, at both line rates, against
//! the table of `quad_protocol::timing` (which docs/protocol.md prints): no measurement more
//! than a little above its row, and no row far above its measurement. `--nocapture` prints the
//! rows.

use integration_tests::answer_times::{self, Measured};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::timing::{Kind, BAUDS};
use std::time::Duration;

/// How far a measurement may lie above its row before the table is called stale: 15 % and
/// 1 ms (a firmware change moves the answers a little; the suggested timeout's margin covers
/// far more).
fn too_slow(bound: Duration, measured: Duration) -> bool {
    measured > bound.mul_f64(1.15) + Duration::from_millis(1)
}

/// How far a row may lie above its measurement before the table is called stale: 30 % and
/// 2 ms (room for a faster firmware before the table must follow).
fn too_loose(bound: Duration, measured: Duration) -> bool {
    bound > measured.mul_f64(1.3) + Duration::from_millis(2)
}

fn measure(bin: &str, baud: u32) -> Vec<Measured> {
    let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
    let mut link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
    answer_times::measure(&mut link)
}

#[test]
fn every_request_kind_is_answered_within_its_documented_time_at_both_rates() {
    let runs = [
        measure(build::FIRMWARE, BAUDS[0]),
        measure(build::FIRMWARE_1MBAUD, BAUDS[1]),
    ];
    let worst: Vec<_> = runs.iter().map(|r| answer_times::worst(r)).collect();
    let mut problems = Vec::new();
    println!("| request | cases | worst @ 115200, µs | worst @ 1000000, µs |");
    for (row, kind) in Kind::ALL.iter().enumerate() {
        let cases = runs[0].iter().filter(|m| m.kind == *kind).count();
        let measured = [worst[0][row].1, worst[1][row].1];
        println!(
            "| {} | {cases} | {} | {} |",
            kind.name(),
            measured[0].as_micros(),
            measured[1].as_micros()
        );
        for (col, &m) in measured.iter().enumerate() {
            let bound = Duration::from_micros(u64::from(kind.worst_us()[col]));
            if too_slow(bound, m) {
                problems.push(format!(
                    "{} @ {}: measured {m:?} > the table's {bound:?}",
                    kind.name(),
                    BAUDS[col]
                ));
            } else if too_loose(bound, m) {
                problems.push(format!(
                    "{} @ {}: the table's {bound:?} is far above the measured {m:?}",
                    kind.name(),
                    BAUDS[col]
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "quad_protocol::timing's table is out of date (update it and docs/protocol.md):\n{}",
        problems.join("\n")
    );
}
