//! The default backend, for hosts with floating-point hardware.

use super::{lanes, poly, Math};

/// Polynomial backend for hosts: [`poly::atan2_deg15`], [`poly::sin_cos_deg9`], `libm` for
/// `sqrt` (one instruction on hosts). It keeps the default [`Math::atan2_3`]: the compiler
/// schedules (and partly vectorizes) the independent scalar calls faster than an explicit
/// four-lane `atan2` on the measured x86-64 host (see `docs/benchmark-journal.md`), and the
/// float operators for comparisons.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fast;

impl Math for Fast {
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        poly::atan2_deg15(y, x)
    }

    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        poly::sin_cos_deg9(x)
    }

    #[inline]
    fn atan2_lanes<const N: usize>(y: &[f32; N], x: &[f32; N]) -> [f32; N] {
        lanes::atan2_deg15_lanes(y, x)
    }

    #[inline]
    fn sqrt_lanes<const N: usize>(x: &[f32; N]) -> [f32; N] {
        lanes::sqrt_lanes(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use seeded_rng::SplitMix64;
    extern crate std;
    use crate::math::test_support::worst_atan2_error;
    use crate::math::{Libm, FRAC_PI_2, PI};
    use std::vec;

    #[test]
    fn fast_atan2_matches_f64_everywhere() {
        let worst = worst_atan2_error(Fast::atan2);
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
    /// `atan2_3` returns exactly three `atan2` calls, including
    /// signed zeros, axes, tiny and huge arguments and NaN-free degenerate pairs.
    #[test]
    fn fast_atan2_3_is_three_atan2_bit_for_bit() {
        let mut vals = vec![
            0.0f32, -0.0, 1.0, -1.0, 1e-30, -1e-30, 3e30, -3e30, 0.5, -2.5,
        ];
        let mut rng = SplitMix64::new(0x1234_5678_9abc_def0u64);
        for _ in 0..200 {
            let state = rng.next_u64();
            vals.push((state >> 40) as f32 / (1u64 << 23) as f32 - 1.0);
        }
        let bits = |a: [f32; 3]| a.map(f32::to_bits);
        for (i, &a) in vals.iter().enumerate() {
            for (j, &b) in vals.iter().enumerate() {
                let c = vals[(i * 7 + j * 3) % vals.len()];
                let d = vals[(i + j * 11) % vals.len()];
                let (y, x) = ([a, c, b], [b, d, a]);
                let want = [0, 1, 2].map(|k| Fast::atan2(y[k], x[k]));
                assert_eq!(bits(Fast::atan2_3(y, x)), bits(want), "y {y:?} x {x:?}");
                assert_eq!(
                    bits(Libm::atan2_3(y, x)),
                    bits([0, 1, 2].map(|k| Libm::atan2(y[k], x[k])))
                );
            }
        }
    }
}
