//! The polynomial kernels behind [`Fast`](super::Fast), and cheaper ones for targets without hardware
//! floating point, for a firmware's own [`Math`](super::Math) backend to pick from.
//!
//! | kernel | max abs error (tests) | suits |
//! |---|---|---|
//! | [`atan2_deg15`] | 3e-7 rad | hosts: branch-free, Estrin |
//! | [`atan2_deg9`] | 1.2e-5 rad (0.0007°) | in-order CPUs with software floats: 6 multiplications, 4 additions, 1 division, no float comparison |
//! | [`atan2_fixed`] | 2e-6 rad (0.0001°) | CPUs with software floats and an integer multiplier (the ATmega2560): an integer division of the mantissas, a table of 32 quadratic cells in 16-bit fixed point |
//! | [`sin_cos_deg9`] | 2e-7 | hosts: branch-free |
//! | [`sin_cos_deg5`] | 7e-7 | software floats: 7 multiplications, 5 additions, no range reduction for \|x\| ≤ π/4 |
//! | [`sin_cos_fixed`] | 1e-6 | CPUs with software floats and an integer multiplier (the ATmega2560): no range reduction for \|x\| ≤ π/4, a table of 26 quadratic cells in 16-bit fixed point, two integer-to-float conversions |

mod cells;
mod fixed;

#[cfg(test)]
pub(super) use cells::ATAN_CELLS;
pub use fixed::{
    atan2_fixed, atan_cells, atan_ratio_q21, sin_cos_cells, sin_cos_fixed, sin_cos_fixed_core,
    sin_cos_fixed_with,
};

use super::{FRAC_PI_2, PI};

const SIGN: u32 = 0x8000_0000;
const ABS: u32 = 0x7fff_ffff;

/// `atan(t) ≈ t·P(t²)` on `[0, 1]`, odd degree 15 (`scripts/fit_polynomials.py`).
pub const ATAN_DEG15: [f32; 8] = [
    0.999_999_34,
    -0.333_298_6,
    0.199_465_66,
    -0.139_086_29,
    0.096_421_95,
    -0.055_912_29,
    0.021_862_93,
    -0.004_054_559,
];

/// `atan(t) ≈ t·P(t²)` on `[0, 1]`, odd degree 9 (`scripts/fit_polynomials.py`): minimax
/// error 1.14e-5 rad.
pub const ATAN_DEG9: [f32; 5] = [
    0.999_866_3,
    -0.330_304_77,
    0.180_159_23,
    -0.085_156_25,
    0.020_845_061,
];

/// `sin r ≈ r·P(r²)` on `[-π/4, π/4]`, degree 9.
const SIN_DEG9: [f32; 5] = [
    1.0,
    -1.666_666_6e-1,
    8.333_326e-3,
    -1.983_867_2e-4,
    2.713_535_5e-6,
];
/// `cos r ≈ P(r²)` on `[-π/4, π/4]`, degree 8.
const COS_DEG8: [f32; 5] = [1.0, -0.5, 4.166_661_6e-2, -1.388_662e-3, 2.437_992_8e-5];
/// `sin r ≈ r·P(r²)` on `[-π/4, π/4]`, degree 5: minimax error 5.6e-7.
const SIN_DEG5: [f32; 3] = [0.999_995, -0.166_601_61, 8.121_557_5e-3];
/// `cos r ≈ P(r²)` on `[-π/4, π/4]`, degree 6: minimax error 2.8e-8.
const COS_DEG6: [f32; 4] = [1.0, -0.499_998_57, 4.165_502_6e-2, -1.358_590_8e-3];

/// `atan t` for `t ∈ [-1, 1]`, degree 15, in Estrin's scheme: the same coefficients as
/// Horner's rule but three multiply–add levels deep instead of seven (a short dependency
/// chain on superscalar CPUs).
pub fn atan_deg15(t: f32) -> f32 {
    let c = &ATAN_DEG15;
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

/// `atan t` for `t ∈ [-1, 1]`, degree 9, Horner's rule (the fewest operations).
pub fn atan_deg9(t: f32) -> f32 {
    let c = &ATAN_DEG9;
    let s = t * t;
    (c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * c[4])))) * t
}

