//! The backend for CPUs without floating-point hardware.

use super::{bits, Libm, Math, TableEntry};
use core::marker::PhantomData;

/// The backend for CPUs without floating-point hardware, with the square root of backend `S`
/// (the ATmega2560 firmware: `SoftFloat<AvrLibm>`, avr-libc's hand-written `sqrt`; the host
/// tests: `SoftFloat<Libm>`, the default, which rounds the same):
///
/// - [`poly::atan2_fixed`](super::poly::atan2_fixed) (through `S`'s [`Math::atan2_fixed`], which a backend may
///   implement for its target, bit for bit the same): an exact integer quotient of the
///   mantissas, then in 16-bit fixed point on the integer multiplier, atan from a table of
///   quadratic cells (error ≤ 2e-6 rad);
/// - [`poly::sin_cos_fixed`](super::poly::sin_cos_fixed) (through `S`'s [`Math::sin_cos_fixed`], likewise): no range
///   reduction within ±π/4, then a table of quadratic cells in 16-bit fixed point
///   (error ≤ 1e-6);
/// - comparisons of the bit patterns (a software-float comparison is a library call, these
///   are a few integer instructions), equal to the float operators on every input;
/// - the kernels' tables read by `S` ([`Math::read_table_cell`]): a
///   plain load for `Libm`; from flash for the firmware's `AvrLibm`, on the AVR, where the
///   tables are linked into flash ([`TABLES_IN_PROGRAM_MEMORY`](super::TABLES_IN_PROGRAM_MEMORY)).
///
/// Against [`DefaultMath`](super::DefaultMath) the angles of a leg or body solve differ by at most about 4e-6 rad
/// (the fixed-point arctangent's error plus rounding; `tests/avr_kernels.rs`).
#[derive(Debug, Clone, Copy, Default)]
pub struct SoftFloat<S: Math = Libm>(PhantomData<S>);

impl<S: Math> Math for SoftFloat<S> {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        S::sqrt(x)
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        S::atan2_fixed(y, x)
    }

    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        S::sin_cos_fixed(x)
    }

    fn gt_zero(x: f32) -> bool {
        bits::gt_zero(x)
    }

    fn lt_nonneg(a: f32, b: f32) -> bool {
        bits::lt_nonneg(a, b)
    }

    fn within(x: f32, lo: f32, hi: f32) -> bool {
        bits::within(x, bits::interval(lo, hi))
    }

    fn within_keys(x: f32, _lo: f32, _hi: f32, keys: (i32, i32)) -> bool {
        bits::within(x, keys)
    }

    fn read_table_cell<const N: usize>(entry: TableEntry<[u16; N]>) -> [u16; N] {
        S::read_table_cell(entry)
    }

    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        S::atan2_fixed(y, x)
    }

    #[inline]
    fn sin_cos_fixed(x: f32) -> (f32, f32) {
        S::sin_cos_fixed(x)
    }
}
