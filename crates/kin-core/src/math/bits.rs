//! Float comparisons as integer comparisons of the bit patterns, with the semantics of the
//! float operators (NaN included): [`SoftFloat`](super::SoftFloat)'s comparisons.

/// Bits of +∞; larger patterns with a clear sign bit are NaNs.
pub(super) const INF: u32 = 0x7f80_0000;

/// `x > 0.0`: the patterns `1 ..= INF` (positive subnormals to +∞).
pub(super) fn gt_zero(x: f32) -> bool {
    x.to_bits().wrapping_sub(1) < INF
}

/// `a < b` for `a`, `b` with a clear sign bit or NaN: non-negative floats order as
/// their patterns; a NaN `b` (pattern above INF, or sign set) fails the second test, a
/// NaN `a` the first.
pub(super) fn lt_nonneg(a: f32, b: f32) -> bool {
    let (a, b) = (a.to_bits(), b.to_bits());
    a < b && b <= INF
}

/// A key that orders non-NaN floats as `<` does, with −0 = +0 (sign–magnitude to
/// two's complement); positive NaNs sort above +∞, negative NaNs below −∞.
pub(super) const fn key(x: f32) -> i32 {
    let b = x.to_bits() as i32;
    if b < 0 {
        i32::MIN.wrapping_sub(b)
    } else {
        b
    }
}

/// Keys `(lo, hi)` of a closed interval for [`within`]; an interval with a NaN bound
/// admits nothing, as the float comparisons do.
#[inline]
pub(super) const fn interval(lo: f32, hi: f32) -> (i32, i32) {
    const fn nan(v: f32) -> bool {
        v.to_bits() & 0x7fff_ffff > INF
    }
    if nan(lo) || nan(hi) {
        (i32::MAX, i32::MIN)
    } else {
        (key(lo), key(hi))
    }
}

/// `lo <= x && x <= hi` for the keys of [`interval`] (a NaN `x` fails one of the two).
pub(super) fn within(x: f32, (lo, hi): (i32, i32)) -> bool {
    let k = key(x);
    lo <= k && k <= hi
}

#[cfg(test)]
mod tests {
    use seeded_rng::SplitMix64;
    extern crate std;
    use crate::math::{
        bits, finite, finite_ordered, interval_keys, nonneg_finite, positive_finite, Fast, Libm,
        Math, SoftFloat,
    };
    use std::vec;

    /// [`SoftFloat`]'s integer comparisons equal the float operators on special values and on
    /// random bit patterns (NaNs of both signs included).
    #[test]
    fn bit_comparisons_equal_float_comparisons() {
        let mut vals = vec![
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::from_bits(0x8000_0001),
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7f80_0001),
            f32::from_bits(0xff80_0001),
            f32::from_bits(0x7fff_ffff),
            f32::from_bits(0xffff_ffff),
        ];
        let mut rng = SplitMix64::new(0x9e37_79b9_7f4a_7c15u64);
        for _ in 0..300 {
            let state = rng.next_u64();
            vals.push(f32::from_bits((state >> 32) as u32));
        }
        for &a in &vals {
            assert_eq!(bits::gt_zero(a), a > 0.0, "{a:e} > 0");
            assert_eq!(finite(a), a.is_finite(), "finite {a:e}");
            assert_eq!(
                positive_finite(a),
                a.is_finite() && a > 0.0,
                "0 < {a:e} < inf"
            );
            assert_eq!(
                nonneg_finite(a),
                a.is_finite() && a >= 0.0,
                "0 <= {a:e} < inf"
            );
            for &b in &vals {
                let nonneg = |v: f32| v.is_sign_positive() || v.is_nan();
                assert_eq!(
                    finite_ordered(a, b),
                    a.is_finite() && b.is_finite() && a <= b,
                    "{a:e} <= {b:e}, finite"
                );
                if nonneg(a) && nonneg(b) {
                    assert_eq!(bits::lt_nonneg(a, b), a < b, "{a:e} < {b:e}");
                }
                for &x in vals.iter().step_by(7) {
                    assert_eq!(
                        bits::within(x, bits::interval(a, b)),
                        x >= a && x <= b,
                        "{a:e} <= {x:e} <= {b:e}"
                    );
                    let keys = interval_keys(a, b);
                    assert_eq!(
                        SoftFloat::<Libm>::within_keys(x, a, b, keys),
                        x >= a && x <= b,
                        "{a:e} <= {x:e} <= {b:e}, keys"
                    );
                    assert_eq!(
                        Fast::within_keys(x, a, b, keys),
                        x >= a && x <= b,
                        "{a:e} <= {x:e} <= {b:e}, default"
                    );
                }
            }
        }
    }
}
