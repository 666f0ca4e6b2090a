//! A stateful trot / walk stepper: the velocity command may change at any time, footholds are
//! planned at each lift-off, and a stop ends every stride at the neutral stance.
//!
//! [`super::gait::Gait`] is a closed form of one constant twist. The [`Walker`] keeps the
//! state that a changing command needs, and advances by a time step ([`Walker::step`]):
//!
//! - **Phases** as in [`super::gait`]: leg `i` has phase `φ_i = frac(φ + o_i)`, swing for
//!   `φ_i < 1 − d`, stance after; the global phase `φ` advances by `dt/T` per step.
//! - **Stance**: the foot stays fixed in the world while the body moves by the *current*
//!   command: over a step `dt` its body-frame position `p` becomes `X(−dt)·p`
//!   ([`super::gait::displace`]), exact no-slip for any command history.
//! - **Lift-off**: the foot's touch-down point is planned with the command of that instant,
//!   `X(d·T/2)·n_i` (the closed form's touch-down, `n_i` the neutral foothold); the swing runs
//!   from the foot's actual position to it along the [`PathKind`] path
//!   ([`super::gait::swing_foot`]). Under a constant command the feet follow the closed
//!   form [`super::gait::Gait`] (to rounding: the stance is integrated step by step).
//! - **Stop** ([`Walker::stop`]): the command becomes zero; every leg finishes its stride,
//!   steps once more onto its neutral foothold if it is not there, and then stays down
//!   ("parked"). [`Walker::is_stopped`] once all four are parked: the nominal stance at the
//!   walk's height, reached in at most two cycles.
//!
//! ## Reach: the stride disc
//! The feet use a horizontal disc of radius `R` ([`WalkerParams::reach_radius_m`]) around each
//! neutral foothold, from the ground up to the swing apex. [`Walker::new`] checks that cylinder
//! by inverse kinematics at [`Walker::ENVELOPE_SAMPLES`] points per leg: the 8 vertices of the
//! octagon circumscribing the disc (radius `R / cos 22.5°`) at the ground and at the apex, and
//! the neutral foothold at the apex. The octagon contains the disc, so the outer boundary of the
//! workspace (a ball, convex) that contains the samples contains the whole cylinder; the inner
//! boundaries and the joint limits are checked at the samples only (the device's preflight
//! adds their margins, and its run-time IK remains the last check).
//!
//! A velocity command is admitted ([`Walker::check_velocity`]) when every planned lift-off
//! and touch-down point lies within `R / f` of its neutral foothold, `f = 1 + 2σ/(5d)` for the
//! Bézier swing (its overshoot beyond the chord, `σ = 1 − d`) and 1 for the other shapes.
//! The stance between them is an arc of the circle through `n_i` about the instantaneous centre
//! of rotation (or a segment), whose distance from `n_i` grows with time when `|ω|·d·T ≤ π`,
//! which is also required; the swing's horizontal path lies on the chord (plus the overshoot).
//! When the command changes during a stance, the stance feet keep moving with the body and
//! could leave the disc of `R / f` (from which a swing's overshoot stays within `R`): the
//! body's displacement of that step is then halved (up to three times, then zero) until every
//! stance foot stays inside, and [`Walker::saturated`] reports it.

use super::gait::{check_timing, displace, swing_foot, Gait, GaitParams, Pattern, Velocity};
use super::path::PathKind;
use super::{
    check_reach, finite, fract01, positive, Contact, Error, Expected, Frame, Param, Phase,
};
use crate::body::{BodyConfig, Pose};
use crate::math::Math;
use crate::robot::{LegId, Robot};
use crate::rotation::RotationOrder;
use crate::vec::Vec3;

