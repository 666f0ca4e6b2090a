//! # firmware-avr — the hardware shell of the quadruped's ATmega2560 (Arduino Mega 2560)
//!
//! Everything that touches registers lives here; the device's behaviour (decode → IK →
//! calibration → outputs) lives in the portable crate `quad-device`, which [`app`] runs.
//!
//! | module | what |
//! |---|---|
//! | [`app`] | bring-up and main loop around the device controller (`quad_device::Device`) |
//! | [`servo`] | 12 servo outputs on the output-compare units of Timer1/3/4/5 (50 Hz, 0.5 µs ticks), applied between pulses without waiting, `embedded_hal::pwm::SetDutyCycle` per channel, `quad_device::ServoOutputs` |
//! | [`clock`] | millisecond clock on Timer2 (`quad_device::Clock`) |
//! | [`eeprom`] | the EEPROM as calibration storage (`quad_device::Storage`) |
//! | [`mem`] | `memcpy` and `memset`, four bytes per loop step |
//! | [`usart`] | USART0: receive and transmit by interrupt through lock-free rings |
//! | [`twi`] | the TWI (I²C) master at 400 kHz by interrupt, bus recovery |
//! | [`imu`] | the MPU-6050 driver: probe, configuration, periodic bursts into `Device::on_imu`, typed faults |
//! | [`watchdog`] | watchdog enable/feed and the reset cause |
//! | [`stack`] | SRAM painting at boot and the high-water mark of the stack |
//! | [`mod@bench`] | the cycle benchmark's request loop (used by the `bench` binaries only) |
//!
//! The CPU clock is [`F_CPU_HZ`] (the Mega's 16 MHz crystal).
//!
//! Binaries: `firmware` (115,200 baud) and `firmware-1mbaud` (1,000,000 baud) run [`app::run`];
//! `bench` and `bench-libm` serve the cycle benchmark ([`mod@bench`]).
//!
//! Interrupt handlers must be defined in the binary crate (a handler in a library is not
//! pulled in by the linker): each binary forwards `USART0_RX` to [`usart::on_rx_interrupt`],
//! `USART0_UDRE` to [`usart::on_udre_interrupt`] (the firmware binaries; the benchmark
//! transmits by polling), `TIMER2_COMPA` to [`clock::on_tick_interrupt`], `TWI` to [`twi::on_interrupt`] and
//! `EE_READY` to [`eeprom::on_ready_interrupt`] (the firmware binaries through [`forward_interrupts!`]).

#![no_std]
#![feature(asm_experimental_arch)]
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs)]

pub mod app;
pub mod bench;
pub mod clock;
pub mod eeprom;
pub mod harness;
pub mod imu;
pub mod mem;
pub mod servo;
pub mod stack;
pub mod twi;
pub mod usart;
pub mod watchdog;

pub use avr_device::atmega2560 as pac;

/// CPU clock frequency, Hz.
pub const F_CPU_HZ: u32 = 16_000_000;

/// Puts every output into its safe state and waits for the watchdog: all servo compare
/// outputs disconnected (pins low), interrupts off. No `core::fmt`: its formatting machinery
/// would take kilobytes of flash and SRAM for a message nobody reads on the board.
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    avr_device::interrupt::disable();
    // SAFETY: interrupts are off and this function never returns, so no other code can hold
    // the timer peripherals while they are stolen here.
    let dp = unsafe { pac::Peripherals::steal() };
    servo::force_all_low(&dp);
    loop {
        // Not feeding the watchdog: it resets the MCU (when enabled).
        core::hint::spin_loop();
    }
}
