//! Scalar math backends.
//!
//! Every kinematic routine is generic over a [`Math`] backend so that each target picks the
//! fastest correct implementation of the few transcendental functions and comparisons the
//! kinematics needs, while the algebra stays in one place and every backend runs on every
//! target (the host tests run them all):
//!
//! - [`Fast`] (the default, [`DefaultMath`]): minimax polynomials for `atan2` and `sin`/`cos`
//!   (absolute error ≤ 3e-7 rad, about one f32 ulp at π; see the tests), `libm` for `sqrt`.
//!   `atan2` is branch-free (random quadrants cost no mispredictions) and its polynomial is
//!   evaluated in Estrin's scheme (a short dependency chain). Quick on hosts with hardware
//!   floating point. See `BENCHMARKS.md`.
//! - [`Libm`]: the `libm` crate's correctly rounded-ish `atan2f`, `sinf`, `cosf`, `sqrtf`.
//!   The reference the others are tested against.
//! - [`SoftFloat`]: the choices for CPUs without floating-point hardware (the ATmega2560
//!   firmware's backend is `SoftFloat` over avr-libc's square root): the kernels
//!   [`poly::atan2_fixed`] and [`poly::sin_cos_fixed`] (tables of quadratic cells in fixed
//!   point), which cost far fewer software-float operations, comparisons of the bit patterns instead of software-float comparisons, and
//!   the four legs of a body solved one after the other. The kernels' tables are the one thing
//!   a backend must read per target ([`Math::read_table_cell`]): on the AVR they stay in flash,
//!   out of the scarce SRAM, and the backend reads them with `lpm`. A backend may also supply
//!   the arctangent kernel and the sine/cosine kernel's fixed-point core in its own form for
//!   its target, bit for bit the same ([`Math::atan2_fixed`], [`Math::sin_cos_fixed`]; the
//!   AVR's are in assembly).
//!
//! The polynomial coefficients come from `scripts/fit_polynomials.py` (a weighted least-squares
//! minimax fit), and so do the fixed-point kernels' cell tables (quadratics through Chebyshev
//! nodes).

use core::marker::PhantomData;

/// The few scalar functions and comparisons the kinematics needs. All angles are in radians.
///
/// Only `sqrt`, `atan2` and `sin_cos` have no default. The comparisons default to the float
/// operators; a backend overrides them where another form is faster on its target and equal
/// in result (NaN included), as [`SoftFloat`] does.
pub trait Math {
    /// Whether the full-body IK interleaves the four legs' solves, stage by stage across the
    /// legs (out-of-order CPUs overlap their independent dependency chains), rather than
    /// solving the legs one after the other through one out-of-line leg solve (in-order CPUs
    /// gain nothing from the interleaving, and the firmware keeps one copy of the leg solve).
    /// The results are the same, bit for bit.
    const STAGE_LEGS: bool = true;

    /// Whether code that can take either shape keeps one copy of its float operations, with
    /// run-time indices, rather than a copy specialised to each case (the rotation matrix of
    /// the six orders: [`crate::rotation::matrix`]): true where every float operation is a
    /// library call and its code counts (a soft-float target's flash), false where the
    /// specialised copies run faster. The results are the same, bit for bit.
    const SHARE_FLOAT_CODE: bool = false;