/// Four-quadrant arctangent, odd degree-15 polynomial: absolute error ≤ 3e-7 rad,
/// `atan2(±0, ±0)` as libm (±0 or ±π). Branch-free, so random quadrants cost no
/// mispredictions: the octant's offset comes from a 4-entry table (a select would become a
/// branch).
#[inline]
pub fn atan2_deg15(y: f32, x: f32) -> f32 {
    let ax = libm::fabsf(x);
    let ay = libm::fabsf(y);
    // Written as comparisons (not f32::min/max) so that they compile to minss/maxss.
    let num = if ay < ax { ay } else { ax };
    let den = if ay > ax { ay } else { ax };
    let t = num / den;
    // atan2(±0, ±0): 0/0 is NaN, which this comparison maps to t = 0, giving ±0 or ±π by
    // the signs, as libm does.
    let t = if t > 0.0 { t } else { 0.0 };
    let swap = (ay > ax) as u32;
    let x_neg = x.to_bits() >> 31;
    let y_sign = y.to_bits() & SIGN;
    // |atan2| = offset ± atan(t) by (swap, x < 0): (0, +), (π, −), (π/2, −), (π/2, +); then
    // the sign of y. A table lookup, not a select, which the compiler would turn into a
    // branch that random quadrants mispredict.
    const OFFSET: [f32; 4] = [0.0, PI, FRAC_PI_2, FRAC_PI_2];
    let t_sign = ((swap ^ x_neg) << 31) ^ y_sign;
    let offset = OFFSET[((swap << 1) | x_neg) as usize];
    let offset = f32::from_bits(offset.to_bits() | y_sign);
    offset + atan_deg15(f32::from_bits(t.to_bits() ^ t_sign))
}

/// Four-quadrant arctangent, odd degree-9 polynomial: absolute error ≤ 1.2e-5 rad
/// (0.0007°), `atan2(±0, ±0)` as libm (±0 or ±π). For CPUs with software floating point:
/// one division, 6 multiplications, at most 5 additions, and the octant found by integer
/// comparisons of the bit patterns (no float comparison, no table).
#[inline]
pub fn atan2_deg9(y: f32, x: f32) -> f32 {
    let (yb, xb) = (y.to_bits(), x.to_bits());
    let (ay, ax) = (yb & ABS, xb & ABS);
    // For non-negative floats the bit patterns order as the values do.
    let swap = ay > ax;
    let (num, den) = if swap { (ax, ay) } else { (ay, ax) };
    let p = if den == 0 {
        0.0
    } else {
        atan_deg9(f32::from_bits(num) / f32::from_bits(den))
    };
    let r = match (swap, xb & SIGN != 0) {
        (false, false) => p,
        (false, true) => PI - p,
        (true, false) => FRAC_PI_2 - p,
        (true, true) => FRAC_PI_2 + p,
    };
    // r ≥ 0 in every octant: the sign of y goes on by its bit.
    f32::from_bits(r.to_bits() | (yb & SIGN))
}

/// `(sin x, cos x)` with degree-9/8 polynomials after a Cody–Waite reduction to
/// `[-π/4, π/4]`; absolute error ≤ 2e-7. Branch-free.
#[inline]
pub fn sin_cos_deg9(x: f32) -> (f32, f32) {
    let (k, r) = reduce(x);
    let r2 = r * r;
    let r4 = r2 * r2;
    // Estrin's scheme: (a + b·r²) + r⁴·((c + d·r²) + e·r⁴), a short dependency chain.
    let (s, c) = (&SIN_DEG9, &COS_DEG8);
    let sin = r * ((s[0] + s[1] * r2) + r4 * ((s[2] + s[3] * r2) + s[4] * r4));
    let cos = (c[0] + c[1] * r2) + r4 * ((c[2] + c[3] * r2) + c[4] * r4);
    quadrant(k, sin, cos)
}

/// `(sin x, cos x)` with degree-5/6 polynomials on `[-π/4, π/4]` (Horner), absolute error
/// ≤ 7e-7; arguments within ±π/4 (body rotations) skip the range reduction, found by an
/// integer comparison. For CPUs with software floating point.
#[inline]
pub fn sin_cos_deg5(x: f32) -> (f32, f32) {
    const FRAC_PI_4_BITS: u32 = 0x3f49_0fdb; // π/4 rounded to f32
    let (k, r) = if x.to_bits() & ABS <= FRAC_PI_4_BITS {
        (0, x)
    } else {
        reduce(x)
    };
    let r2 = r * r;
    let (s, c) = (&SIN_DEG5, &COS_DEG6);
    let sin = r * (s[0] + r2 * (s[1] + r2 * s[2]));
    let cos = c[0] + r2 * (c[1] + r2 * (c[2] + r2 * c[3]));
    if k == 0 {
        (sin, cos)
    } else {
        quadrant(k, sin, cos)
    }
}

/// Quadrant `k = round(x / (π/2))` modulo 4 and `r = x − k·π/2` in two parts
/// (Cody–Waite).
fn reduce(x: f32) -> (u32, f32) {
    const INV_FRAC_PI_2: f32 = core::f32::consts::FRAC_2_PI;
    const PIO2_HI: f32 = 1.570_312_5; // exact in 11 bits
    const PIO2_LO: f32 = 4.838_268e-4;
    // Round to nearest by adding and subtracting 1.5·2²³ (exact for |x·2/π| < 2²²; beyond,
    // any nearby integer does as well as libm::roundf): inline, no call, no branch.
    const ROUND: f32 = 12_582_912.0;
    let shifted = x * INV_FRAC_PI_2 + ROUND;
    let k = shifted - ROUND;
    // `shifted` = 1.5·2²³ + k has the unit in its last mantissa place, and 1.5·2²³ is a
    // multiple of 4: its low two bits are k mod 4, with no float-to-integer conversion (a
    // saturating one is a library call and three comparisons on CPUs without
    // floating-point hardware).
    (shifted.to_bits() & 3, (x - k * PIO2_HI) - k * PIO2_LO)
}

