//! Cycle benchmark of the straightforward build: kin-core's `Libm` backend (Rust libm) on
//! compiler-builtins' soft-float, without avr-libc (see `firmware_avr::bench`). Backend 2 only.

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

use firmware_avr::bench::{self, Backend, Prepared};
use firmware_avr::usart::{self, Baud, Usart0};
use kin_core::math::Libm;
use kin_core::Math;

/// Primitives (compiler-builtins and Rust libm): 0 add, 1 mul, 2 div, 3 sqrt, 4 atan2.
static PRIMS: [bench::PrimFn; 5] = [
    |a, b| a + b,
    |a, b| a * b,
    |a, b| a / b,
    |a, _| Libm::sqrt(a),
    |a, b| Libm::atan2(a, b),
];

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::stack::paint();
    let dp = firmware_avr::pac::Peripherals::take().unwrap();
    let mut usart = Usart0::new(dp.USART0, Baud::B1000000);
    // SAFETY: the handler is defined below and touches only its own state.
    unsafe { avr_device::interrupt::enable() };
    // The solver built at boot, as the firmware builds its own.
    let robot = core::hint::black_box(bench::ROBOT);
    let backends = [Backend {
        id: 2,
        solve: &Prepared::<Libm>::new(&robot),
    }];
    bench::serve(
        &mut usart,
        &dp.PORTA,
        &backends,
        &PRIMS,
        &mut bench::NoMotion,
    )
}

#[avr_device::interrupt(atmega2560)]
fn USART0_RX() {
    usart::on_rx_interrupt();
}
