//! The fixed-point kernels for CPUs without floating-point hardware.

use super::cells::{join, ATAN_CELLS, SIN_COS_CELLS};
use super::{quadrant, reduce, ABS, SIGN};
use crate::math::{Math, TableEntry};

/// `a·b` of two 16-bit numbers from its four 8 × 8-bit partial products: on the
/// ATmega2560 four hardware multiplications inline, where `a as u32 * b as u32` would call
/// a 32 × 32-bit routine. Only the fixed-point kernels use it, those of CPUs without
/// floating-point hardware, so every target compiles this one form.
fn mul_16x16(a: u16, b: u16) -> u32 {
    let (a0, a1, b0, b1) = (a as u8 as u16, a >> 8, b as u8 as u16, b >> 8);
    let mid = (a0 * b1) as u32 + (a1 * b0) as u32;
    (a0 * b0) as u32 + (mid << 8) + (((a1 * b1) as u32) << 16)
}

/// Four-quadrant arctangent for CPUs without hardware floating point: the exact integer
/// quotient `t = min(|x|,|y|) / max(|x|,|y|)` of the two floats' mantissas
/// ([`atan_ratio_q21`]), then atan(t) from a table of 32 quadratic cells
/// (`ATAN_CELL_A_Q29`) in 16-bit fixed point (three 16 × 16-bit products), the octant
/// added in fixed point, and one integer-to-float conversion: on the ATmega2560 far fewer
/// cycles than [`atan2_deg9`](super::atan2_deg9) in software floats (see `docs/benchmark-journal.md`). Absolute
/// error ≤ 2e-6 rad (tests; the cells' 9.4e-7 plus the truncation of `t` to 2⁻²¹ and the
/// rounding of the result). `atan2(±0, ±0)` as libm (±0 or ±π); exact on the axes. The
/// backend `M` reads the tables ([`Math::read_table_cell`]: in flash on the AVR), the
/// kernel's only per-target part; [`SoftFloat`](crate::math::SoftFloat) passes its own.
///
/// Formats: `t` in Q21 (`T = ⌊t·2²¹⌋`, exact: no float rounding, so that a backend's own
/// implementation ([`Math::atan2_fixed`]) can match it bit for bit), the cell offset `d`
/// in Q21, the result in Q29 (π < 2²).
///
/// Never inlined: on the AVR its `mul` instructions stay in this function's own small stack
/// frame, clear of an LLVM AVR miscompilation in frames beyond the reach of a short
/// displacement (see the firmware's emulator test
/// `no_mul_result_is_clobbered_by_a_frame_pointer_adjustment`); hosts do not use this kernel
/// in their backends, so the call costs them nothing.
#[inline(never)]
pub fn atan2_fixed<M: Math + ?Sized>(y: f32, x: f32) -> f32 {
    const FRAC_PI_2_Q29: u32 = 843_314_857; // round(π/2 · 2²⁹)
    const PI_Q29: u32 = 1_686_629_713; // round(π · 2²⁹)
    let (yb, xb) = (y.to_bits(), x.to_bits());
    let (ay, ax) = (yb & ABS, xb & ABS);
    let swap = ay > ax;
    let (num, den) = if swap { (ax, ay) } else { (ay, ax) };
    // The octant in one byte (swap, x < 0, y < 0): fewer registers to keep.
    let octant = swap as u8 | ((xb >> 30) as u8 & 2) | ((yb >> 29) as u8 & 4);
    // p = atan(t) in Q29, t ∈ [0, 1].
    let p: u32 = if den == 0 {
        0
    } else {
        let big_t = atan_ratio_q21(num, den);
        // Cell k = ⌊32·t⌋ (t = 1: cell 32) and the offset d = t − k/32 in Q21 (16 bits).
        let k = (big_t >> 16) as usize;
        let d = big_t as u16;
        // b·d: Q36 → Q29; d² in Q26; c·d²: Q42 → Q29 (below b·d for d < 1/32).
        let [a_lo, a_hi, b, c] = M::read_table_cell(ATAN_CELLS.entry(k));
        let lin = (mul_16x16(d, b) + (1 << 6)) >> 7;
        let d_sq = (mul_16x16(d, d) >> 16) as u16;
        let quad = (mul_16x16(d_sq, c) + (1 << 12)) >> 13;
        join(a_lo, a_hi) + lin - quad
    };
    let r = match octant & 3 {
        0 => p,
        2 => PI_Q29 - p,
        1 => FRAC_PI_2_Q29 - p,
        _ => FRAC_PI_2_Q29 + p,
    };
    // r ≥ 0; r·2⁻²⁹ by the exponent (r = 0 stays 0), then the sign of y.
    let r = if r == 0 {
        0
    } else {
        (r as f32).to_bits() - (29 << 23)
    };
    f32::from_bits(r | ((octant as u32 & 4) << 29))
}

