//! [`kin_core::Math`] on avr-libc's hand-written assembly float routines.
//!
//! On AVR, C `double` is 32 bits, so avr-libc's `double atan2(double, double)` is
//! `fn(f32, f32) -> f32`.
//!
//! **Every binary that uses this crate must invoke [`link_avr_libc!`]** once at its top level.
//! It expands to `#[link(name = "m")] extern "C" {}` *in the binary crate*: rustc passes a
//! binary's own native libraries before the upstream crates, so `-lm` then precedes Rust's
//! compiler-builtins on the linker command line. Besides the functions named here, the float
//! primitives `__divsf3`, the comparisons, the conversions, … of the whole program then come
//! from avr-libc (faster than compiler-builtins' soft-float, and smaller; the per-primitive
//! cycles are in `docs/benchmark-journal.md`), and `__addsf3`, `__subsf3`, `__mulsf3` from
//! [`float`]: a fast path in the binary's own code in front of avr-libc's routines, and `sqrt`
//! from [`mod@sqrt`]: avr-libc's bits in fewer cycles (the binary needs
//! `#![feature(asm_experimental_arch)]` for them). The `#[link(name = "m")]` attribute in
//! this library crate would put `-lm` *after* compiler-builtins, and then the
//! `extern "C" fn atan2` below silently binds to compiler-builtins' weak 64-bit `atan2` —
//! wrong values and a large soft-double implementation. Check the linked ELF with
//! `avr-nm firmware.elf | grep -E ' (atan2|sqrt|sin|cos)$'`: each must be `T`, not `W` (the
//! emulator tests do).
//!
//! The baseline benchmark (`bench-libm`) neither uses this crate nor links `libm.a`, and so
//! measures the plain Rust soft-float build.

#![no_std]
#![cfg(target_arch = "avr")]
// `asm!` on the AVR (the `lpm` of `read_table_cell`, the kernels `atan2_fixed` and
// `sin_cos_fixed`).
#![feature(asm_experimental_arch)]

/// The AVR assembly that swaps the two float operands, r25:r24:r23:r22 and r21:r20:r19:r18,
/// through r27:r26 (six `movw`): one text for the `asm!` templates of the kernels that order
/// their operands by magnitude (the arctangent, the sine/cosine, the float addition). The
/// `asm!` block must declare r27:r26 clobbered or hold nothing there. Exported (hidden) for
/// [`float_primitives!`], which expands in the binaries.
#[doc(hidden)]
#[macro_export]
macro_rules! swap_operands {
    () => {
        "movw r26, r22\nmovw r22, r18\nmovw r18, r26\nmovw r26, r24\nmovw r24, r20\nmovw r20, r26"
    };
}

pub mod float;
pub mod sqrt;

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
        // IK moves its results through memory; the saving is in `docs/benchmark-journal.md`).
        #[link(name = "c")]
        extern "C" {}
        // The fast `__addsf3`, `__subsf3`, `__mulsf3` in front of avr-libc's (see `float`):
        // defined here, in the binary's own code, they are the ones linked.
        $crate::float_primitives!();
        // `sqrt` with avr-libc's bits, faster (see `sqrt`): defined here, `libm.a`'s
        // `sqrt.o` is never extracted.
        $crate::sqrt_primitive!();
    };
}

// Resolved by avr-libc's libm.a, which the binary links through `link_avr_libc!` (`sqrt` by
// the binary's own definition from `sqrt_primitive!`, avr-libc's results to the bit).
extern "C" {
    fn sqrt(x: f32) -> f32;
    fn atan2(y: f32, x: f32) -> f32;
    fn sin(x: f32) -> f32;
    fn cos(x: f32) -> f32;
}

/// avr-libc's `sqrt` (its bits, from [`mod@sqrt`]: correctly rounded), `atan2`, `sin` and
/// `cos` (within 2 ulp of the correctly rounded result for the arguments the kinematics
/// passes).
#[derive(Debug, Clone, Copy, Default)]
pub struct AvrLibm;

impl Math for AvrLibm {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        // SAFETY: a pure function of its argument, without preconditions (`mod@sqrt`).
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

