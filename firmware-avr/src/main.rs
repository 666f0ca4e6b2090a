//! The firmware: hardware bring-up and the main loop. The device's behaviour is plugged in at
//! the marked place; until the device controller exists, `interim` answers a minimal binary
//! command set so that the outputs can be tested for real.

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

mod interim;

avr_libc_math::link_avr_libc!();

use firmware_avr::clock::{self, Clock};
use firmware_avr::servo::Servos;
use firmware_avr::usart::{self, Baud, Usart0};
use firmware_avr::watchdog::{self, Timeout, Watchdog};

/// Line rate of USART0.
const BAUD: Baud = Baud::B115200;

/// Watchdog timeout: far above the longest main-loop iteration (one body-pose solve, < 5 ms).
const WATCHDOG_TIMEOUT: Timeout = Timeout::Ms250;

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::stack::paint();
    let dp = firmware_avr::pac::Peripherals::take().unwrap();
    let reset_cause = watchdog::take_reset_cause(&dp.CPU);
    let mut watchdog = Watchdog::enable(dp.WDT, WATCHDOG_TIMEOUT);
    let mut servos = Servos::new(
        dp.TC1, dp.TC3, dp.TC4, dp.TC5, dp.PORTB, dp.PORTE, dp.PORTH, dp.PORTL,
    );
    let clock = Clock::new(dp.TC2);
    let mut usart = Usart0::new(dp.USART0, BAUD);
    // SAFETY: the handlers are defined below and touch only their own state.
    unsafe { avr_device::interrupt::enable() };

    // --- device behaviour: replace `interim` by the device controller here ---
    let mut app = interim::Interim::new(reset_cause);
    loop {
        watchdog.feed();
        app.poll(&mut usart, &mut servos, &clock);
    }
}

#[avr_device::interrupt(atmega2560)]
fn USART0_RX() {
    usart::on_rx_interrupt();
}

#[avr_device::interrupt(atmega2560)]
fn TIMER2_COMPA() {
    clock::on_tick_interrupt();
}