/// The first of [`atan2_fixed`]'s 33 cells `[a_lo, a_hi, b, c]` (cell `k` is `k` rows
/// further, contiguous), for a backend's own form of the kernel ([`Math::atan2_fixed`]);
/// read like any cell ([`Math::read_table_cell`]: in program memory on the AVR).
pub fn atan_cells() -> TableEntry<[u16; 4]> {
    ATAN_CELLS.entry(0)
}

/// [`atan2_fixed`]'s quotient `T = ⌊t·2²¹⌋` of `t = num / den`, exact, from the bits
/// `num ≤ den` of two non-negative floats, `den ≠ 0` (so `T ≤ 2²¹`): the 24-bit mantissas
/// (subnormals without the implicit one, at exponent 1) divided,
/// `T = ⌊mₙ·2²¹ / m_d⌋ >> (e_d − eₙ)`. `den` infinite: `T = 2²¹` (t = 1) when `num` is
/// infinite too, else 0; a NaN gives some `T ≤ 2²¹`. Integer arithmetic only, so that a
/// backend's own form of the kernel ([`Math::atan2_fixed`]) can equal it bit for bit,
/// which a float division's rounding would make harder.
pub fn atan_ratio_q21(num: u32, den: u32) -> u32 {
    const INF: u32 = 0x7f80_0000;
    if den >= INF {
        return if num >= INF { 1 << 21 } else { 0 };
    }
    let (en, ed) = (num >> 23, den >> 23);
    let implicit = |e: u32| if e == 0 { 0 } else { 1 << 23 };
    let mn = (num & 0x7f_ffff) | implicit(en);
    let md = (den & 0x7f_ffff) | implicit(ed);
    // mn < 2·md (md ≥ 2²³ or, den subnormal, mn ≤ md): q < 2²², so a shift of 22 or
    // more leaves 0.
    let q = ((mn as u64) << 21) / md as u64;
    let shift = ed.max(1) - en.max(1);
    if shift >= 22 {
        0
    } else {
        (q >> shift) as u32
    }
}

/// `(sin x, cos x)` for CPUs without hardware floating point: arguments within ±π/4 (body
/// rotations) skip the range reduction (an integer comparison finds them); then `|r|` in
/// Q24 from the float's mantissa, sine and cosine from a table of 26 quadratic cells
/// (`SIN_CELL_A_Q29`, `COS_CELL_A_Q29`) in 16-bit fixed point (five 16 × 16-bit
/// products for both), two integer-to-float conversions: on the ATmega2560 far fewer
/// cycles than [`sin_cos_deg5`](super::sin_cos_deg5)'s twelve software-float operations (see
/// `docs/benchmark-journal.md`). Absolute error ≤ 1e-6 (tests; the cells' 8.4e-7 in this
/// arithmetic).
/// `sin_cos_fixed(0) = (0, 1)`; odd in the sine, even in the cosine. The backend `M` reads
/// the tables, as for [`atan2_fixed`].
///
/// Never inlined, for [`atan2_fixed`]'s reason (its `mul` instructions in a small frame).
/// In two parts, so that a backend can supply the fixed-point part in its own form
/// ([`Math::sin_cos_fixed`]): the range reduction and quadrant ([`sin_cos_fixed_with`])
/// around the cells ([`sin_cos_fixed_core`]).
#[inline(never)]
pub fn sin_cos_fixed<M: Math + ?Sized>(x: f32) -> (f32, f32) {
    sin_cos_fixed_with(x, sin_cos_fixed_core::<M>)
}

/// [`sin_cos_fixed`] with the fixed-point part `core`, which maps the bits of the reduced
/// argument `r` (`|r| ≤ π/4` and the rounding of the reduction; any bits for NaN and
/// infinite `x`) to those of `(sin r, cos r)`: [`sin_cos_fixed_core`], or a backend's own
/// form of it, bit for bit the same ([`Math::sin_cos_fixed`]).
///
/// The range reduction is out of line (`sin_cos_fixed_reduced`): the common case, within
/// ±π/4, then keeps none of its registers.
pub fn sin_cos_fixed_with<F: FnOnce(u32) -> (u32, u32)>(x: f32, core: F) -> (f32, f32) {
    const FRAC_PI_4_BITS: u32 = 0x3f49_0fdb; // π/4 rounded to f32
    if x.to_bits() & ABS > FRAC_PI_4_BITS {
        sin_cos_fixed_reduced(x, core)
    } else {
        let (sin, cos) = core(x.to_bits());
        (f32::from_bits(sin), f32::from_bits(cos))
    }
}

