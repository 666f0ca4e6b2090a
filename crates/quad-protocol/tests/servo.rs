//! Servo calibration mapping: never NaN, always within `[min_us, max_us]` or a typed error,
//! the pulse ↔ angle round trip, and the validation rules.

use proptest::prelude::*;
use quad_protocol::servo::{
    self, Calibration, Error, PULSE_MAX_US, PULSE_MIN_US, US_PER_RAD_MAX, US_PER_RAD_MIN,
    ZERO_RAD_LIMIT,
};

/// f32 rounding of an angle of a few rad after a handful of operations, rad.
const ANGLE_F32_TOL_RAD: f32 = 1e-5;

/// f32 rounding of a pulse of at most 5400 half-µs (ulp 2⁻¹¹) after a handful of operations,
/// half-µs.
const PULSE_F32_TOL_HALF_US: f64 = 0.002;

/// Largest difference between an angle and the angle of its rounded pulse: half a tick
/// (0.25 µs) over the gain, plus f32 rounding.
fn angle_resolution_rad(c: &Calibration) -> f32 {
    0.25 / c.us_per_rad + ANGLE_F32_TOL_RAD
}

fn arb_valid_calibration() -> impl Strategy<Value = Calibration> {
    (
        -ZERO_RAD_LIMIT..=ZERO_RAD_LIMIT,
        any::<bool>(),
        US_PER_RAD_MIN..=US_PER_RAD_MAX,
        PULSE_MIN_US..PULSE_MAX_US,
        1u16..=(PULSE_MAX_US - PULSE_MIN_US),
        0.0f32..=1.0,
    )
        .prop_map(|(zero_rad, reversed, us_per_rad, min_us, span, c)| {
            let max_us = (min_us + span).min(PULSE_MAX_US).max(min_us + 1);
            let center_us = min_us + (f32::from(max_us - min_us) * c) as u16;
            Calibration {
                zero_rad,
                reversed,
                us_per_rad,
                center_us,
                min_us,
                max_us,
            }
        })
        .prop_filter("max within bounds", |c| c.max_us <= PULSE_MAX_US)
}

/// Any calibration at all, from raw bits.
fn arb_any_calibration() -> impl Strategy<Value = Calibration> {
    (
        any::<u32>(),
        any::<bool>(),
        any::<u32>(),
        any::<u16>(),
        any::<u16>(),
        any::<u16>(),
    )
        .prop_map(|(z, reversed, g, center_us, min_us, max_us)| Calibration {
            zero_rad: f32::from_bits(z),
            reversed,
            us_per_rad: f32::from_bits(g),
            center_us,
            min_us,
            max_us,
        })
}

/// Any f32 bit pattern, NaN and infinities included, and a dense band of ordinary angles.
fn arb_angle() -> impl Strategy<Value = f32> {
    prop_oneof![any::<u32>().prop_map(f32::from_bits), -4.0f32..4.0]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    #[test]
    fn pulse_is_within_travel_or_a_typed_error(c in arb_any_calibration(), a in arb_angle()) {
        match c.pulse_half_us(a) {
            Ok(p) => {
                prop_assert!(c.validate().is_ok());
                prop_assert!(a.is_finite());
                prop_assert!(p >= 2 * c.min_us && p <= 2 * c.max_us, "{p} outside {c:?}");
            }
            Err(e) => {
                let valid = c.validate();
                if let Err(v) = valid {
                    prop_assert_eq!(e, v);
                } else if !a.is_finite() {
                    prop_assert_eq!(e, Error::NonFiniteAngle);
                } else {
                    prop_assert!(matches!(e, Error::BelowMin | Error::AboveMax), "{e:?}");
                }
            }
        }
    }

    #[test]
    fn errors_name_the_right_side(c in arb_valid_calibration(), a in -10.0f32..10.0) {
        let (lo, hi) = c.angle_limits_rad().unwrap();
        match c.pulse_half_us(a) {
            Ok(_) => {
                let tol = angle_resolution_rad(&c);
                prop_assert!(a >= lo - tol && a <= hi + tol);
            }
            Err(Error::BelowMin) => {
                // Below min means the angle lies on the side of the travel that maps to min_us.
                let at_min = c.angle_rad(c.min_half_us()).unwrap();
                let beyond = if c.reversed { a > at_min } else { a < at_min };
                prop_assert!(beyond, "{} not beyond {}", a, at_min);
            }
            Err(Error::AboveMax) => {
                let at_max = c.angle_rad(c.max_half_us()).unwrap();
                let beyond = if c.reversed { a < at_max } else { a > at_max };
                prop_assert!(beyond, "{} not beyond {}", a, at_max);
            }
            Err(e) => prop_assert!(false, "unexpected {e:?}"),
        }
    }

    #[test]
    fn angle_of_a_pulse_is_finite_and_maps_back_to_it(c in arb_valid_calibration(), t in 0.0f32..=1.0) {
        let span = c.max_half_us() - c.min_half_us();
        let p = c.min_half_us() + (f32::from(span) * t) as u16;
        let a = c.angle_rad(p).unwrap();
        prop_assert!(a.is_finite());
        prop_assert_eq!(c.pulse_half_us(a), Ok(p));
    }

    #[test]
    fn pulse_of_an_angle_is_within_half_a_tick(c in arb_valid_calibration(), t in 0.0f32..=1.0) {
        let (lo, hi) = c.angle_limits_rad().unwrap();
        let a = lo + (hi - lo) * t;
        if let Ok(p) = c.pulse_half_us(a) {
            // f64 oracle of the formula.
            let exact_half_us = 2.0
                * (f64::from(c.center_us)
                    + f64::from(c.sign())
                        * f64::from(c.us_per_rad)
                        * (f64::from(a) - f64::from(c.zero_rad)));
            prop_assert!((f64::from(p) - exact_half_us).abs() <= 0.5 + PULSE_F32_TOL_HALF_US);
            let back = c.angle_rad(p).unwrap();
            prop_assert!((back - a).abs() <= angle_resolution_rad(&c));
        }
    }

    #[test]
    fn monotonic_in_the_calibrated_direction(c in arb_valid_calibration(), a in -3.0f32..3.0, d in 0.0f32..0.5) {
        if let (Ok(p1), Ok(p2)) = (c.pulse_half_us(a), c.pulse_half_us(a + d)) {
            if c.reversed {
                prop_assert!(p2 <= p1);
            } else {
                prop_assert!(p2 >= p1);
            }
        }
    }

    #[test]
    fn pulses_outside_the_travel_have_no_angle(c in arb_valid_calibration(), p in any::<u16>()) {
        match c.angle_rad(p) {
            Ok(a) => {
                prop_assert!(a.is_finite());
                prop_assert!(p >= c.min_half_us() && p <= c.max_half_us());
            }
            Err(e) => prop_assert_eq!(
                e,
                if p < c.min_half_us() { Error::BelowMin } else { Error::AboveMax }
            ),
        }
    }
}

