//! The classes of arguments every AVR kernel is checked on ([`crate::kernels`]): the edges of
//! each kernel's input space enumerated, random arguments on top.
//!
//! An edge class lists, for each edge (a power of two of an argument or of a ratio the kernel
//! forms, a table cell boundary, a multiple of π/4, the exponents where a fast path hands
//! over to avr-libc's), the 2¹² floats nearest it on each side, in every variant of the class
//! (signs, argument order, octant, the other argument's mantissa and exponent). Index `i` of a
//! class runs through the variants first and then outwards from the edge, so that any prefix
//! of a class holds the values nearest its edges. [`plan`] draws a seeded share of every class
//! (the CI's), [`Class::size`] says how many values a class holds in all (the long campaign
//! enumerates every finite class).
//!
//! | kernel | classes |
//! |---|---|
//! | `atan2_fixed` | the ratio `t = min/max` near every `2⁻ᵏ`, `k = 0..=24` (the quotient `T = ⌊t·2²¹⌋` near each power of two, its base-256 digits' edges included); `t` near every cell boundary `j/32`; the axes, the diagonals and signed zeros at every exponent; special pairs; subnormal pairs; random bits |
//! | `sin_cos_fixed` | `|x|` near every `2ᵏ`, `k = −27..=127` (the core's shift of the mantissa, the reduction's range); near every cell boundary `j/32`; near every multiple of π/4 up to 64 (octants, quadrants, the ±π/4 switch); specials and subnormals; random bits |
//! | `add`, `sub` | every exponent difference `0..=32` × the four signs × both orders × mantissas that carry, round to even or cancel, at the exponents where the fast path hands over (1, 2, 24–26, 252–254) and inside; near-equal magnitudes; special pairs; random bits |
//! | `mul` | the result's exponent near both ends of the normal range (the fast path's bounds) × mantissas whose product carries into the next binade × signs; operands at the exponent bounds; special pairs; random bits |
//! | `sqrt` | every power of two of the f32 range (subnormal ones included); specials, negatives; random bits |

use crate::kernels::Kernel;
use seeded_rng::SplitMix64;

/// Floats enumerated on each side of an edge.
pub const SIDE: u64 = 1 << 12;

/// Values of a random class (indices are hashed into bit patterns: any size will do).
const RANDOM_SIZE: u64 = 1 << 40;

/// The generator of a class: its values by index.
type Gen = Box<dyn Fn(u64) -> [u32; 2] + Send + Sync>;

/// One class of arguments of a kernel.
pub struct Class {
    /// Its name in reports.
    pub name: &'static str,
    /// How many values it holds (random classes: a virtual size far beyond any run).
    pub size: u64,
    /// Whether it is random bits (rather than an enumeration).
    pub random: bool,
    gen: Gen,
}

impl Class {
    fn edges(
        name: &'static str,
        size: u64,
        gen: impl Fn(u64) -> [u32; 2] + Send + Sync + 'static,
    ) -> Class {
        Class {
            name,
            size,
            random: false,
            gen: Box::new(gen),
        }
    }

    fn random(name: &'static str, gen: impl Fn(u64) -> [u32; 2] + Send + Sync + 'static) -> Class {
        Class {
            name,
            size: RANDOM_SIZE,
            random: true,
            gen: Box::new(gen),
        }
    }

    /// Value `i` of the class (`i < size`).
    pub fn get(&self, i: u64) -> [u32; 2] {
        (self.gen)(i)
    }
}

/// The float bits `d` steps from the edge `center` (magnitude bits): `j = 2d` the `d`-th float
/// at or above it, `j = 2d + 1` the `d`-th below it; saturating at 0 and at infinity.
fn walk(center: u32, j: u64) -> u32 {
    let d = (j >> 1) as i64;
    let c = i64::from(center & 0x7fff_ffff);
    let v = if j & 1 == 0 { c + d } else { c - 1 - d };
    v.clamp(0, 0x7f80_0000) as u32
}

