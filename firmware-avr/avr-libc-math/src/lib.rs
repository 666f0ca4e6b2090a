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
// `asm!` on the AVR (the `lpm` of `read_table_cell`, the arctangent's division).
#![feature(asm_experimental_arch)]

use core::arch::asm;
use kin_core::math::{poly, SoftFloat, TableEntry};
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

    // kin-core links its fixed-point kernels' tables into flash on the AVR
    // (`kin_core::math::TABLES_IN_PROGRAM_MEMORY`), so that avr-gcc's startup does not copy
    // them into SRAM; `lpm` reads them there. Written here rather than with the `avr-progmem`
    // crate: its reads go byte by byte through a buffer in memory (a store and a load per
    // byte, and stack space in the kernels, which keep small frames for the reason given on
    // `poly::atan2_fixed`), where a cell is a run of `lpm Rd, Z+` straight into the registers
    // the kernel computes with; and it has had no release for the toolchains since 2023.

    /// [`poly::atan2_fixed`] with its quotient divided in assembly ([`ratio_q21`]): the same
    /// bits, in fewer cycles (see `BENCHMARKS.md`).
    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        poly::atan2_fixed_with::<Self>(y, x, ratio_q21)
    }

    #[inline(always)]
    fn read_table_cell<const N: usize>(entry: TableEntry<[u16; N]>) -> [u16; N] {
        const { assert!(N <= 8, "kin-core's cells are at most 8 words") };
        let mut z = entry.addr().cast::<u8>();
        let mut cell = [0u16; N];
        // Straight-line code, one read per word (each `N > i` is a constant): a loop, which
        // opt-level "s" does not unroll, would keep the cell in memory.
        for_each_word!(i in 0 1 2 3 4 5 6 7 => {
            if N > i {
                cell[i] = lpm_word(&mut z);
            }
        });
        cell
    }
}