#[test]
fn validation_rules() {
    let ok = Calibration::STANDARD;
    assert_eq!(ok.validate(), Ok(()));
    let cases = [
        (
            Calibration {
                zero_rad: f32::NAN,
                ..ok
            },
            Error::BadZero,
        ),
        (
            Calibration {
                zero_rad: f32::INFINITY,
                ..ok
            },
            Error::BadZero,
        ),
        (
            Calibration {
                zero_rad: 6.3,
                ..ok
            },
            Error::BadZero,
        ),
        (
            Calibration {
                us_per_rad: f32::NAN,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                us_per_rad: 0.0,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                us_per_rad: -636.0,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                us_per_rad: f32::INFINITY,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                us_per_rad: 49.0,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                us_per_rad: 5001.0,
                ..ok
            },
            Error::BadGain,
        ),
        (
            Calibration {
                min_us: 2000,
                max_us: 2000,
                ..ok
            },
            Error::BadBounds,
        ),
        (
            Calibration {
                min_us: 2100,
                max_us: 2000,
                ..ok
            },
            Error::BadBounds,
        ),
        (Calibration { min_us: 299, ..ok }, Error::BadBounds),
        (Calibration { max_us: 2701, ..ok }, Error::BadBounds),
        (
            Calibration {
                center_us: 999,
                ..ok
            },
            Error::CenterOutOfBounds,
        ),
        (
            Calibration {
                center_us: 2001,
                ..ok
            },
            Error::CenterOutOfBounds,
        ),
    ];
    for (c, e) in cases {
        assert_eq!(c.validate(), Err(e), "{c:?}");
        assert_eq!(c.pulse_half_us(0.0), Err(e));
        assert_eq!(c.angle_rad(3000), Err(e));
    }
    // The extreme admissible values are accepted.
    let edge = Calibration {
        zero_rad: -ZERO_RAD_LIMIT,
        reversed: true,
        us_per_rad: US_PER_RAD_MAX,
        center_us: PULSE_MAX_US,
        min_us: PULSE_MIN_US,
        max_us: PULSE_MAX_US,
    };
    assert_eq!(edge.validate(), Ok(()));
}

#[test]
fn non_finite_and_huge_angles_are_typed_errors() {
    let c = Calibration::STANDARD;
    assert_eq!(c.pulse_half_us(f32::NAN), Err(Error::NonFiniteAngle));
    assert_eq!(c.pulse_half_us(f32::INFINITY), Err(Error::NonFiniteAngle));
    assert_eq!(
        c.pulse_half_us(f32::NEG_INFINITY),
        Err(Error::NonFiniteAngle)
    );
    assert_eq!(c.pulse_half_us(f32::MAX), Err(Error::AboveMax));
    assert_eq!(c.pulse_half_us(f32::MIN), Err(Error::BelowMin));
    let r = Calibration {
        reversed: true,
        ..c
    };
    assert_eq!(r.pulse_half_us(f32::MAX), Err(Error::BelowMin));
    assert_eq!(r.pulse_half_us(f32::MIN), Err(Error::AboveMax));
}

#[test]
fn rounding_is_half_up_at_the_tick() {
    // 1 µs per rad would be refused; use 100 µs/rad: 0.0025 rad = 0.25 µs = half a tick.
    let c = Calibration {
        us_per_rad: 100.0,
        ..Calibration::STANDARD
    };
    assert_eq!(c.pulse_half_us(0.0), Ok(3000));
    assert_eq!(c.pulse_half_us(0.002), Ok(3000)); // 0.4 tick
    assert_eq!(c.pulse_half_us(0.003), Ok(3001)); // 0.6 tick
    assert_eq!(c.pulse_half_us(-0.003), Ok(2999));
    assert_eq!(servo::half_us_to_us(3001), 1500.5);
}

#[test]
fn travel_ends_are_inclusive() {
    let c = Calibration::STANDARD;
    let (lo, hi) = c.angle_limits_rad().unwrap();
    assert_eq!(c.pulse_half_us(lo), Ok(2000));
    assert_eq!(c.pulse_half_us(hi), Ok(4000));
    assert!((hi - core::f32::consts::FRAC_PI_4).abs() < 1e-6);
    assert!((lo + core::f32::consts::FRAC_PI_4).abs() < 1e-6);
}
