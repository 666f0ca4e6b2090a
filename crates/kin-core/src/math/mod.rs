//! Scalar math backends.
//!
//! Every kinematic routine is generic over a [`Math`] backend so that each target picks the
//! fastest correct implementation of the few transcendental functions and comparisons the
//! kinematics needs, while the algebra stays in one place and every backend runs on every
//! target (the host tests run them all):
//!
//! - [`Fast`] (the default, [`DefaultMath`]): minimax polynomials for `atan2` and `sin`/`cos`
//!   (absolute error ≤ 3e-7 rad, about one f32 ulp at π; see the tests), `libm` for `sqrt`.
//!   `atan2` is branch-free (random quadrants cost no mispredictions) and its polynomial is
//!   evaluated in Estrin's scheme (a short dependency chain). Quick on hosts with hardware
//!   floating point. See `BENCHMARKS.md`.
//! - [`Libm`]: the `libm` crate's correctly rounded-ish `atan2f`, `sinf`, `cosf`, `sqrtf`.
//!   The reference the others are tested against.
//! - [`SoftFloat`]: the choices for CPUs without floating-point hardware (the ATmega2560
//!   firmware's backend is `SoftFloat` over avr-libc's square root): the kernels
//!   [`poly::atan2_fixed`] and [`poly::sin_cos_fixed`] (tables of quadratic cells in fixed
//!   point), which cost far fewer software-float operations, and comparisons of the bit
//!   patterns instead of software-float comparisons. The kernels' tables are the one thing a
//!   backend must read per target ([`Math::read_table_cell`]): on the AVR they stay in flash,
//!   out of the scarce SRAM, and the backend reads them with `lpm`. A backend may also supply
//!   the arctangent kernel and the sine/cosine kernel's fixed-point core in its own form for
//!   its target, bit for bit the same ([`Math::atan2_fixed`], [`Math::sin_cos_fixed`]; the
//!   AVR's are in assembly).
//!
//! The polynomial coefficients come from `scripts/fit_polynomials.py` (a weighted least-squares
//! minimax fit), and so do the fixed-point kernels' cell tables (quadratics through Chebyshev
//! nodes).

mod bits;
mod fast;
mod lanes;
mod libm;
pub mod poly;
mod soft_float;
mod table;

pub use fast::Fast;
pub use libm::Libm;
pub use soft_float::SoftFloat;
pub use table::{TableEntry, TABLES_IN_PROGRAM_MEMORY};