    /// Square root; the argument is never negative when called from this crate.
    fn sqrt(x: f32) -> f32;
    /// Four-quadrant arctangent of `y / x`, in `[-π, π]`; `atan2(0, 0)` must be finite.
    fn atan2(y: f32, x: f32) -> f32;
    /// `(sin x, cos x)`.
    fn sin_cos(x: f32) -> (f32, f32);
    /// Three independent arctangents `[atan2(y[0], x[0]), atan2(y[1], x[1]),
    /// atan2(y[2], x[2])]` (a leg's abduction, knee and hip). A backend may evaluate them
    /// together (e.g. in SIMD lanes), but must return exactly what three [`Math::atan2`] calls
    /// return. The default makes the three calls (always inlined: the arrays must not pass
    /// through memory, which costs store-forwarding stalls on x86-64).
    #[inline(always)]
    fn atan2_3(y: [f32; 3], x: [f32; 3]) -> [f32; 3] {
        [
            Self::atan2(y[0], x[0]),
            Self::atan2(y[1], x[1]),
            Self::atan2(y[2], x[2]),
        ]
    }
    /// `x > 0.0`.
    #[inline(always)]
    fn gt_zero(x: f32) -> bool {
        x > 0.0
    }
    /// `a < b` for `a`, `b` that are each `≥ +0` (sign bit clear: squares, sums of squares,
    /// distances) or NaN.
    #[inline(always)]
    fn lt_nonneg(a: f32, b: f32) -> bool {
        a < b
    }
    /// `lo <= x && x <= hi` (false when any of them is NaN).
    #[inline(always)]
    fn within(x: f32, lo: f32, hi: f32) -> bool {
        (x >= lo) & (x <= hi)
    }
    /// `lo <= x && x <= hi` (as [`Math::within`]) for a fixed interval whose
    /// [`interval_keys`] `keys` the caller computed once: the default compares the floats,
    /// a backend that compares bit patterns ([`SoftFloat`]) compares `x`'s key with `keys`
    /// (no per-call work on the bounds).
    #[inline(always)]
    fn within_keys(x: f32, lo: f32, hi: f32, keys: (i32, i32)) -> bool {
        let _ = keys;
        Self::within(x, lo, hi)
    }
    /// Reads one cell of a fixed-point kernel's table ([`poly::atan2_fixed`],
    /// [`poly::sin_cos_fixed`]): `N` consecutive 16-bit words, see [`TableEntry`]. The only
    /// per-target part of those kernels: the default is a plain load, right wherever the tables
    /// are ordinary read-only data; where this crate links them into program memory (the AVR's
    /// flash, see [`TABLES_IN_PROGRAM_MEMORY`]) a backend must read them there, and the default
    /// does not compile for it.
    #[inline(always)]
    fn read_table_cell<const N: usize>(entry: TableEntry<[u16; N]>) -> [u16; N] {
        entry.read_data_memory::<Self>()
    }
    /// The fixed-point arctangent [`poly::atan2_fixed`] with this backend's table reads: the
    /// arctangent of [`SoftFloat`] over this backend. A backend overrides it only with a
    /// faster form of the same kernel for its target (the AVR's, in assembly, from the
    /// table [`poly::atan_cells`]): an override must return the same bits as
    /// `poly::atan2_fixed::<Self>` for every input (NaN arguments: a bounded value), which
    /// its target's tests check.
    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        poly::atan2_fixed::<Self>(y, x)
    }
    /// The fixed-point sine and cosine [`poly::sin_cos_fixed`] with this backend's table
    /// reads: the `sin_cos` of [`SoftFloat`] over this backend. A backend overrides it only
    /// with a faster form of the same kernel for its target (the AVR's: the range reduction
    /// and quadrant of [`poly::sin_cos_fixed_with`] around an assembly form of
    /// [`poly::sin_cos_fixed_core`]): an override must return the same bits as
    /// `poly::sin_cos_fixed::<Self>` for every input (NaN and infinite arguments: bounded
    /// values), which its target's tests check.
    #[inline]
    fn sin_cos_fixed(x: f32) -> (f32, f32) {
        poly::sin_cos_fixed::<Self>(x)
    }
}

/// Whether this target links the fixed-point kernels' tables ([`poly::atan2_fixed`],
/// [`poly::sin_cos_fixed`]) into program memory: on the AVR, avr-gcc's startup code copies all
/// ordinary read-only data into SRAM, the scarcest memory of the ATmega2560, so there the
/// tables go to flash (`.progmem.data`, which the linker script keeps in the first 64 KB, as
/// `lpm` needs) and must be read with `lpm` by the backend ([`Math::read_table_cell`]). The
/// tables' declaration (`flash_tables!`) is the other place that names the target; elsewhere
/// they are ordinary read-only data.
pub const TABLES_IN_PROGRAM_MEMORY: bool = cfg!(target_arch = "avr");

/// The address of one entry of a fixed-point kernel's table (a cell), for
/// [`Math::read_table_cell`]; made only by this crate, from an index checked against the
/// table's length. The tables are reachable through nothing else, and the entry's one plain
/// load ([`Math`]'s default read) does not compile where the tables are in program memory: no
/// Rust code loads them there, which would read SRAM at a flash address.
#[derive(Clone, Copy)]
pub struct TableEntry<T: 'static>(&'static T);

/// The address only: formatting the entry must not load it (see [`TableEntry`]).
impl<T: 'static> core::fmt::Debug for TableEntry<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("TableEntry")
            .field(&(self.0 as *const T))
            .finish()
    }
}

impl<T: Copy + 'static> TableEntry<T> {
    /// The entry's address: in program memory when [`TABLES_IN_PROGRAM_MEMORY`], else in data
    /// memory. Valid for the whole program (the tables are immutable statics).
    #[inline(always)]
    pub fn addr(self) -> *const T {
        self.0
    }

    /// The plain load of [`Math`]'s default table reads, for the backend `M`: refused when
    /// `M` is compiled for a target whose tables are in program memory (a post-monomorphization
    /// error names the fix), so that a backend that forgets the flash read does not build.
    #[inline(always)]
    fn read_data_memory<M: ?Sized>(self) -> T {
        let () = ReadsDataMemory::<M>::CHECK;
        *self.0
    }
}

/// The compile-time check of [`TableEntry::read_data_memory`], per backend `M` (generic so
/// that it is evaluated only for a backend that uses the plain load).
struct ReadsDataMemory<M: ?Sized>(PhantomData<M>);

