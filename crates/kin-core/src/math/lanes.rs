//! Lane forms of [`Fast`](super::Fast)'s kernels for the batch solves ([`crate::batch`]): the
//! same operations in the same order as the scalar kernels, bit for bit, written so that the
//! compiler vectorises a loop over the lanes (selects instead of table reads, no calls it
//! cannot see through).

use super::{poly, FRAC_PI_2, PI};

const SIGN: u32 = 0x8000_0000;

/// [`poly::atan2_deg15`] of every lane. The scalar kernel reads its octant's offset from a
/// 4-entry table (a select there becomes a branch); across lanes a table read is a gather,
/// which x86-64's baseline lacks, so here the offset is selected by masks: the same value,
/// so the same bits.
#[inline]
pub(super) fn atan2_deg15_lanes<const N: usize>(y: &[f32; N], x: &[f32; N]) -> [f32; N] {
    let mut out = [0.0; N];
    for ((o, &y), &x) in out.iter_mut().zip(y).zip(x) {
        *o = atan2_deg15_select(y, x);
    }
    out
}

/// [`poly::atan2_deg15`] with the octant's offset by masks instead of a table.
#[inline]
fn atan2_deg15_select(y: f32, x: f32) -> f32 {
    let ax = libm::fabsf(x);
    let ay = libm::fabsf(y);
    let num = if ay < ax { ay } else { ax };
    let den = if ay > ax { ay } else { ax };
    let t = num / den;
    let t = if t > 0.0 { t } else { 0.0 };
    let swap = (ay > ax) as u32;
    let x_neg = x.to_bits() >> 31;
    let y_sign = y.to_bits() & SIGN;
    let t_sign = ((swap ^ x_neg) << 31) ^ y_sign;
    // The table [0, π, π/2, π/2] at (swap << 1) | x_neg: π/2 when swapped, else π when x < 0,
    // else 0.
    let swap_mask = swap.wrapping_neg();
    let x_neg_mask = x_neg.wrapping_neg();
    let offset_bits =
        (swap_mask & FRAC_PI_2.to_bits()) | (!swap_mask & x_neg_mask & PI.to_bits()) | y_sign;
    f32::from_bits(offset_bits) + poly::atan_deg15(f32::from_bits(t.to_bits() ^ t_sign))
}

/// `libm::sqrtf` of every lane: IEEE square roots, correctly rounded either way, so the same
/// bits. On x86-64 by `sqrtps`, four lanes at a time (the compiler joins two into one AVX
/// instruction where the caller is compiled for AVX): libm's square root there is an inline
/// `sqrtss` that the vectoriser cannot see through, and stable `no_std` Rust has no other
/// square root that it can.
#[inline]
pub(super) fn sqrt_lanes<const N: usize>(x: &[f32; N]) -> [f32; N] {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_loadu_ps, _mm_sqrt_ps, _mm_storeu_ps};
        let mut out = [0.0f32; N];
        let (ins, outs) = (x.chunks_exact(4), out.chunks_exact_mut(4));
        for (i, o) in ins.zip(outs) {
            // SAFETY: SSE is part of x86-64's baseline; `i` and `o` are 4 floats long, which
            // the unaligned load and store read and write.
            #[allow(unsafe_code)]
            unsafe {
                _mm_storeu_ps(o.as_mut_ptr(), _mm_sqrt_ps(_mm_loadu_ps(i.as_ptr())));
            }
        }
        for k in N - N % 4..N {
            out[k] = libm::sqrtf(x[k]);
        }
        out
    }
    #[cfg(not(target_arch = "x86_64"))]
    core::array::from_fn(|i| libm::sqrtf(x[i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use seeded_rng::SplitMix64;

    #[test]
    fn sqrt_lanes_equal_libm_bit_for_bit() {
        let mut rng = SplitMix64::new(0x5c47);
        for _ in 0..100_000 {
            let x: [f32; 7] =
                core::array::from_fn(|_| f32::from_bits(rng.next_u64() as u32 & 0x7fff_ffff));
            let got = sqrt_lanes(&x);
            for (g, v) in got.iter().zip(x) {
                let want = libm::sqrtf(v);
                assert!(
                    g.to_bits() == want.to_bits() || (g.is_nan() && want.is_nan()),
                    "{v}"
                );
            }
        }
        let special = [
            0.0f32,
            -0.0,
            f32::INFINITY,
            f32::MIN_POSITIVE,
            1e-45,
            f32::MAX,
            -1.0,
            f32::NAN,
        ];
        let got = sqrt_lanes(&special);
        for (g, v) in got.iter().zip(special) {
            let want = libm::sqrtf(v);
            assert!(
                g.to_bits() == want.to_bits() || (g.is_nan() && want.is_nan()),
                "{v}"
            );
        }
    }

    #[test]
    fn atan2_lanes_equal_the_scalar_kernel_bit_for_bit() {
        let special = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            3e38,
            -3e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut rng = SplitMix64::new(0x1a2e_5a7a);
        let mut ys = [0.0f32; 8];
        let mut xs = [0.0f32; 8];
        let check = |ys: &[f32; 8], xs: &[f32; 8]| {
            let got = atan2_deg15_lanes(ys, xs);
            for i in 0..8 {
                let want = poly::atan2_deg15(ys[i], xs[i]);
                assert!(
                    got[i].to_bits() == want.to_bits() || (got[i].is_nan() && want.is_nan()),
                    "atan2({}, {}): {} vs {}",
                    ys[i],
                    xs[i],
                    got[i],
                    want
                );
            }
        };
        for (k, &a) in special.iter().enumerate() {
            for (j, &b) in special.iter().enumerate() {
                ys[(k + j) % 8] = a;
                xs[(k + j) % 8] = b;
                check(&ys, &xs);
            }
        }
        for _ in 0..200_000 {
            for i in 0..8 {
                let bits = rng.next_u64();
                // Half the lanes random bit patterns, half ordinary magnitudes.
                if bits & 1 == 0 {
                    ys[i] = f32::from_bits((bits >> 32) as u32);
                    xs[i] = f32::from_bits(bits as u32);
                } else {
                    ys[i] = ((bits >> 40) as f32 / (1u64 << 23) as f32) - 1.0;
                    xs[i] = ((bits >> 8) as u32 as f32 / u32::MAX as f32) * 2.0 - 1.0;
                }
            }
            check(&ys, &xs);
        }
    }
}