/// Parameters of a [`Walker`] (the robot is given apart: the walker keeps its neutral
/// footholds, not the robot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkerParams {
    /// Stance height `H` (hip plane above the ground), m.
    pub stance_height_m: f32,
    /// Gait cycle `T`, s.
    pub cycle_s: f32,
    /// Stance fraction `d` ∈ (0, 1).
    pub duty_factor: f32,
    /// Phase offsets `o_i` in leg order FL, FR, RL, RR, cycles.
    pub phase_offsets: [f32; 4],
    /// Apex of the swing above the ground, m (the semicircle's apex is half its stride).
    pub step_height_m: f32,
    /// Swing shape.
    pub swing: PathKind,
    /// Rotation order of the pose (the body stays at the zero pose; for consumers).
    pub order: RotationOrder,
    /// Radius `R` of the horizontal disc around each neutral foothold that the feet may use, m.
    pub reach_radius_m: f32,
}

impl WalkerParams {
    /// Default [`WalkerParams::reach_radius_m`] as a fraction of the stance height.
    pub const DEFAULT_REACH_RADIUS_FRACTION: f32 = 0.2;

    /// `pattern` at `stance_height_m` with [`GaitParams::new`]'s cycle, step height, swing and
    /// rotation order, and a reach radius of [`Self::DEFAULT_REACH_RADIUS_FRACTION`]·H.
    pub fn new(pattern: Pattern, stance_height_m: f32) -> WalkerParams {
        WalkerParams {
            stance_height_m,
            cycle_s: GaitParams::DEFAULT_CYCLE_S,
            duty_factor: pattern.duty_factor(),
            phase_offsets: pattern.phase_offsets(),
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * stance_height_m,
            swing: GaitParams::DEFAULT_SWING,
            order: RotationOrder::default(),
            reach_radius_m: Self::DEFAULT_REACH_RADIUS_FRACTION * stance_height_m,
        }
    }

    /// Checks the parameters: those of [`Gait::new`] that need no robot (finite values,
    /// `H > 0`, `T > 0`, `d ∈ (0, 1)`, the step height ≥ 0 and below the hips) and `R > 0`.
    pub fn checked(self) -> Result<CheckedWalkerParams, Error> {
        check_timing(
            self.stance_height_m,
            self.cycle_s,
            self.duty_factor,
            &self.phase_offsets,
            self.step_height_m,
        )?;
        positive(self.reach_radius_m, Param::ReachRadiusM)?;
        Ok(CheckedWalkerParams(self))
    }

    /// The Bézier swing's overshoot factor `f` (module docs), 1 for the other shapes.
    fn overshoot_factor(&self) -> f32 {
        let d = self.duty_factor;
        match self.swing {
            PathKind::Bezier => 1.0 + 2.0 * (1.0 - d) / (5.0 * d),
            _ => 1.0,
        }
    }

    /// The closed-form gait of these parameters on `robot` at a constant `velocity`.
    pub fn gait_params(&self, robot: Robot, velocity: Velocity) -> GaitParams {
        GaitParams {
            robot,
            stance_height_m: self.stance_height_m,
            cycle_s: self.cycle_s,
            duty_factor: self.duty_factor,
            phase_offsets: self.phase_offsets,
            step_height_m: self.step_height_m,
            velocity,
            swing: self.swing,
            order: self.order,
        }
    }
}

/// [`WalkerParams`] that passed their checks ([`WalkerParams::checked`]): a walker built from
/// them ([`Walker::standing`]) needs no fallible step, so a caller can build it where it is
/// stored instead of moving it out of a `Result`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckedWalkerParams(WalkerParams);

/// One leg's state.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Leg {
    /// Foot, body frame, m.
    foot: Vec3,
    /// Where the current (or last) swing started, body frame, m.
    lift_off: Vec3,
    /// Where it ends, body frame, m.
    touch_down: Vec3,
    /// Stopped at its neutral foothold for good.
    parked: bool,
}

/// One step of [`Walker::step`], as its legs see it.
struct Span {
    /// Global phase before the step, cycles.
    old: f32,
    /// After the step, cycles.
    new: f32,
    /// The step's duration, s.
    dt_s: f32,
    /// Fraction of the command by which the body moves over the step.
    scale: f32,
    /// `(R/f)²`, m².
    r_sq: f32,
}

