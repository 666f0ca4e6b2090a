//! Robot description: leg identities, leg geometry, hip mounts, joint limits, knee bend, and the
//! two presets taken from the papers.

use crate::math::{finite_ordered, nonneg_finite, positive_finite};
use crate::vec::Vec3;
use core::fmt;

/// One of the four legs. Left legs have side sign `s = +1`, right legs `s = −1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LegId {
    /// Front left.
    FL = 0,
    /// Front right.
    FR = 1,
    /// Rear left.
    RL = 2,
    /// Rear right.
    RR = 3,
}

impl LegId {
    /// All legs in the canonical order FL, FR, RL, RR (the order of every 12-angle array).
    pub const ALL: [LegId; 4] = [LegId::FL, LegId::FR, LegId::RL, LegId::RR];

    /// Index in [`LegId::ALL`].
    #[inline]
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Leg from its index in [`LegId::ALL`].
    #[inline]
    pub const fn from_index(i: usize) -> Option<LegId> {
        match i {
            0 => Some(LegId::FL),
            1 => Some(LegId::FR),
            2 => Some(LegId::RL),
            3 => Some(LegId::RR),
            _ => None,
        }
    }

    /// Side sign `s`: `+1` for left legs, `−1` for right legs.
    #[inline]
    pub const fn side(self) -> f32 {
        match self {
            LegId::FL | LegId::RL => 1.0,
            LegId::FR | LegId::RR => -1.0,
        }
    }

    /// True for the front legs.
    #[inline]
    pub const fn is_front(self) -> bool {
        matches!(self, LegId::FL | LegId::FR)
    }

    /// True for the left legs.
    #[inline]
    pub const fn is_left(self) -> bool {
        matches!(self, LegId::FL | LegId::RL)
    }

    /// `v` (given for the front left corner, `x, y ≥ 0`) moved to this leg's corner of the
    /// body: `x` negated for rear legs, `y` for right legs.
    pub const fn at_corner(self, v: Vec3) -> Vec3 {
        Vec3::new(
            if self.is_front() { v.x } else { -v.x },
            if self.is_left() { v.y } else { -v.y },
            v.z,
        )
    }

    /// Short name: `FL`, `FR`, `RL`, `RR`.
    pub const fn name(self) -> &'static str {
        match self {
            LegId::FL => "FL",
            LegId::FR => "FR",
            LegId::RL => "RL",
            LegId::RR => "RR",
        }
    }

    /// Parses `FL`, `FR`, `RL`, `RR` (case-insensitive).
    pub fn parse(s: &str) -> Option<LegId> {
        LegId::ALL
            .into_iter()
            .find(|l| l.name().eq_ignore_ascii_case(s.trim()))
    }
}

impl fmt::Display for LegId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One of the three joints of a leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Joint {
    /// Abduction / adduction, about the body x axis (seed 000 θ1, seed 001 β).
    Abduction = 0,
    /// Hip flexion, about the abducted y axis (seed 000 θ2, seed 001 α).
    Hip = 1,
    /// Knee, about the abducted y axis, relative to the femur (seed 000 θ3, seed 001 φ).
    Knee = 2,
}

impl Joint {
    /// All joints in array order.
    pub const ALL: [Joint; 3] = [Joint::Abduction, Joint::Hip, Joint::Knee];

    /// Lower-case name: `abduction`, `hip`, `knee`.
    pub const fn name(self) -> &'static str {
        match self {
            Joint::Abduction => "abduction",
            Joint::Hip => "hip",
            Joint::Knee => "knee",
        }
    }
}

impl fmt::Display for Joint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which of the two planar solutions the knee takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum KneeBend {
    /// knee ≤ 0: the knee joint sits behind the hip–foot line (the default).
    #[default]
    Backward,
    /// knee ≥ 0: the knee joint sits in front of the hip–foot line.
    Forward,
}

/// Joint angles of one leg in the canonical convention (radians).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JointAngles {
    /// Abduction angle (rad), rotation about the hip frame's x axis.
    pub abduction_rad: f32,
    /// Hip angle (rad), rotation of the femur about the abducted y axis; 0 = straight down.
    pub hip_rad: f32,
    /// Knee angle (rad), rotation of the tibia relative to the femur; 0 = straight leg.
    pub knee_rad: f32,
}

