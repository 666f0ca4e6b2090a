//! The firmware's sine/cosine kernel `AvrLibm::sin_cos_fixed` (its fixed-point part in
//! assembly) against the portable `poly::sin_cos_fixed` compiled for the AVR, bit for bit, in
//! simavr: both are primitives of the benchmark firmware (`bench.elf`), one result at a time,
//! run on the same seeded random arguments (a wide exponent range, both sides of ±π/4,
//! multiples of π/2, huge, subnormal, signed zeros, infinities, NaNs). The portable kernel's
//! bits are also those of the host's (`SoftFloat`) for finite arguments: integer arithmetic,
//! correctly rounded conversions and the same software-float range reduction on both.
//!
//! The firmware is built once per test process (`quad_host::emu::build`); the test fails —
//! never skips — when it cannot be built.

use integration_tests::avr_bench::{primitive_op as op, random_float as float, BenchFirmware};
use kin_core::math::{poly, SoftFloat};
use quad_host::emu::build;
use seeded_rng::SplitMix64 as Rng;

/// Random arguments compared.
const ARGUMENTS: usize = 20_000;

/// One argument of a kind chosen at random.
fn argument(rng: &mut Rng) -> f32 {
    let pick = rng.next_u64();
    let exp = |rng: &mut Rng, lo: u32, hi: u32| lo + (rng.next_u64() % (hi - lo + 1) as u64) as u32;
    let sign = ((pick >> 20) as u32 & 1) << 31;
    match pick % 8 {
        // Any exponent, infinities and NaNs included.
        0 => {
            let e = exp(rng, 0, 255);
            float(rng, e)
        }
        // Within ±π/4 and a little beyond (body rotations, joint angles).
        1 | 2 => {
            let e = exp(rng, 95, 127);
            float(rng, e)
        }
        // Up to a few turns.
        3 => {
            let e = exp(rng, 120, 132);
            float(rng, e)
        }
        // Within a few ulps of ±π/4.
        4 => {
            let d = exp(rng, 0, 16) as i32 - 8;
            f32::from_bits((0x3f49_0fdb_i32 + d) as u32 | sign)
        }
        // Within a few ulps of a multiple of π/2.
        5 => {
            let k = exp(rng, 1, 64) as f32;
            let at = k * core::f32::consts::FRAC_PI_2;
            let d = exp(rng, 0, 16) as i32 - 8;
            f32::from_bits((at.to_bits() as i32 + d) as u32 | sign)
        }
        // Subnormals and the smallest normals.
        6 => {
            let e = exp(rng, 0, 2);
            float(rng, e)
        }
        // Huge, up to the largest finite.
        _ => {
            let e = exp(rng, 150, 254);
            float(rng, e)
        }
    }
}

#[test]
fn asm_sin_cos_fixed_is_the_portable_kernel_bit_for_bit() {
    let elf = build::firmware_elf(build::BENCH).unwrap_or_else(|e| panic!("{e}"));
    let mut fw = BenchFirmware::boot(&elf);
    let (portable, asm) = (
        op("poly::sin_cos_fixed sin|cos"),
        op("AvrLibm::sin_cos_fixed sin|cos"),
    );
    let mut rng = Rng::new(0x005c_05f1);
    let mut arguments = vec![
        0.0f32,
        -0.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        f32::MAX,
        f32::MIN,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::from_bits(0x8000_0001),
        f32::from_bits(0x007f_ffff),
        core::f32::consts::FRAC_PI_4,
        -core::f32::consts::FRAC_PI_4,
        f32::from_bits(core::f32::consts::FRAC_PI_4.to_bits() + 1),
        core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI,
        -core::f32::consts::PI,
        1.0,
        0.3,
        -0.05,
    ];
    arguments.extend((0..ARGUMENTS).map(|_| argument(&mut rng)));
    // (sum, count) of the assembly's and the portable kernel's cycles within ±π/4 and beyond.
    let mut cycles = [[(0u64, 0u64); 2]; 2];
    for &x in &arguments {
        let host = poly::sin_cos_fixed::<SoftFloat>(x);
        let beyond = usize::from(x.to_bits() & 0x7fff_ffff > 0x3f49_0fdb);
        for (which, select, host) in [("sin", 0.0f32, host.0), ("cos", 1.0, host.1)] {
            let (cp, rp) = fw.primitive(portable, x, select);
            let (ca, ra) = fw.primitive(asm, x, select);
            for (i, c) in [cp, ca].into_iter().enumerate() {
                cycles[i][beyond].0 += c;
                cycles[i][beyond].1 += 1;
            }
            assert_eq!(
                ra.to_bits(),
                rp.to_bits(),
                "{which}({x:e} [{:#010x}]): asm {ra:e}, portable {rp:e}",
                x.to_bits()
            );
            // NaN and infinite arguments reduce to a NaN whose sign is the software-float
            // library's choice (avr-libc's and the host's differ): bounded results on both,
            // not the same ones.
            assert!(
                !x.is_finite() || rp.to_bits() == host.to_bits(),
                "{which}({x:e} [{:#010x}]): AVR {rp:e}, host {host:e}",
                x.to_bits()
            );
            assert!(rp.abs() <= 1.0, "{which}({x:e}) = {rp:e}");
        }
    }
    let mean = |(sum, n): (u64, u64)| sum as f64 / n.max(1) as f64;
    eprintln!(
        "sin_cos_fixed on the AVR, {} arguments (one result a call): within ±π/4 portable \
         {:.0}, asm {:.0} cycles; beyond portable {:.0}, asm {:.0} cycles (means)",
        arguments.len(),
        mean(cycles[0][0]),
        mean(cycles[1][0]),
        mean(cycles[0][1]),
        mean(cycles[1][1]),
    );
}
