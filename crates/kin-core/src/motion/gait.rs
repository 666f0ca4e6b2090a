//! Trot / walk gait generator driven by a body velocity command, built on the foot paths.
//!
//! The body moves at a constant twist: velocity `v = (forward, lateral)` in its own frame and
//! yaw rate `ω` (counter-clockwise positive, REP 103). Over a time `s` it is displaced by
//! `X(s) = (Rz(ω·s), p(s))` with `p(s) = ∫₀ˢ Rz(ω·u)·v du`.
//!
//! Leg `i` has phase `φ_i = frac(t/T + o_i)`: swing for `φ < 1 − d`, stance after (duty factor
//! `d`). In stance the foot is fixed in the world at `X(t_mid)·n_i`, where `t_mid` is the middle
//! of that stance and `n_i` the neutral foothold (nominal stance at height `H`); in the body
//! frame it is therefore `X(t_mid − t)·n_i` — exact no-slip for any `v` and `ω`, and symmetric
//! about `n_i`. In swing the foot moves, in the body frame, from its lift-off point
//! `X(−dT/2)·n_i` to its next touch-down point `X(dT/2)·n_i` along the chosen
//! [`PathKind`] (stride = their distance, apex = the step height). For
//! a straight command (`ω = 0`) the stance is the paths' linear stance and the Bézier swing
//! joins it with C1 continuity.
//!
//! Precision: the world coordinates are f32. A straight command moves the body away from the
//! origin without bound, and the resolution of the feet in the world (hence of the IK input
//! `foot − body`) degrades with the distance: about 60 µm at 700 m (one hour at 0.2 m/s). A
//! turning command keeps the body on a circle.

use super::path::{AnyPath, FootPath, PathKind, Stride};
use super::{
    check_reach, finite, fract01, non_negative, positive, Contact, Error, Frame, Motion, Phase,
};
use super::{Expected, Param};
use crate::body::{BodyConfig, Pose};
use crate::math::{wrap_pi, DefaultMath, Math};
use crate::robot::{LegId, Robot};
use crate::rotation::RotationOrder;
use crate::vec::Vec3;

/// Body velocity command, in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Velocity {
    /// Forward speed (body x), m/s.
    pub forward_m_s: f32,
    /// Lateral speed (body y, left positive), m/s.
    pub lateral_m_s: f32,
    /// Yaw rate (about z, counter-clockwise positive), rad/s.
    pub yaw_rad_s: f32,
}

/// A named footfall pattern: phase offsets and duty factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Pattern {
    /// Diagonal pairs in antiphase: FL + RR at 0, FR + RL at ½; duty 0.75, so the pairs hand
    /// the body over with all four feet down. At duty ½ each stance pair carries half the body
    /// alone for its whole stance; on position servos whose error grows with the load the two
    /// loaded knees sag through the stance and eat the stride (docs/twin.md: a quarter of the
    /// commanded distance on seed 000's robot, a roll-over on seed 001's).
    Trot,
    /// Lateral-sequence walk RL → FL → RR → FR, a quarter cycle apart; duty 0.75 (always three
    /// feet down).
    Walk,
}

impl Pattern {
    /// Phase offsets in leg order FL, FR, RL, RR, cycles.
    pub const fn phase_offsets(self) -> [f32; 4] {
        match self {
            Pattern::Trot => [0.0, 0.5, 0.5, 0.0],
            Pattern::Walk => [0.25, 0.75, 0.0, 0.5],
        }
    }

    /// Stance fraction of the cycle.
    pub const fn duty_factor(self) -> f32 {
        match self {
            Pattern::Trot => 0.75,
            Pattern::Walk => 0.75,
        }
    }

    /// `trot` or `walk`.
    pub const fn name(self) -> &'static str {
        match self {
            Pattern::Trot => "trot",
            Pattern::Walk => "walk",
        }
    }
}

