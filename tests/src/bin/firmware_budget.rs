//! `cargo xtask ci budget`: builds the release firmware, measures its flash, static SRAM and
//! worst stack in simavr (see `integration_tests::budget`), prints them with the margins and
//! fails when a figure is over budget or a table
//! read with `lpm` lies beyond the lowest 64 KB of flash. `firmware-budget ELF` measures another firmware ELF.

use integration_tests::{avr_bench, budget};
use quad_host::emu::build;
use std::process::ExitCode;

fn main() -> ExitCode {
    let elf = match std::env::args_os().nth(1) {
        Some(path) => path.into(),
        None => build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}")),
    };
    let poses = avr_bench::targets().poses;
    let figures = budget::measure(&elf, &poses[..4]);
    println!("firmware budget ({}):\n{figures}", elf.display());
    let image = quad_host::emu::elf::Elf::read(&elf).unwrap_or_else(|e| panic!("{e}"));
    let objects = image.flash_objects();
    let lpm_end = objects.iter().map(|o| o.end()).max().unwrap_or(0);
    let beyond = budget::lpm_reach_violations(&elf);
    println!(
        "lpm    {} data objects in flash end at {lpm_end:#07x} of {:#07x} (lpm's reach), margin {} B",
        objects.len(),
        budget::LPM_REACH_BYTES,
        i64::from(budget::LPM_REACH_BYTES) - i64::from(lpm_end)
    );
    for o in &beyond {
        eprintln!(
            "firmware budget: {} at {:#07x}..{:#07x} lies beyond lpm's 64 KB reach",
            o.name,
            o.addr,
            o.end()
        );
    }
    if !figures.within_budget() {
        eprintln!("firmware budget: over budget");
    }
    if figures.within_budget() && beyond.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