/// A float of biased exponent `e` and mantissa `m` (23 bits), positive.
fn float(e: u32, m: u32) -> u32 {
    (e << 23) | (m & 0x7f_ffff)
}

/// Hashes an index into 64 random-looking bits (SplitMix64's output function).
fn hash(i: u64) -> u64 {
    SplitMix64::new(i).next_u64()
}

/// Mantissas that carry, round or cancel: zero, the last bits, all ones, halves, alternating
/// bits and runs.
const MANTISSAS: [u32; 12] = [
    0, 1, 2, 0x3f_ffff, 0x40_0000, 0x40_0001, 0x7f_fffe, 0x7f_ffff, 0x55_5555, 0x2a_aaaa,
    0x7f_f000, 0x00_0fff,
];

/// Special values: signed zeros, subnormals, the smallest normal, one, the largest, infinities
/// and NaNs (quiet, signalling, both signs, payloads).
const SPECIALS: [u32; 24] = [
    0x0000_0000,
    0x8000_0000,
    0x0000_0001,
    0x8000_0001,
    0x0040_0000,
    0x007f_ffff,
    0x807f_ffff,
    0x0080_0000,
    0x8080_0000,
    0x0080_0001,
    0x3f80_0000,
    0xbf80_0000,
    0x3f7f_ffff,
    0x7f7f_ffff,
    0xff7f_ffff,
    0x7f80_0000,
    0xff80_0000,
    0x7fc0_0000,
    0xffc0_0000,
    0x7f80_0001,
    0x7fff_ffff,
    0xffff_ffff,
    0x4049_0fdb,
    0x3f49_0fdb,
];

/// Every class of `kernel`'s arguments, edges first, random last.
pub fn classes(kernel: Kernel) -> Vec<Class> {
    match kernel {
        Kernel::Atan2Fixed | Kernel::Atan2FixedPortable => atan2_classes(),
        Kernel::SinCosFixed | Kernel::SinCosFixedPortable => sin_cos_classes(),
        Kernel::Add | Kernel::Sub => add_classes(),
        Kernel::Mul => mul_classes(),
        Kernel::Sqrt => sqrt_classes(),
    }
}

/// The pair `(num, den)` in octant `o` (bit 0: swapped, bit 1: x negative, bit 2: y negative)
/// as the arguments `(y, x)`.
fn octant(num: u32, den: u32, o: u64) -> [u32; 2] {
    let (y, x) = if o & 1 == 0 { (num, den) } else { (den, num) };
    let sx = if o & 2 == 0 { 0 } else { 0x8000_0000 };
    let sy = if o & 4 == 0 { 0 } else { 0x8000_0000 };
    [y | sy, x | sx]
}

/// Denominator exponents of the ratio classes: the smallest normal, the kinematics' range,
/// the largest.
const DEN_EXPONENTS: [u32; 4] = [1, 100, 127, 254];

/// Denominator mantissas of the ratio classes: [`MANTISSAS`]' first eight, which include the
/// reciprocal estimate's least precise region's neighbours (all ones, halves).
const DEN_MANTISSAS: [u32; 8] = [
    0, 1, 0x3f_ffff, 0x40_0000, 0x44_f7ff, 0x7f_fffe, 0x7f_ffff, 0x55_5555,
];

/// Variants of a ratio class: denominator exponent × mantissa × octant.
const RATIO_VARIANTS: u64 = (DEN_EXPONENTS.len() * DEN_MANTISSAS.len() * 8) as u64;

/// The denominator and octant of ratio variant `v`.
fn ratio_variant(v: u64) -> (u32, u64) {
    let o = v % 8;
    let m = DEN_MANTISSAS[(v / 8) as usize % DEN_MANTISSAS.len()];
    let e = DEN_EXPONENTS[(v / 8 / DEN_MANTISSAS.len() as u64) as usize];
    (float(e, m), o)
}

