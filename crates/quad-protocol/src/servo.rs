//! Hobby-servo calibration and the angle ↔ pulse mapping shared by the firmware and the host.
//!
//! One joint drives one servo. The pulse width for a joint angle is
//!
//! ```text
//! pulse_us = center_us + s · us_per_rad · (angle_rad − zero_rad)      s = −1 if reversed, else +1
//! ```
//!
//! and is valid only within `[min_us, max_us]`; outside it the mapping returns a typed error
//! (never a clamped pulse, never NaN). Pulses travel and are written to the timers in **half
//! microseconds** (`pulse_half_us`): the ATmega2560's 16-bit timers with prescaler 8 at 16 MHz
//! tick every 0.5 µs, so one half-µs is one timer tick and `OCRn = pulse_half_us` exactly.
//!
//! The computation is fixed so that every IEEE-754 f32 implementation gives the same bits:
//! `half = 2 · (center_us + s · (us_per_rad · (angle_rad − zero_rad)))`, then rounded half-up to
//! an integer (`floor(half + 0.5)`), then checked against `[2·min_us, 2·max_us]`.
//!
//! [`PulseMap`] is a calibration validated once and precomputed for that mapping
//! ([`Calibration::pulse_map`]); [`Calibration::pulse_half_us`] is `pulse_map()` followed by
//! [`PulseMap::pulse_half_us`]. The map computes `half = 2·center_us + (s·2·us_per_rad) ·
//! (angle_rad − zero_rad)` (three float operations) and rounds on the bits of `half`, with the
//! same result as the form above for every angle:
//!
//! - Doubling is exact in binary floating point, so it commutes with each rounding except when
//!   a value leaves the normal range. A product `us_per_rad · (angle_rad − zero_rad)` in the
//!   subnormal range is far below half an ulp of `center_us ≥` [`PULSE_MIN_US`]: both forms
//!   give `2·center_us`. A product near overflow gives both forms a `half` beyond 65,536 of the
//!   product's sign (±∞ included), refused alike. Otherwise both give the same `half`, bit for
//!   bit.
//! - Every valid travel lies within `[600, 5400]` half-µs. A `half` below 512 or from 8192
//!   (negative, ±0, ±∞ included) is refused without rounding; within `[512, 8192)` the ulp of
//!   `half` is at most 2⁻¹¹, `half + 0.5` is exact or rounds within the same integer, and
//!   `floor(half + 0.5)` is taken from the bits. (Outside that interval the float addition
//!   itself may round to the next integer, e.g. `0.5 − 2⁻²⁵ + 0.5` gives 1.0; those pulses are
//!   refused either way.)

use crate::wire::wire_enum;
use core::fmt;
use serde::{Deserialize, Serialize};

/// Lowest pulse width any calibration may allow, µs.
pub const PULSE_MIN_US: u16 = 300;
/// Highest pulse width any calibration may allow, µs.
pub const PULSE_MAX_US: u16 = 2700;
/// Smallest admissible servo gain, µs per rad.
pub const US_PER_RAD_MIN: f32 = 50.0;
/// Largest admissible servo gain, µs per rad.
pub const US_PER_RAD_MAX: f32 = 5000.0;
/// Largest admissible |zero_rad|, rad (one full turn).
pub const ZERO_RAD_LIMIT: f32 = core::f32::consts::TAU;

/// The sign bit of an `f32`.
const SIGN_BIT: u32 = 1 << 31;

/// The bits of +∞; above them (sign cleared), NaN.
const INF_BITS: u32 = 0x7f80_0000;

/// The bits of 512.0: every `half` below it (in half-µs) lies below any valid travel.
const ROUNDED_LOW_BITS: u32 = 0x4400_0000;

/// The bits of 8192.0: every `half` from it on lies above any valid travel.
const ROUNDED_END_BITS: u32 = 0x4600_0000;

/// The high halves of the bits of +∞, 512.0 and 8192.0, whose low halves are zero: the high
/// half of a float's bits compares with them as its whole bits compare with the whole
/// constants (two bytes instead of four on an 8-bit CPU).
const INF_HIGH: u16 = (INF_BITS >> 16) as u16;
/// See [`INF_HIGH`]; signed, so that every negative float (sign bit set) lies below.
const ROUNDED_LOW_HIGH: i16 = (ROUNDED_LOW_BITS >> 16) as i16;
/// See [`INF_HIGH`].
const ROUNDED_END_HIGH: u16 = (ROUNDED_END_BITS >> 16) as u16;

