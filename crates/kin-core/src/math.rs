//! Scalar math backends.
//!
//! Every kinematic routine is generic over a [`Math`] backend so that each target picks the
//! fastest correct implementation of the few transcendental functions the kinematics needs,
//! while the algebra stays in one place:
//!
//! - [`Fast`] (the default, [`DefaultMath`]): minimax polynomials for `atan2` and `sin`/`cos`
//!   (absolute error ≤ 3e-7 rad, about one f32 ulp at π; see the tests), `libm` for `sqrt`.
//!   `atan2` is branch-free (random quadrants cost no mispredictions) and its polynomial is
//!   evaluated in Estrin's scheme (a short dependency chain); quick on hosts with hardware
//!   floating point. See `BENCHMARKS.md`.
//! - [`Libm`]: the `libm` crate's correctly rounded-ish `atan2f`, `sinf`, `cosf`, `sqrtf`.
//!   The reference the others are tested against.
//! - Firmware may implement [`Math`] itself, e.g. on top of avr-libc's hand-written assembly.
//!
//! The polynomial coefficients come from `scripts/fit_polynomials.py` (a weighted least-squares
//! minimax fit); they are constants, not tables (the one table is `atan2`'s four quadrant
//! offsets, 16 bytes).

/// The few scalar functions the kinematics needs. All angles are in radians.
pub trait Math {
    /// Square root; the argument is never negative when called from this crate.
    fn sqrt(x: f32) -> f32;
    /// Four-quadrant arctangent of `y / x`, in `[-π, π]`; `atan2(0, 0)` must be finite.
    fn atan2(y: f32, x: f32) -> f32;
    /// `(sin x, cos x)`.
    fn sin_cos(x: f32) -> (f32, f32);
}

/// The backend used by the convenience functions of this crate.
pub type DefaultMath = Fast;

/// Reference backend: the `libm` crate.
#[derive(Debug, Clone, Copy, Default)]
pub struct Libm;

impl Math for Libm {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }
}

/// Polynomial backend: `atan2` from an odd degree-15 minimax polynomial on `[0, 1]` and
/// `sin`/`cos` from degree-7/8 polynomials after a Cody–Waite reduction to `[-π/4, π/4]`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fast;

const FRAC_PI_2: f32 = core::f32::consts::FRAC_PI_2;
const PI: f32 = core::f32::consts::PI;

/// atan(t) ≈ t·P(t²) on [0, 1]; fit by `scripts/fit_polynomials.py`.
const ATAN_COEFFS: [f32; 8] = [
    0.999_999_34,
    -0.333_298_6,
    0.199_465_66,
    -0.139_086_29,
    0.096_421_95,
    -0.055_912_29,
    0.021_862_93,
    -0.004_054_559,
];

/// atan(t) ≈ t·P(t²) on [0, 1], with P evaluated in Estrin's scheme: the same
/// coefficients as Horner's rule but three multiply–add levels deep instead of seven, which
/// shortens the dependency chain of the IK.
#[inline]
fn atan_unit(t: f32) -> f32 {
    let c = &ATAN_COEFFS;
    let s = t * t;
    let s2 = s * s;
    let s4 = s2 * s2;
    let p01 = c[0] + c[1] * s;
    let p23 = c[2] + c[3] * s;
    let p45 = c[4] + c[5] * s;
    let p67 = c[6] + c[7] * s;
    let q0 = p01 + p23 * s2;
    let q1 = p45 + p67 * s2;
    (q0 + q1 * s4) * t
}