impl JointAngles {
    /// Builds the angles from `(abduction, hip, knee)` in radians.
    #[inline]
    pub const fn new(abduction_rad: f32, hip_rad: f32, knee_rad: f32) -> Self {
        JointAngles {
            abduction_rad,
            hip_rad,
            knee_rad,
        }
    }

    /// `[abduction, hip, knee]`.
    #[inline]
    pub const fn to_array(self) -> [f32; 3] {
        [self.abduction_rad, self.hip_rad, self.knee_rad]
    }

    /// From `[abduction, hip, knee]`.
    #[inline]
    pub const fn from_array(a: [f32; 3]) -> Self {
        JointAngles::new(a[0], a[1], a[2])
    }

    /// The angle of one joint.
    #[inline]
    pub const fn get(self, joint: Joint) -> f32 {
        self.to_array()[joint as usize]
    }

    /// True when all three angles are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.abduction_rad.is_finite() && self.hip_rad.is_finite() && self.knee_rad.is_finite()
    }
}

/// Link lengths of one leg (all legs are alike), metres.
///
/// `foot_in_hip = Rx(abduction)·([0, s·d_lat, −d_ax] + Ry(hip)·[0,0,−femur] + Ry(hip+knee)·[0,0,−tibia])`
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LegGeometry {
    /// Lateral offset of the leg plane from the abduction axis, perpendicular to the leg plane
    /// (seed 000's coxa `La`), m.
    pub d_lat_m: f32,
    /// Offset of the hip joint below the abduction axis, along the leg plane (seed 001's `l0`), m.
    pub d_ax_m: f32,
    /// Hip-to-knee length (seed 000 `Lb`, seed 001 `l1`), m.
    pub femur_m: f32,
    /// Knee-to-foot length (seed 000 `Lc`, seed 001 `l2`), m.
    pub tibia_m: f32,
}

/// Closed interval of admissible angles for each joint, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JointLimits {
    /// Lower bounds `[abduction, hip, knee]`, rad.
    pub min_rad: [f32; 3],
    /// Upper bounds `[abduction, hip, knee]`, rad.
    pub max_rad: [f32; 3],
}

impl JointLimits {
    /// No limit beyond the full turn `[-π, π]` on each joint.
    pub const FULL_TURN: JointLimits = JointLimits {
        min_rad: [-core::f32::consts::PI; 3],
        max_rad: [core::f32::consts::PI; 3],
    };

    /// True when `angle_rad` lies within the limits of `joint`.
    #[inline]
    pub fn admits(&self, joint: Joint, angle_rad: f32) -> bool {
        let j = joint as usize;
        angle_rad >= self.min_rad[j] && angle_rad <= self.max_rad[j]
    }

    /// `angles` with each angle clamped into its joint's interval.
    #[inline]
    pub fn clamp(&self, angles: JointAngles) -> JointAngles {
        let mut a = angles.to_array();
        for (i, v) in a.iter_mut().enumerate() {
            *v = v.clamp(self.min_rad[i], self.max_rad[i]);
        }
        JointAngles::from_array(a)
    }

    /// The first joint of `angles` outside its limits, if any.
    #[inline]
    pub fn first_violation(&self, angles: JointAngles) -> Option<Joint> {
        Joint::ALL
            .into_iter()
            .find(|&j| !self.admits(j, angles.get(j)))
    }

    /// Distance (rad) from `angle_rad` to the nearest limit of `joint`; negative outside.
    #[inline]
    pub fn margin(&self, joint: Joint, angle_rad: f32) -> f32 {
        let j = joint as usize;
        let lo = angle_rad - self.min_rad[j];
        let hi = self.max_rad[j] - angle_rad;
        if lo < hi {
            lo
        } else {
            hi
        }
    }

    /// Limits with the knee interval mirrored (`[a, b]` → `[−b, −a]`), for the other knee bend.
    #[inline]
    pub fn mirrored_knee(self) -> JointLimits {
        let mut out = self;
        out.min_rad[2] = -self.max_rad[2];
        out.max_rad[2] = -self.min_rad[2];
        out
    }
}

