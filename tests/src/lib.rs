//! Cross-crate tests live in `tests/tests/*.rs`; this library holds what they share.
//!
//! - [`avr`]: build the ATmega2560 firmware and run it in simavr.
//! - [`avr_bench`]: the firmware's IK cycle benchmark (`cargo xtask avr-bench`).

pub mod avr;
pub mod avr_bench;