/// The few scalar functions and comparisons the kinematics needs. All angles are in radians.
///
/// Only `sqrt`, `atan2` and `sin_cos` have no default. The comparisons default to the float
/// operators; a backend overrides them where another form is faster on its target and equal
/// in result (NaN included), as [`SoftFloat`] does.
pub trait Math {
    /// Square root; the argument is never negative when called from this crate.
    fn sqrt(x: f32) -> f32;
    /// Four-quadrant arctangent of `y / x`, in `[-π, π]`; `atan2(0, 0)` must be finite.
    fn atan2(y: f32, x: f32) -> f32;
    /// `(sin x, cos x)`.
    fn sin_cos(x: f32) -> (f32, f32);
    /// Three independent arctangents `[atan2(y[0], x[0]), atan2(y[1], x[1]),
    /// atan2(y[2], x[2])]` (a leg's abduction, knee and hip). A backend may evaluate them
    /// together (e.g. in SIMD lanes), but must return exactly what three [`Math::atan2`] calls
    /// return. The default makes the three calls (always inlined: the arrays must not pass
    /// through memory, which costs store-forwarding stalls on x86-64).
    #[inline(always)]
    fn atan2_3(y: [f32; 3], x: [f32; 3]) -> [f32; 3] {
        [
            Self::atan2(y[0], x[0]),
            Self::atan2(y[1], x[1]),
            Self::atan2(y[2], x[2]),
        ]
    }
    /// `N` independent arctangents `atan2(y[i], x[i])`, lane by lane (the batch solves of
    /// [`crate::batch`]): exactly what `N` [`Math::atan2`] calls return. The default makes the
    /// calls; a backend overrides it with a form the compiler vectorises, bit for bit the same
    /// ([`Fast`]'s selects its octant's offset where its scalar form reads a table).
    #[inline]
    fn atan2_lanes<const N: usize>(y: &[f32; N], x: &[f32; N]) -> [f32; N] {
        core::array::from_fn(|i| Self::atan2(y[i], x[i]))
    }
    /// `N` square roots, lane by lane (the batch solves of [`crate::batch`]): exactly what `N`
    /// [`Math::sqrt`] calls return. The default makes the calls; a backend overrides it with a
    /// vector form where it has one, bit for bit the same.
    #[inline]
    fn sqrt_lanes<const N: usize>(x: &[f32; N]) -> [f32; N] {
        core::array::from_fn(|i| Self::sqrt(x[i]))
    }
    /// `x > 0.0`.
    fn gt_zero(x: f32) -> bool {
        x > 0.0
    }
    /// `a < b` for `a`, `b` that are each `≥ +0` (sign bit clear: squares, sums of squares,
    /// distances) or NaN.
    fn lt_nonneg(a: f32, b: f32) -> bool {
        a < b
    }
    /// `lo <= x && x <= hi` (false when any of them is NaN).
    fn within(x: f32, lo: f32, hi: f32) -> bool {
        (x >= lo) & (x <= hi)
    }
    /// `lo <= x && x <= hi` (as [`Math::within`]) for a fixed interval whose
    /// [`interval_keys`] `keys` the caller computed once: the default compares the floats,
    /// a backend that compares bit patterns ([`SoftFloat`]) compares `x`'s key with `keys`
    /// (no per-call work on the bounds).
    fn within_keys(x: f32, lo: f32, hi: f32, keys: (i32, i32)) -> bool {
        let _ = keys;
        Self::within(x, lo, hi)
    }
    /// Reads one cell of a fixed-point kernel's table ([`poly::atan2_fixed`],
    /// [`poly::sin_cos_fixed`]): `N` consecutive 16-bit words, see [`TableEntry`]. The only
    /// per-target part of those kernels: the default is a plain load, right wherever the tables
    /// are ordinary read-only data; where this crate links them into program memory (the AVR's
    /// flash, see [`TABLES_IN_PROGRAM_MEMORY`]) a backend must read them there, and the default
    /// does not compile for it.
    fn read_table_cell<const N: usize>(entry: TableEntry<[u16; N]>) -> [u16; N] {
        entry.read_data_memory::<Self>()
    }
    /// The fixed-point arctangent [`poly::atan2_fixed`] with this backend's table reads: the
    /// arctangent of [`SoftFloat`] over this backend. A backend overrides it only with a
    /// faster form of the same kernel for its target (the AVR's, in assembly, from the
    /// table [`poly::atan_cells`]): an override must return the same bits as
    /// `poly::atan2_fixed::<Self>` for every input (NaN arguments: a bounded value), which
    /// its target's tests check.
    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        poly::atan2_fixed::<Self>(y, x)
    }
    /// The fixed-point sine and cosine [`poly::sin_cos_fixed`] with this backend's table
    /// reads: the `sin_cos` of [`SoftFloat`] over this backend. A backend overrides it only
    /// with a faster form of the same kernel for its target (the AVR's: the range reduction
    /// and quadrant of [`poly::sin_cos_fixed_with`] around an assembly form of
    /// [`poly::sin_cos_fixed_core`]): an override must return the same bits as
    /// `poly::sin_cos_fixed::<Self>` for every input (NaN and infinite arguments: bounded
    /// values), which its target's tests check.
    #[inline]
    fn sin_cos_fixed(x: f32) -> (f32, f32) {
        poly::sin_cos_fixed::<Self>(x)
    }
}

/// The backend used by the convenience functions of this crate.
pub type DefaultMath = Fast;

const FRAC_PI_2: f32 = core::f32::consts::FRAC_PI_2;
const PI: f32 = core::f32::consts::PI;

/// The keys of the closed interval `[lo, hi]` for [`Math::within_keys`]: integers that order
/// as the floats do (−0 = +0), `(i32::MAX, i32::MIN)` (admitting nothing) when a bound is NaN.
#[inline]
pub const fn interval_keys(lo: f32, hi: f32) -> (i32, i32) {
    bits::interval(lo, hi)
}

/// `x.is_finite()` from the exponent bits, on every target (core's `is_finite` is a float
/// comparison, a library call on CPUs without floating-point hardware): finite when the
/// exponent (bits 30..23) is short of all ones, tested as one byte (a byte compare on an 8-bit
/// CPU rather than a 32-bit mask).
pub(crate) const fn finite(x: f32) -> bool {
    (x.to_bits() >> 23) as u8 != u8::MAX
}

/// `x.is_finite() && x > 0.0` from the bits: the patterns of the positive subnormals to the
/// largest finite float.
pub(crate) const fn positive_finite(x: f32) -> bool {
    x.to_bits().wrapping_sub(1) < bits::INF - 1
}

/// `x.is_finite() && x >= 0.0` from the bits: +0 to the largest finite float, or −0.
pub(crate) const fn nonneg_finite(x: f32) -> bool {
    let b = x.to_bits();
    b < bits::INF || b == 0x8000_0000
}

/// `lo.is_finite() && hi.is_finite() && lo <= hi` from the bits.
pub(crate) const fn finite_ordered(lo: f32, hi: f32) -> bool {
    finite(lo) && finite(hi) && bits::key(lo) <= bits::key(hi)
}

