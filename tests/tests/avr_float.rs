//! The firmware's float primitives `__addsf3`, `__subsf3` and `__mulsf3` (a fast path in
//! assembly in front of avr-libc's, `avr_libc_math::float`) against avr-libc's own path
//! (`__addsf3x` or `__mulsf3x`, then `__fp_round`), bit for bit, in simavr: both are
//! primitives of the benchmark firmware (`bench.elf`), run on the same seeded pairs — random
//! bit patterns; exponent differences 0 to 30 in both orders and with both signs
//! (cancellation); rounding ties and near-ties (mantissas with few significant bits);
//! results at the edges of overflow and underflow; signed zeros, subnormals, infinities and
//! NaNs; mantissas all ones or all zeros.
//!
//! For finite arguments avr-libc's results are also compared with the host's IEEE
//! single-precision ones; the differences are counted and printed, not asserted (the
//! firmware's primitives promise avr-libc's bits, not more).
//!
//! A second test checks that the firmware and the benchmark firmware link these routines, not
//! avr-libc's two-instruction wrappers (`addsf3.o`, `mulsf3.o` of `libm.a`).
//!
//! The firmware is built once per test process (`quad_host::emu::build`); the tests fail —
//! never skip — when it cannot be built.

use integration_tests::avr_bench::{primitive_op as op, BenchFirmware};
use integration_tests::symbols;
use quad_host::emu::build;
use seeded_rng::SplitMix64 as Rng;

/// Pairs compared per operation.
const PAIRS: usize = 100_000;

/// An operation compared: name, the firmware's primitive, avr-libc's, the host's.
type Operation = (
    &'static str,
    &'static str,
    &'static str,
    fn(f32, f32) -> f32,
);

/// The operations compared.
const OPERATIONS: [Operation; 3] = [
    ("add", "add", "avr-libc add", |a, b| a + b),
    ("sub", "sub", "avr-libc sub", |a, b| a - b),
    ("mul", "mul", "avr-libc mul", |a, b| a * b),
];

/// A number in `lo..=hi`.
fn int(rng: &mut Rng, lo: u32, hi: u32) -> u32 {
    lo + rng.below((hi - lo + 1) as u64) as u32
}

/// A mantissa (23 bits): random, all zeros, all ones, or with few significant bits (a random
/// number of trailing zeros: rounding ties and near-ties in sums and products).
fn mantissa(rng: &mut Rng) -> u32 {
    let bits = rng.next_u64() as u32 & 0x7f_ffff;
    match rng.below(8) {
        0 => 0,
        1 => 0x7f_ffff,
        2..=4 => {
            let zeros = int(rng, 0, 23);
            bits >> zeros << zeros
        }
        _ => bits,
    }
}

/// The float of the given biased exponent (clamped to 0..=255) and a mantissa from
/// [`mantissa`], with a random sign.
fn float(rng: &mut Rng, exponent: i32) -> f32 {
    let sign = (rng.next_u64() & 1) as u32;
    f32::from_bits(sign << 31 | (exponent.clamp(0, 255) as u32) << 23 | mantissa(rng))
}

/// One pair of a kind chosen at random (`mul`: the exponent edges are those of a product).
fn pair(rng: &mut Rng, mul: bool) -> (f32, f32) {
    let (a, b) = match rng.below(8) {
        // Any bit patterns.
        0 => (
            f32::from_bits(rng.next_u64() as u32),
            f32::from_bits(rng.next_u64() as u32),
        ),
        // Exponent differences 0 to 30 (with both signs: cancellation), the kinematics'
        // range and beyond.
        1..=3 => {
            let e = int(rng, 90, 160) as i32;
            let d = int(rng, 0, 30) as i32;
            (float(rng, e), float(rng, e - d))
        }
        // Anywhere in the normal range.
        4 => {
            let e = int(rng, 31, 254) as i32;
            let d = int(rng, 0, 30) as i32;
            (float(rng, e), float(rng, e - d))
        }
        // Near overflow.
        5 => {
            if mul {
                let ea = int(rng, 100, 254) as i32;
                let er = int(rng, 250, 256) as i32;
                (float(rng, ea), float(rng, er - ea + 127))
            } else {
                let e = int(rng, 248, 254) as i32;
                let d = int(rng, 0, 3) as i32;
                (float(rng, e), float(rng, e - d))
            }
        }
        // Near underflow, subnormals included.
        6 => {
            if mul {
                let ea = int(rng, 1, 150) as i32;
                let er = int(rng, 0, 30) as i32 - 25;
                (float(rng, ea), float(rng, er - ea + 127))
            } else {
                let e = int(rng, 0, 30) as i32;
                let d = int(rng, 0, 3) as i32;
                (float(rng, e), float(rng, e - d))
            }
        }
        // Signed zeros, infinities and NaNs against anything.
        _ => {
            let special = [
                0.0f32,
                -0.0,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::NAN,
                -f32::NAN,
                f32::from_bits(0x7f80_0001),
                f32::from_bits(1),
            ][rng.below(8) as usize];
            let e = int(rng, 0, 255) as i32;
            (special, float(rng, e))
        }
    };
    if rng.below(2) == 0 {
        (a, b)
    } else {
        (b, a)
    }
}