fn atan2_classes() -> Vec<Class> {
    let mut out = Vec::new();
    // The ratio near 2^-k: num = den·2^-k ± 2^12 floats.
    for k in 0..=24i32 {
        out.push(Class::edges(
            leak(format!("ratio 2^-{k}")),
            2 * SIDE * RATIO_VARIANTS,
            move |i| {
                let (den, o) = ratio_variant(i % RATIO_VARIANTS);
                let num = walk(scaled_bits(den, -k), i / RATIO_VARIANTS);
                octant(num, den, o)
            },
        ));
    }
    // The ratio near each cell boundary j/32 (j = 32 is the ratio 1, above).
    for j in 1..32u32 {
        out.push(Class::edges(
            leak(format!("cell {j}/32")),
            2 * SIDE * RATIO_VARIANTS,
            move |i| {
                let (den, o) = ratio_variant(i % RATIO_VARIANTS);
                let center = (f64::from(f32::from_bits(den)) * f64::from(j) / 32.0) as f32;
                let num = walk(center.to_bits(), i / RATIO_VARIANTS);
                octant(num, den, o)
            },
        ));
    }
    // The axes and the diagonals: (±0, v), (v, ±0), (±v, ±v) at every exponent.
    out.push(Class::edges(
        "axes and diagonals",
        3 * 256 * MANTISSAS.len() as u64 * 4,
        |i| {
            let signs = i % 4;
            let m = MANTISSAS[(i / 4) as usize % MANTISSAS.len()];
            let e = (i / 4 / MANTISSAS.len() as u64 % 256) as u32;
            let v = float(e, m);
            let (a, b) = match i / 4 / MANTISSAS.len() as u64 / 256 {
                0 => (0, v),
                1 => (v, 0),
                _ => (v, v),
            };
            [
                a | ((signs as u32 & 1) << 31),
                b | ((signs as u32 & 2) << 30),
            ]
        },
    ));
    out.push(special_pairs());
    out.push(Class::random("subnormal pairs", |i| {
        let h = hash(i);
        [h as u32 & 0x807f_ffff, (h >> 32) as u32 & 0x80ff_ffff]
    }));
    out.push(random_pairs());
    out
}

fn sin_cos_classes() -> Vec<Class> {
    let mut out = Vec::new();
    // |x| near 2^k: the core's mantissa shift (126 − e) and its end (e > 126), the reduction.
    out.push(Class::edges("|x| near 2^k", 2 * SIDE * 2 * 155, |i| {
        let sign = (i & 1) as u32;
        let k = (i / 2 % 155) as i32 - 27;
        let center = float((127 + k) as u32, 0);
        [walk(center, i / 2 / 155) | sign << 31, 0]
    }));
    out.push(Class::edges("cell j/32", 2 * SIDE * 2 * 26, |i| {
        let sign = (i & 1) as u32;
        let j = (i / 2 % 26) as u32 + 1;
        let center = (j as f32 / 32.0).to_bits();
        [walk(center, i / 2 / 26) | sign << 31, 0]
    }));
    out.push(Class::edges("m·π/4", 2 * SIDE * 2 * 64, |i| {
        let sign = (i & 1) as u32;
        let m = (i / 2 % 64) + 1;
        let center = (m as f64 * core::f64::consts::FRAC_PI_4) as f32;
        [walk(center.to_bits(), i / 2 / 64) | sign << 31, 0]
    }));
    out.push(Class::edges(
        "specials and subnormals",
        SPECIALS.len() as u64 + 2 * SIDE,
        |i| {
            let n = SPECIALS.len() as u64;
            if i < n {
                [SPECIALS[i as usize], 0]
            } else {
                // Subnormals spread over their range, both signs.
                let j = i - n;
                [
                    ((j >> 1) as u32 * 2047 + 1) & 0x7f_ffff | ((j & 1) as u32) << 31,
                    0,
                ]
            }
        },
    ));
    out.push(Class::random("random bits", |i| [hash(i) as u32, 0]));
    out
}

/// Biased exponents where the addition's fast path hands over to avr-libc's (it takes 25..=253)
/// and inside it.
const ADD_EXPONENTS: [u32; 10] = [1, 2, 24, 25, 26, 100, 127, 252, 253, 254];