/// `⌊x⌋`: equal to `libm::floorf` on every input (tested against it), written with one
/// float-to-integer conversion and back rather than libm's bit manipulation of the pattern,
/// whose 32-bit shifts and masks are a few hundred bytes of code on an 8-bit CPU (the
/// firmware's flash; the conversions are linked there anyway).
pub fn floor(x: f32) -> f32 {
    // From 2^23 on (and ±∞, NaN) every f32 is whole already.
    if !(x.abs() < 8_388_608.0) {
        return x;
    }
    let t = x as i32 as f32;
    if t == x {
        x // Whole (keeps the sign of −0).
    } else if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `⌈x⌉`: equal to `libm::ceilf` on every input, as `−⌊−x⌋` ([`floor`]).
#[inline]
pub fn ceil(x: f32) -> f32 {
    -floor(-x)
}

/// Wraps an angle into `(-π, π]`.
pub fn wrap_pi(angle_rad: f32) -> f32 {
    let two_pi = 2.0 * PI;
    // The nearest whole turn by `floor` (libm's `roundf` is a second copy of its bit
    // manipulation on a soft-float target); a half turn either way is put right below.
    let mut a = angle_rad - two_pi * floor(angle_rad / two_pi + 0.5);
    if a <= -PI {
        a += two_pi;
    }
    if a > PI {
        a -= two_pi;
    }
    a
}

/// Wraps an angle into `[0, 2π)`.
#[inline]
pub fn wrap_two_pi(angle_rad: f32) -> f32 {
    let two_pi = 2.0 * PI;
    let mut a = angle_rad - two_pi * floor(angle_rad / two_pi);
    if a >= two_pi {
        a -= two_pi;
    }
    if a < 0.0 {
        a += two_pi;
    }
    a
}

/// What the kernels' tests share: the arctangent error sweep and the kernels' bounds.
#[cfg(test)]
pub(crate) mod test_support {
    use super::PI;

    /// Largest |atan2 − f64 atan2| of `f` over a 720-step circle at several radii, rad.
    pub(crate) fn worst_atan2_error(f: impl Fn(f32, f32) -> f32) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..=720 {
            for r in [1e-3f32, 0.3, 1.0, 7.0] {
                let ang = -PI + (i as f32) * (2.0 * PI / 720.0);
                let (y, x) = (r * libm::sinf(ang), r * libm::cosf(ang));
                let got = f(y, x) as f64;
                let want = (y as f64).atan2(x as f64);
                let mut d = (got - want).abs();
                if d > core::f64::consts::PI {
                    d = 2.0 * core::f64::consts::PI - d;
                }
                worst = worst.max(d);
            }
        }
        worst
    }

    /// Error bound of [`atan2_deg9`](super::poly::atan2_deg9) (the fit's 1.14e-5 plus f32 rounding).
    pub(crate) const ATAN2_DEG9_TOL_RAD: f64 = 1.2e-5;

    /// Error bound of [`atan2_fixed`](super::poly::atan2_fixed).
    pub(crate) const ATAN2_FIXED_TOL_RAD: f64 = 3.5e-5;
}

#[cfg(test)]
mod tests {
    use super::*;
    use seeded_rng::SplitMix64;
    extern crate std;

    #[test]
    fn wrap_pi_lands_in_the_half_open_turn_on_the_same_angle() {
        let mut rng = SplitMix64::new(0x77a9);
        let halves = [PI, -PI, 3.0 * PI, -3.0 * PI, 0.5 * PI, 0.0, -0.0];
        let random = (0..100_000).map(|_| (rng.next_u64() % 2_000_001) as f32 * 1e-4 - 100.0);
        for a in halves.into_iter().chain(random) {
            let w = wrap_pi(a);
            assert!(w > -PI && w <= PI, "{a}: {w}");
            let turns = (f64::from(a) - f64::from(w)) / (2.0 * core::f64::consts::PI);
            assert!((turns - turns.round()).abs() < 1e-5, "{a}: {w}");
        }
    }

    #[test]
    fn floor_and_ceil_equal_libm_on_special_and_random_inputs() {
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            0.999_999_94,
            -0.999_999_94,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_608.0,
            16_777_217.0,
            1e-45,
            -1e-45,
            2.147_483_6e9,
            -2.147_483_6e9,
            3.4e38,
            -3.4e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        let mut rng = SplitMix64::new(0xf100_c0de);
        let random = (0..100_000).map(|_| f32::from_bits(rng.next_u64() as u32));
        for x in special.into_iter().chain(random) {
            for (got, want) in [(floor(x), ::libm::floorf(x)), (ceil(x), ::libm::ceilf(x))] {
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{x:e}: {got:e} vs {want:e}"
                );
            }
        }
    }
    #[test]
    fn wraps() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-6);
        assert!((wrap_two_pi(-0.5) - (2.0 * PI - 0.5)).abs() < 1e-6);
        assert!(wrap_two_pi(2.0 * PI) < 1e-6);
    }
}
