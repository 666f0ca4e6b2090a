//! The test harness firmware (see `firmware_avr::harness`): the firmware's kernels beside their
//! references, and the firmware's IK (`AvrFast`, the solver built once as the device builds
//! it), over batches in SRAM.

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]
// `link_avr_libc!` and `avr_libc_references!` define routines with `global_asm!`.
#![feature(asm_experimental_arch)]

use avr_libc_math::{AvrFast, AvrLibm};

avr_libc_math::link_avr_libc!();
firmware_avr::avr_libc_references!();

use firmware_avr::harness::{self, KernelFn};
use firmware_avr::usart::{self, Baud, Usart0};
use kin_core::math::poly;
use kin_core::{body, Math};

/// The kernels, by id: 0 `AvrLibm::atan2_fixed` (the firmware's arctangent, asm) and 1
/// `poly::atan2_fixed` (the portable kernel on the AVR); 2 `AvrLibm::sin_cos_fixed` (the
/// firmware's sine and cosine, asm part) and 3 `poly::sin_cos_fixed` (portable); the
/// firmware's float primitives beside avr-libc's own in one record, `(firmware, avr-libc)`:
/// 4 add, 5 sub, 6 mul, 7 `sqrt`.
static KERNELS: [KernelFn; 8] = [
    |a, b| {
        let r = AvrLibm::atan2_fixed(f32::from_bits(a), f32::from_bits(b));
        (r.to_bits(), 0)
    },
    |a, b| {
        let r = poly::atan2_fixed::<AvrFast>(f32::from_bits(a), f32::from_bits(b));
        (r.to_bits(), 0)
    },
    |a, _| {
        let (s, c) = AvrLibm::sin_cos_fixed(f32::from_bits(a));
        (s.to_bits(), c.to_bits())
    },
    |a, _| {
        let (s, c) = poly::sin_cos_fixed::<AvrFast>(f32::from_bits(a));
        (s.to_bits(), c.to_bits())
    },
    |a, b| {
        let (a, b) = (f32::from_bits(a), f32::from_bits(b));
        // SAFETY: the shim follows the C calling convention.
        (f32::to_bits(a + b), unsafe { libc_addsf3(a, b) }.to_bits())
    },
    |a, b| {
        let (a, b) = (f32::from_bits(a), f32::from_bits(b));
        // SAFETY: as above.
        (f32::to_bits(a - b), unsafe { libc_subsf3(a, b) }.to_bits())
    },
    |a, b| {
        let (a, b) = (f32::from_bits(a), f32::from_bits(b));
        // SAFETY: as above.
        (f32::to_bits(a * b), unsafe { libc_mulsf3(a, b) }.to_bits())
    },
    |a, _| {
        let a = f32::from_bits(a);
        // SAFETY: a C function of one `double` (32-bit on the AVR), no preconditions.
        (
            AvrLibm::sqrt(a).to_bits(),
            unsafe { avr_libc_sqrt(a) }.to_bits(),
        )
    },
];

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::stack::paint();
    let dp = firmware_avr::pac::Peripherals::take().unwrap();
    let mut usart = Usart0::new(dp.USART0, Baud::B1000000);
    // SAFETY: the handler is defined below and touches only its own state.
    unsafe { avr_device::interrupt::enable() };
    let robot = core::hint::black_box(kin_core::Robot::shahriar2023());
    let solver = body::Solver::<AvrFast>::with_math(&robot);
    harness::serve(&mut usart, &KERNELS, &solver)
}

#[avr_device::interrupt(atmega2560)]
fn USART0_RX() {
    usart::on_rx_interrupt();
}
