//! Cycle benchmark on avr-libc's float routines (see `firmware_avr::bench`).
//!
//! Backends: 0 = `AvrLibm` (avr-libc math), 1 = kin-core `Fast` (polynomials), 2 = kin-core
//! `Libm` (Rust libm), 3 = `AvrFast` (`sqrt` with avr-libc's bits, kin-core's `poly::atan2_fixed` in
//! `AvrLibm`'s assembly form and `poly::sin_cos_fixed` with its fixed-point part in
//! `AvrLibm`'s assembly), all on avr-libc's float primitives
//! (`__mulsf3`, …), each with its solver built once at boot ([`bench::Prepared`]); 4 = `AvrFast`
//! with its solver built in every call ([`bench::PerCall`]).

#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]
// `link_avr_libc!` defines the float primitives with `global_asm!`.
#![feature(asm_experimental_arch)]

use avr_libc_math::{AvrFast, AvrLibm};

avr_libc_math::link_avr_libc!();
use firmware_avr::bench::{self, Backend, PerCall, Prepared};
use firmware_avr::usart::{self, Baud, Usart0};
use kin_core::attitude::{Estimator, Gains};
use kin_core::math::{poly, Fast, Libm};
use kin_core::{BodyConfig, Math, Pose, RotationOrder};

/// Primitives: 0 add, 1 mul, 2 div, 3 sqrt, 4 atan2, 5 sin, 6 cos, 7 less-than,
/// 8 `Fast::atan2`, 9 `Fast::sin_cos` (sum of both); parts of the body IK on `AvrFast`:
/// 10 the rotation matrix (roll = yaw = a, pitch = b), 11 the four feet in their hip frames
/// (including the matrix); kin-core's kernels for `AvrFast`: 12 `poly::atan2_fixed` (the
/// portable form, which the firmware does not use),
/// 13 `poly::atan2_deg9`, 14 `poly::sin_cos_deg5`, 15 `poly::sin_cos_fixed` (sums of both);
/// 16 `AvrLibm::atan2_fixed` (the firmware's form of kernel 12, the same bits);
/// 17 `AvrLibm::sin_cos_fixed` (the firmware's form of kernel 15, the same bits; the sum of
/// both); 18 `poly::sin_cos_fixed` and 19 `AvrLibm::sin_cos_fixed` one result at a time (the
/// sine for `b = +0`, else the cosine), for the bit-for-bit comparison; 20 sub; avr-libc's
/// own path for the float primitives (`avr_libc_math::float` puts a fast path in front of
/// it), for the bit-for-bit comparison: 21 add, 22 sub, 23 mul; 24 avr-libc's own `sqrt`
/// (`avr_libc_math::sqrt` replaces it; 3 is the firmware's), for the same comparison; the
/// attitude estimator on `AvrFast` (`kin_core::attitude`), one 10 ms sample of a gyro rate
/// `(a, b, 0.01)` rad/s and a tilted specific force: 25 the update, 26 the update and the roll
/// and pitch.
static PRIMS: [bench::PrimFn; 27] = [
    |a, b| a + b,
    |a, b| a * b,
    |a, b| a / b,
    |a, _| AvrLibm::sqrt(a),
    |a, b| AvrLibm::atan2(a, b),
    |a, _| AvrLibm::sin_cos(a).0,
    |a, _| AvrLibm::sin_cos(a).1,
    |a, b| if a < b { 1.0 } else { 0.0 },
    |a, b| Fast::atan2(a, b),
    |a, _| {
        let (s, c) = Fast::sin_cos(a);
        s + c
    },
    |a, b| {
        let m = kin_core::rotation::matrix::<AvrFast>(RotationOrder::Zyx, a, b, a);
        core::hint::black_box(m).rows[0][0]
    },
    |a, b| {
        let robot = core::hint::black_box(bench::ROBOT);
        let feet = kin_core::body::Solver::<AvrFast>::with_math(&robot).feet_in_hips(
            &Pose::rotation(a, b, a),
            &BodyConfig::default(),
            &robot.stance_feet(bench::STANCE_HEIGHT_M),
        );
        core::hint::black_box(feet)[0].x
    },
    |a, b| poly::atan2_fixed::<AvrFast>(a, b),
    |a, b| poly::atan2_deg9(a, b),
    |a, _| {
        let (s, c) = poly::sin_cos_deg5(a);
        s + c
    },
    |a, _| {
        let (s, c) = poly::sin_cos_fixed::<AvrFast>(a);
        s + c
    },
    |a, b| AvrLibm::atan2_fixed(a, b),
    |a, _| {
        let (s, c) = AvrLibm::sin_cos_fixed(a);
        s + c
    },
    |a, b| {
        let (s, c) = poly::sin_cos_fixed::<AvrFast>(a);
        if b.to_bits() == 0 {
            s
        } else {
            c
        }
    },
    |a, b| {
        let (s, c) = AvrLibm::sin_cos_fixed(a);
        if b.to_bits() == 0 {
            s
        } else {
            c
        }
    },
    |a, b| a - b,
    // SAFETY (these three): the shims below follow the C calling convention.
    |a, b| unsafe { libc_addsf3(a, b) },
    |a, b| unsafe { libc_subsf3(a, b) },
    |a, b| unsafe { libc_mulsf3(a, b) },
    // SAFETY: a C function of one `double` (32-bit on the AVR), no preconditions.
    |a, _| unsafe { avr_libc_sqrt(a) },
    |a, b| {
        let mut e = core::hint::black_box(Estimator::<AvrFast>::new(Gains::DEFAULT));
        e.update([a, b, 0.01], [0.8, -0.6, 9.7], 0.01);
        core::hint::black_box(e).up()[0]
    },
    |a, b| {
        let mut e = core::hint::black_box(Estimator::<AvrFast>::new(Gains::DEFAULT));
        e.update([a, b, 0.01], [0.8, -0.6, 9.7], 0.01);
        core::hint::black_box(e).attitude().roll_rad
    },
];

// avr-libc's own float primitives and `sqrt` (`libc_addsf3`, …, `avr_libc_sqrt`): the
// references of the tests `avr_float` and `avr_sqrt`.
firmware_avr::avr_libc_references!();

#[avr_device::entry]
fn main() -> ! {
    firmware_avr::stack::paint();
    let dp = firmware_avr::pac::Peripherals::take().unwrap();
    let mut usart = Usart0::new(dp.USART0, Baud::B1000000);
    // SAFETY: the handlers are defined below and touch only their own state.
    unsafe { avr_device::interrupt::enable() };
    let mut motion = bench::EngineBench::<AvrFast>::new();
    // The solvers built at boot, as the firmware builds its own; the robot behind
    // `black_box`, so that their constants are read from memory as the device reads them.
    let robot = core::hint::black_box(bench::ROBOT);
    let backends = [
        Backend {
            id: 0,
            solve: &Prepared::<AvrLibm>::new(&robot),
        },
        Backend {
            id: 1,
            solve: &Prepared::<Fast>::new(&robot),
        },
        Backend {
            id: 2,
            solve: &Prepared::<Libm>::new(&robot),
        },
        Backend {
            id: 3,
            solve: &Prepared::<AvrFast>::new(&robot),
        },
        Backend {
            id: 4,
            solve: &PerCall::<AvrFast>::new(bench::ROBOT),
        },
    ];
    bench::serve(&mut usart, &dp.PORTA, &backends, &PRIMS, &mut motion)
}

#[avr_device::interrupt(atmega2560)]
fn USART0_RX() {
    usart::on_rx_interrupt();
}
