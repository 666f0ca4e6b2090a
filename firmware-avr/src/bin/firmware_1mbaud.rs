//! The firmware at 1,000,000 baud (exact at 16 MHz; the Mega's USB-serial bridge supports it).
//! Everything is in [`firmware_avr::app`].

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]
// `link_avr_libc!` defines the float primitives with `global_asm!`.
#![feature(asm_experimental_arch)]

avr_libc_math::link_avr_libc!();

use firmware_avr::usart::Baud;

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::app::run(Baud::B1000000)
}

firmware_avr::forward_interrupts!();