const _: () = {
    assert!(INF_BITS & 0xffff == 0 && ROUNDED_LOW_BITS & 0xffff == 0);
    assert!(ROUNDED_END_BITS & 0xffff == 0);
    assert!(f32::from_bits(ROUNDED_LOW_BITS) == 512.0);
    assert!(f32::from_bits(ROUNDED_END_BITS) == 8192.0);
    // A `half` below 512 rounds to at most 512 ticks, one from 8192 to at least 8192.
    assert!(2 * PULSE_MIN_US > 512);
    assert!(2 * PULSE_MAX_US < 8192);
};

/// `⌊half + 0.5⌋` of the `half` whose bits are `bits`, for `half` in `[512, 8192)`, from its
/// bits: no float addition (a library call on the ATmega2560). Exact: `half + 0.5` is exact
/// there or, crossing a power of two, rounds to a value of the same integer part.
#[inline(always)]
fn round_half_up_512_8192(bits: u32) -> u16 {
    // `half = m·2^(e − 150)` with the 24-bit significand `m` and `e` in 136..=139, so
    // `⌊half + 0.5⌋ = ⌊(m + 2^(149 − e)) / 2^(150 − e)⌋`. The lowest 8 bits of `m` lie below
    // the rounding bit (`149 − e ≥ 10`) and drop first; the 16 bits left hold the implicit one
    // at bit 15 (where `bits` has the exponent's lowest bit).
    let e = (bits >> 23) as u8;
    let m16 = (bits >> 8) as u16 | 0x8000;
    ((m16 >> (141 - e)) + 1) >> 1
}

/// Gain of a standard hobby servo: 1000 µs per 90° (and 2000 µs per 180°), µs per rad.
pub const STANDARD_US_PER_RAD: f32 = 2000.0 / core::f32::consts::PI;

wire_enum! {
    /// Why an angle or a pulse cannot be mapped, or why a calibration is refused.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[non_exhaustive]
    pub enum Error {
        /// The angle is NaN or infinite.
        0 => NonFiniteAngle,
        /// The pulse would be shorter than `min_us`.
        1 => BelowMin,
        /// The pulse would be longer than `max_us`.
        2 => AboveMax,
        /// `zero_rad` is not finite or |zero_rad| > [`ZERO_RAD_LIMIT`].
        3 => BadZero,
        /// `us_per_rad` is not finite or lies outside [[`US_PER_RAD_MIN`], [`US_PER_RAD_MAX`]].
        4 => BadGain,
        /// `min_us < max_us` within [[`PULSE_MIN_US`], [`PULSE_MAX_US`]] does not hold.
        5 => BadBounds,
        /// `center_us` lies outside `[min_us, max_us]`.
        6 => CenterOutOfBounds,
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Error::NonFiniteAngle => "angle is not finite",
            Error::BelowMin => "pulse would be below min_us",
            Error::AboveMax => "pulse would be above max_us",
            Error::BadZero => "zero_rad must be finite with |zero_rad| <= 2*pi",
            Error::BadGain => "us_per_rad must be finite, within [50, 5000]",
            Error::BadBounds => "min_us < max_us must hold within [300, 2700] us",
            Error::CenterOutOfBounds => "center_us must lie within [min_us, max_us]",
        })
    }
}

impl core::error::Error for Error {}

/// Calibration of one servo: where its zero is, which way it turns, its gain and its travel.
///
/// Field order is the wire order (see `docs/protocol.md`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Joint angle at which the servo sits at `center_us`, rad (fine trim of the horn).
    pub zero_rad: f32,
    /// True when a positive joint angle needs a shorter pulse (servo mounted mirrored).
    pub reversed: bool,
    /// Gain, µs of pulse per rad of joint angle (> 0; the direction is `reversed`).
    pub us_per_rad: f32,
    /// Pulse at `zero_rad`, µs.
    #[serde(with = "crate::wire::shared")]
    pub center_us: u16,
    /// Shortest admissible pulse, µs (mechanical stop or servo limit).
    #[serde(with = "crate::wire::shared")]
    pub min_us: u16,
    /// Longest admissible pulse, µs.
    #[serde(with = "crate::wire::shared")]
    pub max_us: u16,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration::STANDARD
    }
}