fn add_classes() -> Vec<Class> {
    let n_m = MANTISSAS.len() as u64;
    let n_e = ADD_EXPONENTS.len() as u64;
    vec![
        // Every exponent difference × signs × order × mantissa pairs × exponent.
        Class::edges(
            "exponent difference × signs × order × mantissas",
            33 * 4 * 2 * n_m * n_m * n_e,
            move |i| {
                let signs = i % 4;
                let order = i / 4 % 2;
                let ma = MANTISSAS[(i / 8 % n_m) as usize];
                let mb = MANTISSAS[(i / 8 / n_m % n_m) as usize];
                let ea = ADD_EXPONENTS[(i / 8 / n_m / n_m % n_e) as usize];
                let d = (i / 8 / n_m / n_m / n_e) as u32;
                let a = float(ea, ma);
                let b = if d < ea {
                    float(ea - d, mb)
                } else {
                    mb >> (d - ea + 1).min(31)
                };
                let (a, b) = if order == 0 { (a, b) } else { (b, a) };
                [
                    a | ((signs as u32 & 1) << 31),
                    b | ((signs as u32 & 2) << 30),
                ]
            },
        ),
        // Near-equal magnitudes: cancellation of every depth, both signs.
        Class::edges(
            "near-equal magnitudes",
            2 * SIDE * 4 * n_m * n_e,
            move |i| {
                let signs = i % 4;
                let m = MANTISSAS[(i / 4 % n_m) as usize];
                let e = ADD_EXPONENTS[(i / 4 / n_m % n_e) as usize];
                let a = float(e, m);
                let b = walk(a, i / 4 / n_m / n_e);
                [
                    a | ((signs as u32 & 1) << 31),
                    b | ((signs as u32 & 2) << 30),
                ]
            },
        ),
        special_pairs(),
        random_pairs(),
    ]
}

fn mul_classes() -> Vec<Class> {
    let n_m = MANTISSAS.len() as u64;
    // Result exponents eA + eB − 127 near the normal range's ends (the fast path takes
    // 1..=252) and the operands' splits of them.
    const TARGETS: [i32; 14] = [-24, -2, -1, 0, 1, 2, 3, 250, 251, 252, 253, 254, 255, 256];
    const SPLITS: [u32; 6] = [1, 2, 64, 127, 200, 254];
    vec![
        Class::edges(
            "result exponent bounds × mantissas × signs",
            TARGETS.len() as u64 * SPLITS.len() as u64 * n_m * n_m * 4,
            move |i| {
                let signs = i % 4;
                let ma = MANTISSAS[(i / 4 % n_m) as usize];
                let mb = MANTISSAS[(i / 4 / n_m % n_m) as usize];
                let ea = SPLITS[(i / 4 / n_m / n_m % SPLITS.len() as u64) as usize];
                let target = TARGETS[(i / 4 / n_m / n_m / SPLITS.len() as u64) as usize];
                let eb = (target + 127 - ea as i32).clamp(0, 255) as u32;
                [
                    float(ea, ma) | ((signs as u32 & 1) << 31),
                    float(eb, mb) | ((signs as u32 & 2) << 30),
                ]
            },
        ),
        Class::edges("operand exponent bounds", 2 * SIDE * 6 * 4, |i| {
            const E: [u32; 6] = [0, 1, 2, 253, 254, 255];
            let signs = i % 4;
            let e = E[(i / 4 % 6) as usize];
            let a = walk(float(e, 0), i / 4 / 6);
            let b = hash(i) as u32 & 0x7fff_ffff;
            [
                a | ((signs as u32 & 1) << 31),
                b | ((signs as u32 & 2) << 30),
            ]
        }),
        special_pairs(),
        random_pairs(),
    ]
}

