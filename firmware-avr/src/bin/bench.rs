//! Cycle benchmark on avr-libc's float routines (see `firmware_avr::bench`).
//!
//! Backends: 0 = `AvrLibm` (avr-libc math), 1 = kin-core `Fast` (polynomials), 2 = kin-core
//! `Libm` (Rust libm), all on avr-libc's float primitives (`__mulsf3`, …).

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

use avr_libc_math::AvrLibm;

avr_libc_math::link_avr_libc!();
use firmware_avr::bench::{self, Backend};
use firmware_avr::usart::{self, Baud, Usart0};
use kin_core::math::{Fast, Libm};

static BACKENDS: [Backend; 3] = [
    Backend {
        id: 0,
        leg: bench::leg_with::<AvrLibm>,
        body: bench::body_with::<AvrLibm>,
    },
    Backend {
        id: 1,
        leg: bench::leg_with::<Fast>,
        body: bench::body_with::<Fast>,
    },
    Backend {
        id: 2,
        leg: bench::leg_with::<Libm>,
        body: bench::body_with::<Libm>,
    },
];

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::stack::paint();
    let dp = firmware_avr::pac::Peripherals::take().unwrap();
    let mut usart = Usart0::new(dp.USART0, Baud::B1000000);
    // SAFETY: the handlers are defined below and touch only their own state.
    unsafe { avr_device::interrupt::enable() };
    bench::serve(&mut usart, &dp.PORTA, &BACKENDS)
}

#[avr_device::interrupt(atmega2560)]
fn USART0_RX() {
    usart::on_rx_interrupt();
}
