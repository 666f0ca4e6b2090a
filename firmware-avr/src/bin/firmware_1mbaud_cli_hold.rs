//! **Test only, defective on purpose**: the 1,000,000-baud firmware whose receive path keeps
//! interrupts off for [`HOLD_CYCLES`] cycles (3 byte times at 1 Mbaud) on every pass of the
//! main loop, longer than the chip's two-byte receive buffer covers. The emulator tests run it
//! to show that the emulated USART loses bytes as the chip would and counts them. Never flash
//! it. Everything else is [`firmware_avr::app`].

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]
// `link_avr_libc!` defines the float primitives with `global_asm!`.
#![feature(asm_experimental_arch)]

avr_libc_math::link_avr_libc!();

use firmware_avr::usart::Baud;

/// Cycles with interrupts off after each read of the receive ring (one byte is 160 cycles at
/// 1 Mbaud).
const HOLD_CYCLES: u32 = 480;

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::app::run_with_receive_hold(Baud::B1000000, HOLD_CYCLES)
}

firmware_avr::forward_interrupts!();