fn sqrt_classes() -> Vec<Class> {
    vec![
        // Every power of two 2^-149 ..= 2^127 (subnormal ones included).
        Class::edges("powers of two", 2 * SIDE * 277, |i| {
            let k = (i % 277) as i32 - 149;
            let center = if k < -126 {
                1u32 << (k + 149)
            } else {
                float((k + 127) as u32, 0)
            };
            [walk(center, i / 277), 0]
        }),
        Class::edges(
            "specials and negatives",
            SPECIALS.len() as u64 + 2 * SIDE,
            |i| {
                let n = SPECIALS.len() as u64;
                if i < n {
                    [SPECIALS[i as usize], 0]
                } else {
                    [hash(i) as u32 | 0x8000_0000, 0]
                }
            },
        ),
        Class::random("random bits", |i| [hash(i) as u32, 0]),
    ]
}

/// Every ordered pair of [`SPECIALS`] and every special against mantissa patterns at every
/// exponent.
fn special_pairs() -> Class {
    let n = SPECIALS.len() as u64;
    let n_m = MANTISSAS.len() as u64;
    Class::edges("special pairs", n * n + 2 * n * 256 * n_m, move |i| {
        if i < n * n {
            [SPECIALS[(i % n) as usize], SPECIALS[(i / n) as usize]]
        } else {
            let j = i - n * n;
            let s = SPECIALS[(j % n) as usize];
            let m = MANTISSAS[(j / n % n_m) as usize];
            let e = (j / n / n_m % 256) as u32;
            let v = float(e, m);
            if j / n / n_m / 256 == 0 {
                [s, v]
            } else {
                [v, s]
            }
        }
    })
}

/// Uniform random bit patterns (NaNs and infinities included).
fn random_pairs() -> Class {
    Class::random("random bits", |i| {
        let h = hash(i);
        [h as u32, (h >> 32) as u32]
    })
}

/// `bits · 2^shift` of a positive finite float as the bits of the nearest f32 (subnormals
/// and underflow to zero included).
fn scaled_bits(bits: u32, shift: i32) -> u32 {
    ((f64::from(f32::from_bits(bits)) * 2f64.powi(shift)) as f32).to_bits()
}

/// A class name made at run time, kept for the process (a few dozen per kernel).
fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

/// One class's part of a share ([`plan`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Part {
    /// The class's index.
    pub class: usize,
    /// How many of its values.
    pub count: u64,
    /// The seed of its random picks.
    pub seed: u64,
}

/// A share of a kernel's classes: `evaluations` values in all (or every value, when the
/// classes hold fewer), spread evenly: a class smaller than its share entirely, the rest of
/// the budget spread over the larger ones. [`sample`] draws each part's values.
pub fn plan(classes: &[Class], evaluations: u64, seed: u64) -> Vec<Part> {
    // Shares: the smallest classes first, each taking at most an even part of what is left.
    let mut order: Vec<usize> = (0..classes.len()).collect();
    order.sort_by_key(|&c| classes[c].size);
    let mut counts = vec![0u64; classes.len()];
    let mut left = evaluations;
    for (n, &c) in order.iter().enumerate() {
        let even = left.div_ceil((classes.len() - n) as u64);
        counts[c] = classes[c].size.min(even);
        left -= counts[c].min(left);
    }
    let mut rng = SplitMix64::new(seed);
    counts
        .into_iter()
        .enumerate()
        .map(|(class, count)| Part {
            class,
            count,
            seed: rng.next_u64(),
        })
        .collect()
}

/// The values of `part` of `class`: a random class's `count` values from a seeded offset; an
/// edge class entirely when it holds no more, else its first `count / 2` indices (the values
/// nearest its edges, every variant) and seeded random indices from the rest.
pub fn sample<'a>(class: &'a Class, part: &Part) -> impl Iterator<Item = [u32; 2]> + 'a {
    let mut rng = SplitMix64::new(part.seed);
    let base = rng.next_u64() >> 24;
    let (count, near) = (part.count, part.count / 2);
    (0..count).map(move |i| {
        if class.random {
            class.get(base + i)
        } else if class.size <= count || i < near {
            class.get(i)
        } else {
            class.get(near + rng.next_u64() % (class.size - near))
        }
    })
}