/// A trot / walk stepper with a changing velocity command: see the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Walker {
    /// The gait's parameters.
    p: WalkerParams,
    /// The neutral footholds, body frame, m.
    neutral: [Vec3; 4],
    /// `R / f`: the radius within which the planned footholds lie and the stance feet stay
    /// (module docs), m; computed once, as are the next two.
    stance_radius_m: f32,
    /// `1 − d`: the leg phase at which the swing ends, cycles.
    swing_end: f32,
    /// `d·T/2`: half a stance, s.
    half_stance_s: f32,
    /// The velocity command.
    velocity: Velocity,
    /// Global gait phase `φ`, cycles in `[0, 1)`.
    phase: f32,
    /// Each leg's state, in the order of [`LegId::ALL`](crate::LegId::ALL).
    legs: [Leg; 4],
    /// A stop was asked for ([`Walker::is_stopping`]).
    stopping: bool,
    /// The last step moved the body less than commanded ([`Walker::saturated`]).
    saturated: bool,
}

impl Walker {
    /// Number of envelope points per leg ([`Walker::envelope`]).
    pub const ENVELOPE_SAMPLES: usize = 17;

    /// Validates the parameters (those of [`Gait::new`] on `robot` at zero velocity, and
    /// `R > 0`) and the reach of the stride cylinder (module docs; a failure names
    /// `reach_radius_m`), and starts at phase 0 standing on the neutral footholds (`robot`'s
    /// [`Robot::stance_feet`] at `H`) with a zero command. The reach checks run on the
    /// [`DefaultMath`](crate::DefaultMath) backend.
    pub fn new(robot: &Robot, p: WalkerParams) -> Result<Walker, Error> {
        Gait::new(p.gait_params(*robot, Velocity::default()))?;
        let walker = Self::on_stance(p, robot.stance_feet(p.stance_height_m))?;
        let cfg = walker.body_config();
        for k in 0..Self::ENVELOPE_SAMPLES {
            check_reach(
                robot,
                &Pose::default(),
                &cfg,
                &walker.envelope(k),
                Param::ReachRadiusM,
            )?;
        }
        Ok(walker)
    }

    /// [`Walker::new`]'s parameter checks without the robot's validation and the reach checks,
    /// standing on `neutral_feet` (the robot's [`Robot::stance_feet`] at `H`): for a caller
    /// that validated its robot already and checks the reach itself by running the envelope's
    /// points through its own IK (a device's start check).
    pub fn on_stance(p: WalkerParams, neutral_feet: [Vec3; 4]) -> Result<Walker, Error> {
        Ok(Self::standing(p.checked()?, &neutral_feet))
    }

    /// [`Walker::on_stance`] with parameters checked already: at phase 0 standing on
    /// `neutral_feet` (the robot's [`Robot::stance_feet`] at `H`) with a zero command.
    pub fn standing(p: CheckedWalkerParams, neutral_feet: &[Vec3; 4]) -> Walker {
        let leg = |n: Vec3| Leg {
            foot: n,
            lift_off: n,
            touch_down: n,
            parked: false,
        };
        Walker {
            stance_radius_m: p.0.reach_radius_m / p.0.overshoot_factor(),
            swing_end: 1.0 - p.0.duty_factor,
            half_stance_s: 0.5 * p.0.duty_factor * p.0.cycle_s,
            p: p.0,
            neutral: *neutral_feet,
            legs: neutral_feet.map(leg),
            phase: 0.0,
            velocity: Velocity::default(),
            stopping: false,
            saturated: false,
        }
    }

    /// The parameters.
    pub const fn params(&self) -> &WalkerParams {
        &self.p
    }

    /// Rotation order and pivot of the walker's (zero) pose.
    pub fn body_config(&self) -> BodyConfig {
        BodyConfig {
            order: self.p.order,
            pivot_m: Vec3::ZERO,
        }
    }