/// Everything the kinematics needs to know about a robot. Equal ([`PartialEq`]) when every
/// field is: [`Robot::equals`].
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Robot {
    /// Leg link lengths (identical for all legs).
    pub leg: LegGeometry,
    /// Distance between front and rear hip mounts along x, m.
    pub body_length_m: f32,
    /// Distance between left and right hip mounts along y, m.
    pub body_width_m: f32,
    /// Joint limits of every leg, expressed for [`Robot::knee_bend`].
    pub limits: JointLimits,
    /// Which planar IK solution the knee takes.
    pub knee_bend: KneeBend,
}

impl PartialEq for Robot {
    fn eq(&self, other: &Robot) -> bool {
        self.equals(other)
    }
}

/// Why a robot description was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum RobotError {
    /// A length is negative, zero where it must be positive, or not finite.
    BadLength(&'static str),
    /// A joint limit is not finite or its minimum exceeds its maximum.
    BadLimit(Joint),
}

impl fmt::Display for RobotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RobotError::BadLength(name) => {
                write!(
                    f,
                    "`{name}` must be a finite length (> 0, or ≥ 0 for offsets), in metres"
                )
            }
            RobotError::BadLimit(j) => {
                write!(
                    f,
                    "joint limits of `{j}` must be finite with min ≤ max, in radians"
                )
            }
        }
    }
}

impl core::error::Error for RobotError {}

/// How far short of the folded end of its range the knee rests in the rest pose
/// ([`Robot::rest_leg`]), rad.
pub const REST_KNEE_MARGIN_RAD: f32 = 0.2;

impl Robot {
    /// Seed 000 (Shahriar 2023) Table 4: La = 0.044 m (lateral, ⟂ leg plane), Lb = 0.28 m,
    /// Lc = 0.277 m, body 0.6 × 0.28 m. Its IK treats every quadrant of the abduction circle, so
    /// abduction and hip are limited only to a full turn.
    pub const fn shahriar2023() -> Robot {
        Robot {
            leg: LegGeometry {
                d_lat_m: 0.044,
                d_ax_m: 0.0,
                femur_m: 0.28,
                tibia_m: 0.277,
            },
            body_length_m: 0.6,
            body_width_m: 0.28,
            limits: JointLimits {
                min_rad: [-core::f32::consts::PI, -core::f32::consts::PI, -2.8],
                max_rad: [core::f32::consts::PI, core::f32::consts::PI, -0.05],
            },
            knee_bend: KneeBend::Backward,
        }
    }

    /// Seed 001 (Fernando 2025): l0 = 0.15 m (along the leg plane), l1 = l2 = 0.45 m, hips at
    /// (±0.5, ±0.25) m.
    pub const fn fernando2025() -> Robot {
        Robot {
            leg: LegGeometry {
                d_lat_m: 0.0,
                d_ax_m: 0.15,
                femur_m: 0.45,
                tibia_m: 0.45,
            },
            body_length_m: 1.0,
            body_width_m: 0.5,
            limits: JointLimits {
                min_rad: [-0.8, -1.6, -2.8],
                max_rad: [0.8, 1.6, -0.05],
            },
            knee_bend: KneeBend::Backward,
        }
    }

    /// A preset by name: `shahriar2023` or `fernando2025`.
    pub fn preset(name: &str) -> Option<Robot> {
        match name {
            "shahriar2023" => Some(Robot::shahriar2023()),
            "fernando2025" => Some(Robot::fernando2025()),
            _ => None,
        }
    }

