//! The world around the robot during a run: a level floor, a slope, a floor that tilts during
//! the run, a sideways push on the body (`quadctl sim --slope-deg`, `--slope-axis`,
//! `--tilt-floor`, `--push-n-s`).
//!
//! The twin's floor is a plane on a mocap body through the world's origin (the robot starts
//! over it). A slope turns it about the world's x axis ([`SlopeAxis::Roll`]: a positive angle
//! raises the floor on the robot's left, and the robot, placed on it, rolls by the same angle)
//! or y axis ([`SlopeAxis::Pitch`]: a positive angle lowers the floor ahead, the robot pitches
//! nose down). A tilting floor turns further by [`TILT_FLOOR_RAD`] at a constant rate over
//! [`TILT_DURATION_S`] from [`DISTURBANCE_AT_S`]. A push is a constant force of
//! `impulse / PUSH_DURATION_S` along the world's +y axis (the robot's left at the start; a
//! negative impulse pushes it to the right) at the body's centre of mass from
//! [`DISTURBANCE_AT_S`] for [`PUSH_DURATION_S`] (MuJoCo's `xfrc_applied`). Times are on the
//! motion's clock (after [`crate::SETTLE_S`]); a run with a tilt or a push lasts at least
//! [`OBSERVE_AFTER_S`] past the disturbance's end (a stand-up holds its stance that long).

use core::fmt;
use serde::{Deserialize, Serialize};

/// When a tilt or a push starts, on the motion's clock, s: half a second after the stand-up's
/// ramp ([`crate::motions::STAND_RAMP_S`]) has brought the body to its stance.
pub const DISTURBANCE_AT_S: f32 = 2.5;
/// How far a tilting floor turns, rad (10°).
pub const TILT_FLOOR_RAD: f32 = 10.0 * core::f32::consts::PI / 180.0;
/// How long a tilting floor takes to turn, s (10°/s).
pub const TILT_DURATION_S: f32 = 1.0;
/// How long the push's force acts, s.
pub const PUSH_DURATION_S: f32 = 0.1;
/// A run with a tilt or a push lasts at least this long after the disturbance's end, s.
pub const OBSERVE_AFTER_S: f32 = 3.0;
/// The steepest slope (and slope plus tilt) the twin takes, rad (30°): beyond, the feet's
/// friction (μ = 0.8 holds to 38.7°) and the stand-up's crouch are no longer the question.
pub const MAX_SLOPE_RAD: f32 = 30.0 * core::f32::consts::PI / 180.0;

/// The world axis a slope turns the floor about.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlopeAxis {
    /// About x (the robot's forward axis at the start): the robot rolls with the floor.
    #[default]
    Roll,
    /// About y (the robot's left at the start): the robot pitches with the floor.
    Pitch,
}

impl SlopeAxis {
    /// Both axes.
    pub const ALL: [SlopeAxis; 2] = [SlopeAxis::Roll, SlopeAxis::Pitch];

    /// The command-line name.
    pub const fn name(self) -> &'static str {
        match self {
            SlopeAxis::Roll => "roll",
            SlopeAxis::Pitch => "pitch",
        }
    }
}

/// The floor's tilt during the run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tilt {
    /// Start, motion clock, s.
    pub start_s: f32,
    /// Duration, s.
    pub duration_s: f32,
    /// The angle turned (added to the slope), rad.
    pub by_rad: f32,
}

/// The floor: its slope and its tilt during the run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Floor {
    /// The axis of the slope and of the tilt.
    pub axis: SlopeAxis,
    /// The slope from the start, rad (0: level).
    pub slope_rad: f32,
    /// A tilt during the run.
    pub tilt: Option<Tilt>,
}

/// A sideways push on the body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Push {
    /// The impulse, N·s, along the world's +y (negative: −y).
    pub impulse_n_s: f32,
    /// Start, motion clock, s.
    pub at_s: f32,
    /// How long the force acts, s.
    pub duration_s: f32,
}

/// The world of a run: a level floor and no push by default.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Scenario {
    /// The floor.
    pub floor: Floor,
    /// A push.
    pub push: Option<Push>,
}

/// Why a scenario was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The slope, or the slope plus the tilt, is not finite or steeper than
    /// [`MAX_SLOPE_RAD`].
    Slope {
        /// The floor's steepest angle, rad.
        rad: f32,
    },
    /// The push's impulse is not finite.
    Push {
        /// The impulse, N·s.
        impulse_n_s: f32,
    },
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ScenarioError::Slope { rad } => write!(
                f,
                "slope_deg: the floor would reach {:.1}°; the twin takes at most ±{:.0}°",
                rad.to_degrees(),
                MAX_SLOPE_RAD.to_degrees()
            ),
            ScenarioError::Push { impulse_n_s } => {
                write!(f, "push_n_s: {impulse_n_s} is not a finite impulse")
            }
        }
    }
}

impl std::error::Error for ScenarioError {}