/// Parameters of a [`Gait`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaitParams {
    /// The robot.
    pub robot: Robot,
    /// Stance height `H` (hip plane above the ground), m.
    pub stance_height_m: f32,
    /// Gait cycle `T`, s.
    pub cycle_s: f32,
    /// Stance fraction `d` ∈ (0, 1).
    pub duty_factor: f32,
    /// Phase offsets `o_i` in leg order FL, FR, RL, RR, cycles.
    pub phase_offsets: [f32; 4],
    /// Apex of the swing above the ground, m (not used by the semicircle, whose apex is half
    /// its stride).
    pub step_height_m: f32,
    /// Body velocity command.
    pub velocity: Velocity,
    /// Swing shape.
    pub swing: PathKind,
    /// Rotation order of the pose (only yaw changes, so this matters only to consumers).
    pub order: RotationOrder,
}

impl GaitParams {
    /// Default cycle, s (with the trot's duty factor, the shape the physics twin found to keep
    /// both presets' joints under their servos' stall torque with the most distance:
    /// docs/twin.md).
    pub const DEFAULT_CYCLE_S: f32 = 1.0;
    /// Default step height as a fraction of the stance height.
    pub const DEFAULT_STEP_HEIGHT_FRACTION: f32 = 0.15;
    /// Default swing shape: the Bézier swing, which joins a straight stance with C1 continuity.
    pub const DEFAULT_SWING: PathKind = PathKind::Bezier;

    /// `pattern` on `robot` at `stance_height_m`, standing still (zero velocity), with a cycle
    /// of [`Self::DEFAULT_CYCLE_S`], a step height of [`Self::DEFAULT_STEP_HEIGHT_FRACTION`]·H
    /// and the [`Self::DEFAULT_SWING`].
    pub fn new(pattern: Pattern, robot: Robot, stance_height_m: f32) -> GaitParams {
        GaitParams {
            robot,
            stance_height_m,
            cycle_s: Self::DEFAULT_CYCLE_S,
            duty_factor: pattern.duty_factor(),
            phase_offsets: pattern.phase_offsets(),
            step_height_m: Self::DEFAULT_STEP_HEIGHT_FRACTION * stance_height_m,
            velocity: Velocity::default(),
            swing: Self::DEFAULT_SWING,
            order: RotationOrder::default(),
        }
    }
}

/// `sin(x)/x` from `sin_x` = `sin(x)`, exact at 0.
fn sinc(sin_x: f32, x: f32) -> f32 {
    if libm::fabsf(x) < 1e-3 {
        1.0 - x * x / 6.0
    } else {
        sin_x / x
    }
}

/// Body displacement `X(s)` of the constant twist `velocity` over a time `s` (s, negative
/// too), applied to a point `n` of the body frame: `p(s) + Rz(ω·s)·n` with
/// `p(s) = ∫₀ˢ Rz(ω·u)·v du` (see the module docs). `X(−s)` is the inverse of `X(s)`.
pub fn displace<M: Math>(velocity: &Velocity, s: f32, n: Vec3) -> Vec3 {
    let v = velocity;
    let x = v.yaw_rad_s * s;
    // Two sines, each used twice: on a soft-float target each evaluation is costly.
    let (sn, cs) = M::sin_cos(x);
    let (sh, _) = M::sin_cos(0.5 * x);
    let a = s * sinc(sn, x); // ∫ cos
    let b = s * sh * sinc(sh, 0.5 * x); // ∫ sin = (1 − cos x)/ω
    Vec3::new(
        v.forward_m_s * a - v.lateral_m_s * b + cs * n.x - sn * n.y,
        v.forward_m_s * b + v.lateral_m_s * a + sn * n.x + cs * n.y,
        n.z,
    )
}