/// Whether `x` is a normal number (not zero, subnormal, infinite or NaN).
fn normal(x: f32) -> bool {
    x.is_normal()
}

#[test]
fn float_primitives_are_avr_libc_bit_for_bit() {
    let elf = build::firmware_elf(build::BENCH).unwrap_or_else(|e| panic!("{e}"));
    let mut fw = BenchFirmware::boot(&elf);
    let mut rng = Rng::new(0x00f1_0a75);
    for (name, ours, libc, host) in OPERATIONS {
        let (ours, libc) = (op(ours), op(libc));
        let mut pairs = vec![
            (1.0f32, 1.0f32),
            (1.0, -1.0),
            (-1.0, 1.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (f32::MAX, f32::MAX),
            (f32::MAX, -f32::MAX),
            (f32::MIN_POSITIVE, -f32::MIN_POSITIVE),
            (f32::MIN_POSITIVE, 0.5),
            (1.0, f32::EPSILON / 2.0),
            (1.0, -f32::EPSILON / 4.0),
            (1.0, f32::from_bits(0x3380_0001)),
            (f32::INFINITY, f32::NEG_INFINITY),
            (f32::NAN, 1.0),
        ];
        pairs.extend((0..PAIRS).map(|_| pair(&mut rng, name == "mul")));
        let (mut cycles_ours, mut cycles_libc, mut n_fast) = (0u64, 0u64, 0u64);
        let (mut fast_ours, mut fast_libc) = (0u64, 0u64);
        let mut ieee_differences = 0usize;
        for &(a, b) in &pairs {
            let (co, ro) = fw.primitive(ours, a, b);
            let (cl, rl) = fw.primitive(libc, a, b);
            cycles_ours += co;
            cycles_libc += cl;
            assert_eq!(
                ro.to_bits(),
                rl.to_bits(),
                "{name}({a:e} [{:#010x}], {b:e} [{:#010x}]): firmware {ro:e} [{:#010x}], \
                 avr-libc {rl:e} [{:#010x}]",
                a.to_bits(),
                b.to_bits(),
                ro.to_bits(),
                rl.to_bits()
            );
            let ieee = host(a, b);
            if normal(a) && normal(b) && normal(ieee) {
                n_fast += 1;
                fast_ours += co;
                fast_libc += cl;
            }
            if a.is_finite() && b.is_finite() && ieee.to_bits() != rl.to_bits() {
                if ieee_differences < 10 {
                    eprintln!(
                        "{name}({a:e} [{:#010x}], {b:e} [{:#010x}]): avr-libc {rl:e} \
                         [{:#010x}], IEEE {ieee:e} [{:#010x}]",
                        a.to_bits(),
                        b.to_bits(),
                        rl.to_bits(),
                        ieee.to_bits()
                    );
                }
                ieee_differences += 1;
            }
        }
        let n = pairs.len() as f64;
        eprintln!(
            "{name} on the AVR, {} pairs: firmware {:.1} cycles, avr-libc {:.1} cycles (mean); \
             normal arguments and result ({n_fast} pairs): firmware {:.1}, avr-libc {:.1}; \
             avr-libc differs from IEEE on {ieee_differences} pairs of finite arguments",
            pairs.len(),
            cycles_ours as f64 / n,
            cycles_libc as f64 / n,
            fast_ours as f64 / n_fast as f64,
            fast_libc as f64 / n_fast as f64,
        );
    }
}

#[test]
fn the_fast_primitives_are_linked_not_avr_libc_wrappers() {
    for bin in [build::FIRMWARE, build::BENCH] {
        let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
        let symbols = symbols::of_elf(&elf);
        for name in ["__addsf3", "__subsf3", "__mulsf3"] {
            let found = symbols::named(&symbols, name);
            assert_eq!(found.len(), 1, "{bin}: {name} defined once: {found:?}");
            // avr-libc's members are 8 to 14 bytes (`__addsf3` has no size at all); the fast
            // path is longer.
            let size = found[0].size_bytes;
            assert!(
                size.is_some_and(|s| s > 64),
                "{bin}: {name} is not the fast path: {:?}",
                found[0]
            );
        }
    }
}