impl Calibration {
    /// A standard servo: 1500 µs at angle 0, [`STANDARD_US_PER_RAD`], travel 1000–2000 µs
    /// (±π/4 rad), not reversed.
    pub const STANDARD: Calibration = Calibration {
        zero_rad: 0.0,
        reversed: false,
        us_per_rad: STANDARD_US_PER_RAD,
        center_us: 1500,
        min_us: 1000,
        max_us: 2000,
    };

    /// Checks every field against the admissible ranges (see [`Error`]).
    pub fn validate(&self) -> Result<(), Error> {
        // Compared as bit patterns: for non-negative floats their order is that of the values,
        // and every NaN, infinity and negative value (sign bit set) lies above the finite
        // positive bounds, so it is refused as the float comparisons refuse it. On the ATmega2560
        // each float comparison is a library call.
        if self.zero_rad.to_bits() & !SIGN_BIT > ZERO_RAD_LIMIT.to_bits() {
            return Err(Error::BadZero);
        }
        let gain = self.us_per_rad.to_bits();
        if !(US_PER_RAD_MIN.to_bits() <= gain && gain <= US_PER_RAD_MAX.to_bits()) {
            return Err(Error::BadGain);
        }
        if !(PULSE_MIN_US <= self.min_us
            && self.min_us < self.max_us
            && self.max_us <= PULSE_MAX_US)
        {
            return Err(Error::BadBounds);
        }
        if !(self.min_us <= self.center_us && self.center_us <= self.max_us) {
            return Err(Error::CenterOutOfBounds);
        }
        Ok(())
    }

    /// Direction sign `s`: `−1.0` when reversed, else `+1.0`.
    #[inline]
    pub const fn sign(&self) -> f32 {
        if self.reversed {
            -1.0
        } else {
            1.0
        }
    }

    /// Lowest admissible pulse, half-µs.
    #[inline]
    pub const fn min_half_us(&self) -> u16 {
        self.min_us.saturating_mul(2)
    }

    /// Highest admissible pulse, half-µs.
    #[inline]
    pub const fn max_half_us(&self) -> u16 {
        self.max_us.saturating_mul(2)
    }

    /// Joint angle → pulse width in half-µs (timer ticks of 0.5 µs).
    ///
    /// `half = 2·(center_us + s·(us_per_rad·(angle_rad − zero_rad)))`, rounded half-up, and
    /// accepted only within `[2·min_us, 2·max_us]` (module docs). Validates the calibration
    /// with each call: to map many angles through one calibration, use its
    /// [`Calibration::pulse_map`].
    ///
    /// # Errors
    /// The calibration's own [`Error`] when it is invalid; [`Error::NonFiniteAngle`];
    /// [`Error::BelowMin`] / [`Error::AboveMax`] when the rounded pulse leaves the travel.
    pub fn pulse_half_us(&self, angle_rad: f32) -> Result<u16, Error> {
        self.pulse_map()?.pulse_half_us(angle_rad)
    }

    /// The calibration validated and precomputed for mapping angles to pulses: a mapping of
    /// many angles through one calibration validates it once (see [`PulseMap`]).
    ///
    /// # Errors
    /// The calibration's own [`Error`] when it is invalid ([`Calibration::validate`]).
    pub fn pulse_map(&self) -> Result<PulseMap, Error> {
        self.validate()?;
        // `2·us_per_rad` as one more in the exponent: a valid gain is normal and far from
        // overflow, so this is the exact doubling without a float multiplication (a library
        // call on the ATmega2560).
        let gain_bits = self.us_per_rad.to_bits() + (1 << 23);
        let sign_bit = if self.reversed { SIGN_BIT } else { 0 };
        Ok(PulseMap {
            // A valid centre is at most `PULSE_MAX_US`: the double fits.
            center_half_us: f32::from(self.center_us * 2),
            gain_half_us_per_rad: f32::from_bits(gain_bits | sign_bit),
            zero_rad: self.zero_rad,
            min_half_us: self.min_half_us(),
            max_half_us: self.max_half_us(),
        })
    }