impl<M: ?Sized> ReadsDataMemory<M> {
    const CHECK: () = assert!(
        !TABLES_IN_PROGRAM_MEMORY,
        "this target keeps the fixed-point kernels' tables in program memory: the Math backend \
         must read them there (override Math::read_table_cell)"
    );
}

/// A constant table of a fixed-point kernel, readable only through [`Table::entry`] and a
/// backend's [`Math::read_table_cell`] (the array is private, so no code can index it with a
/// plain load).
struct Table<T: 'static, const N: usize>([T; N]);

impl<T: Copy + 'static, const N: usize> Table<T, N> {
    /// Entry `i` (panics when `i ≥ N`, as indexing does).
    #[inline(always)]
    fn entry(&'static self, i: usize) -> TableEntry<T> {
        // Indexing checks the bounds and takes the address, without a load.
        TableEntry(&self.0[i])
    }
}

/// Declares the kernels' tables as [`Table`] statics, in program memory on the AVR
/// ([`TABLES_IN_PROGRAM_MEMORY`]; `.progmem.data` is the section avr-gcc's linker script keeps
/// in flash and its startup code does not copy to SRAM).
macro_rules! flash_tables {
    ($($(#[$doc:meta])* $vis:vis static $name:ident: [$t:ty; $n:expr] = $value:expr;)+) => {
        $(
            $(#[$doc])*
            // `unsafe_code` flags a static's `link_section` because plain loads of data placed
            // in another memory would be wrong: [`Table`] admits only the backend's reads.
            #[cfg_attr(
                target_arch = "avr",
                allow(unsafe_code),
                link_section = ".progmem.data"
            )]
            $vis static $name: Table<$t, $n> = Table($value);
        )+
    };
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
}

/// The backend for CPUs without floating-point hardware, with the square root of backend `S`
/// (the ATmega2560 firmware: `SoftFloat<AvrLibm>`, avr-libc's hand-written `sqrt`; the host
/// tests: `SoftFloat<Libm>`, the default, which rounds the same):
///
/// - [`poly::atan2_fixed`] (through `S`'s [`Math::atan2_fixed`], which a backend may
///   implement for its target, bit for bit the same): an exact integer quotient of the
///   mantissas, then in 16-bit fixed point on the integer multiplier, atan from a table of
///   quadratic cells (error ≤ 2e-6 rad);
/// - [`poly::sin_cos_fixed`] (through `S`'s [`Math::sin_cos_fixed`], likewise): no range
///   reduction within ±π/4, then a table of quadratic cells in 16-bit fixed point
///   (error ≤ 1e-6);
/// - comparisons of the bit patterns (a software-float comparison is a library call, these
///   are a few integer instructions), equal to the float operators on every input;
/// - the four legs of a body solved one after the other ([`Math::STAGE_LEGS`] false);
/// - one copy of the float code where the crate has the choice ([`Math::SHARE_FLOAT_CODE`]);
/// - the kernels' tables read by `S` ([`Math::read_table_cell`]): a
///   plain load for `Libm`; from flash for the firmware's `AvrLibm`, on the AVR, where the
///   tables are linked into flash ([`TABLES_IN_PROGRAM_MEMORY`]).
///
/// Against [`DefaultMath`] the angles of a leg or body solve differ by at most about 4e-6 rad
/// (the fixed-point arctangent's error plus rounding; `tests/avr_kernels.rs`).
#[derive(Debug, Clone, Copy, Default)]
pub struct SoftFloat<S: Math = Libm>(PhantomData<S>);

impl<S: Math> Math for SoftFloat<S> {
    const STAGE_LEGS: bool = false;
    const SHARE_FLOAT_CODE: bool = true;

    #[inline]
    fn sqrt(x: f32) -> f32 {
        S::sqrt(x)
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        S::atan2_fixed(y, x)
    }

    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        S::sin_cos_fixed(x)
    }

    #[inline(always)]
    fn gt_zero(x: f32) -> bool {
        bits::gt_zero(x)
    }

    #[inline(always)]
    fn lt_nonneg(a: f32, b: f32) -> bool {
        bits::lt_nonneg(a, b)
    }

    #[inline(always)]
    fn within(x: f32, lo: f32, hi: f32) -> bool {
        bits::within(x, bits::interval(lo, hi))
    }

    #[inline(always)]
    fn within_keys(x: f32, _lo: f32, _hi: f32, keys: (i32, i32)) -> bool {
        bits::within(x, keys)
    }

    #[inline(always)]
    fn read_table_cell<const N: usize>(entry: TableEntry<[u16; N]>) -> [u16; N] {
        S::read_table_cell(entry)
    }

    #[inline]
    fn atan2_fixed(y: f32, x: f32) -> f32 {
        S::atan2_fixed(y, x)
    }

    #[inline]
    fn sin_cos_fixed(x: f32) -> (f32, f32) {
        S::sin_cos_fixed(x)
    }
}

const FRAC_PI_2: f32 = core::f32::consts::FRAC_PI_2;
const PI: f32 = core::f32::consts::PI;

