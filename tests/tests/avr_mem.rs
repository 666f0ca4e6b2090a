//! The firmware's `memcpy` and `memset` (`firmware_avr::mem`, four bytes per loop step) on the
//! emulated chip: the `mem-check` binary copies and fills every length from 0 to 80 bytes at
//! every alignment of source and destination, compares each result and the bytes around it
//! with a byte loop's, and reports `K`, or `X` and the first failure.
//!
//! The firmware is built once per test process (`quad_host::emu::build`); the test fails —
//! never skips — when it cannot be built.

use quad_host::emu::{build, Mega2560};

#[test]
fn memcpy_and_memset_match_their_definition_at_every_length_and_alignment() {
    let elf = build::firmware_elf("mem-check").unwrap_or_else(|e| panic!("{e}"));
    let mut mcu = Mega2560::new(&elf).unwrap_or_else(|e| panic!("{e}"));
    let verdict = mcu
        .read_exact(1, 200_000_000)
        .unwrap_or_else(|got| panic!("no verdict from mem-check (got {got:?})"));
    if verdict != b"K" {
        let detail = mcu.read_exact(4, 1_000_000).unwrap_or_default();
        let what = ["memcpy", "memset"];
        match detail[..] {
            [op, len, src, dst] => panic!(
                "{} fails: {len} bytes, source offset {src}, destination offset {dst}",
                what.get(usize::from(op)).unwrap_or(&"?")
            ),
            _ => panic!("mem-check answered {verdict:?} {detail:?}"),
        }
    }
}
