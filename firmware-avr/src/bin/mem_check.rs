//! Checks the firmware's `memcpy` and `memset` ([`firmware_avr::mem`]) on the chip: every
//! length from 0 to 80 bytes at every alignment (0 to 3) of source and destination, against
//! a byte loop, the bytes around the destination included. Sends `K` at 1,000,000 baud when
//! all pass, else `X` and the length and the offsets of the first failure (the emulator test
//! `avr_mem` reads it).

#![no_std]
#![no_main]

use core::hint::black_box;
use firmware_avr::usart::{Baud, Usart0};

/// Longest length checked, bytes.
const MAX_LEN: usize = 80;
/// Buffer: the longest length, three bytes of offset and four guard bytes.
const BUF: usize = MAX_LEN + 8;

/// The source pattern's byte `i` (no run of equal bytes, no zero run).
fn source_byte(i: usize) -> u8 {
    (i as u8).wrapping_mul(7).wrapping_add(3)
}

/// The destination's byte `i` before the call.
fn guard_byte(i: usize) -> u8 {
    0xE0 ^ i as u8
}

/// The first failing case: 0 `memcpy`, 1 `memset`; length, source and destination offsets.
fn check() -> Option<[u8; 4]> {
    let mut src = [0u8; BUF];
    let mut dst = [0u8; BUF];
    for (i, s) in src.iter_mut().enumerate() {
        *s = source_byte(i);
    }
    for len in 0..=MAX_LEN {
        for so in 0..4 {
            for d_off in 0..4 {
                for (i, d) in dst.iter_mut().enumerate() {
                    *d = guard_byte(i);
                }
                // Opaque length and pointers: the calls stay calls of `memcpy`.
                let n = black_box(len);
                // SAFETY: both ranges lie within their buffers (`so`, `d_off` ≤ 3,
                // `n` ≤ MAX_LEN) and the buffers are distinct.
                unsafe {
                    core::ptr::copy_nonoverlapping(
                        black_box(src.as_ptr().add(so)),
                        black_box(dst.as_mut_ptr().add(d_off)),
                        n,
                    );
                }
                for (i, &d) in dst.iter().enumerate() {
                    let want = if (d_off..d_off + len).contains(&i) {
                        source_byte(i - d_off + so)
                    } else {
                        guard_byte(i)
                    };
                    if d != want {
                        return Some([0, len as u8, so as u8, d_off as u8]);
                    }
                }
            }
        }
        for d_off in 0..4 {
            for (i, d) in dst.iter_mut().enumerate() {
                *d = guard_byte(i);
            }
            let value = black_box(0x5A ^ len as u8);
            // SAFETY: within `dst` (`d_off` ≤ 3, `len` ≤ MAX_LEN).
            unsafe {
                core::ptr::write_bytes(
                    black_box(dst.as_mut_ptr().add(d_off)),
                    value,
                    black_box(len),
                );
            }
            for (i, &d) in dst.iter().enumerate() {
                let want = if (d_off..d_off + len).contains(&i) {
                    value
                } else {
                    guard_byte(i)
                };
                if d != want {
                    return Some([1, len as u8, 0, d_off as u8]);
                }
            }
        }
    }
    None
}

#[avr_device::entry]
fn main() -> ! {
    let Some(dp) = firmware_avr::pac::Peripherals::take() else {
        panic!()
    };
    let mut usart = Usart0::new(dp.USART0, Baud::B1000000);
    match check() {
        None => usart.write(b'K'),
        Some(failure) => {
            usart.write(b'X');
            usart.write_all(&failure);
        }
    }
    usart.flush();
    loop {
        core::hint::spin_loop();
    }
}
