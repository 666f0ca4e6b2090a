//! The ATmega2560 firmware on the host: building its ELFs and running them in simavr
//! in-process.
//!
//! - [`build`]: `cd firmware-avr && cargo build --release` (nightly + `build-std`, through that
//!   directory's `rust-toolchain.toml`), once per process; fails loudly when it cannot build —
//!   an emulator test or demo never skips.
//! - [`Mega2560`]: one ELF in simavr at 16 MHz, instruction by instruction, with a cycle
//!   counter that survives resets, USART0 in both directions (bytes time-stamped in cycles),
//!   the twelve servo pins (Timer1/3/4/5 incl. port L) with pulse capture, SRAM, I/O registers
//!   and EEPROM access, reset detection, fault injection (a hung CPU), and a virtual MPU-6050
//!   on the TWI ([`Mega2560::attach_imu`], fed by a [`SharedImuSource`]).
//! - [`elf`]: section sizes and symbol addresses of an ELF (flash, static SRAM, the stack
//!   paint's start).
//!
//! The link to the firmware over its UART, with line timing and faults, is
//! [`crate::link::emulator`].

pub mod build;
pub mod elf;
// The only unsafe code of this crate: simavr's C API.
#[allow(unsafe_code)]
mod simavr;

pub use simavr::{
    EmuError, ImuBus, InterruptsOff, Mega2560, Pulse, Resets, SharedImuSource, EEPROM_LEN,
};

/// CPU clock of the Mega 2560, Hz.
pub const F_CPU_HZ: u32 = 16_000_000;

/// CPU cycles per microsecond.
pub const CYCLES_PER_US: u64 = 16;

/// CPU cycles per servo timer tick (prescaler 8: 0.5 µs).
pub const CYCLES_PER_TICK: u64 = 8;

/// Servo period, timer ticks (20 ms).
pub const PERIOD_TICKS: u64 = 40_000;

/// Servo period, CPU cycles.
pub const PERIOD_CYCLES: u64 = PERIOD_TICKS * CYCLES_PER_TICK;

/// The twelve servo outputs in channel order (`3·leg + joint`, legs FL, FR, RL, RR; joints
/// abduction, hip, knee): port letter and bit (OC1A/B/C = PB5-7, OC3A/B/C = PE3-5,
/// OC4A/B/C = PH3-5, OC5A/B/C = PL3-5). See `firmware-avr/src/servo.rs` and
/// `docs/hardware.md`.
pub const SERVO_PINS: [(char, u8); 12] = [
    ('B', 5),
    ('B', 6),
    ('B', 7),
    ('E', 3),
    ('E', 4),
    ('E', 5),
    ('H', 3),
    ('H', 4),
    ('H', 5),
    ('L', 3),
    ('L', 4),
    ('L', 5),
];

/// The benchmark firmware's marker pin (PA0, Mega header D22).
pub const MARKER_PIN: (char, u8) = ('A', 0);

/// Converts CPU cycles to a duration.
pub fn cycles_to_duration(cycles: u64) -> std::time::Duration {
    // 62.5 ns per cycle.
    std::time::Duration::from_nanos(cycles * 125 / 2)
}

/// Converts a duration to CPU cycles (rounded down).
pub fn duration_to_cycles(d: std::time::Duration) -> u64 {
    (d.as_nanos() * 2 / 125) as u64
}

/// Converts a duration to CPU cycles, rounded up: waiting this many cycles lets at least `d`
/// pass (a caller that compares durations must not be left a fraction of a cycle short).
pub fn duration_to_cycles_ceil(d: std::time::Duration) -> u64 {
    (d.as_nanos() * 2).div_ceil(125) as u64
}
