//! The single-precision `__addsf3`, `__subsf3` and `__mulsf3` of every binary that invokes
//! [`link_avr_libc!`](crate::link_avr_libc): a fast path for the common case in front of
//! avr-libc's own routines, with avr-libc's bits for every input.
//!
//! avr-libc's `__addsf3` is `call __addsf3x; jmp __fp_round` (and `__mulsf3` the same with
//! `__mulsf3x`): unpacking by `__fp_split3`, the operation on a 32-bit mantissa, rounding by
//! `__fp_round`, each a call with its special-case tests. These versions do the common case
//! — both operands normal, the result normal — in registers, in one pass, rounded to nearest
//! even as `__fp_round` rounds; every other input jumps to avr-libc's path with the original
//! operands untouched (`call __addsf3x` or `call __mulsf3x`, then `jmp __fp_round`, exactly
//! avr-libc's wrappers), so zeros, subnormals, infinities, NaNs, overflow and underflow keep
//! avr-libc's results to the bit. Hand-written because these three are the firmware's
//! commonest calls (the kinematics' arithmetic) and the fast path is measured faster than
//! avr-libc's (see `docs/benchmark-journal.md`); the library keeps every special case. The
//! emulator test `avr_float` compares the bits with avr-libc's on seeded pairs of every kind.
//!
//! Which operands take the fast path (decided from the exponents alone, before any register
//! is changed, so that the fallback sees the arguments as passed):
//!
//! - addition and subtraction: both biased exponents in 25..=253, and the magnitudes not equal
//!   with different signs (an exact cancellation). Then the result can neither overflow (an
//!   exponent of at most 254 after the carry and the rounding) nor fall below the normal range
//!   (cancellation removes at most 24 bits). Also one operand ±0 and the other normal (with
//!   an exponent in 25..=253 when it is A): the result is the other operand, exactly as
//!   avr-libc returns it;
//! - multiplication: both exponents in 1..=254 with a result exponent `eA + eB − 127` in
//!   1..=252, so the rounded result is normal.
//!
//! # Why these definitions are the linked ones
//!
//! [`link_avr_libc!`](crate::link_avr_libc) expands [`float_primitives!`](crate::float_primitives)
//! in the binary crate: the routines are then part of the binary's own object code, and the
//! linker takes a member from an archive (`libm.a`, compiler-builtins) only for a symbol still
//! undefined when it reaches it. No member of avr-libc's `addsf3.o` (`__addsf3`, `__subsf3`)
//! or `mulsf3.o` (`__mulsf3`) is therefore ever extracted — they define nothing else — while
//! `__addsf3x`, `__mulsf3x` and `__fp_round`, which the fallback calls, come from `libm.a` as
//! before. A binary without the macro (the soft-float baseline `bench-libm`) keeps
//! compiler-builtins' routines: these could not link there.
//!
//! # Registers
//!
//! The avr-gcc convention: A in r25:r22, B in r21:r18, the result in r25:r22; r0, r18–r27,
//! r30, r31 and the flags (T included) are clobbered, r1 is zero on return. avr-libc's
//! versions clobber the same set. The avr-libc members that call these routines (`atan2`,
//! `square`, `__fp_powsodd` in the benchmark firmware; the firmware links only `sqrt`, which
//! calls none of them) keep nothing in those registers across the calls (`__fp_powsodd`
//! pushes Z around its `__mulsf3`).

