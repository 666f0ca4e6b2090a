//! # quad-device — the quadruped's device controller, `no_std`, no allocation
//!
//! Everything the ATmega2560 does, independent of the target, so that the firmware is a thin
//! shell (registers, interrupts, main loop) and the host can run the very same code in its
//! UART simulator:
//!
//! ```text
//! bytes ─▶ Accumulator ─▶ HostToDevice ─▶ kin-core IK / joint limits ─▶ servo calibration
//!                                                       │                      │
//!                         DeviceToHost (Ack + Readback, or Nack) ◀─ 12 outputs ◀┘
//! ```
//!
//! - [`Device`]: the controller ([`Device::receive`] for bytes, [`Device::poll`] for the
//!   link-loss failsafe and the 50 Hz servo frames, [`Device::handle`] at message level,
//!   [`Device::start_motion`] and its siblings for the motion engine). Its documentation lists
//!   the behaviour and invariants.
//! - [`balance`]: the inertial sensor's readings → attitude, body leveling, fall detection,
//!   the start check ([`Device::on_imu`]).
//! - [`engine`]: the motion engine (stand-up, sit, the papers' motions, the walk) and the one
//!   joint-speed limiter every output passes.
//! - [`hal`]: the traits a target implements — [`ServoOutputs`] (twelve pulse widths in 0.5 µs
//!   timer ticks, enable/disable), [`Clock`] (monotonic ms) and [`Storage`] (EEPROM-like bytes).
//!   The kin-core [`kin_core::Math`] backend is a type parameter: the firmware passes its
//!   avr-libc backend, the host [`kin_core::DefaultMath`].
//! - [`config`]: the robot preset, pose interpretation and failsafe at power-on, and the default
//!   servo calibration.
//! - [`store`]: the calibration table and (protocol 2.4) the robot in storage, each in two banks
//!   with a generation counter and a CRC.
//! - `sim` (feature `sim`, needs `alloc`): in-memory servo outputs, clock and EEPROM, the one set
//!   of fakes the host's simulated link, the twin and the tests use.
//!
//! ## Firmware sketch
//!
//! What `firmware-avr`'s `app::run` does, in short: the controller is built stopped where it
//! will live (no second copy on the stack), then booted there, and the main loop hands it the
//! bytes the USART's receive interrupt queued.
//!
//! ```text
//! let mut device = Device::<_, _, _, AvrFast>::stopped(Config::shahriar2023(), servos, clock, eeprom)?;
//! device.boot();                                      // calibration from EEPROM, stance held
//! loop {
//!     let n = usart.read_into(&mut chunk);            // bytes queued by the USART RX interrupt
//!     device.receive(&chunk[..n], |piece| usart.send(piece)); // answers, in pieces as they are final
//!     device.poll();                                  // link-loss failsafe, motion frame
//! }
//! ```
//!
//! ## Memory
//! A [`Device`] holds one receive buffer ([`device::RX_LEN`] bytes plus the accumulator's
//! state; the answer frame, at most [`device::TX_LEN`] bytes, is encoded there once the request
//! is decoded), the calibration table, the held target and the output angles and pulses, the
//! configuration with the robot, the motion [`engine`] (the running motion's parameters and
//! state, one ramp, the limiter) and a few flags. Saving or loading the calibration streams one record at a time. Its
//! size on the ATmega2560 is in `docs/benchmark-journal.md`, the firmware's flash and SRAM in
//! `BENCHMARKS.md`; `cargo xtask ci budget` checks them against the budget.

#![no_std]
#![forbid(unsafe_code)]

#[cfg(feature = "sim")]
extern crate alloc;

pub mod balance;
pub mod config;
pub mod device;
pub mod engine;
pub mod hal;
pub mod imu;
#[cfg(feature = "sim")]
pub mod sim;
pub mod store;

pub use config::{default_calibration, Config, ConfigError, ValidConfig};
pub use device::Device;
pub use hal::{Clock, ServoOutputs, Storage};
pub use imu::{ImuFault, ImuReading, ImuSample};