    /// Neutral footholds (nominal stance at height `H`), body frame, m.
    pub const fn neutral_feet(&self) -> [Vec3; 4] {
        self.neutral
    }

    /// Envelope point `k` (`< ENVELOPE_SAMPLES`) of the four legs, body frame, m: octagon
    /// vertices `0..8` at the ground, `8..16` at the apex, `16` the neutral foothold at the
    /// apex (module docs). Out-of-range `k` gives the neutral footholds.
    pub fn envelope(&self, k: usize) -> [Vec3; 4] {
        // cos(22.5°): the octagon of vertex radius R / cos(π/8) circumscribes the disc of R.
        const COS_PI_8: f32 = 0.923_879_5;
        let apex = match self.p.swing {
            PathKind::Semicircle => self.p.reach_radius_m,
            _ => self.p.step_height_m,
        };
        let mut d = Vec3::ZERO;
        if k < 16 {
            // The vertex in direction k·45°: the one at 0° or 45°, turned by quarter turns
            // (a swap and a sign change each: exact, and no table, which the AVR would hold in
            // SRAM).
            let r = self.p.reach_radius_m / COS_PI_8;
            let (mut x, mut y) = if k.is_multiple_of(2) {
                (r, 0.0)
            } else {
                let h = r * core::f32::consts::FRAC_1_SQRT_2;
                (h, h)
            };
            for _ in 0..(k / 2) % 4 {
                (x, y) = (-y, x);
            }
            d = Vec3::new(x, y, if k < 8 { 0.0 } else { apex });
        } else if k == 16 {
            d.z = apex;
        }
        core::array::from_fn(|i| self.neutral[i] + d)
    }

    /// True when every lift-off and touch-down point planned under the constant command `v`
    /// lies within `sqrt(radius_sq)` of its neutral foothold, horizontally.
    fn footholds_within<M: Math>(&self, v: &Velocity, radius_sq: f32) -> bool {
        let half = self.half_stance_s;
        for &n in &self.neutral {
            for s in [half, -half] {
                if !(off_sq(&displace::<M>(v, s, n), &n) <= radius_sq) {
                    return false;
                }
            }
        }
        true
    }

    /// Checks a velocity command: finite components, `|ω|·d·T ≤ π`, and the planned footholds
    /// within the stride disc (module docs). A component that is too large on its own is named
    /// (`forward_m_s`, `lateral_m_s`, `yaw_rad_s`); a combination that is, `velocity`.
    pub fn check_velocity<M: Math>(&self, v: &Velocity) -> Result<(), Error> {
        // Each component alone, then all three together.
        const NAMES: [Param; 4] = [
            Param::ForwardMS,
            Param::LateralMS,
            Param::YawRadS,
            Param::Velocity,
        ];
        finite(v.forward_m_s, Param::ForwardMS)?;
        finite(v.lateral_m_s, Param::LateralMS)?;
        finite(v.yaw_rad_s, Param::YawRadS)?;
        let stance_s = self.p.duty_factor * self.p.cycle_s;
        if !(libm::fabsf(v.yaw_rad_s) * stance_s <= core::f32::consts::PI) {
            return Err(Error::OutOfRange {
                parameter: Param::YawRadS,
                expected: Expected::HalfTurnPerStance,
            });
        }
        let r = self.stance_radius_m;
        for (k, &name) in NAMES.iter().enumerate() {
            let mut single = *v;
            if k != 0 && k != 3 {
                single.forward_m_s = 0.0;
            }
            if k != 1 && k != 3 {
                single.lateral_m_s = 0.0;
            }
            if k != 2 && k != 3 {
                single.yaw_rad_s = 0.0;
            }
            if !self.footholds_within::<M>(&single, r * r) {
                return Err(Error::OutOfRange {
                    parameter: name,
                    expected: Expected::WithinGaitReach,
                });
            }
        }
        Ok(())
    }