/// [`sin_cos_fixed_with`] beyond ±π/4: the range reduction, `core`, the quadrant.
///
/// A NaN or infinite `x` takes `core`'s value for the quiet NaN in quadrant 0: the
/// reduction would turn it into a NaN whose payload (and so the quadrant read from its low
/// bits) is the software-float library's choice, which differs between avr-libc and a
/// host; this way every target gives the same bounded bits.
// Out of line: the common case keeps none of its registers (`BENCHMARKS.md`, `sin_cos_fixed`).
#[inline(never)]
fn sin_cos_fixed_reduced<F: FnOnce(u32) -> (u32, u32)>(x: f32, core: F) -> (f32, f32) {
    if !crate::math::finite(x) {
        let (sin, cos) = core(f32::NAN.to_bits());
        return (f32::from_bits(sin), f32::from_bits(cos));
    }
    let (k, r) = reduce(x);
    let (sin, cos) = core(r.to_bits());
    quadrant(k, f32::from_bits(sin), f32::from_bits(cos))
}

/// The bits of `(sin r, cos r)` from those of `r` (`rb`), [`sin_cos_fixed`]'s fixed-point
/// part: `|r|` in Q24 from the float's mantissa, truncated, clamped to the end of the
/// cells; cell `k = ⌊32·|r|⌋` ([`sin_cos_cells`]) and offset `d` in Q21; five 16 × 16-bit
/// products, each rounded as below; two integer-to-float conversions, correctly rounded,
/// and the sign of `r` on the sine. Integer arithmetic only, so that a backend's own form
/// ([`Math::sin_cos_fixed`]) can equal it bit for bit.
pub fn sin_cos_fixed_core<M: Math + ?Sized>(rb: u32) -> (u32, u32) {
    // The end of the cells, 26/32 in Q24 (less one): beyond it only the results of a
    // range reduction of huge arguments, for which any bounded value will do.
    const CELLS_END_Q24: u32 = (26 << 19) - 1;
    // |r| = m·2^(e − 150) with the 24-bit mantissa m: R = |r|·2²⁴ = m >> (126 − e),
    // truncated (2⁻²⁴ is far below the cells' error); 0 for |r| < 2⁻²⁴ and subnormals.
    let e = (rb >> 23) & 0xff;
    let m = (rb & 0x007f_ffff) | 0x0080_0000;
    let big_r = if e > 126 {
        CELLS_END_Q24
    } else if 126 - e > 24 {
        0
    } else {
        (m >> (126 - e)).min(CELLS_END_Q24)
    };
    // Cell k = ⌊32·|r|⌋, offset d in Q21 (16 bits), d² in Q26.
    let cell = (big_r >> 19) as usize;
    let d = ((big_r & 0x7_ffff) >> 3) as u16;
    let d_sq = (mul_16x16(d, d) >> 16) as u16;
    // b·d: Q36 (sine) or Q37 (cosine) → Q29; c·d²: Q42 → Q29.
    let [sa_lo, sa_hi, sb, sc, ca_lo, ca_hi, cb, cc] =
        M::read_table_cell(SIN_COS_CELLS.entry(cell));
    let sin_q = join(sa_lo, sa_hi) + ((mul_16x16(d, sb) + (1 << 6)) >> 7)
        - ((mul_16x16(d_sq, sc) + (1 << 12)) >> 13);
    let cos_q = join(ca_lo, ca_hi)
        - ((mul_16x16(d, cb) + (1 << 7)) >> 8)
        - ((mul_16x16(d_sq, cc) + (1 << 12)) >> 13);
    (q29_bits(sin_q) | (rb & SIGN), q29_bits(cos_q))
}

/// The first of [`sin_cos_fixed`]'s 26 cells `[sa_lo, sa_hi, sb, sc, ca_lo, ca_hi, cb, cc]`
/// (the sine's `[a_lo, a_hi, b, c]`, then the cosine's; cell `k` is `k` rows further,
/// contiguous), for a backend's own form of [`sin_cos_fixed_core`]; read like any cell
/// ([`Math::read_table_cell`]: in program memory on the AVR).
pub fn sin_cos_cells() -> TableEntry<[u16; 8]> {
    SIN_COS_CELLS.entry(0)
}

