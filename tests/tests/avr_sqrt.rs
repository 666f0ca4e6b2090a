//! The firmware's square root (`AvrLibm::sqrt`, the `sqrt` primitive of the benchmark firmware
//! `bench.elf`) against avr-libc's `sqrt` called directly, bit for bit, in simavr, on seeded
//! arguments: random bit patterns; every biased exponent with random mantissas; perfect squares
//! and their neighbours (±1 to 3 ulp); arguments whose root lies one ulp either side of a
//! rounding midpoint (`(m + ½)²` for 24-bit `m`, rounded down and up); mantissas all ones or
//! all zeros; signed zeros, subnormals, negative numbers, infinities and NaNs.
//!
//! avr-libc's results are also compared with the host's IEEE `f32::sqrt` for every finite
//! non-negative argument: avr-libc's square root is correctly rounded to nearest, so the
//! firmware's is too.
//!
//! A second test checks that the firmware and the benchmark firmware link `avr_libc_math`'s
//! `sqrt`, and not `libm.a`'s `sqrt.o`.
//!
//! The firmware is built once per test process (`quad_host::emu::build`); the test fails —
//! never skips — when it cannot be built.

use integration_tests::avr_bench::{primitive_op as op, BenchFirmware};
use integration_tests::symbols;
use quad_host::emu::build;
use seeded_rng::SplitMix64 as Rng;

/// Seeded arguments compared (besides the fixed special cases).
const ARGUMENTS: usize = 100_000;

/// The firmware's square root and avr-libc's, by their primitive names in `bench.elf`.
const OURS: &str = "sqrt";
const AVR_LIBC: &str = "avr-libc sqrt";

/// A number in `lo..=hi`.
fn int(rng: &mut Rng, lo: u32, hi: u32) -> u32 {
    lo + rng.below((hi - lo + 1) as u64) as u32
}

/// A positive float with biased exponent `exponent` and a random mantissa.
fn with_exponent(exponent: u32, rng: &mut Rng) -> f32 {
    f32::from_bits(exponent << 23 | rng.next_u64() as u32 & 0x7f_ffff)
}

/// `x` moved by `ulps` units in the last place (bit patterns of non-negative floats).
fn step(x: f32, ulps: i32) -> f32 {
    f32::from_bits(x.to_bits().wrapping_add_signed(ulps))
}

/// One argument of a kind chosen at random.
fn argument(rng: &mut Rng) -> f32 {
    match rng.below(8) {
        // Any bit pattern.
        0 => f32::from_bits(rng.next_u64() as u32),
        // Any exponent, random mantissa (a random sign one time in eight).
        1 | 2 => {
            let x = with_exponent(int(rng, 0, 255), rng);
            if rng.below(8) == 0 {
                -x
            } else {
                x
            }
        }
        // The kinematics' range (sums of squares of lengths in metres).
        3 => with_exponent(int(rng, 100, 135), rng),
        // A perfect square of a 24-bit mantissa (scaled to any exponent), ± up to 3 ulp.
        4 => {
            let m = int(rng, 1 << 23, (1 << 24) - 1) as f64;
            let scale = 2f64.powi(int(rng, 0, 100) as i32 - 50);
            // m² has at most 48 bits: rounded to 24, the nearest float to a square.
            let square = ((m * scale) * (m * scale)) as f32;
            step(square, int(rng, 0, 6) as i32 - 3)
        }
        // A root at a rounding midpoint: (m + ½)², rounded down or up, ± 1 ulp.
        5 | 6 => {
            let m = int(rng, 1 << 23, (1 << 24) - 1) as f64 + 0.5;
            let scale = 2f64.powi(int(rng, 0, 100) as i32 - 50);
            let exact = (m * scale) * (m * scale);
            let rounded = exact as f32;
            let below = if (rounded as f64) > exact {
                step(rounded, -1)
            } else {
                rounded
            };
            step(below, int(rng, 0, 3) as i32 - 1)
        }
        // Mantissas all ones or all zeros, any exponent.
        _ => {
            let e = int(rng, 0, 255);
            let m = if rng.below(2) == 0 { 0 } else { 0x7f_ffff };
            f32::from_bits(e << 23 | m)
        }
    }
}

#[test]
fn sqrt_is_avr_libc_bit_for_bit_and_correctly_rounded() {
    let elf = build::firmware_elf(build::BENCH).unwrap_or_else(|e| panic!("{e}"));
    let mut fw = BenchFirmware::boot(&elf);
    let (ours, libc) = (op(OURS), op(AVR_LIBC));
    let mut rng = Rng::new(0x5a47_0f1e);
    let mut args = vec![
        0.0f32,
        -0.0,
        1.0,
        2.0,
        4.0,
        0.5,
        f32::MAX,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::from_bits(0x007f_ffff),
        -f32::from_bits(1),
        -1.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7f80_0001),
        f32::from_bits(0x7fbf_ffff),
        step(1.0, -1),
        step(1.0, 1),
        step(4.0, -1),
    ];
    args.extend((0..ARGUMENTS).map(|_| argument(&mut rng)));
    let (mut cycles_ours, mut cycles_libc) = (0u64, 0u64);
    let (mut n_normal, mut normal_ours, mut normal_libc) = (0u64, 0u64, 0u64);
    for &x in &args {
        let (co, ro) = fw.primitive(ours, x, 0.0);
        let (cl, rl) = fw.primitive(libc, x, 0.0);
        cycles_ours += co;
        cycles_libc += cl;
        if x.is_normal() && x > 0.0 {
            n_normal += 1;
            normal_ours += co;
            normal_libc += cl;
        }
        assert_eq!(
            ro.to_bits(),
            rl.to_bits(),
            "sqrt({x:e} [{:#010x}]): firmware {ro:e} [{:#010x}], avr-libc {rl:e} [{:#010x}]",
            x.to_bits(),
            ro.to_bits(),
            rl.to_bits()
        );
        if x.is_finite() && x >= 0.0 {
            let ieee = x.sqrt();
            assert_eq!(
                rl.to_bits(),
                ieee.to_bits(),
                "sqrt({x:e} [{:#010x}]): avr-libc {rl:e} [{:#010x}], IEEE {ieee:e} [{:#010x}]",
                x.to_bits(),
                rl.to_bits(),
                ieee.to_bits()
            );
        }
    }
    let n = args.len() as f64;
    eprintln!(
        "sqrt on the AVR, {} arguments: firmware {:.1} cycles, avr-libc {:.1} cycles (mean); \
         positive normal arguments ({n_normal}): firmware {:.1}, avr-libc {:.1}",
        args.len(),
        cycles_ours as f64 / n,
        cycles_libc as f64 / n,
        normal_ours as f64 / n_normal as f64,
        normal_libc as f64 / n_normal as f64,
    );
}

#[test]
fn the_firmware_links_its_own_sqrt_not_avr_libcs() {
    for bin in [build::FIRMWARE, build::BENCH] {
        let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
        let symbols = symbols::of_elf(&elf);
        let kinds = |name: &str| -> Vec<char> {
            symbols::named(&symbols, name)
                .iter()
                .map(|s| s.kind)
                .collect()
        };
        assert_eq!(kinds("sqrt"), ['T'], "{bin}: sqrt defined once, strongly");
        // avr-libc's `sqrt.o` defines `sqrt` and `sqrtf` at one address: its `sqrtf` absent,
        // the member was not extracted (the firmware's `sqrt` replaces it).
        assert!(
            kinds("sqrtf").is_empty(),
            "{bin}: libm.a's sqrt.o is linked"
        );
    }
}
