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

/// The bits of 65536.0, the first pulse beyond a `u16` of half-µs.
const HALF_US_END_BITS: u32 = 0x4780_0000;

/// `⌊x⌋` of a finite `x` in `[0, 2³²)`, from the bits: `x as u32` without the saturating
/// conversion's float comparisons (library calls on the ATmega2560).
#[inline(always)]
fn floor_nonneg(x: f32) -> u32 {
    let bits = x.to_bits();
    let e = (bits >> 23) as i32; // the sign bit is clear
    if e < 127 {
        0
    } else {
        let m = (bits & 0x007f_ffff) | 0x0080_0000;
        // x = m·2^(e − 150)
        if e >= 150 {
            m << (e - 150)
        } else {
            // Whole bytes first: a variable shift is a loop of single-bit steps on 8-bit CPUs.
            let s = (150 - e) as u32;
            let (m, s) = if s >= 16 {
                (m >> 16, s - 16)
            } else if s >= 8 {
                (m >> 8, s - 8)
            } else {
                (m, s)
            };
            m >> s
        }
    }
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
        // positive bounds, so it is refused as the float comparisons refuse it. The device
        // validates a calibration with every pulse it maps; on the ATmega2560 each float
        // comparison is a library call.
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
    /// accepted only within `[2·min_us, 2·max_us]`.
    ///
    /// # Errors
    /// The calibration's own [`Error`] when it is invalid; [`Error::NonFiniteAngle`];
    /// [`Error::BelowMin`] / [`Error::AboveMax`] when the rounded pulse leaves the travel.
    pub fn pulse_half_us(&self, angle_rad: f32) -> Result<u16, Error> {
        self.validate()?;
        // The comparisons on the bit patterns, equal to the float comparisons they stand for
        // (each float comparison is a library call on the ATmega2560, which maps twelve pulses
        // per command and per servo frame; the tests hold them to the float forms).
        if angle_rad.to_bits() & !SIGN_BIT >= INF_BITS {
            return Err(Error::NonFiniteAngle);
        }
        // Finite inputs: the only non-finite outcome is ±inf from the product, never NaN.
        let offset_us = self.us_per_rad * (angle_rad - self.zero_rad);
        let signed_us = if self.reversed { -offset_us } else { offset_us };
        let half = 2.0 * (f32::from(self.center_us) + signed_us);
        let bits = half.to_bits();
        if bits & !SIGN_BIT > INF_BITS {
            // NaN: unreachable for a validated calibration and a finite angle; kept so that no
            // NaN can ever turn into a pulse.
            return Err(Error::NonFiniteAngle);
        }
        // `half < 0.0`: the sign bit of anything but −0.
        if bits > SIGN_BIT {
            return Err(Error::BelowMin);
        }
        // `half >= 65536.0` for a non-negative `half` (+∞ included).
        if bits & !SIGN_BIT >= HALF_US_END_BITS {
            return Err(Error::AboveMax);
        }
        let ticks = floor_nonneg(half + 0.5);
        if ticks < u32::from(self.min_half_us()) {
            Err(Error::BelowMin)
        } else if ticks > u32::from(self.max_half_us()) {
            Err(Error::AboveMax)
        } else {
            Ok(ticks as u16)
        }
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

/// A pulse in half-µs as µs (exact in f32).
#[inline]
pub fn half_us_to_us(pulse_half_us: u16) -> f32 {
    f32::from(pulse_half_us) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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

    #[test]
    fn floor_of_the_bits_is_the_truncating_conversion() {
        for x in [
            0.0f32,
            0.25,
            0.5,
            0.999_999_94,
            1.0,
            1.5,
            2.0,
            1000.5,
            65_535.5,
            65_536.49,
            1e9,
        ] {
            assert_eq!(floor_nonneg(x), x as u32, "{x}");
        }
        let mut x = 0.5f32;
        while x < 70_000.0 {
            assert_eq!(floor_nonneg(x), x as u32, "{x}");
            x = f32::from_bits(x.to_bits() + 997);
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