    /// Names of the presets accepted by [`Robot::preset`].
    pub const PRESETS: [&'static str; 2] = ["shahriar2023", "fernando2025"];

    /// The same robot with the other knee bend; the knee limits are mirrored with it, so a pose
    /// admitted with one bend is admitted by its mirror image with the other.
    pub fn with_knee_bend(mut self, bend: KneeBend) -> Robot {
        if bend != self.knee_bend {
            self.limits = self.limits.mirrored_knee();
            self.knee_bend = bend;
        }
        self
    }

    /// Checks lengths and limits: femur and tibia > 0, offsets ≥ 0, body sizes ≥ 0, limits
    /// finite with min ≤ max. A `const fn`: a firmware whose robot is a constant checks it
    /// at compile time.
    pub const fn validate(&self) -> Result<(), RobotError> {
        // Integer tests of the bit patterns, equal to the float comparisons they replace (a
        // software-float comparison is a library call on CPUs without floating-point hardware,
        // and a firmware's engine validates its robot before every motion).
        let bad_length = if !positive_finite(self.leg.femur_m) {
            "femur_m"
        } else if !positive_finite(self.leg.tibia_m) {
            "tibia_m"
        } else if !nonneg_finite(self.leg.d_lat_m) {
            "d_lat_m"
        } else if !nonneg_finite(self.leg.d_ax_m) {
            "d_ax_m"
        } else if !nonneg_finite(self.body_length_m) {
            "body_length_m"
        } else if !nonneg_finite(self.body_width_m) {
            "body_width_m"
        } else {
            ""
        };
        if !bad_length.is_empty() {
            return Err(RobotError::BadLength(bad_length));
        }
        // An index loop: iterators are not available in a `const fn`.
        let mut j = 0;
        while j < Joint::ALL.len() {
            if !finite_ordered(self.limits.min_rad[j], self.limits.max_rad[j]) {
                return Err(RobotError::BadLimit(Joint::ALL[j]));
            }
            j += 1;
        }
        Ok(())
    }

    /// `self == other` (field by field, float `==`), usable in a `const fn`: a
    /// configuration that names a preset is checked against the preset's robot at compile
    /// time. The one definition of [`Robot`]'s equality.
    pub const fn equals(&self, other: &Robot) -> bool {
        let (a, b) = (self, other);
        let mut j = 0;
        while j < 3 {
            if a.limits.min_rad[j] != b.limits.min_rad[j]
                || a.limits.max_rad[j] != b.limits.max_rad[j]
            {
                return false;
            }
            j += 1;
        }
        a.leg.d_lat_m == b.leg.d_lat_m
            && a.leg.d_ax_m == b.leg.d_ax_m
            && a.leg.femur_m == b.leg.femur_m
            && a.leg.tibia_m == b.leg.tibia_m
            && a.body_length_m == b.body_length_m
            && a.body_width_m == b.body_width_m
            && a.knee_bend as u8 == b.knee_bend as u8
    }

    /// The rest pose of one leg (every leg alike): folded under the body — abduction 0, knee
    /// [`REST_KNEE_MARGIN_RAD`] short of the folded end of its range (the minimum for
    /// [`KneeBend::Backward`], the maximum for [`KneeBend::Forward`]), hip at minus half the
    /// knee, which puts the foot below its hip joint. The limits may exclude it
    /// ([`JointLimits::first_violation`]).
    pub fn rest_leg(&self) -> JointAngles {
        let l = &self.limits;
        let knee = match self.knee_bend {
            KneeBend::Backward => l.min_rad[2] + REST_KNEE_MARGIN_RAD,
            KneeBend::Forward => l.max_rad[2] - REST_KNEE_MARGIN_RAD,
        };
        JointAngles::new(0.0, -0.5 * knee, knee)
    }

    /// Hip (abduction-axis) mount of `leg` in the body frame: `(±length/2, ±width/2, 0)`.
    #[inline]
    pub const fn hip_in_body(&self, leg: LegId) -> Vec3 {
        leg.at_corner(Vec3::new(
            0.5 * self.body_length_m,
            0.5 * self.body_width_m,
            0.0,
        ))
    }

    /// Nominal stance for stance height `height_m`: each foot straight below its hip, in the
    /// plane of the zero-abduction leg: `hip_in_body + (0, s·d_lat, −H)` (world = body frame).
    pub fn stance_feet(&self, height_m: f32) -> [Vec3; 4] {
        // The front left foot moved to each corner: the same sums as hip plus offset, one set
        // of float operations instead of one per leg.
        let front_left = Vec3::new(
            0.5 * self.body_length_m,
            0.5 * self.body_width_m + self.leg.d_lat_m,
            -height_m,
        );
        core::array::from_fn(|i| LegId::ALL[i].at_corner(front_left))
    }
}