/// The bits of the float `v·2⁻²⁹` (`v < 2³¹`, positive): one integer-to-float conversion,
/// then the exponent lowered by 29 (`v = 0` stays +0).
fn q29_bits(v: u32) -> u32 {
    if v == 0 {
        0
    } else {
        (v as f32).to_bits() - (29 << 23)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use seeded_rng::SplitMix64;
    extern crate std;
    use crate::math::test_support::{worst_atan2_error, ATAN2_FIXED_TOL_RAD};
    use crate::math::{poly, SoftFloat};

    #[test]
    fn atan2_fixed_matches_f64_everywhere() {
        let worst = worst_atan2_error(poly::atan2_fixed::<SoftFloat>);
        assert!(
            worst < ATAN2_FIXED_TOL_RAD,
            "worst atan2_fixed error {worst}"
        );
        let mut worst = 0.0f64;
        let mut t = 1.0e-12f32;
        while t < 1.0 {
            let d = (poly::atan2_fixed::<SoftFloat>(t, 1.0) as f64 - (t as f64).atan()).abs();
            worst = worst.max(d);
            t *= 1.001;
        }
        for i in 0..=200_000 {
            let t = i as f32 / 200_000.0;
            for (y, x) in [(t, 1.0f32), (1.0, t), (-t, -1.0), (-1.0, t * 3.0)] {
                let d = (poly::atan2_fixed::<SoftFloat>(y, x) as f64 - (y as f64).atan2(x as f64))
                    .abs();
                worst = worst.max(d);
            }
        }
        assert!(
            worst < ATAN2_FIXED_TOL_RAD,
            "worst atan2_fixed error {worst}"
        );
        // No panic (debug overflow checks) and a finite result on any bit pattern but NaN.
        let mut rng = SplitMix64::new(0x2545_f491_4f6c_dd1du64);
        for _ in 0..100_000 {
            let state = rng.next_u64();
            let (y, x) = (
                f32::from_bits(state as u32),
                f32::from_bits((state >> 32) as u32),
            );
            let r = poly::atan2_fixed::<SoftFloat>(y, x);
            if !(y.is_nan() || x.is_nan() || (y.is_infinite() && x.is_infinite())) {
                let want = (y as f64).atan2(x as f64);
                assert!(
                    (r as f64 - want).abs() < ATAN2_FIXED_TOL_RAD,
                    "atan2_fixed({y:e}, {x:e}) = {r}"
                );
            }
        }
    }

    /// [`poly::atan_ratio_q21`]: exact at its edges (infinities, subnormals, equal
    /// magnitudes, the smallest ratios) and against the exact rational quotient elsewhere.
    #[test]
    fn atan_ratio_q21_is_the_exact_floor() {
        use poly::atan_ratio_q21 as ratio;
        let inf = f32::INFINITY.to_bits();
        assert_eq!(ratio(inf, inf), 1 << 21);
        assert_eq!(ratio(f32::MAX.to_bits(), inf), 0);
        assert_eq!(ratio(0, inf), 0);
        assert_eq!(ratio(1, 1), 1 << 21);
        assert_eq!(ratio(1, 2), 1 << 20);
        assert_eq!(ratio(12, 0x0080_0000), 3);
        assert_eq!(ratio(0x0040_0000, 0x0080_0000), 1 << 20);
        assert_eq!(ratio(1.0f32.to_bits(), 2.0f32.to_bits()), 1 << 20);
        assert_eq!(ratio(1.0f32.to_bits(), 2.0f32.powi(21).to_bits()), 1);
        assert_eq!(ratio(0.99f32.to_bits(), 2.0f32.powi(21).to_bits()), 0);
        assert_eq!(ratio(0, 1.0f32.to_bits()), 0);
        // The value of a finite float's bits as mantissa · 2^(exponent − 150).
        let parts = |b: u32| {
            let e = b >> 23;
            let m = (b & 0x7f_ffff) | if e == 0 { 0 } else { 1 << 23 };
            (m as u128, e.max(1) as i32)
        };
        let mut rng = SplitMix64::new(0x0a7a_2f1d);
        for _ in 0..200_000 {
            let state = rng.next_u64();
            let (a, b) = (
                state as u32 & 0x7fff_ffff,
                (state >> 32) as u32 & 0x7fff_ffff,
            );
            let b = b >> (state as u32 >> 27); // wide exponent differences
            let (num, den) = (a.min(b), a.max(b));
            if den == 0 || den >= inf {
                continue;
            }
            let ((mn, en), (md, ed)) = (parts(num), parts(den));
            let s = (ed - en) as u32;
            // ⌊mn·2²¹ / (md·2^s)⌋ in 128-bit integers (s < 106 here, else 0).
            let want = if s > 100 {
                0
            } else {
                ((mn << 21) / (md << s)) as u32
            };
            assert_eq!(ratio(num, den), want, "{num:#x} / {den:#x}");
        }
    }

    /// [`poly::atan2_fixed`]'s cells: the tight bound of its documentation, on the circle,
    /// densely over `t` in every cell, and at the cells' edges.
    #[test]
    fn atan2_fixed_cells_are_within_2e_6() {
        const TOL_RAD: f64 = 2.0e-6;
        let mut worst = worst_atan2_error(poly::atan2_fixed::<SoftFloat>);
        for i in 0..=400_000 {
            let t = i as f32 / 400_000.0;
            for (y, x) in [(t, 1.0f32), (1.0, t), (-t, -1.0), (-1.0, -t)] {
                let d = (poly::atan2_fixed::<SoftFloat>(y, x) as f64 - (y as f64).atan2(x as f64))
                    .abs();
                worst = worst.max(d);
            }
        }
        for k in 0..=32u32 {
            let edge = k as f32 / 32.0;
            for t in [
                f32::from_bits(edge.to_bits().saturating_sub(1)),
                edge,
                f32::from_bits(edge.to_bits() + 1).min(1.0),
            ] {
                let d = (poly::atan2_fixed::<SoftFloat>(t, 1.0) as f64 - (t as f64).atan()).abs();
                worst = worst.max(d);
            }
        }
        std::eprintln!("atan2_fixed: worst error {worst:e} rad");
        assert!(worst < TOL_RAD, "worst atan2_fixed error {worst}");
    }
    #[test]
    fn sin_cos_fixed_matches_f64() {
        const TOL: f64 = 1.0e-6;
        let mut worst = 0.0f64;
        for i in -400_000..=400_000 {
            let x = i as f32 * 0.000_025; // ±10 rad, across the ±π/4 switch and every cell
            let (s, c) = poly::sin_cos_fixed::<SoftFloat>(x);
            worst = worst
                .max((s as f64 - (x as f64).sin()).abs())
                .max((c as f64 - (x as f64).cos()).abs());
            assert_eq!(
                poly::sin_cos_fixed::<SoftFloat>(-x),
                (-s, c),
                "odd sine, even cosine at {x}"
            );
        }
        let q = core::f32::consts::FRAC_PI_4;
        for x in [
            f32::from_bits(q.to_bits() - 1),
            q,
            f32::from_bits(q.to_bits() + 1),
            1e-30,
            f32::MIN_POSITIVE,
            1e-7,
        ] {
            let (s, c) = poly::sin_cos_fixed::<SoftFloat>(x);
            worst = worst
                .max((s as f64 - (x as f64).sin()).abs())
                .max((c as f64 - (x as f64).cos()).abs());
        }
        std::eprintln!("sin_cos_fixed: worst error {worst:e}");
        assert!(worst < TOL, "worst sin/cos error {worst}");
        assert_eq!(poly::sin_cos_fixed::<SoftFloat>(0.0), (0.0, 1.0));
        // Bounded on any finite argument (huge ones are not reduced exactly).
        let mut rng = SplitMix64::new(0x5eed_5eed_0000_0001u64);
        for _ in 0..100_000 {
            let x = f32::from_bits(rng.next_u64() as u32);
            if x.is_finite() {
                let (s, c) = poly::sin_cos_fixed::<SoftFloat>(x);
                assert!(
                    s.abs() <= 1.0 && c.abs() <= 1.0,
                    "sin_cos_fixed({x:e}) = ({s}, {c})"
                );
            }
        }
    }

    /// The byte-wise 16 × 16-bit product is the product.
    #[test]
    fn byte_wise_product_is_the_product() {
        let mut rng = SplitMix64::new(0x0123_4567_89ab_cdefu64);
        for _ in 0..200_000 {
            let state = rng.next_u64();
            let (a, b) = (state as u16, (state >> 16) as u16);
            assert_eq!(mul_16x16(a, b), a as u32 * b as u32);
        }
        for (a, b) in [
            (0u16, 0u16),
            (65535, 65535),
            (65535, 1),
            (255, 256),
            (256, 256),
        ] {
            assert_eq!(mul_16x16(a, b), a as u32 * b as u32);
        }
    }
}