/// The polynomial kernels behind [`Fast`], and cheaper ones for targets without hardware
/// floating point, for a firmware's own [`Math`] backend to pick from.
///
/// | kernel | max abs error (tests) | suits |
/// |---|---|---|
/// | [`atan2_deg15`](poly::atan2_deg15) | 3e-7 rad | hosts: branch-free, Estrin |
/// | [`atan2_deg9`](poly::atan2_deg9) | 1.2e-5 rad (0.0007°) | in-order CPUs with software floats: 6 multiplications, 4 additions, 1 division, no float comparison |
/// | [`atan2_fixed`](poly::atan2_fixed) | 2e-6 rad (0.0001°) | CPUs with software floats and an integer multiplier (the ATmega2560): an integer division of the mantissas, a table of 32 quadratic cells in 16-bit fixed point |
/// | [`sin_cos_deg9`](poly::sin_cos_deg9) | 2e-7 | hosts: branch-free |
/// | [`sin_cos_deg5`](poly::sin_cos_deg5) | 7e-7 | software floats: 7 multiplications, 5 additions, no range reduction for \|x\| ≤ π/4 |
/// | [`sin_cos_fixed`](poly::sin_cos_fixed) | 1e-6 | CPUs with software floats and an integer multiplier (the ATmega2560): no range reduction for \|x\| ≤ π/4, a table of 26 quadratic cells in 16-bit fixed point, two integer-to-float conversions |
pub mod poly {
    use super::{Math, Table, FRAC_PI_2, PI};

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
    #[inline(always)]
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
    #[inline(always)]
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

    /// [`atan2_fixed`]'s arctangent on `t ∈ [0, 1]` in 32 cells of width 1/32 (and cell 32,
    /// `t = 1` alone): in cell `k`, `atan(k/32 + d) ≈ a + b·d − c·d²` for `d ∈ [0, 1/32)`, the
    /// quadratic through the cell's three Chebyshev nodes, rounded to `a` in Q29 (`a₀ = 0`:
    /// exact at `t = 0`), `b` in Q15 and `c` in Q16 (`c ≥ 0`, atan being concave there), from
    /// `scripts/fit_polynomials.py`: error 9.4e-7 rad in this fixed-point arithmetic. Three
    /// 16 × 16-bit products per arctangent instead of a polynomial's seven; the tables are
    /// what it costs (in flash on the AVR: [`ATAN_CELLS`]).
    const ATAN_CELL_A_Q29: [u32; 33] = [
        0,
        16_771_589,
        33_510_678,
        50_184_805,
        66_762_427,
        83_213_099,
        99_507_789,
        115_619_162,
        131_521_807,
        147_192_431,
        162_609_989,
        177_755_778,
        192_613_475,
        207_169_131,
        221_411_131,
        235_330_121,
        248_918_896,
        262_172_285,
        275_086_996,
        287_661_475,
        299_895_737,
        311_791_212,
        323_350_581,
        334_577_621,
        345_477_059,
        356_054_431,
        366_315_948,
        376_268_384,
        385_918_958,
        395_275_239,
        404_345_057,
        413_136_426,
        421_657_471,
    ];

    /// `b` of [`ATAN_CELL_A_Q29`]'s cells, Q15.
    const ATAN_CELL_B_Q15: [u16; 33] = [
        32_774, 32_742, 32_646, 32_488, 32_269, 31_992, 31_660, 31_276, 30_844, 30_369, 29_856,
        29_308, 28_730, 28_128, 27_505, 26_866, 26_215, 25_556, 24_892, 24_227, 23_563, 22_903,
        22_250, 21_605, 20_970, 20_347, 19_737, 19_140, 18_557, 17_990, 17_438, 16_902, 16_383,
    ];

    /// `c` of [`ATAN_CELL_A_Q29`]'s cells, Q16.
    const ATAN_CELL_C_Q16: [u16; 33] = [
        1023, 3058, 5057, 6998, 8861, 10_625, 12_276, 13_800, 15_187, 16_430, 17_524, 18_470,
        19_268, 19_922, 20_438, 20_824, 21_086, 21_236, 21_282, 21_235, 21_105, 20_901, 20_633,
        20_311, 19_942, 19_535, 19_097, 18_633, 18_151, 17_655, 17_150, 16_640, 16_128,
    ];

    /// [`sin_cos_fixed`]'s sine on `r ∈ [0, 0.8125]` (π/4 and the rounding of a range
    /// reduction) in 26 cells of width 1/32: in cell `k`, `sin(k/32 + d) ≈ a + b·d − c·d²` for
    /// `d ∈ [0, 1/32)`, the quadratic through the cell's three Chebyshev nodes
    /// (`scripts/fit_polynomials.py`), `a` in Q29 (`a₀ = 0`), `b` in Q15, `c` in Q16.
    const SIN_CELL_A_Q29: [u32; 26] = [
        0,
        16_774_400,
        33_532_506,
        50_257_868,
        66_934_153,
        83_545_079,
        100_074_424,
        116_506_049,
        132_823_907,
        149_012_065,
        165_054_715,
        180_936_192,
        196_640_988,
        212_153_767,
        227_459_382,
        242_542_886,
        257_389_552,
        271_984_881,
        286_314_621,
        300_364_780,
        314_121_638,
        327_571_761,
        340_702_017,
        353_499_582,
        365_951_961,
        378_046_994,
    ];