    /// The largest forward speed admitted alone, m/s: `2·R / (f·d·T)`.
    pub fn max_forward_m_s(&self) -> f32 {
        2.0 * self.p.reach_radius_m
            / (self.p.overshoot_factor() * self.p.duty_factor * self.p.cycle_s)
    }

    /// Sets the velocity command after [`Walker::check_velocity`]; it acts on the stance feet
    /// from the next step and on each foothold from the leg's next lift-off. Ignored (`Ok`)
    /// once stopping.
    pub fn set_velocity<M: Math>(&mut self, v: Velocity) -> Result<(), Error> {
        self.check_velocity::<M>(&v)?;
        if !self.stopping {
            self.velocity = v;
        }
        Ok(())
    }

    /// The velocity command in effect.
    pub const fn velocity(&self) -> Velocity {
        self.velocity
    }

    /// Stops: zero command; each leg finishes its stride and parks on its neutral foothold.
    pub fn stop(&mut self) {
        self.stopping = true;
        self.velocity = Velocity::default();
    }

    /// True once [`Walker::stop`] was called.
    pub const fn is_stopping(&self) -> bool {
        self.stopping
    }

    /// True when all four legs are parked: the nominal stance at the walk's height.
    pub fn is_stopped(&self) -> bool {
        self.legs.iter().all(|l| l.parked)
    }

    /// True when the last step reduced the body's displacement to keep the stance feet in
    /// their discs (module docs).
    pub const fn saturated(&self) -> bool {
        self.saturated
    }

    /// Global gait phase `φ`, cycles in `[0, 1)`.
    pub const fn phase(&self) -> f32 {
        self.phase
    }

    /// True when leg phase `q` is in the swing.
    fn in_swing(&self, q: f32) -> bool {
        q < self.swing_end
    }

    /// Moves `p` by the body displacement `X(rate·s)` of the current command, when there is a
    /// command and `s > 0`: a stance foot over `s` seconds of the body moving by `scale` times
    /// the command is `rate = −scale`, a touch-down point planned `s = d·T/2` ahead `rate = 1`.
    /// A zero command leaves `p` exactly where it is (a stop parks on the neutral foothold).
    fn carry<M: Math>(&self, p: &mut Vec3, s: f32, rate: f32) {
        if self.velocity != Velocity::default() && s > 0.0 {
            *p = displace::<M>(&self.velocity, rate * s, *p);
        }
    }

    /// Advances by `dt_s` (> 0, less than the shorter of swing and stance; one servo frame) on
    /// math backend `M`. A non-finite or non-positive `dt_s` is refused and changes nothing.
    pub fn step<M: Math>(&mut self, dt_s: f32) -> Result<(), Error> {
        positive(dt_s, Param::DtS)?;
        let old = self.phase;
        // Stance feet within R/f: a swing from there overshoots by at most the factor.
        let r = self.stance_radius_m;
        let mut span = Span {
            old,
            new: fract01(old + dt_s / self.p.cycle_s),
            dt_s,
            scale: 1.0,
            r_sq: r * r,
        };
        self.saturated = false;
        let mut next = self.legs;
        for _ in 0..5 {
            let mut inside = true;
            for (i, leg) in next.iter_mut().enumerate() {
                *leg = self.legs[i];
                inside &= self.advance_leg::<M>(i, leg, &span);
            }
            if inside || span.scale == 0.0 {
                break;
            }
            self.saturated = true;
            span.scale = if span.scale > 0.2 {
                0.5 * span.scale
            } else {
                0.0
            };
        }
        self.legs = next;
        self.phase = span.new;
        Ok(())
    }