    /// Pulse width in half-µs → joint angle, rad:
    /// `angle = zero_rad + s·((pulse_half_us/2 − center_us) / us_per_rad)`.
    ///
    /// # Errors
    /// The calibration's own [`Error`] when it is invalid; [`Error::BelowMin`] /
    /// [`Error::AboveMax`] when the pulse lies outside `[2·min_us, 2·max_us]`.
    pub fn angle_rad(&self, pulse_half_us: u16) -> Result<f32, Error> {
        self.validate()?;
        if pulse_half_us < self.min_half_us() {
            return Err(Error::BelowMin);
        }
        if pulse_half_us > self.max_half_us() {
            return Err(Error::AboveMax);
        }
        let delta_us = f32::from(pulse_half_us) * 0.5 - f32::from(self.center_us);
        Ok(self.zero_rad + self.sign() * (delta_us / self.us_per_rad))
    }

    /// The joint-angle interval `(low, high)` whose pulses lie within `[min_us, max_us]`, rad.
    ///
    /// # Errors
    /// The calibration's own [`Error`] when it is invalid.
    pub fn angle_limits_rad(&self) -> Result<(f32, f32), Error> {
        let a = self.angle_rad(self.min_half_us())?;
        let b = self.angle_rad(self.max_half_us())?;
        Ok(if a <= b { (a, b) } else { (b, a) })
    }
}

/// A servo calibration validated once and precomputed for mapping joint angles to pulses
/// ([`Calibration::pulse_map`]): the mapping of [`Calibration::pulse_half_us`], with the same
/// result for every angle, without validating the calibration again and with three float
/// operations instead of five (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseMap {
    /// `2·center_us`, half-µs.
    center_half_us: f32,
    /// `s·2·us_per_rad` (negative when reversed), half-µs per rad.
    gain_half_us_per_rad: f32,
    /// The calibration's `zero_rad`, rad.
    zero_rad: f32,
    /// `2·min_us`, half-µs.
    min_half_us: u16,
    /// `2·max_us`, half-µs.
    max_half_us: u16,
}

impl PulseMap {
    /// The map of no calibration: it refuses every angle ([`Error::NonFiniteAngle`] when the
    /// angle is not finite, else [`Error::BelowMin`]: an empty travel at 0 µs). All zeros, so
    /// that a table of them costs a memset.
    pub const NONE: PulseMap = PulseMap {
        center_half_us: 0.0,
        gain_half_us_per_rad: 0.0,
        zero_rad: 0.0,
        min_half_us: 0,
        max_half_us: 0,
    };

    /// Lowest admissible pulse, half-µs (`2·min_us`; 0 for [`PulseMap::NONE`]).
    #[inline]
    pub const fn min_half_us(&self) -> u16 {
        self.min_half_us
    }

    /// Highest admissible pulse, half-µs (`2·max_us`; 0 for [`PulseMap::NONE`]).
    #[inline]
    pub const fn max_half_us(&self) -> u16 {
        self.max_half_us
    }

    /// Joint angle → pulse width in half-µs (timer ticks of 0.5 µs): the result of
    /// [`Calibration::pulse_half_us`] on the calibration of this map, for every angle.
    ///
    /// # Errors
    /// [`Error::NonFiniteAngle`]; [`Error::BelowMin`] / [`Error::AboveMax`] when the rounded
    /// pulse leaves the travel.
    pub fn pulse_half_us(&self, angle_rad: f32) -> Result<u16, Error> {
        // The comparisons on the bit patterns, equal to the float comparisons they stand for
        // (each float comparison is a library call on the ATmega2560, which maps twelve pulses
        // per command and per servo frame).
        if (angle_rad.to_bits() >> 16) as u16 & 0x7fff >= INF_HIGH {
            return Err(Error::NonFiniteAngle);
        }
        // Finite inputs: the only non-finite outcome is ±∞ from the product, never NaN (had
        // one come, its bits would be refused below: no NaN can turn into a pulse).
        let half = self.center_half_us + self.gain_half_us_per_rad * (angle_rad - self.zero_rad);
        let bits = half.to_bits();
        let high = (bits >> 16) as u16;
        // `half < 512.0`: the sign bit (any negative value, −0) or below 512's bits.
        if (high as i16) < ROUNDED_LOW_HIGH {
            return Err(Error::BelowMin);
        }
        // `half >= 8192.0` (+∞ included).
        if high >= ROUNDED_END_HIGH {
            return Err(Error::AboveMax);
        }
        let ticks = round_half_up_512_8192(bits);
        if ticks < self.min_half_us {
            Err(Error::BelowMin)
        } else if ticks > self.max_half_us {
            Err(Error::AboveMax)
        } else {
            Ok(ticks)
        }
    }
}