    /// `b` of [`SIN_CELL_A_Q29`]'s cells, Q15.
    const SIN_CELL_B_Q15: [u16; 26] = [
        32_771, 32_755, 32_707, 32_627, 32_515, 32_372, 32_197, 31_990, 31_752, 31_483, 31_184,
        30_854, 30_494, 30_104, 29_684, 29_236, 28_759, 28_254, 27_722, 27_162, 26_576, 25_964,
        25_327, 24_664, 23_978, 23_268,
    ];

    /// `c` of [`SIN_CELL_A_Q29`]'s cells, Q16.
    const SIN_CELL_C_Q16: [u16; 26] = [
        512, 1535, 2557, 3577, 4593, 5604, 6610, 7610, 8602, 9586, 10_560, 11_524, 12_477, 13_417,
        14_345, 15_258, 16_157, 17_040, 17_906, 18_755, 19_585, 20_396, 21_188, 21_958, 22_707,
        23_435,
    ];

    /// [`sin_cos_fixed`]'s cosine in the cells of [`SIN_CELL_A_Q29`]:
    /// `cos(k/32 + d) ≈ a − b·d − c·d²`, `a` in Q29 (`a₀ = 1`: `cos 0` exact), `b` and `c` in
    /// Q16.
    const COS_CELL_A_Q29: [u32; 26] = [
        536_870_912,
        536_608_793,
        535_822_684,
        534_513_352,
        532_682_078,
        530_330_649,
        527_461_361,
        524_077_015,
        520_180_918,
        515_776_872,
        510_869_179,
        505_462_631,
        499_562_508,
        493_174_570,
        486_305_055,
        478_960_672,
        471_148_592,
        462_876_443,
        454_152_304,
        444_984_692,
        435_382_560,
        425_355_285,
        414_912_657,
        404_064_875,
        392_822_529,
        381_196_599,
    ];

    /// `b` of [`COS_CELL_A_Q29`]'s cells, Q16.
    const COS_CELL_B_Q16: [u16; 26] = [
        0, 2048, 4094, 6136, 8171, 10_199, 12_217, 14_223, 16_215, 18_192, 20_150, 22_089, 24_006,
        25_900, 27_769, 29_610, 31_423, 33_204, 34_954, 36_669, 38_349, 39_991, 41_593, 43_156,
        44_676, 46_153,
    ];

    /// `c` of [`COS_CELL_A_Q29`]'s cells, Q16.
    const COS_CELL_C_Q16: [u16; 26] = [
        32_764, 32_732, 32_668, 32_572, 32_444, 32_285, 32_094, 31_872, 31_618, 31_334, 31_019,
        30_674, 30_299, 29_895, 29_461, 28_998, 28_507, 27_988, 27_442, 26_870, 26_270, 25_646,
        24_996, 24_322, 23_624, 22_903,
    ];

    flash_tables! {
        /// [`atan2_fixed`]'s cells as the kernel reads them, one row per cell `k`:
        /// `[a_lo, a_hi, b, c]` of [`ATAN_CELL_A_Q29`], [`ATAN_CELL_B_Q15`], [`ATAN_CELL_C_Q16`]
        /// (`a` in two 16-bit halves), so that one read fetches a cell's consecutive bytes.
        pub(super) static ATAN_CELLS: [[u16; 4]; 33] =
            cells(&ATAN_CELL_A_Q29, &ATAN_CELL_B_Q15, &ATAN_CELL_C_Q16);

        /// [`sin_cos_fixed`]'s cells as the kernel reads them: per cell the sine's row
        /// (`[a_lo, a_hi, b, c]` of [`SIN_CELL_A_Q29`], …), then the cosine's.
        static SIN_COS_CELLS: [[u16; 8]; 26] = concat_cells(
            cells(&SIN_CELL_A_Q29, &SIN_CELL_B_Q15, &SIN_CELL_C_Q16),
            cells(&COS_CELL_A_Q29, &COS_CELL_B_Q16, &COS_CELL_C_Q16),
        );
    }

    /// Rows `[a_lo, a_hi, b, c]` of the cells `(a[k], b[k], c[k])`, at compile time.
    const fn cells<const N: usize>(a: &[u32; N], b: &[u16; N], c: &[u16; N]) -> [[u16; 4]; N] {
        let mut rows = [[0; 4]; N];
        let mut k = 0;
        while k < N {
            rows[k] = [a[k] as u16, (a[k] >> 16) as u16, b[k], c[k]];
            k += 1;
        }
        rows
    }

