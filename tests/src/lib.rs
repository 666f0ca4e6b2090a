//! Cross-crate tests live in `tests/tests/*.rs`; this library holds what they share.
//!
//! - [`avr_bench`]: the firmware's IK cycle benchmark (`cargo xtask avr-bench`).
//! - [`budget`]: the firmware's flash and SRAM against its budget (`cargo xtask ci budget`).
//! - [`pins`]: a servo pin's step between two pulses against the joint-speed limiter.
//! - [`symbols`]: which routines a firmware ELF links (`avr-nm`).
//! - [`conformance`]: the conformance kit, exchanges with the firmware recorded as JSON lines.
//! - [`wire`]: raw frames to the emulated firmware and the answers that come back.
//! - [`kernels`], [`kernel_edges`]: the AVR kernels against their twins at their edges.
//! - [`end_to_end`]: the firmware's IK against the host's and f64.
//!
//! Building the firmware and running it in simavr is `quad_host::emu` (one implementation
//! for these tests and `quadctl`).

pub mod answer_times;
pub mod avr_bench;
pub mod budget;
pub mod conformance;
pub mod end_to_end;
pub mod kernel_edges;
pub mod kernels;
pub mod pins;
pub mod symbols;
pub mod wire;
