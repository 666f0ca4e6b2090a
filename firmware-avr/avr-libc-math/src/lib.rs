//! [`kin_core::Math`] on avr-libc's hand-written assembly float routines.
//!
//! On AVR, C `double` is 32 bits, so avr-libc's `double atan2(double, double)` is
//! `fn(f32, f32) -> f32`.
//!
//! **Every binary that uses this crate must invoke [`link_avr_libc!`]** once at its top level.
//! It expands to `#[link(name = "m")] extern "C" {}` *in the binary crate*: rustc passes a
//! binary's own native libraries before the upstream crates, so `-lm` then precedes Rust's
//! compiler-builtins on the linker command line. Besides the functions named here, the float
//! primitives `__addsf3`, `__mulsf3`, `__divsf3`, … of the whole program then come from
//! avr-libc (faster than compiler-builtins' soft-float, and smaller; the per-primitive cycles
//! are in `BENCHMARKS.md`). The same attribute in this library crate puts `-lm` *after*
//! compiler-builtins, and then the `extern "C" fn atan2` below silently binds to
//! compiler-builtins' weak 64-bit `atan2` — wrong values and a large soft-double
//! implementation. Check the linked ELF with
//! `avr-nm firmware.elf | grep -E ' (atan2|sqrt|sin|cos)$'`: each must be `T`, not `W` (the
//! emulator tests do).
//!
//! The baseline benchmark (`bench-libm`) neither uses this crate nor links `libm.a`, and so
//! measures the plain Rust soft-float build.

#![no_std]
#![cfg(target_arch = "avr")]

use kin_core::math::SoftFloat;
use kin_core::Math;

/// Links avr-libc's `libm.a` (and `libc.a`, for its `memcpy`/`memset`) ahead of
/// compiler-builtins; invoke once in each binary that uses [`AvrLibm`] (see the crate docs).
#[macro_export]
macro_rules! link_avr_libc {
    () => {
        #[link(name = "m")]
        extern "C" {}
        // avr-libc's assembly `memcpy`/`memset` instead of compiler-builtins' byte loops (the
        // IK moves its results through memory; the saving is in `BENCHMARKS.md`).
        #[link(name = "c")]
        extern "C" {}
    };
}

// Resolved by avr-libc's libm.a, which the binary links through `link_avr_libc!`.
extern "C" {
    fn sqrt(x: f32) -> f32;
    fn atan2(y: f32, x: f32) -> f32;
    fn sin(x: f32) -> f32;
    fn cos(x: f32) -> f32;
}

/// avr-libc's `sqrt`, `atan2`, `sin` and `cos` (all within 2 ulp of the correctly rounded
/// result for the arguments the kinematics passes).
#[derive(Debug, Clone, Copy, Default)]
pub struct AvrLibm;

impl Math for AvrLibm {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        // SAFETY: a pure function of its argument; avr-libc's `sqrt` has no preconditions.
        unsafe { sqrt(x) }
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        // SAFETY: a pure function of its arguments; `atan2(0, 0)` returns 0 in avr-libc.
        unsafe { atan2(y, x) }
    }

    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        // SAFETY: pure functions of their argument.
        unsafe { (sin(x), cos(x)) }
    }
}

/// The firmware's backend: kin-core's [`SoftFloat`] (the kernels, comparisons and leg staging
/// for CPUs without floating-point hardware; the host tests run the same choices) over
/// avr-libc's `sqrt`, with all float arithmetic on avr-libc's primitives. The fastest mix
/// measured in simavr (see `BENCHMARKS.md`).
///
/// Against the host's [`kin_core::DefaultMath`] the angles of a leg or body solve differ by
/// at most about 4e-6 rad (the fixed-point arctangent's error plus rounding); see the readback
/// bound in `BENCHMARKS.md`.
pub type AvrFast = SoftFloat<AvrLibm>;
