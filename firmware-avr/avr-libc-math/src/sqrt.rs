//! The single-precision `sqrt` of every binary that invokes
//! [`link_avr_libc!`](crate::link_avr_libc) (`double` is 32-bit on the AVR): avr-libc's
//! results to the bit, in fewer cycles for positive arguments.
//!
//! avr-libc's `sqrt` unpacks its argument with `__fp_splitA`, normalises subnormals with
//! `__fp_norm2`, then runs a restoring digit-by-digit root, one root bit per step, on 24-bit
//! registers throughout. This version takes positive normal arguments (the kinematics' sums of
//! squares) in registers, in one pass, with the same digit recurrence staged by width: the
//! trial subtrahend of the first 13 root bits has a zero low byte, so those steps compare,
//! subtract and update it on two bytes only. Positive subnormals are normalised and take the
//! same path. Every other argument — ±0, negative numbers, infinities, NaNs — runs avr-libc's
//! own opening sequence (`__fp_splitA`, then `__fp_mpack` or `__fp_nan`, as its `sqrt` does),
//! so those results stay avr-libc's to the bit. Hand-written because every leg and body solve
//! calls `sqrt` and this version is measured faster than avr-libc's (see
//! `docs/benchmark-journal.md`), which stays the reference. The emulator test `avr_sqrt`
//! compares the bits with avr-libc's `sqrt` (its `sqrt.o` linked under another name into the
//! benchmark firmware) and with the IEEE square root.
//!
//! # The recurrence
//!
//! With the mantissa `m` (hidden bit included, 24 bits) and the biased exponent `e`, the
//! radicand is `X = m'·2^23` with `m' = m` for odd `e`, `2m` for even `e`, so that the root
//! `Q = ⌊√X⌋` has 24 bits; the result's exponent is `(e + 127) / 2` (rounded down). Step `j`
//! (root bits from the top) keeps `S = 2U`, the partial remainder scaled to 25 bits (24 bits
//! and the carry), and the trial `T = P + 2^(22 − j)` where `P` holds the root bits found so
//! far in place: the root bit is `S ≥ T`; the next `S` is `2·(S − T)` when it is set, `2·S`
//! when not, and `T` moves on by adding `K = 2^(22 − j) + 2^(21 − j)` (bit set: the bit joins
//! `P`, the marker moves down) or to `T ^ K` (bit clear: the marker moves down). The square root
//! of a float is never a rounding midpoint (`(2Q + 1)²` is odd), so rounding to nearest is one
//! more root bit, without a sticky bit: rounded up when `√X ≥ Q + ½`, which the recurrence
//! decides with the same trial as its last bit.
//!
//! # Why this definition is the linked one
//!
//! [`link_avr_libc!`](crate::link_avr_libc) expands [`sqrt_primitive!`](crate::sqrt_primitive)
//! in the binary crate, so `sqrt` is defined by the binary's own code and the linker never
//! extracts `libm.a`'s `sqrt.o` (it defines `sqrt` and `sqrtf`, and the firmware references
//! neither elsewhere); its helpers `__fp_splitA`, `__fp_mpack` and `__fp_nan` come from
//! `libm.a` as before. The symbol is `sqrt` itself, not a second name beside avr-libc's, so
//! that `sqrt.o` drops out of the flash (the fallback cannot then call avr-libc's `sqrt`, and
//! replays its opening sequence instead).
//!
//! # Registers
//!
//! The avr-gcc convention: the argument and the result in r25:r22; r0, r18–r27, r30, r31 and
//! the flags (T included) are clobbered, r1 is zero on return, as with avr-libc's `sqrt`. No
//! avr-libc member the firmware links calls `sqrt`.