/// Defines `__addsf3`, `__subsf3` and `__mulsf3` (see the [module docs](crate::float)) in the
/// crate that invokes it; [`link_avr_libc!`](crate::link_avr_libc) does, once per binary.
/// Needs `#![feature(asm_experimental_arch)]` in that crate.
#[macro_export]
macro_rules! float_primitives {
    () => {
        ::core::arch::global_asm!(
            ".section .text.avr_libc_math.float,\"ax\",@progbits",
            ".global __subsf3",
            ".type __subsf3, @function",
            ".global __addsf3",
            ".type __addsf3, @function",
            ".global __mulsf3",
            ".type __mulsf3, @function",
            // avr-libc's path with the arguments as passed (its `__addsf3`).
            "9:",
            "clr r26",
            "clr r27",
            "call __addsf3x",
            "90:",
            "jmp __fp_round",
            // Equal magnitudes: A + A with the same signs; with different signs an exact
            // cancellation, left to avr-libc (+0).
            "8:",
            "mov r0, r25",
            "eor r0, r21",
            "brpl 3f",
            "rjmp 9b",
            // A outside 25..=253: A = ±0 with B normal gives B (avr-libc's result, as
            // `0 + B` is exact), anything else avr-libc's path.
            "20:",
            "cpi r31, 0xe7",
            "brne 9b",
            "or r30, r23",
            "or r30, r22",
            "brne 9b",
            "subi r27, 1",
            "cpi r27, 254",
            "brsh 9b",
            "movw r22, r18",
            "movw r24, r20",
            "ret",
            // B outside 25..=253 (A inside): B = ±0 gives A.
            "21:",
            "cpi r27, 0xe7",
            "brne 9b",
            "or r26, r19",
            "or r26, r18",
            "brne 9b",
            "ret",
            "__subsf3:",
            "subi r21, 0x80",
            "__addsf3:",
            // The biased exponents less 25 to r31 (A) and r27 (B); both must be in 0..=228.
            "movw r30, r24",
            "lsl r30",
            "rol r31",
            "movw r26, r20",
            "lsl r26",
            "rol r27",
            "subi r31, 25",
            "cpi r31, 229",
            "brsh 20b",
            "subi r27, 25",
            "cpi r27, 229",
            "brsh 21b",
            // t = eB − eA to r30; the larger magnitude to A (by the exponents, by the
            // mantissas when these are equal), t then −d with d = eA − eB ≥ 0, and A's
            // exponent to r31 (r27 is not needed any more). d = 0 and d > 0 part here.
            "mov r30, r27",
            "sub r30, r31",
            "brlo 1f",
            "brne 2f",
            "cp r22, r18",
            "cpc r23, r19",
            "cpc r24, r20",
            "breq 8b",
            "brsh 3f",
            // d = 0: the guard and sticky bytes stay zero, the sum (commutative) needs no
            // swap, the difference is taken the right way round (B − A into B's registers,
            // then moved, when B is the larger) and normalised as below (61:).
            "ori r24, 0x80",
            "ori r20, 0x80",
            "clr r26",
            "clr r27",
            "bst r21, 7",
            "eor r21, r25",
            "brpl 51f",
            "sub r18, r22",
            "sbc r19, r23",
            "sbc r20, r24",
            "movw r22, r18",
            "mov r24, r20",
            "rjmp 61f",
            "3:",
            "ori r24, 0x80",
            "ori r20, 0x80",
            "clr r26",
            "clr r27",
            "bst r25, 7",
            "eor r21, r25",
            "brpl 51f",
            "sub r22, r18",
            "sbc r23, r19",
            "sbc r24, r20",
            "rjmp 61f",
            "2:",
            "mov r31, r27",
            "neg r30",
            $crate::swap_operands!(),
            // The result's sign (A's) to T; r21 bit 7: the signs differ (a subtraction).
            "1:",
            "bst r25, 7",
            "eor r21, r25",
            "ori r24, 0x80",
            "ori r20, 0x80",
            // B's mantissa shifted right by d into r20:r19:r18, the guard byte r27 (the
            // eight bits below), and r26, non-zero when any bit lower still is (sticky).
            "clr r26",
            "clr r27",
            "cpi r30, 254",
            "brsh 7f",
            // The shift by k = d mod 8 bits multiplies each byte by f = 2^(8 − k) (r25): the
            // high byte of the product goes to the byte's place, the low byte to the next
            // lower one. f = 2^(t mod 8), from the low bits of t.
            "ldi r25, 1",
            "sbrc r30, 1",
            "ldi r25, 4",
            "sbrc r30, 0",
            "lsl r25",
            "sbrc r30, 2",
            "swap r25",
            // d < 8: only the bits, from the lowest byte (the guard byte is zero); d ≥ 8
            // takes the bytes first (4:, out of line: the rarer case).
            "cpi r30, 249",
            "brlo 4f",
            "3:",
            "mul r18, r25",
            "or r27, r0",
            "mov r18, r1",
            "mul r19, r25",
            "or r18, r0",
            "mov r19, r1",
            "mul r20, r25",
            "or r19, r0",
            "mov r20, r1",
            "clr r1",
            "5:",
            "sbrc r21, 7",
            "rjmp 6f",
            // Same signs: the sum; a carry out shifts it right one place, the guard byte
            // joining the sticky one first (the rounding asks only whether any bit below the
            // guard bit is set, in either: its bits that stay in the guard byte may be there
            // twice, the one leaving it is kept).
            "51:",
            "add r22, r18",
            "adc r23, r19",
            "adc r24, r20",
            "brcc 10f",
            "or r26, r27",
            "ror r24",
            "ror r23",
            "ror r22",
            "ror r27",
            "inc r31",
            "rjmp 10f",
            // d ≥ 8: whole bytes first, what leaves the guard byte joining the sticky one
            // (d ≥ 32 as d = 32: all of B sticky), then the k bits, the guard byte's low
            // product to the sticky one.
            "4:",
            "cpi r30, 225",
            "brsh 2f",
            "ldi r30, 224",
            "2:",
            "or r26, r27",
            "mov r27, r18",
            "mov r18, r19",
            "mov r19, r20",
            "clr r20",
            "subi r30, 0xf8",
            "breq 5b",
            "cpi r30, 249",
            "brlo 2b",
            "mul r27, r25",
            "or r26, r0",
            "mov r27, r1",
            "rjmp 3b",
            // d = 1 or 2: shifted bit by bit, d = 1 (t odd) once.
            "7:",
            "lsr r20",
            "ror r19",
            "ror r18",
            "ror r27",
            "sbrc r30, 0",
            "rjmp 5b",
            "lsr r20",
            "ror r19",
            "ror r18",
            "ror r27",
            "rjmp 5b",
            // Different signs: A − B, the guard byte included, the sticky bits jammed into
            // its lowest bit first: the difference's bits above that one are then those of
            // the exact difference rounded down, and r26 ≠ 0 still stands for what lies
            // below. Then normalised (one place at most unless d ≤ 1, and never more than one
            // with sticky bits; the exponent stays at least 1 since eA ≥ 25): the first place
            // with the guard byte, further ones without it (d ≤ 1 leaves at most its top bit
            // set, shifted out by the first).
            "6:",
            "cpse r26, r1",
            "ori r27, 1",
            "neg r27",
            "sbc r22, r18",
            "sbc r23, r19",
            "sbc r24, r20",
            "61:",
            "brmi 10f",
            "subi r31, 1",
            "lsl r27",
            "rol r22",
            "rol r23",
            "rol r24",
            "brmi 10f",
            "12:",
            "subi r31, 1",
            "lsl r22",
            "rol r23",
            "rol r24",
            "brpl 12b",
            // Pack (exponent r31 + 25 over the mantissa without its leading one, the sign
            // from T), then round to nearest even on the packed bits as `__fp_round` does: up
            // when the guard bit is set and a lower bit is, or the result is odd; a carry
            // out of the mantissa increments the exponent.
            "10:",
            "subi r31, 0xe7",
            "lsl r24",
            "lsr r31",
            "ror r24",
            "mov r25, r31",
            "bld r25, 7",
            "sbrs r27, 7",
            "ret",
            "lsl r27",
            "or r27, r26",
            "brne 14f",
            "sbrs r22, 0",
            "ret",
            "14:",
            "subi r22, 0xff",
            "sbci r23, 0xff",
            "sbci r24, 0xff",
            "sbci r25, 0xff",
            "ret",
            ".size __addsf3, . - __addsf3",
            ".size __subsf3, . - __subsf3",
            // avr-libc's path with the arguments as passed (its `__mulsf3`).
            "19:",
            "call __mulsf3x",
            "rjmp 90b",
            "__mulsf3:",
            // The biased exponents less 1 to r31 (A) and r27 (B), both in 0..=253, and their
            // sum s = eA + eB − 2 in 126..=377 (the result's exponent eA + eB − 127 or one
            // more, in 1..=253 before the rounding and at most 254 after it).
            "movw r30, r24",
            "lsl r30",
            "rol r31",
            "subi r31, 1",
            "cpi r31, 254",
            "brsh 19b",
            "movw r26, r20",
            "lsl r26",
            "rol r27",
            "subi r27, 1",
            "cpi r27, 254",
            "brsh 19b",
            "add r31, r27",
            "brcc 1f",
            "cpi r31, 122",
            "brsh 19b",
            "rjmp 2f",
            "1:",
            "cpi r31, 126",
            "brlo 19b",
            // The sign to T, the exponent eA + eB − 126 = s − 124 (a product in [2^47, 2^48))
            // to r25, the mantissas with their leading ones, a zero in r21.
            "2:",
            "eor r25, r21",
            "bst r25, 7",
            "mov r25, r31",
            "subi r25, 124",
            "ori r24, 0x80",
            "ori r20, 0x80",
            "clr r21",
            // The 48-bit product p of r24:r23:r22 (a2 a1 a0) and r20:r19:r18 (b2 b1 b0),
            // bytes p5..p0. a0·b0 and a1·b1 do not overlap: moved to p1:p0 (r27:r26) and
            // p3:p2 (r31:r30). a1·b0 and a0·b1 then complete the product of the low halves,
            // which fits in p3..p0: no carry leaves p3. p1 and p0 stay as they are, needed
            // only as sticky bits by the rounding. The other products are added from the low
            // place up, p4 (r18, once b0 is used up) and p5 (r19, once b1 is) starting as the
            // first carry into them; the last carry into p4 and the one into p5 fit
            // (p < 2^48).
            "mul r22, r18",
            "movw r26, r0",
            "mul r23, r19",
            "movw r30, r0",
            "mul r23, r18",
            "add r27, r0",
            "adc r30, r1",
            "adc r31, r21",
            "mul r22, r19",
            "add r27, r0",
            "adc r30, r1",
            "adc r31, r21",
            "mul r24, r18",
            "add r30, r0",
            "adc r31, r1",
            "clr r18",
            "rol r18",
            "mul r22, r20",
            "add r30, r0",
            "adc r31, r1",
            "adc r18, r21",
            "mul r24, r19",
            "add r31, r0",
            "adc r18, r1",
            "clr r19",
            "rol r19",
            "mul r23, r20",
            "add r31, r0",
            "adc r18, r1",
            "adc r19, r21",
            "mul r24, r20",
            "add r18, r0",
            "adc r19, r1",
            "clr r1",
            // A product in [2^46, 2^47): one place left, exponent − 1. The mantissa to
            // r24:r23:r22, the guard byte stays r30 (p1's top bit remains a sticky one).
            "sbrc r19, 7",
            "rjmp 4f",
            "lsl r30",
            "rol r31",
            "rol r18",
            "rol r19",
            "dec r25",
            "4:",
            "mov r24, r19",
            "mov r23, r18",
            "mov r22, r31",
            // Pack and round as for the sum, the sticky bits p1 | p0 only when the guard
            // bit is set.
            "lsl r24",
            "lsr r25",
            "ror r24",
            "bld r25, 7",
            "sbrs r30, 7",
            "ret",
            "lsl r30",
            "or r30, r26",
            "or r30, r27",
            "brne 14f",
            "sbrs r22, 0",
            "ret",
            "14:",
            "subi r22, 0xff",
            "sbci r23, 0xff",
            "sbci r24, 0xff",
            "sbci r25, 0xff",
            "ret",
            ".size __mulsf3, . - __mulsf3",
        );
    };
}