    /// Rows `first[k]` followed by `second[k]`, at compile time.
    const fn concat_cells<const N: usize>(
        first: [[u16; 4]; N],
        second: [[u16; 4]; N],
    ) -> [[u16; 8]; N] {
        let mut rows = [[0; 8]; N];
        let mut k = 0;
        while k < N {
            let mut i = 0;
            while i < 4 {
                rows[k][i] = first[k][i];
                rows[k][4 + i] = second[k][i];
                i += 1;
            }
            k += 1;
        }
        rows
    }

    /// `a_lo + a_hi·2¹⁶` of a row of [`cells`].
    #[inline(always)]
    fn join(lo: u16, hi: u16) -> u32 {
        lo as u32 | (hi as u32) << 16
    }

    /// `a·b` of two 16-bit numbers from its four 8 × 8-bit partial products: on the
    /// ATmega2560 four hardware multiplications inline, where `a as u32 * b as u32` would call
    /// a 32 × 32-bit routine. Only the fixed-point kernels use it, those of CPUs without
    /// floating-point hardware, so every target compiles this one form.
    #[inline(always)]
    pub(super) fn mul_16x16(a: u16, b: u16) -> u32 {
        let (a0, a1, b0, b1) = (a as u8 as u16, a >> 8, b as u8 as u16, b >> 8);
        let mid = (a0 * b1) as u32 + (a1 * b0) as u32;
        (a0 * b0) as u32 + (mid << 8) + (((a1 * b1) as u32) << 16)
    }