    /// [`poly::atan2_fixed`] in assembly (the crate's `atan2_fixed`): the same bits, in fewer
    /// cycles (see `docs/benchmark-journal.md`).
    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        atan2_fixed(y, x)
    }

    /// [`poly::sin_cos_fixed`] with its fixed-point part in assembly (the crate's
    /// `sin_cos_fixed`): the same bits, in fewer cycles (see `docs/benchmark-journal.md`).
    #[inline]
    fn sin_cos_fixed(x: f32) -> (f32, f32) {
        sin_cos_fixed(x)
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

/// [`poly::atan2_fixed`] in AVR assembly, bit for bit (the emulator test `avr_atan2` checks
/// [`AvrLibm::atan2_fixed`] against the portable kernel on the AVR):
///
/// - the octant and the magnitudes `num ≤ den` from the bits;
/// - the quotient `T = ⌊t·2²¹⌋` ([`poly::atan_ratio_q21`]) of the 24-bit mantissas on the
///   hardware multiplier, exact: a reciprocal estimate of the denominator (a linear seed and
///   one Newton step, never above the reciprocal), then the `22 − (e_d − eₙ)` quotient bits
///   `T` keeps as base-256 digits (one to three, the first aligned so that the shift of the
///   quotient comes free; a subnormal denominator's quotient in up to six, the leading ones
///   0), each estimated from the remainder's top bytes and the reciprocal,
///   subtracted from the remainder, and made exact by at most two corrections;
/// - the cell `k = T >> 16` read with `lpm` ([`poly::atan_cells`]) and its three
///   16 × 16-bit products with `mul`, each rounded as the portable kernel rounds it;
/// - the octant's angle in Q29, its conversion to a float (normalised bytewise then bitwise,
///   rounded to nearest even) and the sign of `y`.
///
/// Hand-written because LLVM's AVR backend has no such division (`u64` or `u32` division is
/// a library call for a wide quotient with no early stop; the float division the kernel had
/// rounds, which an integer form could not match cheaply), spends twice the instructions on
/// the products' byte moves, and calls a library routine for the conversion.
///
/// Never inlined: one copy in flash for all callers.
#[inline(never)]
fn atan2_fixed(y: f32, x: f32) -> f32 {
    let (yb, xb) = (y.to_bits(), x.to_bits());
    // In 16-bit pairs: byte operands' results cost LLVM a dozen moves to join.
    let (mut lo, mut hi) = (yb as u16, (yb >> 16) as u16);
    // SAFETY: register arithmetic, and `lpm` reads of the cell `k ≤ 32` of kin-core's table in
    // `.progmem.data` (below 64 KB, `lpm`'s reach, as for `lpm_word`). r1, the zero register,
    // is read as zero before the first `mul` and cleared after the last.
    unsafe {
        asm!(
            // q0, q1 are r26, r27 and p0, p1 are r14, r15 (register pairs for `movw`).
            // The octant in o: bit 2 the sign of y, bit 1 the sign of x, bit 0 |y| > |x|
            // (swapped, through q1:q0); n3:n2:n1:n0 = num = min(|y|, |x|), e3:e2:e1:e0 = den =
            // the other.
            "clr {o}",
            "bst r25, 7",
            "bld {o}, 2",
            "bst r21, 7",
            "bld {o}, 1",
            "lsl r25",
            "lsr r25",
            "lsl r21",
            "lsr r21",
            "cp r18, r22",
            "cpc r19, r23",
            "cpc r20, r24",
            "cpc r21, r25",
            "brsh 5f",
            "inc {o}",
            swap_operands!(),
            "5:",
            // den = 0 (num = 0 too): p = 0.
            "cp r18, r1",
            "cpc r19, r1",
            "cpc r20, r1",
            "cpc r21, r1",
            "brne 5f",
            "rjmp 8f",
            "5:",
            // Exponents to n3, e3 (the sign bits are clear), mantissas with their implicit
            // one (none for a subnormal, exponent 0) to n2:n1:n0, e2:e1:e0.
            "lsl r20",
            "rol r21",
            "cp r1, r21",
            "ror r20",
            "lsl r24",
            "rol r25",
            "cp r1, r25",
            "ror r24",
            "clr r26",
            "clr r27",
            "clr {q2}",
            "cpi r21, 255",
            "brne 5f",
            // den infinite (or NaN): T = 2²¹ when num is too, else 0.
            "cpi r25, 255",
            "brne 4f",
            "ldi {q2}, 0x20",
            "4:",
            "rjmp 6f",
            "5:",
            // Subnormals at exponent 1; s = ed − en, T = 0 (so p = 0) when s ≥ 22.
            "cpi r21, 1",
            "adc r21, r1",
            "cpi r25, 1",
            "adc r25, r1",
            "sub r21, r25",
            "cpi r21, 22",
            "brlo 5f",
            "rjmp 8f",
            "5:",
            // T = ⌊mn·2^t / md⌋, t = 21 − s, in base-256 digits: t = 8·j + a, the first digit
            // ⌊mn·2^a / md⌋ (a + 1 bits), then j digits of 8 bits; t in cnt, a in r21.
            "ldi {cnt}, 21",
            "sub {cnt}, r21",
            // den subnormal (md < 2²³; then num is too, s = 0 and mn ≤ md): md shifted left
            // until its bit 23 is set, t one more each time (the same T, in more digits whose
            // leading ones are 0).
            "rjmp 2f",
            "1:",
            "lsl r18",
            "rol r19",
            "rol r20",
            "inc {cnt}",
            "2:",
            "sbrs r20, 7",
            "rjmp 1b",
            "mov r21, {cnt}",
            "andi r21, 7",
            // The remainder R = mn·2^a to r25:r24:r23:r22: R < 2⁸·md (mn < 2·md, a ≤ 7; s = 0:
            // mn ≤ md), so the first digit is < 2⁸ too.
            "clr r25",
            "rjmp 2f",
            "1:",
            "lsl r22",
            "rol r23",
            "rol r24",
            "rol r25",
            "2:",
            "subi r21, 1",
            "brcc 1b",
            // w ≈ 2³⁹/md in p1:p0 (< 2¹⁶), never above it, at most 2⁻⁷·⁸ below it
            // (relative): one Newton step w = y·(2 − y·md/2³¹)·2⁸ from the linear seed
            // y = 103 − ⌊239·d2/2⁸⌋ ≈ 2³¹/md (relative error ≤ 6.5 %; d2 = md's top byte,
            // ≥ 128), y in q2, q0 = 0 as the zero. Both bounds checked for every md (w depends
            // on md >> 8 only): the digits below rely on `w ≤ 2³⁹/md`.
            "ldi {q2}, 239",
            "mul r20, {q2}",
            "ldi {q2}, 103",
            "sub {q2}, r1",
            // P = ⌊md/2⁸⌋·y, P >> 8 plus one to r1:p2 (the one makes up for md's low byte: with
            // the Newton step's own deficit, it keeps w from above 2³⁹/md).
            "mul r19, {q2}",
            "mov {p2}, r1",
            "mul r20, {q2}",
            "sec",
            "adc {p2}, r0",
            "adc r1, r26",
            // z = 2¹⁶ − 1 − r1:p2 ≈ 2¹⁵·(2 − y·md/2³¹) to p1:p2 (positive: 2¹⁵ ± 7 %).
            "com {p2}",
            "com r1",
            "mov r15, r1",
            // w = ⌊y·z / 2⁷⌋ (y·z < 2²³), the low byte of y·z's low product dropped.
            "mul {q2}, {p2}",
            "mov r14, r1",
            "mul {q2}, r15",
            "add r0, r14",
            "adc r1, r26",
            "movw r14, r0",
            "lsl r14",
            "rol r15",
            // One digit a pass, r21 the zero: the estimate q̂ = ⌊(R3:R2 · w) / 2²³⌋ from three
            // products (the low ones dropped) into q0 after the digits move up a byte; q̂ is
            // never above the digit ⌊R/md⌋ (w ≤ 2³⁹/md, every part truncated) and at most 2
            // below it (256·2⁻⁷·⁸ + the dropped parts < 2).
            "clr r21",
            "1:",
            "mov {q2}, r27",
            "mov r27, r26",
            "mul r25, r15",
            "mov {p2}, r0",
            "mov r26, r1",
            "mul r25, r14",
            "add {p2}, r1",
            "adc r26, r21",
            "mul r24, r15",
            "add {p2}, r1",
            "adc r26, r21",
            "lsl {p2}",
            "rol r26",
            // R −= q̂·md (R ≥ 0 stays, < 3·md).
            "mul r26, r18",
            "sub r22, r0",
            "sbc r23, r1",
            "sbc r24, r21",
            "sbc r25, r21",
            "mul r26, r19",
            "sub r23, r0",
            "sbc r24, r1",
            "sbc r25, r21",
            "mul r26, r20",
            "sub r24, r0",
            "sbc r25, r1",
            // The exact digit: while R ≥ md, R −= md and q̂ += 1 (at most twice).
            "2:",
            "cp r22, r18",
            "cpc r23, r19",
            "cpc r24, r20",
            "cpc r25, r21",
            "brcs 3f",
            "sub r22, r18",
            "sbc r23, r19",
            "sbc r24, r20",
            "sbc r25, r21",
            "inc r26",
            "rjmp 2b",
            // R < md: R·2⁸ for the next digit, while t − 8·(digits done) ≥ 0.
            "3:",
            "mov r25, r24",
            "mov r24, r23",
            "mov r23, r22",
            "clr r22",
            "subi {cnt}, 8",
            "brcc 1b",
            "clr r1",
            // The cell k = q2 ≤ 32: Z += 8·k (9 bits), a to p3:p2:p1:p0, b to e1:e0, c to
            // e3:e2; d = q1:q0.
            "6:",
            "lsl {q2}",
            "lsl {q2}",
            "lsl {q2}",
            "adc r31, r1",
            "add r30, {q2}",
            "adc r31, r1",
            "lpm r14, Z+",
            "lpm r15, Z+",
            "lpm {p2}, Z+",
            "lpm {p3}, Z+",
            "lpm r18, Z+",
            "lpm r19, Z+",
            "lpm r20, Z+",
            "lpm r21, Z+",
            "clr {cnt}",
            // d·b to n3:n2:n1:n0; p += (d·b + 2⁶) >> 7 in five bytes: cell 0's b is above
            // 2¹⁵ (32,774), so for d ≥ 65,526 (t just below 2⁻⁵) d·b reaches 2³¹ and its
            // bit 31 is bit 24 of the sum (a four-byte shift lost it: p 2⁻⁵ low).
            "mul r26, r18",
            "movw r22, r0",
            "mul r27, r19",
            "movw r24, r0",
            "mul r26, r19",
            "add r23, r0",
            "adc r24, r1",
            "adc r25, {cnt}",
            "mul r27, r18",
            "add r23, r0",
            "adc r24, r1",
            "adc r25, {cnt}",
            "ldi {q2}, 0x40",
            "add r22, {q2}",
            "adc r23, {cnt}",
            "adc r24, {cnt}",
            "adc r25, {cnt}",
            "clr {q2}",
            "lsl r22",
            "rol r23",
            "rol r24",
            "rol r25",
            "rol {q2}",
            "add r14, r23",
            "adc r15, r24",
            "adc {p2}, r25",
            "adc {p3}, {q2}",
            // d² >> 16 to n3:n2.
            "mul r26, r26",
            "mov r23, r1",
            "mul r27, r27",
            "movw r24, r0",
            "mul r26, r27",
            "add r23, r0",
            "adc r24, r1",
            "adc r25, {cnt}",
            "add r23, r0",
            "adc r24, r1",
            "adc r25, {cnt}",
            // d²·c to e1:e0:q1:q0; p −= (d²·c + 2¹²) >> 13, from q2:e1:e0 after three
            // left shifts of q2:e1:e0:q1 (d²·c < 2³¹).
            "mul r24, r20",
            "movw r26, r0",
            "mul r25, r21",
            "movw r18, r0",
            "mul r24, r21",
            "add r27, r0",
            "adc r18, r1",
            "adc r19, {cnt}",
            "mul r25, r20",
            "add r27, r0",
            "adc r18, r1",
            "adc r19, {cnt}",
            "clr r1",
            "ldi {q2}, 0x10",
            "add r27, {q2}",
            "adc r18, r1",
            "adc r19, r1",
            "clr {q2}",
            "lsl r27",
            "rol r18",
            "rol r19",
            "rol {q2}",
            "lsl r27",
            "rol r18",
            "rol r19",
            "rol {q2}",
            "lsl r27",
            "rol r18",
            "rol r19",
            "rol {q2}",
            "sub r14, r18",
            "sbc r15, r19",
            "sbc {p2}, {q2}",
            "sbc {p3}, r1",
            "rjmp 20f",
            // T = 0 or den = 0: p = 0 (cell 0's a and the rounded products of d = 0 are 0).
            "8:",
            "clr r14",
            "clr r15",
            "clr {p2}",
            "clr {p3}",
            // The octant's angle r to p3:p2:p1:p0: p (octant 0), π − p (2), π/2 − p (1),
            // π/2 + p (3), the constants in Q29 (round(π·2²⁹) = 0x6487ed51).
            "20:",
            "sbrc {o}, 0",
            "rjmp 22f",
            "sbrs {o}, 1",
            "rjmp 24f",
            "ldi r25, 0x51",
            "ldi r21, 0xed",
            "ldi {q2}, 0x87",
            "ldi {cnt}, 0x64",
            "rjmp 23f",
            "22:",
            "ldi r25, 0xa9",
            "ldi r21, 0xf6",
            "ldi {q2}, 0x43",
            "ldi {cnt}, 0x32",
            "sbrs {o}, 1",
            "rjmp 23f",
            "add r14, r25",
            "adc r15, r21",
            "adc {p2}, {q2}",
            "adc {p3}, {cnt}",
            "rjmp 30f",
            "23:",
            "sub r25, r14",
            "sbc r21, r15",
            "sbc {q2}, {p2}",
            "sbc {cnt}, {p3}",
            "mov r14, r25",
            "mov r15, r21",
            "mov {p2}, {q2}",
            "mov {p3}, {cnt}",
            "rjmp 30f",
            // Octant 0: r = p, 0 when p is (the float +0).
            "24:",
            "mov r22, r14",
            "or r22, r15",
            "or r22, {p2}",
            "or r22, {p3}",
            "brne 30f",
            "clr {q2}",
            "rjmp 9f",
            // r > 0 (r < 2³¹) as a float times 2⁻²⁹: the biased exponent 129 less the shifts
            // that bring r's leading one to bit 31, in q2.
            "30:",
            "ldi {q2}, 129",
            "31:",
            "tst {p3}",
            "brne 32f",
            "mov {p3}, {p2}",
            "mov {p2}, r15",
            "mov r15, r14",
            "clr r14",
            "subi {q2}, 8",
            "rjmp 31b",
            "32:",
            "sbrc {p3}, 7",
            "rjmp 33f",
            "lsl r14",
            "rol r15",
            "rol {p2}",
            "rol {p3}",
            "dec {q2}",
            "rjmp 32b",
            // The mantissa p3:p2:p1, rounded by p0 to nearest even; a carry out of it makes
            // the mantissa 2²³ of the next exponent.
            "33:",
            "lsl r14",
            "brcc 34f",
            "brne 35f",
            "sbrs r15, 0",
            "rjmp 34f",
            "35:",
            "sec",
            "adc r15, r1",
            "adc {p2}, r1",
            "adc {p3}, r1",
            "brcc 34f",
            "ror {p3}",
            "inc {q2}",
            // Pack: exponent q2 over the mantissa without its leading one.
            "34:",
            "lsl {p3}",
            "lsr {q2}",
            "ror {p3}",
            // The result to r25:r22 (where the calling convention returns it), with the
            // sign of y.
            "9:",
            "mov r22, r15",
            "mov r23, {p2}",
            "mov r24, {p3}",
            "mov r25, {q2}",
            "bst {o}, 2",
            "bld r25, 7",
            // The arguments and the result where the calling convention has them.
            inout("r23r22") lo,
            inout("r25r24") hi,
            inout("r19r18") xb as u16 => _,
            inout("r21r20") (xb >> 16) as u16 => _,
            // q0, q1.
            out("r26") _,
            out("r27") _,
            q2 = out(reg_upper) _,
            cnt = out(reg_upper) _,
            // p0, p1.
            out("r14") _,
            out("r15") _,
            p2 = out(reg) _,
            p3 = out(reg) _,
            o = out(reg) _,
            inout("Z") poly::atan_cells().addr() => _,
            options(pure, readonly, nostack),
        );
    }
    f32::from_bits((hi as u32) << 16 | lo as u32)
}

/// [`poly::sin_cos_fixed`] with its fixed-point part [`poly::sin_cos_fixed_core`] in AVR
/// assembly, bit for bit (the emulator test `avr_sin_cos` checks [`AvrLibm::sin_cos_fixed`]
/// against the portable kernel on the AVR); the range reduction beyond ±π/4 (software
/// floats) and the quadrant stay the portable kernel's ([`poly::sin_cos_fixed_with`]).
///
/// Never inlined: one copy in flash for all callers.
#[inline(never)]
fn sin_cos_fixed(x: f32) -> (f32, f32) {
    poly::sin_cos_fixed_with(x, |rb| {
        let bits = sin_cos_fixed_core(rb);
        ((bits >> 32) as u32, bits as u32)
    })
}

/// `d·b` of [`sin_cos_fixed_core`]'s cell into `r26:r27:{t2}:{t3}` (low to high), from the
/// next two table bytes at `Z` (`b`) and `d` in `{dh}:{dl}`: four 8 × 8-bit products
/// (`{zero}` as in that block). The same lines for the sine and the cosine.
macro_rules! linear_product {
    () => {
        concat!(
            "lpm {bl}, Z+\n",
            "lpm {bh}, Z+\n",
            "mul {dl}, {bl}\n",
            "mov r26, r0\n",
            "mov r27, r1\n",
            "mul {dh}, {bh}\n",
            "mov {t2}, r0\n",
            "mov {t3}, r1\n",
            "mul {dl}, {bh}\n",
            "add r27, r0\n",
            "adc {t2}, r1\n",
            "adc {t3}, {zero}\n",
            "mul {dh}, {bl}\n",
            "add r27, r0\n",
            "adc {t2}, r1\n",
            "adc {t3}, {zero}\n",
        )
    };
}

/// `(d²·c + 2¹²) >> 13` of [`sin_cos_fixed_core`]'s cell into `{t2}:{t3}:{bl}` (low to high),
/// from the next two table bytes at `Z` (`c`) and `d²` in `{qh}:{ql}`: bytes 1 to 3 of `d²·c`
/// (< 2³¹) with the 2¹², three left shifts (`{zero}` and `{e}` as in that block). The same
/// lines for the sine and the cosine.
macro_rules! quad_term {
    () => {
        concat!(
            "lpm {bl}, Z+\n",
            "lpm {bh}, Z+\n",
            "mul {ql}, {bl}\n",
            "mov r27, r1\n",
            "mul {qh}, {bh}\n",
            "mov {t2}, r0\n",
            "mov {t3}, r1\n",
            "mul {ql}, {bh}\n",
            "add r27, r0\n",
            "adc {t2}, r1\n",
            "adc {t3}, {zero}\n",
            "mul {qh}, {bl}\n",
            "add r27, r0\n",
            "adc {t2}, r1\n",
            "adc {t3}, {zero}\n",
            "ldi {e}, 0x10\n",
            "add r27, {e}\n",
            "adc {t2}, {zero}\n",
            "adc {t3}, {zero}\n",
            "clr {bl}\n",
            "lsl r27\n",
            "rol {t2}\n",
            "rol {t3}\n",
            "rol {bl}\n",
            "lsl r27\n",
            "rol {t2}\n",
            "rol {t3}\n",
            "rol {bl}\n",
            "lsl r27\n",
            "rol {t2}\n",
            "rol {t3}\n",
            "rol {bl}\n",
        )
    };
}

/// [`poly::sin_cos_fixed_core`] in AVR assembly: the bits of `(sin r, cos r)` from those of
/// `r`:
///
/// - `|r|·2²⁴` from the mantissa, shifted bytewise then bitwise, clamped to the cells' end;
/// - the cell `k` read with `lpm` ([`poly::sin_cos_cells`]), its five 16 × 16-bit products
///   with `mul`, each rounded as the portable kernel rounds it;
/// - the sine and the cosine in Q29 to floats (normalised bytewise then bitwise, rounded to
///   nearest even), one loop for both, and the sign of `r` on the sine.
///
/// Hand-written because LLVM's AVR backend turns the mantissa's variable shift into a loop of
/// 32-bit shifts, spends twice the instructions on the products' byte moves, and calls a
/// library routine for each conversion.
///
/// Never inlined: one copy for the two paths of [`poly::sin_cos_fixed_with`]. The bits of the
/// sine above those of the cosine, in one `u64`: the C calling convention returns it in
/// r25:r18, where the assembly leaves them (the Rust one returns it through memory).
#[inline(never)]
extern "C" fn sin_cos_fixed_core(rb: u32) -> u64 {
    // In 16-bit pairs: byte operands' results cost LLVM a dozen moves to join.
    let (mut lo, mut hi) = (rb as u16, (rb >> 16) as u16);
    let (cos_lo, cos_hi): (u16, u16);
    // SAFETY: register arithmetic, and `lpm` reads of the cell `k ≤ 25` of kin-core's table in
    // `.progmem.data` (below 64 KB, `lpm`'s reach, as for `lpm_word`). r1, the zero register,
    // is cleared after the last `mul`.
    unsafe {
        asm!(
            // The sign of r in T; the biased exponent e to r25, the mantissa with its implicit
            // one to r24:r23:r22 (a subnormal's is then wrong, but shifted out: e = 0).
            "bst r25, 7",
            "lsl r24",
            "rol r25",
            "sec",
            "ror r24",
            // R = m >> (126 − e): the cells' end for e > 126, 0 for a shift beyond 23.
            "cpi r25, 127",
            "brsh 2f",
            "ldi {e}, 126",
            "sub {e}, r25",
            "cpi {e}, 24",
            "brsh 3f",
            "sbrs {e}, 4",
            "rjmp 4f",
            "mov r22, r24",
            "clr r23",
            "clr r24",
            "4:",
            "sbrs {e}, 3",
            "rjmp 5f",
            "mov r22, r23",
            "mov r23, r24",
            "clr r24",
            "5:",
            "andi {e}, 7",
            "breq 6f",
            "7:",
            "lsr r24",
            "ror r23",
            "ror r22",
            "dec {e}",
            "brne 7b",
            // min(R, 26·2¹⁹ − 1).
            "6:",
            "cpi r24, 0xd0",
            "brlo 8f",
            "2:",
            "ldi r24, 0xcf",
            "ldi r23, 0xff",
            "ldi r22, 0xff",
            "rjmp 8f",
            "3:",
            "clr r22",
            "clr r23",
            "clr r24",
            // R >> 3: the cell k = R >> 19 in r24, d (Q21) in dh:dl; Z += 16·k.
            "8:",
            "lsr r24",
            "ror r23",
            "ror r22",
            "lsr r24",
            "ror r23",
            "ror r22",
            "lsr r24",
            "ror r23",
            "ror r22",
            "mov {dl}, r22",
            "mov {dh}, r23",
            "ldi {e}, 16",
            "mul r24, {e}",
            "add r30, r0",
            "adc r31, r1",
            "clr {zero}",
            // d² >> 16 (Q26) to qh:ql.
            "mul {dl}, {dl}",
            "mov r27, r1",
            "mul {dh}, {dh}",
            "mov {ql}, r0",
            "mov {qh}, r1",
            "mul {dl}, {dh}",
            "add r27, r0",
            "adc {ql}, r1",
            "adc {qh}, {zero}",
            "add r27, r0",
            "adc {ql}, r1",
            "adc {qh}, {zero}",
            // Sine: a to r25:r22; += (d·b + 2⁶) >> 7 (d·b may reach 2³¹: five bytes).
            "lpm r22, Z+",
            "lpm r23, Z+",
            "lpm r24, Z+",
            "lpm r25, Z+",
            linear_product!(),
            "ldi {e}, 0x40",
            "add r26, {e}",
            "adc r27, {zero}",
            "adc {t2}, {zero}",
            "adc {t3}, {zero}",
            "clr {bl}",
            "lsl r26",
            "rol r27",
            "rol {t2}",
            "rol {t3}",
            "rol {bl}",
            "add r22, r27",
            "adc r23, {t2}",
            "adc r24, {t3}",
            "adc r25, {bl}",
            // −= (d²·c + 2¹²) >> 13: bytes 1 to 3 of d²·c (< 2³¹) and the 2¹², three left
            // shifts, bytes 2 to 4.
            quad_term!(),
            "sub r22, {t2}",
            "sbc r23, {t3}",
            "sbc r24, {bl}",
            "sbc r25, {zero}",
            // Cosine: a to r21:r18; −= (d·b + 2⁷) >> 8 (d·b + 2⁷ < 2³²).
            "lpm r18, Z+",
            "lpm r19, Z+",
            "lpm r20, Z+",
            "lpm r21, Z+",
            linear_product!(),
            "ldi {e}, 0x80",
            "add r26, {e}",
            "adc r27, {zero}",
            "adc {t2}, {zero}",
            "adc {t3}, {zero}",
            "sub r18, r27",
            "sbc r19, {t2}",
            "sbc r20, {t3}",
            "sbc r21, {zero}",
            // −= (d²·c + 2¹²) >> 13, as for the sine.
            quad_term!(),
            "sub r18, {t2}",
            "sbc r19, {t3}",
            "sbc r20, {bl}",
            "sbc r21, {zero}",
            "clr r1",
            // Twice: the value v in r25:r22 (v < 2³¹) to the bits of v·2⁻²⁹ (0 stays +0),
            // then swapped with r21:r18 (the sine first, then the cosine: each ends where
            // it started).
            "ldi {e}, 2",
            "mov {dh}, {e}",
            "10:",
            "mov r26, r22",
            "or r26, r23",
            "or r26, r24",
            "or r26, r25",
            "brne 11f",
            "clr {e}",
            "rjmp 19f",
            // The biased exponent 129 less the shifts that bring v's leading one to bit 31.
            "11:",
            "ldi {e}, 129",
            "12:",
            "tst r25",
            "brne 13f",
            "mov r25, r24",
            "mov r24, r23",
            "mov r23, r22",
            "clr r22",
            "subi {e}, 8",
            "rjmp 12b",
            "13:",
            "sbrc r25, 7",
            "rjmp 14f",
            "lsl r22",
            "rol r23",
            "rol r24",
            "rol r25",
            "dec {e}",
            "rjmp 13b",
            // The mantissa r25:r23, rounded by r22 to nearest even; a carry out of it makes
            // the mantissa 2²³ of the next exponent.
            "14:",
            "lsl r22",
            "brcc 16f",
            "brne 15f",
            "sbrs r23, 0",
            "rjmp 16f",
            "15:",
            "sec",
            "adc r23, r1",
            "adc r24, r1",
            "adc r25, r1",
            "brcc 16f",
            "ror r25",
            "inc {e}",
            // Pack: exponent e over the mantissa without its leading one.
            "16:",
            "lsl r25",
            "lsr {e}",
            "ror r25",
            "19:",
            "mov r22, r23",
            "mov r23, r24",
            "mov r24, r25",
            "mov r25, {e}",
            swap_operands!(),
            "dec {dh}",
            "brne 10b",
            // The sign of r on the sine.
            "bld r25, 7",
            inout("r23r22") lo,
            inout("r25r24") hi,
            out("r19r18") cos_lo,
            out("r21r20") cos_hi,
            out("r27r26") _,
            dl = out(reg) _,
            dh = out(reg) _,
            ql = out(reg) _,
            qh = out(reg) _,
            t2 = out(reg) _,
            t3 = out(reg) _,
            bl = out(reg) _,
            bh = out(reg) _,
            zero = out(reg) _,
            e = out(reg_upper) _,
            inout("Z") poly::sin_cos_cells().addr() => _,
            options(pure, readonly, nostack),
        );
    }
    (hi as u64) << 48 | (lo as u64) << 32 | (cos_hi as u64) << 16 | cos_lo as u64
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
/// [`AvrLibm`]'s `sqrt` (avr-libc's bits) and its reads of the kernels' tables from flash,
/// with all float arithmetic on avr-libc's primitives. The fastest mix
/// measured in simavr (see `docs/benchmark-journal.md`).
///
/// Against the host's [`kin_core::DefaultMath`] the angles of a leg or body solve differ by
/// at most about 4e-6 rad (the fixed-point arctangent's error plus rounding); see the readback
/// bound in `docs/benchmark-journal.md`.
pub type AvrFast = SoftFloat<AvrLibm>;
