//! `memcpy` and `memset` for the firmware, four bytes per loop step.
//!
//! Every move of a message, a solution or an angle array that LLVM does not keep in registers
//! is a call of these two; a request to the controller makes about fifty of them, of 12 to 72
//! bytes. avr-libc's (which the firmware linked before) are written for size: one byte per
//! loop step, 8 cycles a byte for `memcpy`, 6 for `memset`. These copy four bytes per step
//! after the one to three that make the rest a multiple of four: 5 and 3 cycles a byte, for
//! a few dozen bytes of flash. Defined here, they take precedence over the library's
//! (objects are linked before archives). The emulator test `avr_mem` holds both to their
//! definition for every length up to 80 bytes and every alignment of source and destination.
//!
//! The calling convention is avr-gcc's, as for the library's: the destination in r25:r24,
//! the source (or the fill value's low byte) in r23:r22, the length in r21:r20; the
//! destination is returned in r25:r24.

use core::arch::asm;

/// Copies `n` bytes from `src` to `dest` (C's `memcpy`) and returns `dest`.
///
/// # Safety
/// As C's `memcpy`: `src` readable and `dest` writable for `n` bytes, not overlapping.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn memcpy(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
    // SAFETY: the caller's contract; the loop reads `n` bytes from `src` (Z) and writes `n`
    // bytes to `dest` (X), nothing else.
    unsafe {
        asm!(
            // n & 1, then n & 2 bytes; then n / 4 steps of four.
            "sbrs r20, 0",
            "rjmp 1f",
            "ld {t}, Z+",
            "st X+, {t}",
            "1:",
            "sbrs r20, 1",
            "rjmp 2f",
            "ld {t}, Z+",
            "st X+, {t}",
            "ld {t}, Z+",
            "st X+, {t}",
            "2:",
            "lsr r21",
            "ror r20",
            "lsr r21",
            "ror r20",
            "rjmp 4f",
            "3:",
            "ld {t}, Z+",
            "st X+, {t}",
            "ld {t}, Z+",
            "st X+, {t}",
            "ld {t}, Z+",
            "st X+, {t}",
            "ld {t}, Z+",
            "st X+, {t}",
            "4:",
            "subi r20, 1",
            "sbci r21, 0",
            "brcc 3b",
            t = out(reg) _,
            inout("X") dest => _,
            inout("Z") src => _,
            inout("r20") n as u8 => _,
            inout("r21") (n >> 8) as u8 => _,
            options(nostack),
        );
    }
    dest
}

/// Fills `n` bytes at `dest` with the low byte of `c` (C's `memset`) and returns `dest`.
///
/// # Safety
/// As C's `memset`: `dest` writable for `n` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn memset(dest: *mut u8, c: i16, n: usize) -> *mut u8 {
    // SAFETY: the caller's contract; the loop writes `n` bytes to `dest` (X), nothing else.
    unsafe {
        asm!(
            "sbrs r20, 0",
            "rjmp 1f",
            "st X+, {c}",
            "1:",
            "sbrs r20, 1",
            "rjmp 2f",
            "st X+, {c}",
            "st X+, {c}",
            "2:",
            "lsr r21",
            "ror r20",
            "lsr r21",
            "ror r20",
            "rjmp 4f",
            "3:",
            "st X+, {c}",
            "st X+, {c}",
            "st X+, {c}",
            "st X+, {c}",
            "4:",
            "subi r20, 1",
            "sbci r21, 0",
            "brcc 3b",
            c = in(reg) c as u8,
            inout("X") dest => _,
            inout("r20") n as u8 => _,
            inout("r21") (n >> 8) as u8 => _,
            options(nostack),
        );
    }
    dest
}