    /// Four-quadrant arctangent for CPUs without hardware floating point: the exact integer
    /// quotient `t = min(|x|,|y|) / max(|x|,|y|)` of the two floats' mantissas
    /// ([`atan_ratio_q21`]), then atan(t) from a table of 32 quadratic cells
    /// (`ATAN_CELL_A_Q29`) in 16-bit fixed point (three 16 × 16-bit products), the octant
    /// added in fixed point, and one integer-to-float conversion: on the ATmega2560 far fewer
    /// cycles than [`atan2_deg9`] in software floats (see `docs/benchmark-journal.md`). Absolute
    /// error ≤ 2e-6 rad (tests; the cells' 9.4e-7 plus the truncation of `t` to 2⁻²¹ and the
    /// rounding of the result). `atan2(±0, ±0)` as libm (±0 or ±π); exact on the axes. The
    /// backend `M` reads the tables ([`Math::read_table_cell`]: in flash on the AVR), the
    /// kernel's only per-target part; [`SoftFloat`](super::SoftFloat) passes its own.
    ///
    /// Formats: `t` in Q21 (`T = ⌊t·2²¹⌋`, exact: no float rounding, so that a backend's own
    /// implementation ([`Math::atan2_fixed`]) can match it bit for bit), the cell offset `d`
    /// in Q21, the result in Q29 (π < 2²).
    ///
    /// Never inlined: on the AVR its `mul` instructions stay in this function's own small stack
    /// frame, clear of an LLVM AVR miscompilation in frames beyond 63 bytes (see the
    /// firmware's emulator test `no_mul_result_is_clobbered_by_a_frame_pointer_adjustment`);
    /// hosts do not use this kernel in their backends, so the call costs them nothing.
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
    pub fn atan_cells() -> super::TableEntry<[u16; 4]> {
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

    /// `(sin x, cos x)` for CPUs without hardware floating point: arguments within ±π/4 (body
    /// rotations) skip the range reduction (an integer comparison finds them); then `|r|` in
    /// Q24 from the float's mantissa, sine and cosine from a table of 26 quadratic cells
    /// (`SIN_CELL_A_Q29`, `COS_CELL_A_Q29`) in 16-bit fixed point (five 16 × 16-bit
    /// products for both), two integer-to-float conversions: on the ATmega2560 far fewer
    /// cycles than [`sin_cos_deg5`]'s twelve software-float operations (see
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
    #[inline(always)]
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
    #[inline(never)]
    fn sin_cos_fixed_reduced<F: FnOnce(u32) -> (u32, u32)>(x: f32, core: F) -> (f32, f32) {
        if !super::finite(x) {
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
    #[inline(always)]
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
    pub fn sin_cos_cells() -> super::TableEntry<[u16; 8]> {
        SIN_COS_CELLS.entry(0)
    }

    /// The bits of the float `v·2⁻²⁹` (`v < 2³¹`, positive): one integer-to-float conversion,
    /// then the exponent lowered by 29 (`v = 0` stays +0).
    #[inline(always)]
    fn q29_bits(v: u32) -> u32 {
        if v == 0 {
            0
        } else {
            (v as f32).to_bits() - (29 << 23)
        }
    }

    /// Quadrant `k = round(x / (π/2))` modulo 4 and `r = x − k·π/2` in two parts
    /// (Cody–Waite).
    #[inline(always)]
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
    #[inline(always)]
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
}

/// The keys of the closed interval `[lo, hi]` for [`Math::within_keys`]: integers that order
/// as the floats do (−0 = +0), `(i32::MAX, i32::MIN)` (admitting nothing) when a bound is NaN.
#[inline]
pub const fn interval_keys(lo: f32, hi: f32) -> (i32, i32) {
    bits::interval(lo, hi)
}

/// `x.is_finite()` from the exponent bits, on every target (core's `is_finite` is a float
/// comparison, a library call on CPUs without floating-point hardware): finite when the
/// exponent (bits 30..23) is short of all ones, tested as one byte (a byte compare on an 8-bit
/// CPU rather than a 32-bit mask).
#[inline(always)]
pub(crate) const fn finite(x: f32) -> bool {
    (x.to_bits() >> 23) as u8 != u8::MAX
}

/// `x.is_finite() && x > 0.0` from the bits: the patterns of the positive subnormals to the
/// largest finite float.
#[inline(always)]
pub(crate) const fn positive_finite(x: f32) -> bool {
    x.to_bits().wrapping_sub(1) < bits::INF - 1
}

/// `x.is_finite() && x >= 0.0` from the bits: +0 to the largest finite float, or −0.
#[inline(always)]
pub(crate) const fn nonneg_finite(x: f32) -> bool {
    let b = x.to_bits();
    b < bits::INF || b == 0x8000_0000
}

/// `lo.is_finite() && hi.is_finite() && lo <= hi` from the bits.
#[inline(always)]
pub(crate) const fn finite_ordered(lo: f32, hi: f32) -> bool {
    finite(lo) && finite(hi) && bits::key(lo) <= bits::key(hi)
}

/// Float comparisons as integer comparisons of the bit patterns, with the semantics of the
/// float operators (NaN included): [`SoftFloat`]'s comparisons.
mod bits {
    /// Bits of +∞; larger patterns with a clear sign bit are NaNs.
    pub(super) const INF: u32 = 0x7f80_0000;

    /// `x > 0.0`: the patterns `1 ..= INF` (positive subnormals to +∞).
    #[inline(always)]
    pub(super) fn gt_zero(x: f32) -> bool {
        x.to_bits().wrapping_sub(1) < INF
    }

    /// `a < b` for `a`, `b` with a clear sign bit or NaN: non-negative floats order as
    /// their patterns; a NaN `b` (pattern above INF, or sign set) fails the second test, a
    /// NaN `a` the first.
    #[inline(always)]
    pub(super) fn lt_nonneg(a: f32, b: f32) -> bool {
        let (a, b) = (a.to_bits(), b.to_bits());
        a < b && b <= INF
    }

    /// A key that orders non-NaN floats as `<` does, with −0 = +0 (sign–magnitude to
    /// two's complement); positive NaNs sort above +∞, negative NaNs below −∞.
    #[inline(always)]
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
    #[inline(always)]
    pub(super) fn within(x: f32, (lo, hi): (i32, i32)) -> bool {
        let k = key(x);
        lo <= k && k <= hi
    }
}

/// `⌊x⌋`: equal to `libm::floorf` on every input (tested against it), written with one
/// float-to-integer conversion and back rather than libm's bit manipulation of the pattern,
/// whose 32-bit shifts and masks are a few hundred bytes of code on an 8-bit CPU (the
/// firmware's flash; the conversions are linked there anyway). Out of line: one copy.
#[inline(never)]
pub fn floor(x: f32) -> f32 {
    // From 2^23 on (and ±∞, NaN) every f32 is whole already.
    if !(x.abs() < 8_388_608.0) {
        return x;
    }
    let t = x as i32 as f32;
    if t == x {
        x // Whole (keeps the sign of −0).
    } else if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `⌈x⌉`: equal to `libm::ceilf` on every input, as `−⌊−x⌋` ([`floor`]).
#[inline]
pub fn ceil(x: f32) -> f32 {
    -floor(-x)
}

/// Wraps an angle into `(-π, π]`.
///
/// Out of line: its callers wrap once or twice per frame, and on a soft-float target each
/// inlined copy is its own library calls.
#[inline(never)]
pub fn wrap_pi(angle_rad: f32) -> f32 {
    let two_pi = 2.0 * PI;
    // The nearest whole turn by `floor` (libm's `roundf` is a second copy of its bit
    // manipulation on a soft-float target); a half turn either way is put right below.
    let mut a = angle_rad - two_pi * floor(angle_rad / two_pi + 0.5);
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
    let mut a = angle_rad - two_pi * floor(angle_rad / two_pi);
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
    fn wrap_pi_lands_in_the_half_open_turn_on_the_same_angle() {
        let mut rng = SplitMix64::new(0x77a9);
        let halves = [PI, -PI, 3.0 * PI, -3.0 * PI, 0.5 * PI, 0.0, -0.0];
        let random = (0..100_000).map(|_| (rng.next_u64() % 2_000_001) as f32 * 1e-4 - 100.0);
        for a in halves.into_iter().chain(random) {
            let w = wrap_pi(a);
            assert!(w > -PI && w <= PI, "{a}: {w}");
            let turns = (f64::from(a) - f64::from(w)) / (2.0 * core::f64::consts::PI);
            assert!((turns - turns.round()).abs() < 1e-5, "{a}: {w}");
        }
    }

    #[test]
    fn floor_and_ceil_equal_libm_on_special_and_random_inputs() {
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            0.999_999_94,
            -0.999_999_94,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_608.0,
            16_777_217.0,
            1e-45,
            -1e-45,
            2.147_483_6e9,
            -2.147_483_6e9,
            3.4e38,
            -3.4e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        let mut rng = SplitMix64::new(0xf100_c0de);
        let random = (0..100_000).map(|_| f32::from_bits(rng.next_u64() as u32));
        for x in special.into_iter().chain(random) {
            for (got, want) in [(floor(x), libm::floorf(x)), (ceil(x), libm::ceilf(x))] {
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{x:e}: {got:e} vs {want:e}"
                );
            }
        }
    }
    use seeded_rng::SplitMix64;
    extern crate std;
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

    /// Largest |atan2 − f64 atan2| of `f` over a 720-step circle at several radii, rad.
    fn worst_atan2_error(f: impl Fn(f32, f32) -> f32) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..=720 {
            for r in [1e-3f32, 0.3, 1.0, 7.0] {
                let ang = -PI + (i as f32) * (2.0 * PI / 720.0);
                let (y, x) = (r * libm::sinf(ang), r * libm::cosf(ang));
                let got = f(y, x) as f64;
                let want = (y as f64).atan2(x as f64);
                let mut d = (got - want).abs();
                if d > core::f64::consts::PI {
                    d = 2.0 * core::f64::consts::PI - d;
                }
                worst = worst.max(d);
            }
        }
        worst
    }

    /// Error bound of [`poly::atan2_deg9`] (the fit's 1.14e-5 plus f32 rounding).
    const ATAN2_DEG9_TOL_RAD: f64 = 1.2e-5;

    #[test]
    fn atan2_deg9_matches_f64_everywhere() {
        let worst = worst_atan2_error(poly::atan2_deg9);
        assert!(worst < ATAN2_DEG9_TOL_RAD, "worst atan2_deg9 error {worst}");
        // A dense sweep of t = y/x in the first octant, where the polynomial is evaluated.
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let t = i as f32 / 100_000.0;
            let d = (poly::atan2_deg9(t, 1.0) as f64 - (t as f64).atan()).abs();
            worst = worst.max(d);
        }
        assert!(worst < ATAN2_DEG9_TOL_RAD, "worst atan_deg9 error {worst}");
    }

    /// Error bound of [`poly::atan2_fixed`].
    const ATAN2_FIXED_TOL_RAD: f64 = 3.5e-5;

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
        assert_eq!(poly::atan2_deg9(0.0, -1.0), PI);
        assert_eq!(poly::atan2_deg9(1.0, 0.0), FRAC_PI_2);
        assert_eq!(poly::atan2_deg9(-1.0, 0.0), -FRAC_PI_2);
        assert_eq!(poly::atan2_fixed::<SoftFloat>(0.0, -1.0), PI);
        assert_eq!(poly::atan2_fixed::<SoftFloat>(1.0, 0.0), FRAC_PI_2);
        assert_eq!(poly::atan2_fixed::<SoftFloat>(-1.0, 0.0), -FRAC_PI_2);
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
        assert_eq!(poly::sin_cos_deg5(0.0), (0.0, 1.0));
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
            assert_eq!(poly::mul_16x16(a, b), a as u32 * b as u32);
        }
        for (a, b) in [
            (0u16, 0u16),
            (65535, 65535),
            (65535, 1),
            (255, 256),
            (256, 256),
        ] {
            assert_eq!(poly::mul_16x16(a, b), a as u32 * b as u32);
        }
    }

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

    /// The default table read is a plain load of the entry, and an entry's `Debug` shows its
    /// address, not its value.
    #[test]
    fn table_entries_read_and_print_without_a_second_path() {
        use std::format;
        let entry = poly::ATAN_CELLS.entry(32);
        assert_eq!(
            Libm::read_table_cell(entry),
            SoftFloat::<Libm>::read_table_cell(entry)
        );
        assert_eq!(Libm::read_table_cell(entry)[2], 16_383);
        let shown = format!("{entry:?}");
        assert!(shown.starts_with("TableEntry(0x"), "{shown}");
    }

    #[test]
    fn wraps() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-6);
        assert!((wrap_two_pi(-0.5) - (2.0 * PI - 0.5)).abs() < 1e-6);
        assert!(wrap_two_pi(2.0 * PI) < 1e-6);
    }
}