/// A swing foot at leg phase `phase` (in `[0, 1 − duty_factor)`) on its way from `lift_off`
/// to `touch_down` (body frame, m): the [`PathKind`] path over the chord between them (stride =
/// their horizontal distance, apex `step_height_m` above the chord's middle).
pub fn swing_foot<M: Math>(
    swing: PathKind,
    step_height_m: f32,
    duty_factor: f32,
    lift_off: Vec3,
    touch_down: Vec3,
    phase: Phase,
) -> Vec3 {
    let chord = touch_down - lift_off;
    let length = M::sqrt(chord.x * chord.x + chord.y * chord.y);
    let (ux, uy) = if length > 0.0 {
        (chord.x / length, chord.y / length)
    } else {
        (1.0, 0.0)
    };
    let mid = (lift_off + touch_down) * 0.5;
    let path = AnyPath::new(swing, Stride::unchecked(length, step_height_m, duty_factor));
    let o = path.offset::<M>(phase);
    Vec3::new(mid.x + ux * o.x, mid.y + uy * o.x, mid.z + o.z)
}

/// The gait's checks that need no robot: finite values, `H > 0`, `T > 0`, `d ∈ (0, 1)`, the
/// step height ≥ 0 and below the hips (the [`Gait`]'s and the walker's).
pub(crate) fn check_timing(
    stance_height_m: f32,
    cycle_s: f32,
    duty_factor: f32,
    phase_offsets: &[f32; 4],
    step_height_m: f32,
) -> Result<(), Error> {
    positive(stance_height_m, Param::StanceHeightM)?;
    positive(cycle_s, Param::CycleS)?;
    let d = finite(duty_factor, Param::DutyFactor)?;
    if !(d > 0.0 && d < 1.0) {
        return Err(Error::OutOfRange {
            parameter: Param::DutyFactor,
            expected: Expected::OpenUnitInterval,
        });
    }
    for &o in phase_offsets {
        finite(o, Param::PhaseOffsets)?;
    }
    non_negative(step_height_m, Param::StepHeightM)?;
    if !(step_height_m < stance_height_m) {
        return Err(Error::OutOfRange {
            parameter: Param::StepHeightM,
            expected: Expected::BelowStanceHeight,
        });
    }
    Ok(())
}

/// A trot or walk: see the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gait {
    p: GaitParams,
    neutral: [Vec3; 4],
}

impl Gait {
    /// Validates the parameters: finite values, `H > 0`, `T > 0`, `d ∈ (0, 1)`, the step
    /// height ≥ 0 and below the hips; then checks that every foot reaches its neutral foothold
    /// (`stance_height_m`), its lift-off and touch-down points (the velocity command sets the
    /// stride: `velocity`) and its swing apex (`step_height_m`). [`crate::preflight`] sweeps the
    /// whole motion. The reach checks run on the [`DefaultMath`] backend.
    pub fn new(p: GaitParams) -> Result<Gait, Error> {
        let gait = Self::without_reach_check(p)?;
        let cfg = gait.body_config();
        let zero = Pose::default();
        let d = p.duty_factor;
        let reach = |feet: &[Vec3; 4], name| check_reach(&p.robot, &zero, &cfg, feet, name);
        reach(&gait.neutral, Param::StanceHeightM)?;
        let at = |phase: f32| LegId::ALL.map(|leg| gait.foot_in_body::<DefaultMath>(leg, phase).0);
        reach(&at(0.0), Param::Velocity)?;
        reach(&at(1.0 - 0.5 * d), Param::Velocity)?;
        reach(&at(0.5 * (1.0 - d)), Param::StepHeightM)?;
        Ok(gait)
    }

    /// [`Gait::new`]'s parameter checks without its reach checks, for a caller that checks
    /// the reach itself through its own IK (a device's start check).
    pub fn without_reach_check(p: GaitParams) -> Result<Gait, Error> {
        p.robot.validate()?;
        check_timing(
            p.stance_height_m,
            p.cycle_s,
            p.duty_factor,
            &p.phase_offsets,
            p.step_height_m,
        )?;
        finite(p.velocity.forward_m_s, Param::ForwardMS)?;
        finite(p.velocity.lateral_m_s, Param::LateralMS)?;
        finite(p.velocity.yaw_rad_s, Param::YawRadS)?;
        Ok(Gait {
            p,
            neutral: p.robot.stance_feet(p.stance_height_m),
        })
    }