impl Math for Fast {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }

    /// Branch-free: the octant is folded into an offset and a sign chosen next to the
    /// division, so random quadrants cost no mispredicted branches.
    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        const SIGN: u32 = 0x8000_0000;
        let ax = libm::fabsf(x);
        let ay = libm::fabsf(y);
        let swap = ay > ax;
        let x_neg = x.is_sign_negative();
        // Written as comparisons (not f32::min/max) so that they compile to minss/maxss.
        let num = if ay < ax { ay } else { ax };
        let den = if ay > ax { ay } else { ax };
        let t = num / den;
        // atan2(±0, ±0): 0/0 is NaN, which this comparison maps to t = 0, giving ±0 or ±π by
        // the signs, as libm does.
        let t = if t > 0.0 { t } else { 0.0 };
        let y_sign = y.to_bits() & SIGN;
        let t_sign = (((swap != x_neg) as u32) << 31) ^ y_sign;
        // |atan2| = offset ± atan(t) by (swap, x < 0): (0, +), (π, −), (π/2, −), (π/2, +); then
        // the sign of y. A table lookup, not a select, which the compiler would turn into a
        // branch that random quadrants mispredict.
        const OFFSET: [f32; 4] = [0.0, PI, FRAC_PI_2, FRAC_PI_2];
        let offset = OFFSET[((swap as usize) << 1) | x_neg as usize];
        let offset = f32::from_bits(offset.to_bits() | y_sign);
        offset + atan_unit(f32::from_bits(t.to_bits() ^ t_sign))
    }

    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        // Quadrant k = round(x / (π/2)); r = x − k·π/2 in two parts (Cody–Waite).
        const INV_FRAC_PI_2: f32 = core::f32::consts::FRAC_2_PI;
        const PIO2_HI: f32 = 1.570_312_5; // exact in 11 bits
        const PIO2_LO: f32 = 4.838_268e-4;
        // Round to nearest by adding and subtracting 1.5·2²³ (exact for |x·2/π| < 2²²; beyond,
        // any nearby integer does as well as libm::roundf): inline, no call, no branch.
        const ROUND: f32 = 12_582_912.0;
        let k = (x * INV_FRAC_PI_2 + ROUND) - ROUND;
        let r = (x - k * PIO2_HI) - k * PIO2_LO;
        let r2 = r * r;
        let r4 = r2 * r2;
        // Minimax on [-π/4, π/4] (scripts/fit_polynomials.py): error < 1e-9 before rounding.
        // Estrin's scheme: (a + b·r²) + r⁴·((c + d·r²) + e·r⁴), a short dependency chain.
        let s = r
            * ((1.0 - 1.666_666_6e-1 * r2)
                + r4 * ((8.333_326e-3 - 1.983_867_2e-4 * r2) + 2.713_535_5e-6 * r4));
        let c =
            (1.0 - 0.5 * r2) + r4 * ((4.166_661_6e-2 - 1.388_662e-3 * r2) + 2.437_992_8e-5 * r4);
        let q = (k as i32) & 3;
        match q {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }
}

/// Wraps an angle into `(-π, π]`.
#[inline]
pub fn wrap_pi(angle_rad: f32) -> f32 {
    let two_pi = 2.0 * PI;
    let mut a = angle_rad - two_pi * libm::roundf(angle_rad / two_pi);
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
    let mut a = angle_rad - two_pi * libm::floorf(angle_rad / two_pi);
    if a >= two_pi {
        a -= two_pi;
    }
    if a < 0.0 {
        a += two_pi;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_atan2_matches_f64_everywhere() {
        let mut worst = 0.0f64;
        for i in 0..=720 {
            for r in [1e-3f32, 0.3, 1.0, 7.0] {
                let ang = -PI + (i as f32) * (2.0 * PI / 720.0);
                let (y, x) = (r * libm::sinf(ang), r * libm::cosf(ang));
                let got = Fast::atan2(y, x) as f64;
                let want = (y as f64).atan2(x as f64);
                let mut d = (got - want).abs();
                if d > core::f64::consts::PI {
                    d = 2.0 * core::f64::consts::PI - d;
                }
                worst = worst.max(d);
            }
        }
        assert!(worst < 3.0e-7, "worst atan2 error {worst}");
        assert_eq!(Fast::atan2(0.0, 0.0), 0.0);
        assert_eq!(Fast::atan2(0.0, -1.0), PI);
        assert_eq!(Fast::atan2(1.0, 0.0), FRAC_PI_2);
    }

    #[test]
    fn fast_atan2_signed_zeros_and_axes_match_libm() {
        for (y, x) in [
            (0.0f32, 0.0f32),
            (-0.0, 0.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (0.0, 2.0),
            (-0.0, 2.0),
            (0.0, -2.0),
            (-0.0, -2.0),
            (2.0, 0.0),
            (2.0, -0.0),
            (-2.0, 0.0),
            (-2.0, -0.0),
            (1.0, 1.0),
            (-1.0, -1.0),
        ] {
            let (got, want) = (Fast::atan2(y, x), libm::atan2f(y, x));
            assert!(
                (got - want).abs() < 3.0e-7,
                "atan2({y}, {x}) = {got}, libm {want}"
            );
            assert_eq!(
                got.is_sign_negative(),
                want.is_sign_negative(),
                "atan2({y}, {x})"
            );
        }
    }

    #[test]
    fn fast_sin_cos_matches_f64() {
        let mut worst = 0.0f64;
        for i in -4000..=4000 {
            let x = i as f32 * 0.0025; // ±10 rad
            let (s, c) = Fast::sin_cos(x);
            worst = worst
                .max((s as f64 - (x as f64).sin()).abs())
                .max((c as f64 - (x as f64).cos()).abs());
        }
        assert!(worst < 2.0e-7, "worst sin/cos error {worst}");
    }

    #[test]
    fn wraps() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-6);
        assert!((wrap_two_pi(-0.5) - (2.0 * PI - 0.5)).abs() < 1e-6);
        assert!(wrap_two_pi(2.0 * PI) < 1e-6);
    }
}