/// A pulse in half-µs as µs (exact in f32).
#[inline]
pub fn half_us_to_us(pulse_half_us: u16) -> f32 {
    f32::from(pulse_half_us) * 0.5
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    /// [`Calibration::pulse_half_us`] with the float comparisons and conversion written out:
    /// the form the bit-pattern comparisons stand for.
    fn pulse_half_us_float_form(c: &Calibration, angle_rad: f32) -> Result<u16, Error> {
        c.validate()?;
        if !angle_rad.is_finite() {
            return Err(Error::NonFiniteAngle);
        }
        let offset_us = c.us_per_rad * (angle_rad - c.zero_rad);
        let signed_us = if c.reversed { -offset_us } else { offset_us };
        let half = 2.0 * (f32::from(c.center_us) + signed_us);
        if half.is_nan() {
            return Err(Error::NonFiniteAngle);
        }
        if half < 0.0 {
            return Err(Error::BelowMin);
        }
        if half >= 65_536.0 {
            return Err(Error::AboveMax);
        }
        let ticks = (half + 0.5) as u32;
        if ticks < u32::from(c.min_half_us()) {
            Err(Error::BelowMin)
        } else if ticks > u32::from(c.max_half_us()) {
            Err(Error::AboveMax)
        } else {
            Ok(ticks as u16)
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        /// The bit-pattern comparisons give the float form's result on every input: any angle
        /// bits (NaN, infinities, huge values included) and calibrations near and beyond the
        /// limits.
        #[test]
        fn pulse_half_us_equals_the_float_form(
            angle_bits in any::<u32>(),
            angle in -10.0f32..10.0,
            use_bits in any::<bool>(),
            zero_rad in -7.0f32..7.0,
            reversed in any::<bool>(),
            us_per_rad in 40.0f32..6000.0,
            center_us in 0u16..3000,
            min_us in 0u16..3000,
            max_us in 0u16..3000,
        ) {
            let c = Calibration { zero_rad, reversed, us_per_rad, center_us, min_us, max_us };
            let a = if use_bits { f32::from_bits(angle_bits) } else { angle };
            prop_assert_eq!(c.pulse_half_us(a), pulse_half_us_float_form(&c, a));
        }
    }

    /// An angle whose `half` in the float form lies near `half`, then `nudge` ulps (by bit
    /// pattern) away.
    fn angle_near_half(c: &Calibration, half: f64, nudge: i32) -> f32 {
        let s = if c.reversed { -1.0 } else { 1.0 };
        let a = f64::from(c.zero_rad)
            + s * (half / 2.0 - f64::from(c.center_us)) / f64::from(c.us_per_rad);
        f32::from_bits((a as f32).to_bits().wrapping_add_signed(nudge))
    }

    /// The `half` values around which the mapping changes: the travel's ends, the tick
    /// boundaries (x.5), the bounds of the rounding from the bits, 0 and 0.5 (where the float
    /// addition `half + 0.5` itself rounds), 65,536.
    fn edge_halves(c: &Calibration) -> impl Iterator<Item = f64> {
        let (lo, hi) = (f64::from(c.min_half_us()), f64::from(c.max_half_us()));
        [
            -0.5, 0.0, 0.25, 0.5, 1.0, 511.5, 512.0, 599.5, 4095.5, 4096.0, 8191.5, 8192.0,
            65_535.5, 65_536.0, 1e9,
        ]
        .into_iter()
        .chain([
            lo - 1.5,
            lo - 0.5,
            lo,
            lo + 0.5,
            hi - 0.5,
            hi,
            hi + 0.5,
            hi + 1.5,
        ])
        .chain([f64::from(c.center_us) * 2.0 + 0.5])
    }

    fn zero_rad_strategy() -> impl Strategy<Value = f32> {
        prop_oneof![
            -ZERO_RAD_LIMIT..=ZERO_RAD_LIMIT,
            Just(0.0f32),
            Just(-0.0f32),
            // Subnormal, either sign.
            any::<u32>().prop_map(|b| f32::from_bits(b & 0x807f_ffff)),
            Just(ZERO_RAD_LIMIT),
            Just(-ZERO_RAD_LIMIT),
            // Beyond the limit by an ulp, NaN, infinities: refused alike.
            Just(f32::from_bits(ZERO_RAD_LIMIT.to_bits() + 1)),
            Just(f32::NAN),
            Just(f32::NEG_INFINITY),
        ]
    }

    fn gain_strategy() -> impl Strategy<Value = f32> {
        prop_oneof![
            4 => US_PER_RAD_MIN..=US_PER_RAD_MAX,
            1 => Just(US_PER_RAD_MIN),
            1 => Just(US_PER_RAD_MAX),
            1 => Just(STANDARD_US_PER_RAD),
            1 => Just(f32::from_bits(US_PER_RAD_MIN.to_bits() - 1)),
            1 => Just(f32::from_bits(US_PER_RAD_MAX.to_bits() + 1)),
        ]
    }

    /// `(center_us, min_us, max_us)`: valid ones with the travel's extremes, and some
    /// refused (a centre of 0 among them).
    fn bounds_strategy() -> impl Strategy<Value = (u16, u16, u16)> {
        (
            prop_oneof![Just(PULSE_MIN_US), PULSE_MIN_US..PULSE_MAX_US],
            prop_oneof![Just(PULSE_MAX_US), PULSE_MIN_US + 1..=PULSE_MAX_US],
            0u8..8,
            any::<u16>(),
        )
            .prop_map(|(min_us, max_us, pick, r)| {
                let (min_us, max_us) = if min_us < max_us {
                    (min_us, max_us)
                } else {
                    (max_us - 1, min_us)
                };
                let center_us = match pick {
                    0 => min_us,
                    1 => max_us,
                    2 => 0,
                    3 => r,
                    _ => min_us + r % (max_us - min_us + 1),
                };
                (center_us, min_us, max_us)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40_000))]
        /// The precomputed map gives the float form's result (the former computation of
        /// `pulse_half_us`) for every angle: any bits (NaN, infinities, subnormals, ±0, huge),
        /// angles a few ulps around the travel's ends and the tick boundaries, zero_rad
        /// subnormal and ±0, the extreme gains and centres, reversed or not; a refused
        /// calibration gives its error from `pulse_map` and from `pulse_half_us` alike.
        #[test]
        fn pulse_map_equals_the_float_form(
            zero_rad in zero_rad_strategy(),
            reversed in any::<bool>(),
            us_per_rad in gain_strategy(),
            (center_us, min_us, max_us) in bounds_strategy(),
            kind in 0u8..4,
            angle_bits in any::<u32>(),
            angle in -4.0f32..4.0,
            edge in any::<prop::sample::Index>(),
            nudge in -3i32..=3,
        ) {
            let c = Calibration { zero_rad, reversed, us_per_rad, center_us, min_us, max_us };
            let a = match kind {
                0 => f32::from_bits(angle_bits),
                1 => angle,
                _ => {
                    let halves: Vec<f64> = edge_halves(&c).collect();
                    angle_near_half(&c, *edge.get(&halves), nudge)
                }
            };
            let expected = pulse_half_us_float_form(&c, a);
            prop_assert_eq!(c.pulse_map().and_then(|m| m.pulse_half_us(a)), expected);
            prop_assert_eq!(c.pulse_half_us(a), expected);
        }
    }

    #[test]
    fn rounding_from_the_bits_is_the_float_rounding_from_512_to_8192() {
        // Every f32 in [512, 8192).
        for bits in ROUNDED_LOW_BITS..ROUNDED_END_BITS {
            let half = f32::from_bits(bits);
            let float_form = (half + 0.5) as u32;
            assert_eq!(
                u32::from(round_half_up_512_8192(bits)),
                float_form,
                "{half}"
            );
        }
    }

    #[test]
    fn the_float_addition_of_one_half_rounds_below_512() {
        // Why the map refuses a `half` below 512 before rounding it from the bits: there
        // `half + 0.5` itself may round up to the next integer.
        assert_eq!(0.5f32 - f32::EPSILON / 4.0, f32::from_bits(0x3eff_ffff));
        assert_eq!(f32::from_bits(0x3eff_ffff) + 0.5, 1.0);
    }

    /// Calibrations at the edges of what `validate` admits.
    fn edge_calibrations() -> Vec<Calibration> {
        let mut out = Vec::new();
        for reversed in [false, true] {
            for us_per_rad in [
                US_PER_RAD_MIN,
                US_PER_RAD_MAX,
                STANDARD_US_PER_RAD,
                1234.567,
            ] {
                for zero_rad in [0.0, -0.0, f32::from_bits(1), -ZERO_RAD_LIMIT, 0.3] {
                    for (center_us, min_us, max_us) in [
                        (PULSE_MIN_US, PULSE_MIN_US, PULSE_MAX_US),
                        (PULSE_MAX_US, PULSE_MIN_US, PULSE_MAX_US),
                        (1500, 1000, 2000),
                        (2048, 2047, 2049),
                    ] {
                        out.push(Calibration {
                            zero_rad,
                            reversed,
                            us_per_rad,
                            center_us,
                            min_us,
                            max_us,
                        });
                    }
                }
            }
        }
        out
    }

    #[test]
    fn pulse_map_at_the_tick_boundaries_and_travel_ends() {
        for c in edge_calibrations() {
            let m = c.pulse_map().unwrap();
            assert_eq!(m.min_half_us(), c.min_half_us());
            assert_eq!(m.max_half_us(), c.max_half_us());
            for half in edge_halves(&c) {
                for nudge in -40..=40 {
                    let a = angle_near_half(&c, half, nudge);
                    assert_eq!(
                        m.pulse_half_us(a),
                        pulse_half_us_float_form(&c, a),
                        "{c:?} near {half}: {a:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn pulse_map_of_overflowing_products() {
        for c in edge_calibrations() {
            let m = c.pulse_map().unwrap();
            let up = if c.reversed {
                Error::BelowMin
            } else {
                Error::AboveMax
            };
            let down = if c.reversed {
                Error::AboveMax
            } else {
                Error::BelowMin
            };
            // `us_per_rad · d` finite while `2·us_per_rad · d` overflows, and beyond.
            let edge = f32::MAX / c.us_per_rad;
            for a in [
                f32::MAX,
                edge,
                edge * 0.75,
                edge * 0.5,
                f32::from_bits((edge * 0.5).to_bits() + 1),
                f32::from_bits((edge * 0.5).to_bits() - 1),
                1e30,
            ] {
                assert_eq!(m.pulse_half_us(a), Err(up), "{c:?} {a}");
                assert_eq!(m.pulse_half_us(-a), Err(down), "{c:?} {a}");
                assert_eq!(pulse_half_us_float_form(&c, a), Err(up), "{c:?} {a}");
                assert_eq!(pulse_half_us_float_form(&c, -a), Err(down), "{c:?} {a}");
            }
        }
    }

    #[test]
    fn pulse_map_of_subnormal_and_zero_products() {
        let tiny = [
            0.0f32,
            -0.0,
            f32::from_bits(1),
            f32::from_bits(0x8000_0001),
            f32::from_bits(0x007f_ffff),
            f32::from_bits(0x807f_ffff),
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        for zero_rad in tiny {
            for reversed in [false, true] {
                for us_per_rad in [US_PER_RAD_MIN, US_PER_RAD_MAX] {
                    let c = Calibration {
                        zero_rad,
                        reversed,
                        us_per_rad,
                        ..Calibration::STANDARD
                    };
                    let m = c.pulse_map().unwrap();
                    for a in tiny {
                        // A product far below half an ulp of the centre leaves the centre.
                        assert_eq!(m.pulse_half_us(a), Ok(3000), "{c:?} {a:?}");
                        assert_eq!(pulse_half_us_float_form(&c, a), Ok(3000), "{c:?} {a:?}");
                    }
                }
            }
        }
        // A centre of 0, where a subnormal product would not vanish, is refused.
        let c = Calibration {
            center_us: 0,
            zero_rad: f32::from_bits(1),
            ..Calibration::STANDARD
        };
        assert_eq!(c.pulse_map(), Err(Error::CenterOutOfBounds));
        assert_eq!(c.pulse_half_us(0.0), Err(Error::CenterOutOfBounds));
    }

    #[test]
    fn pulse_map_refuses_what_validate_refuses() {
        let base = Calibration::STANDARD;
        for c in [
            Calibration {
                zero_rad: f32::NAN,
                ..base
            },
            Calibration {
                us_per_rad: f32::INFINITY,
                ..base
            },
            Calibration {
                us_per_rad: 0.0,
                ..base
            },
            Calibration { min_us: 0, ..base },
            Calibration {
                max_us: PULSE_MAX_US + 1,
                ..base
            },
            Calibration {
                center_us: 2001,
                ..base
            },
        ] {
            let e = c.validate().unwrap_err();
            assert_eq!(c.pulse_map(), Err(e));
            assert_eq!(c.pulse_half_us(0.0), Err(e));
            assert_eq!(c.pulse_half_us(f32::NAN), Err(e));
        }
    }

    #[test]
    fn the_empty_map_maps_no_angle() {
        let m = PulseMap::NONE;
        for a in [0.0f32, -0.0, 1.0, -1.0, 1e30, f32::MAX, f32::from_bits(1)] {
            assert_eq!(m.pulse_half_us(a), Err(Error::BelowMin), "{a}");
            assert_eq!(m.pulse_half_us(-a), Err(Error::BelowMin), "{a}");
        }
        for a in [f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(m.pulse_half_us(a), Err(Error::NonFiniteAngle), "{a}");
        }
    }

    #[test]
    fn validate_compares_gain_and_zero_as_the_float_comparisons_do() {
        let edge = [
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -1.0,
            US_PER_RAD_MIN,
            US_PER_RAD_MAX,
            f32::from_bits(US_PER_RAD_MIN.to_bits() - 1),
            f32::from_bits(US_PER_RAD_MAX.to_bits() + 1),
            ZERO_RAD_LIMIT,
            -ZERO_RAD_LIMIT,
            f32::from_bits(ZERO_RAD_LIMIT.to_bits() + 1),
            -f32::from_bits(ZERO_RAD_LIMIT.to_bits() + 1),
            1000.0,
            -1000.0,
        ];
        for v in edge {
            let gain = Calibration {
                us_per_rad: v,
                ..Calibration::STANDARD
            };
            let gain_ok = (US_PER_RAD_MIN..=US_PER_RAD_MAX).contains(&v);
            assert_eq!(gain.validate().is_ok(), gain_ok, "us_per_rad {v:?}");
            let zero = Calibration {
                zero_rad: v,
                ..Calibration::STANDARD
            };
            let zero_ok = v.is_finite() && v.abs() <= ZERO_RAD_LIMIT;
            assert_eq!(zero.validate().is_ok(), zero_ok, "zero_rad {v:?}");
        }
    }

    #[test]
    fn standard_centre_is_1500_us() {
        assert_eq!(Calibration::STANDARD.pulse_half_us(0.0), Ok(3000));
        assert_eq!(Calibration::STANDARD.angle_rad(3000), Ok(0.0));
    }

    #[test]
    fn standard_travel_ends() {
        let c = Calibration::STANDARD;
        let q = core::f32::consts::FRAC_PI_4;
        assert_eq!(c.pulse_half_us(q), Ok(4000));
        assert_eq!(c.pulse_half_us(-q), Ok(2000));
        assert_eq!(c.pulse_half_us(q + 0.01), Err(Error::AboveMax));
        assert_eq!(c.pulse_half_us(-q - 0.01), Err(Error::BelowMin));
    }

    #[test]
    fn reversed_flips_direction() {
        let c = Calibration {
            reversed: true,
            ..Calibration::STANDARD
        };
        assert_eq!(c.pulse_half_us(0.5), Ok(3000 - 637));
        assert_eq!(c.pulse_half_us(-0.5), Ok(3000 + 637));
    }
}