    /// The parameters.
    pub const fn params(&self) -> &GaitParams {
        &self.p
    }

    /// Neutral footholds (nominal stance at height `H`), body frame, m.
    pub const fn neutral_feet(&self) -> [Vec3; 4] {
        self.neutral
    }

    /// Body displacement `X(s)` applied to a point `n` of the body frame: `p(s) + Rz(ω·s)·n`.
    fn displaced<M: Math>(&self, s: f32, n: Vec3) -> Vec3 {
        displace::<M>(&self.p.velocity, s, n)
    }

    /// Foot of `leg` in the body frame at leg phase `phase` (cycles; wrapped), and its contact.
    pub fn foot_in_body<M: Math>(&self, leg: LegId, phase: f32) -> (Vec3, Contact) {
        let phase = Phase::wrap(phase);
        let (t, d) = (self.p.cycle_s, self.p.duty_factor);
        let n = self.neutral[leg.index()];
        let swing_end = 1.0 - d;
        if phase.value() >= swing_end {
            // Time since the middle of the stance.
            let tau = (phase.value() - (1.0 - 0.5 * d)) * t;
            return (self.displaced::<M>(-tau, n), Contact::Stance);
        }
        let half_stance = 0.5 * d * t;
        let lift_off = self.displaced::<M>(-half_stance, n);
        let touch_down = self.displaced::<M>(half_stance, n);
        (
            swing_foot::<M>(
                self.p.swing,
                self.p.step_height_m,
                d,
                lift_off,
                touch_down,
                phase,
            ),
            Contact::Swing,
        )
    }

    /// Phase of `leg` at time `t_s`, cycles in `[0, 1)`.
    pub fn leg_phase(&self, leg: LegId, t_s: f32) -> f32 {
        fract01(fract01(t_s / self.p.cycle_s) + self.p.phase_offsets[leg.index()])
    }

    /// Stride of each leg in the body frame for the current command (distance between lift-off
    /// and touch-down points), m.
    pub fn step_length_m(&self, leg: LegId) -> f32 {
        let half = 0.5 * self.p.duty_factor * self.p.cycle_s;
        let n = self.neutral[leg.index()];
        (self.displaced::<DefaultMath>(half, n) - self.displaced::<DefaultMath>(-half, n)).norm()
    }
}

impl Motion for Gait {
    fn robot(&self) -> &Robot {
        &self.p.robot
    }

    fn body_config(&self) -> BodyConfig {
        BodyConfig::about_centre(self.p.order)
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        finite(t_s, Param::TS)?;
        let body = self.displaced::<M>(t_s, Vec3::ZERO);
        let yaw = wrap_pi(self.p.velocity.yaw_rad_s * t_s);
        let (sn, cs) = M::sin_cos(yaw);
        let mut feet = [Vec3::ZERO; 4];
        let mut contact = [Contact::Stance; 4];
        for leg in LegId::ALL {
            let (f, c) = self.foot_in_body::<M>(leg, self.leg_phase(leg, t_s));
            feet[leg.index()] = Vec3::new(
                body.x + cs * f.x - sn * f.y,
                body.y + sn * f.x + cs * f.y,
                body.z + f.z,
            );
            contact[leg.index()] = c;
        }
        Ok(Frame {
            pose: Pose {
                yaw_rad: yaw,
                x_m: body.x,
                y_m: body.y,
                ..Pose::default()
            },
            feet_in_world: feet,
            contact,
        })
    }

    fn period_s(&self) -> Option<f32> {
        Some(self.p.cycle_s)
    }
}