/// `(sin x, cos x)` from those of the reduced argument in quadrant `k` (mod 4).
fn quadrant(k: u32, sin: f32, cos: f32) -> (f32, f32) {
    // (sin, cos), (cos, −sin), (−sin, −cos), (−cos, sin) for k = 0, 1, 2, 3: swapped for
    // odd k, the first negated for k = 2, 3, the second for k = 1, 2 (sign bits flipped,
    // exactly the negation).
    let (a, b) = if k & 1 == 0 { (sin, cos) } else { (cos, sin) };
    (
        f32::from_bits(a.to_bits() ^ ((k & 2) << 30)),
        f32::from_bits(b.to_bits() ^ ((k.wrapping_add(1) & 2) << 30)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use crate::math::poly;
    use crate::math::test_support::{worst_atan2_error, ATAN2_DEG9_TOL_RAD, ATAN2_FIXED_TOL_RAD};
    use crate::math::SoftFloat;

    #[test]
    fn atan2_deg9_matches_f64_everywhere() {
        let worst = worst_atan2_error(atan2_deg9);
        assert!(worst < ATAN2_DEG9_TOL_RAD, "worst atan2_deg9 error {worst}");
        // A dense sweep of t = y/x in the first octant, where the polynomial is evaluated.
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let t = i as f32 / 100_000.0;
            let d = (atan2_deg9(t, 1.0) as f64 - (t as f64).atan()).abs();
            worst = worst.max(d);
        }
        assert!(worst < ATAN2_DEG9_TOL_RAD, "worst atan_deg9 error {worst}");
    }
    #[test]
    fn polynomial_atan2_signed_zeros_and_axes_match_libm() {
        let cases = [
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
            (1.0, -1.0),
            (-1.0, 1.0),
        ];
        for (y, x) in cases {
            let want = libm::atan2f(y, x);
            for (name, got, tol) in [
                ("deg15", poly::atan2_deg15(y, x), 3.0e-7),
                ("deg9", poly::atan2_deg9(y, x), ATAN2_DEG9_TOL_RAD as f32),
                (
                    "fixed",
                    poly::atan2_fixed::<SoftFloat>(y, x),
                    ATAN2_FIXED_TOL_RAD as f32,
                ),
            ] {
                assert!(
                    (got - want).abs() < tol,
                    "{name} atan2({y}, {x}) = {got}, libm {want}"
                );
                assert_eq!(
                    got.is_sign_negative(),
                    want.is_sign_negative(),
                    "{name} atan2({y}, {x})"
                );
            }
        }
        // Exact on the axes.
        assert_eq!(atan2_deg9(0.0, -1.0), PI);
        assert_eq!(atan2_deg9(1.0, 0.0), FRAC_PI_2);
        assert_eq!(atan2_deg9(-1.0, 0.0), -FRAC_PI_2);
        assert_eq!(atan2_fixed::<SoftFloat>(0.0, -1.0), PI);
        assert_eq!(atan2_fixed::<SoftFloat>(1.0, 0.0), FRAC_PI_2);
        assert_eq!(atan2_fixed::<SoftFloat>(-1.0, 0.0), -FRAC_PI_2);
    }
    #[test]
    fn sin_cos_deg5_matches_f64() {
        let mut worst = 0.0f64;
        for i in -40_000..=40_000 {
            let x = i as f32 * 0.00025; // ±10 rad, across the ±π/4 switch
            let (s, c) = poly::sin_cos_deg5(x);
            worst = worst
                .max((s as f64 - (x as f64).sin()).abs())
                .max((c as f64 - (x as f64).cos()).abs());
        }
        assert!(worst < 7.0e-7, "worst sin/cos error {worst}");
        // Both sides of π/4 agree (the reduction is skipped on one side only).
        let q = core::f32::consts::FRAC_PI_4;
        let (below, above) = (
            f32::from_bits(q.to_bits() - 1),
            f32::from_bits(q.to_bits() + 1),
        );
        for x in [below, q, above, -below, -q, -above] {
            let (s, c) = poly::sin_cos_deg5(x);
            assert!((s as f64 - (x as f64).sin()).abs() < 7.0e-7, "sin {x}");
            assert!((c as f64 - (x as f64).cos()).abs() < 7.0e-7, "cos {x}");
        }
        assert_eq!(sin_cos_deg5(0.0), (0.0, 1.0));
    }
}
