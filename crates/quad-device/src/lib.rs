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
//!   link-loss failsafe, [`Device::handle`] at message level). Its documentation lists the
//!   behaviour and invariants.
//! - [`hal`]: the traits a target implements — [`ServoOutputs`] (twelve pulse widths in 0.5 µs
//!   timer ticks, enable/disable), [`Clock`] (monotonic ms) and [`Storage`] (EEPROM-like bytes).
//!   The kin-core [`kin_core::Math`] backend is a type parameter: the firmware passes its
//!   avr-libc backend, the host [`kin_core::DefaultMath`].
//! - [`config`]: the robot preset, pose interpretation and failsafe at power-on, and the default
//!   servo calibration.
//! - [`store`]: the calibration table in storage, two banks with a generation counter and a CRC.
//!
//! ## Firmware sketch
//!
//! ```text
//! let mut device = Device::<_, _, _, AvrLibcMath>::new(Config::fernando2025(), pwm, millis, eeprom)?;
//! loop {
//!     while let Some(chunk) = rx_ring.take() {        // bytes queued by the USART RX interrupt
//!         device.receive(chunk, |frame| usart_write_all(frame));
//!     }
//!     device.poll();
//! }
//! ```
//!
//! ## Memory
//! A [`Device`] holds one receive buffer ([`device::RX_LEN`] = 128 B + 13 B of accumulator
//! state), one transmit buffer ([`device::TX_LEN`] = 131 B), the calibration table (12 × 15 B),
//! the held angles and pulses (73 B), the configuration with the robot (66 B) and a few flags:
//! 608 B on the ATmega2560 (alignment 1; a compile-time assertion in AVR builds keeps it
//! ≤ 640 B). Saving or loading the calibration streams 15-byte records.

#![no_std]
#![forbid(unsafe_code)]

pub mod config;
pub mod device;
pub mod hal;
pub mod store;

pub use config::{default_calibration, Config, ConfigError};
pub use device::Device;
pub use hal::{Clock, ServoOutputs, Storage};

/// The size of a [`Device`] on the ATmega2560 (alignment 1, 16-bit `usize`), checked when
/// building for AVR: the whole firmware has 8 KB of SRAM and a 2 KB budget for static data and
/// stack.
#[cfg(target_arch = "avr")]
mod avr_size {
    use super::*;

    struct Null;
    impl ServoOutputs for Null {
        fn set_pulses(&mut self, _: &[u16; 12]) {}
        fn set_enabled(&mut self, _: bool) {}
    }
    impl Clock for Null {
        fn now_ms(&self) -> u32 {
            0
        }
    }
    impl Storage for Null {
        type Error = ();
        fn read(&mut self, _: u16, _: &mut [u8]) -> Result<(), ()> {
            Ok(())
        }
        fn write(&mut self, _: u16, _: &[u8]) -> Result<(), ()> {
            Ok(())
        }
    }

    /// Upper bound of `size_of::<Device>()` on the ATmega2560, bytes.
    const DEVICE_SRAM_MAX: usize = 640;
    const _: () = assert!(core::mem::size_of::<Device<Null, Null, Null>>() <= DEVICE_SRAM_MAX);
}