/// Defines `sqrt` (see the [module docs](mod@crate::sqrt)) in the crate that invokes it;
/// [`link_avr_libc!`](crate::link_avr_libc) does, once per binary. Needs
/// `#![feature(asm_experimental_arch)]` in that crate.
#[macro_export]
macro_rules! sqrt_primitive {
    () => {
        ::core::arch::global_asm!(
            ".section .text.avr_libc_math.sqrt,\"ax\",@progbits",
            ".global sqrt",
            ".type sqrt, @function",
            // Exponent 0 or 255 (positive). A subnormal: shifted left k places until its
            // leading one is bit 23, then the path below with e − 1 = −k (r31 = ⌊−k / 2⌋,
            // the carry k's parity).
            "21:",
            "cpi r31, 255",
            "brne 20f",
            "cp r1, r22",
            "cpc r1, r23",
            "cpc r1, r24",
            "brcc 20f",
            "clr r31",
            "22:",
            "dec r31",
            "lsl r22",
            "rol r23",
            "rol r24",
            "brpl 22b",
            "andi r24, 0x7f",
            "asr r31",
            "rjmp 30f",
            // ±0, negative numbers, infinities and NaNs: avr-libc's `sqrt` from its start,
            // which returns through `__fp_mpack` (±0, +∞, NaN) or `__fp_nan`. Only a negative
            // number reaches `__fp_splitA`'s finite non-zero case here.
            "20:",
            "call __fp_splitA",
            "brcs 23f",
            "and r25, r25",
            "brne 25f",
            "rjmp 24f",
            "23:",
            "brne 24f",
            "brts 25f",
            "24:",
            "jmp __fp_mpack",
            "25:",
            "jmp __fp_nan",
            "sqrt:",
            // The biased exponent less 1 to r31, in 0..=253 for a normal argument; the sign
            // to the carry.
            "movw r30, r24",
            "lsl r30",
            "rol r31",
            "brcs 20b",
            "subi r31, 1",
            "cpi r31, 254",
            "brsh 21b",
            // The fraction to r24:r22; r31 = (e − 1) / 2, the carry set for an even `e`.
            "andi r24, 0x7f",
            "lsr r31",
            // S for j = 1 (the first root bit is always one): m' − 2^23, that is the fraction
            // for odd `e` (carry clear), 2·(fraction + 2^22) for even `e` (25 bits, the carry
            // the top one). T = 2^23 + 2^21, K = 2^21 + 2^20 in T's upper two bytes, 13 steps.
            "30:",
            "brcc 1f",
            "subi r24, 0xc0",
            "lsl r22",
            "rol r23",
            "rol r24",
            "1:",
            "ldi r20, 0xa0",
            "clr r19",
            "clr r18",
            "ldi r27, 0x30",
            "clr r26",
            "ldi r30, 13",
            // Root bits 1 to 13: T's low byte is zero, so S ≥ T on the upper two bytes (or
            // S ≥ 2^24, the carry); then S ← 2·(S − T) or 2·S.
            "3:",
            "brcs 4f",
            "cp r23, r19",
            "cpc r24, r20",
            "brlo 5f",
            "4:",
            "sub r23, r19",
            "sbc r24, r20",
            "add r19, r26",
            "adc r20, r27",
            "rjmp 6f",
            "5:",
            "eor r19, r26",
            "eor r20, r27",
            "6:",
            "lsr r27",
            "ror r26",
            "lsl r22",
            "rol r23",
            "rol r24",
            "dec r30",
            "brne 3b",
            // Root bits 14 to 22 on three bytes, K (2^8 + 2^7 first) in T's lower two; the
            // last step leaves T = P (K's lower bit, 2^−1, falls off).
            "ldi r27, 1",
            "ldi r26, 0x80",
            "ldi r30, 9",
            "7:",
            "brcs 8f",
            "cp r22, r18",
            "cpc r23, r19",
            "cpc r24, r20",
            "brlo 10f",
            "8:",
            "sub r22, r18",
            "sbc r23, r19",
            "sbc r24, r20",
            "add r18, r26",
            "adc r19, r27",
            "rjmp 11f",
            "10:",
            "eor r18, r26",
            "eor r19, r27",
            "11:",
            "lsr r27",
            "ror r26",
            "lsl r22",
            "rol r23",
            "rol r24",
            "dec r30",
            "brne 7b",
            // The last root bit and the rounding bit, both S ≥ P + 1 (integers: the trial's
            // half-unit rounded up); r21 counts them, the result's mantissa is P + r21.
            "ori r18, 1",
            "clr r21",
            "brcs 14f",
            "cp r22, r18",
            "cpc r23, r19",
            "cpc r24, r20",
            "brlo 15f",
            "14:",
            "sub r22, r18",
            "sbc r23, r19",
            "sbc r24, r20",
            "inc r21",
            "15:",
            "lsl r22",
            "rol r23",
            "rol r24",
            "brcs 16f",
            "cp r22, r18",
            "cpc r23, r19",
            "cpc r24, r20",
            "brlo 17f",
            "16:",
            "inc r21",
            "17:",
            "andi r18, 0xfe",
            // Pack: the exponent (e − 1) / 2 + 64 = (e + 127) / 2 over P without its leading
            // one, then + r21 (a carry out of the mantissa increments the exponent).
            "subi r31, 0xc0",
            "lsl r20",
            "lsr r31",
            "ror r20",
            "movw r22, r18",
            "mov r24, r20",
            "mov r25, r31",
            "add r22, r21",
            "adc r23, r1",
            "adc r24, r1",
            "adc r25, r1",
            "ret",
            ".size sqrt, . - sqrt",
        );
    };
}