    /// Advances leg `i`'s state `l` over `span`. False when the leg ends the step in stance
    /// with its foot moved farther out, beyond `R/f` (the step must move the body less). A
    /// foot already outside (it cannot be, by the checks) may stay.
    fn advance_leg<M: Math>(&self, i: usize, l: &mut Leg, span: &Span) -> bool {
        if l.parked {
            return true;
        }
        let n = &self.neutral[i];
        let before_sq = off_sq(&l.foot, n);
        let t = self.p.cycle_s;
        let o = self.p.phase_offsets[i];
        let (q0, q1) = (leg_phase(o, span.old), leg_phase(o, span.new));
        // Wrapped through 1 → 0: lift-off, after `(1 − q0)·T` of stance.
        let lift_off = q1 < q0;
        let stance_only = !lift_off && !self.in_swing(q0);
        if lift_off || stance_only {
            // The foot fixed in the world up to the lift-off or the step's end.
            let s = if lift_off {
                shorter((1.0 - q0) * t, span.dt_s)
            } else {
                span.dt_s
            };
            self.carry::<M>(&mut l.foot, s, -span.scale);
        }
        if lift_off {
            if self.stopping && l.foot == *n {
                l.parked = true;
                return true;
            }
            l.lift_off = l.foot;
            // The touch-down point planned now: `X(d·T/2)·n` with the current command.
            l.touch_down = *n;
            self.carry::<M>(&mut l.touch_down, self.half_stance_s, 1.0);
        }
        if !stance_only {
            if self.in_swing(q1) {
                l.foot = swing_foot::<M>(
                    self.p.swing,
                    self.p.step_height_m,
                    self.p.duty_factor,
                    l.lift_off,
                    l.touch_down,
                    // A leg phase is in [0, 1) already.
                    Phase(q1),
                );
                return true;
            }
            // Touch-down in this step, `(q1 − (1 − d))·T` ago.
            l.foot = l.touch_down;
            self.carry::<M>(
                &mut l.foot,
                shorter((q1 - self.swing_end) * t, span.dt_s),
                -span.scale,
            );
        }
        let after_sq = off_sq(&l.foot, n);
        !(after_sq > span.r_sq && after_sq > before_sq)
    }

    /// Feet and contacts now; the body stays at the zero pose, so the world frame is the body
    /// frame.
    pub fn frame(&self) -> Frame {
        let mut contact = [Contact::Stance; 4];
        for (i, c) in contact.iter_mut().enumerate() {
            if !self.legs[i].parked && self.in_swing(leg_phase(self.p.phase_offsets[i], self.phase))
            {
                *c = Contact::Swing;
            }
        }
        Frame {
            pose: Pose::default(),
            feet_in_world: self.feet(),
            contact,
        }
    }

    /// The four feet now, body frame, m ([`Walker::frame`]'s without the contacts).
    pub fn feet(&self) -> [Vec3; 4] {
        // Borrowed, not `map`ped: the legs' whole states would be copied first.
        core::array::from_fn(|i| self.legs[i].foot)
    }

    /// Foot of `leg` now, body frame, m.
    pub fn foot(&self, leg: LegId) -> Vec3 {
        self.legs[leg.index()].foot
    }
}

/// Squared horizontal distance of `p` from `n`, m².
fn off_sq(p: &Vec3, n: &Vec3) -> f32 {
    let q = *p - *n;
    q.x * q.x + q.y * q.y
}

/// The smaller of a span `a_s` and the step `dt_s` (finite, > 0): `f32::min` for a `dt_s` that
/// is never NaN, as one comparison, where `min` links a libm routine on the AVR.
fn shorter(a_s: f32, dt_s: f32) -> f32 {
    if a_s < dt_s {
        a_s
    } else {
        dt_s
    }
}

/// Phase of a leg with phase offset `offset` at global phase `phase`, cycles in `[0, 1)`.
fn leg_phase(offset: f32, phase: f32) -> f32 {
    fract01(phase + offset)
}

#[cfg(test)]
mod tests {
    use super::shorter;

    #[test]
    fn shorter_is_min_for_every_span_and_a_positive_step() {
        let spans = [0.0, -0.0, 0.01, 0.02, 0.03, 1.0, f32::INFINITY, f32::NAN];
        for &a in &spans {
            for dt in [0.001, 0.02, 0.5] {
                assert_eq!(shorter(a, dt).to_bits(), a.min(dt).to_bits(), "{a} {dt}");
            }
        }
    }
}
