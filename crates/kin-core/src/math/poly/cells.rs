//! The fixed-point kernels' tables of quadratic cells.

use crate::math::table::{flash_tables, Table};

/// [`atan2_fixed`](super::atan2_fixed)'s arctangent on `t ∈ [0, 1]` in 32 cells of width 1/32 (and cell 32,
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
    32_774, 32_742, 32_646, 32_488, 32_269, 31_992, 31_660, 31_276, 30_844, 30_369, 29_856, 29_308,
    28_730, 28_128, 27_505, 26_866, 26_215, 25_556, 24_892, 24_227, 23_563, 22_903, 22_250, 21_605,
    20_970, 20_347, 19_737, 19_140, 18_557, 17_990, 17_438, 16_902, 16_383,
];

/// `c` of [`ATAN_CELL_A_Q29`]'s cells, Q16.
const ATAN_CELL_C_Q16: [u16; 33] = [
    1023, 3058, 5057, 6998, 8861, 10_625, 12_276, 13_800, 15_187, 16_430, 17_524, 18_470, 19_268,
    19_922, 20_438, 20_824, 21_086, 21_236, 21_282, 21_235, 21_105, 20_901, 20_633, 20_311, 19_942,
    19_535, 19_097, 18_633, 18_151, 17_655, 17_150, 16_640, 16_128,
];

/// [`sin_cos_fixed`](super::sin_cos_fixed)'s sine on `r ∈ [0, 0.8125]` (π/4 and the rounding of a range
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
    32_771, 32_755, 32_707, 32_627, 32_515, 32_372, 32_197, 31_990, 31_752, 31_483, 31_184, 30_854,
    30_494, 30_104, 29_684, 29_236, 28_759, 28_254, 27_722, 27_162, 26_576, 25_964, 25_327, 24_664,
    23_978, 23_268,
];

/// `c` of [`SIN_CELL_A_Q29`]'s cells, Q16.
const SIN_CELL_C_Q16: [u16; 26] = [
    512, 1535, 2557, 3577, 4593, 5604, 6610, 7610, 8602, 9586, 10_560, 11_524, 12_477, 13_417,
    14_345, 15_258, 16_157, 17_040, 17_906, 18_755, 19_585, 20_396, 21_188, 21_958, 22_707, 23_435,
];

/// [`sin_cos_fixed`](super::sin_cos_fixed)'s cosine in the cells of [`SIN_CELL_A_Q29`]:
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
    25_900, 27_769, 29_610, 31_423, 33_204, 34_954, 36_669, 38_349, 39_991, 41_593, 43_156, 44_676,
    46_153,
];

/// `c` of [`COS_CELL_A_Q29`]'s cells, Q16.
const COS_CELL_C_Q16: [u16; 26] = [
    32_764, 32_732, 32_668, 32_572, 32_444, 32_285, 32_094, 31_872, 31_618, 31_334, 31_019, 30_674,
    30_299, 29_895, 29_461, 28_998, 28_507, 27_988, 27_442, 26_870, 26_270, 25_646, 24_996, 24_322,
    23_624, 22_903,
];

flash_tables! {
    /// [`atan2_fixed`](super::atan2_fixed)'s cells as the kernel reads them, one row per cell `k`:
    /// `[a_lo, a_hi, b, c]` of [`ATAN_CELL_A_Q29`], [`ATAN_CELL_B_Q15`], [`ATAN_CELL_C_Q16`]
    /// (`a` in two 16-bit halves), so that one read fetches a cell's consecutive bytes.
    pub(in crate::math) static ATAN_CELLS: [[u16; 4]; 33] =
        cells(&ATAN_CELL_A_Q29, &ATAN_CELL_B_Q15, &ATAN_CELL_C_Q16);

    /// [`sin_cos_fixed`](super::sin_cos_fixed)'s cells as the kernel reads them: per cell the sine's row
    /// (`[a_lo, a_hi, b, c]` of [`SIN_CELL_A_Q29`], …), then the cosine's.
    pub(super) static SIN_COS_CELLS: [[u16; 8]; 26] = concat_cells(
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
pub(super) fn join(lo: u16, hi: u16) -> u32 {
    lo as u32 | (hi as u32) << 16
}
