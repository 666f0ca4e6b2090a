//! `cargo xtask ci budget`: builds the release firmware, measures its flash, static SRAM and
//! worst stack in simavr (see `integration_tests::budget`), prints them with the margins and
//! fails when a figure is over budget. `firmware-budget ELF` measures another firmware ELF.

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
    if figures.within_budget() {
        ExitCode::SUCCESS
    } else {
        eprintln!("firmware budget: over budget");
        ExitCode::FAILURE
    }
}