/// [`poly::atan_ratio_q21`] in AVR assembly, bit for bit (the emulator test `avr_atan2` checks
/// [`AvrLibm::atan2_fixed`] against the portable kernel): `T = ⌊t·2²¹⌋` of the magnitudes'
/// bits `num ≤ den`, `den ≠ 0`. A restoring division of the 24-bit mantissas that stops after
/// the `22 − (e_d − eₙ)` quotient bits `T` keeps (the shift of the quotient comes free), one
/// compare-and-subtract per bit in three-byte registers. Hand-written because LLVM's AVR
/// backend has no such division: `u64` or `u32` division is a library call for a 64- or
/// 32-bit quotient with no early stop, and the float division it replaced rounds.
#[inline(always)]
fn ratio_q21(num: u32, den: u32) -> u32 {
    let [mut n0, mut n1, mut n2, mut n3] = num.to_le_bytes();
    let [d0, d1, mut d2, mut d3] = den.to_le_bytes();
    let (q0, q1, q2): (u8, u8, u8);
    // SAFETY: register arithmetic only (r1 is read as the zero register, never written).
    unsafe {
        asm!(
            // Exponents to n3, d3 (the sign bits are clear), mantissas with their implicit
            // one (none for a subnormal, exponent 0) to n2:n1:n0, d2:d1:d0.
            "lsl {d2}",
            "rol {d3}",
            "cp r1, {d3}",
            "ror {d2}",
            "lsl {n2}",
            "rol {n3}",
            "cp r1, {n3}",
            "ror {n2}",
            "cpi {d3}, 255",
            "breq 7f",
            // Subnormals at exponent 1; s = ed − en, T = 0 when s ≥ 22.
            "cpi {d3}, 1",
            "adc {d3}, r1",
            "cpi {n3}, 1",
            "adc {n3}, r1",
            "sub {d3}, {n3}",
            "cpi {d3}, 22",
            "brsh 8f",
            "ldi {cnt}, 22",
            "sub {cnt}, {d3}",
            // The quotient's bits go in inverted (the carry of a compare that fails is 1), into
            // ones that end as the leading zeros.
            "ldi {q2}, 0xff",
            "mov {q0}, {q2}",
            "mov {q1}, {q2}",
            // The first bit: mn ≥ md (mn < 2·md), no shift.
            "rjmp 2f",
            "1:",
            "lsl {n0}",
            "rol {n1}",
            "rol {n2}",
            // Remainder ≥ 2²⁴ > md: subtract (the borrow of the low 24 bits is then set).
            "brcs 3f",
            "2:",
            "cp {n0}, {d0}",
            "cpc {n1}, {d1}",
            "cpc {n2}, {d2}",
            "brcs 4f",
            "3:",
            "sub {n0}, {d0}",
            "sbc {n1}, {d1}",
            "sbc {n2}, {d2}",
            "clc",
            "4:",
            "rol {q0}",
            "rol {q1}",
            "rol {q2}",
            "dec {cnt}",
            "brne 1b",
            "com {q0}",
            "com {q1}",
            "com {q2}",
            "rjmp 9f",
            // den infinite (or NaN): T = 2²¹ when num is too, else 0.
            "7:",
            "clr {q0}",
            "clr {q1}",
            "ldi {q2}, 0",
            "cpi {n3}, 255",
            "brne 9f",
            "ldi {q2}, 0x20",
            "rjmp 9f",
            "8:",
            "clr {q0}",
            "clr {q1}",
            "clr {q2}",
            "9:",
            n0 = inout(reg) n0,
            n1 = inout(reg) n1,
            n2 = inout(reg) n2,
            n3 = inout(reg_upper) n3,
            d0 = in(reg) d0,
            d1 = in(reg) d1,
            d2 = inout(reg) d2,
            d3 = inout(reg_upper) d3,
            q0 = out(reg) q0,
            q1 = out(reg) q1,
            q2 = out(reg_upper) q2,
            cnt = out(reg_upper) _,
            options(pure, nomem, nostack),
        );
    }
    let _ = (n0, n1, n2, n3, d2, d3);
    u32::from_le_bytes([q0, q1, q2, 0])
}

/// Repeats `$body` with `$i` bound to each listed index in turn.
macro_rules! for_each_word {
    ($i:ident in $($n:literal)+ => $body:block) => {
        $({
            let $i: usize = $n;
            $body
        })+
    };
}
use for_each_word;

/// The 16-bit word at `*z` in flash (little-endian), advancing `z` past it.
#[inline(always)]
fn lpm_word(z: &mut *const u8) -> u16 {
    let (lo, hi): (u8, u8);
    // SAFETY: `z` walks a cell of a kin-core table in `.progmem.data` (`read_table_cell`), which
    // the avr6 linker script places at the start of flash, below 64 KB (`lpm`'s reach; a table
    // beyond it would fail to link, its address truncated). `lpm` only reads flash.
    unsafe {
        asm!(
            "lpm {lo}, Z+",
            "lpm {hi}, Z+",
            lo = out(reg) lo,
            hi = out(reg) hi,
            inout("Z") *z,
            options(pure, readonly, nostack, preserves_flags),
        );
    }
    u16::from_le_bytes([lo, hi])
}

/// The firmware's backend: kin-core's [`SoftFloat`] (the kernels, comparisons and leg staging
/// for CPUs without floating-point hardware; the host tests run the same choices) over
/// avr-libc's `sqrt` and [`AvrLibm`]'s reads of the kernels' tables from flash, with all float
/// arithmetic on avr-libc's primitives. The fastest mix
/// measured in simavr (see `BENCHMARKS.md`).
///
/// Against the host's [`kin_core::DefaultMath`] the angles of a leg or body solve differ by
/// at most about 4e-6 rad (the fixed-point arctangent's error plus rounding); see the readback
/// bound in `BENCHMARKS.md`.
pub type AvrFast = SoftFloat<AvrLibm>;