impl Scenario {
    /// A floor inclined by `slope_deg` about `axis`, tilting by [`TILT_FLOOR_RAD`] more during
    /// the run when `tilt_floor`, and a push of `push_n_s` (none: no push).
    ///
    /// # Errors
    /// [`ScenarioError`] for a slope steeper than [`MAX_SLOPE_RAD`] or a value that is not
    /// finite.
    pub fn new(
        axis: SlopeAxis,
        slope_deg: f32,
        tilt_floor: bool,
        push_n_s: Option<f32>,
    ) -> Result<Scenario, ScenarioError> {
        let slope_rad = slope_deg.to_radians();
        let tilt = tilt_floor.then_some(Tilt {
            start_s: DISTURBANCE_AT_S,
            duration_s: TILT_DURATION_S,
            by_rad: TILT_FLOOR_RAD,
        });
        let steepest = slope_rad + tilt.map_or(0.0, |t| t.by_rad);
        for rad in [slope_rad, steepest] {
            // `!(x <= max)` also refuses NaN.
            if !(rad.abs() <= MAX_SLOPE_RAD) {
                return Err(ScenarioError::Slope { rad });
            }
        }
        let push = match push_n_s {
            None => None,
            Some(impulse_n_s) if impulse_n_s.is_finite() => Some(Push {
                impulse_n_s,
                at_s: DISTURBANCE_AT_S,
                duration_s: PUSH_DURATION_S,
            }),
            Some(impulse_n_s) => return Err(ScenarioError::Push { impulse_n_s }),
        };
        Ok(Scenario {
            floor: Floor {
                axis,
                slope_rad,
                tilt,
            },
            push,
        })
    }

    /// True for a level floor and no push (the twin's default world).
    pub fn is_plain(&self) -> bool {
        self.floor.slope_rad == 0.0 && self.floor.tilt.is_none() && self.push.is_none()
    }

    /// The end of the tilt or the push, motion clock, s (none without either).
    pub fn disturbance_end_s(&self) -> Option<f32> {
        let tilt = self.floor.tilt.map(|t| t.start_s + t.duration_s);
        let push = self.push.map(|p| p.at_s + p.duration_s);
        match (tilt, push) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    /// The shortest run that shows the answer to the disturbance, s: its end plus
    /// [`OBSERVE_AFTER_S`] (none without a tilt or a push).
    pub fn min_duration_s(&self) -> Option<f32> {
        self.disturbance_end_s().map(|end| end + OBSERVE_AFTER_S)
    }

    /// What an accelerometer on the body reads at rest on the floor at the start, m/s²: the
    /// reaction to gravity `g` turned into a body standing on the slope.
    pub fn at_rest_accel_m_s2(&self, g_m_s2: f32) -> [f32; 3] {
        let (s, c) = self.floor.slope_rad.sin_cos();
        match self.floor.axis {
            // Rx(θ)ᵀ·(0, 0, g) and Ry(θ)ᵀ·(0, 0, g).
            SlopeAxis::Roll => [0.0, g_m_s2 * s, g_m_s2 * c],
            SlopeAxis::Pitch => [-g_m_s2 * s, 0.0, g_m_s2 * c],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slope_beyond_the_limit_or_not_finite_is_refused_naming_the_field() {
        let e = Scenario::new(SlopeAxis::Roll, 25.0, true, None).unwrap_err();
        assert!(e.to_string().starts_with("slope_deg"), "{e}");
        assert!(Scenario::new(SlopeAxis::Pitch, f32::NAN, false, None).is_err());
        let e = Scenario::new(SlopeAxis::Roll, 0.0, false, Some(f32::INFINITY)).unwrap_err();
        assert!(e.to_string().starts_with("push_n_s"), "{e}");
        assert!(Scenario::new(SlopeAxis::Roll, -20.0, true, Some(-3.0)).is_ok());
    }

    #[test]
    fn the_run_lasts_past_the_disturbance() {
        let s = Scenario::new(SlopeAxis::Roll, 0.0, true, Some(2.0)).unwrap();
        assert!(!s.is_plain());
        let end = DISTURBANCE_AT_S + TILT_DURATION_S.max(PUSH_DURATION_S);
        assert_eq!(s.disturbance_end_s(), Some(end));
        assert_eq!(s.min_duration_s(), Some(end + OBSERVE_AFTER_S));
        assert!(Scenario::default().is_plain());
        assert_eq!(Scenario::default().min_duration_s(), None);
    }

    #[test]
    fn at_rest_on_a_slope_the_accelerometer_leans_uphill() {
        let g = 9.81;
        let roll = Scenario::new(SlopeAxis::Roll, 10.0, false, None).unwrap();
        let a = roll.at_rest_accel_m_s2(g);
        // Rolled left side up: gravity's reaction leans towards the body's +y.
        assert!(a[1] > 1.7 && a[1] < 1.71 && a[0] == 0.0, "{a:?}");
        let pitch = Scenario::new(SlopeAxis::Pitch, 10.0, false, None).unwrap();
        let a = pitch.at_rest_accel_m_s2(g);
        // Nose down: towards the body's −x.
        assert!(a[0] < -1.7 && a[1] == 0.0, "{a:?}");
        assert_eq!(Scenario::default().at_rest_accel_m_s2(g), [0.0, 0.0, g]);
    }
}
