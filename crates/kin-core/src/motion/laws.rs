//! Body-motion laws of seed 001 (eq. 6–11) and feet following a path under a held body
//! (seed 000 §3.2).
//!
//! ## Seed 001 leg numbering
//! Leg 1 = FL (ρ = (0.5, 0.25) m), 2 = FR (0.5, −0.25), 3 = RR (−0.5, −0.25), 4 = RL
//! (−0.5, 0.25). The crossed pairs of eq. 10–11 are (1, 3) = FL + RR and (2, 4) = FR + RL.
//!
//! ## Heights
//! Seed 001 puts the contact points at `z_K = 0` with the body centre above them; here the
//! world frame is the body frame of the nominal pose, so the ground is `z = −H` with `H` the
//! stance height (≈ 0.9294 m for seed 001's initial pose with [`Robot::fernando2025`]).

use super::path::{AnyPath, FootPath};
use super::{
    check_reach, finite, finite_feet, fract01, non_negative, positive, Contact, Error, Frame,
    Motion, Phase,
};
use super::{Expected, Param};
use crate::body::{BodyConfig, Pose};
use crate::math::{wrap_pi, DefaultMath, Math};
use crate::paper;
use crate::robot::{JointAngles, LegId, Robot};
use crate::rotation::RotationOrder;
use crate::vec::Vec3;
use core::f32::consts::PI;

/// Feet in the world frame of the nominal pose for all four legs at joint angles `q`:
/// `hip_in_body + leg::forward(q)`.
pub fn stance_from_angles(robot: &Robot, q: JointAngles) -> [Vec3; 4] {
    LegId::ALL.map(|leg| robot.hip_in_body(leg) + crate::leg::forward(&robot.leg, leg, q))
}

/// Seed 001's initial stance (eq. 5: φ = 120°, α = 60°, β = 0) for `robot`, via
/// [`paper::from_seed001`] and forward kinematics. With [`Robot::fernando2025`] the feet are
/// straight below the hips at `z = −(l0 + (l1 + l2)·sin 60°)` ≈ −0.9294 m.
pub fn seed001_stance(robot: &Robot) -> [Vec3; 4] {
    stance_from_angles(robot, paper::from_seed001(paper::SEED001_INITIAL))
}

/// Stance height of seed 000's pose sweeps (roll ±28°, pitch ±21°, yaw ±21°) with
/// [`Robot::shahriar2023`], m: 0.40 m, 72 % of the 0.557 m leg, leaves ≥ 4 cm of reach at the
/// extremes (see the tests for the margins).
pub const SEED000_SWEEP_STANCE_HEIGHT_M: f32 = 0.40;

/// The axis a [`Sway`] rotates about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Axis {
    /// Roll θ, about x (seed 001 eq. 6).
    Roll,
    /// Pitch γ, about y (seed 001 eq. 8).
    Pitch,
    /// Yaw ψ, about z (seed 000's twisting posture).
    Yaw,
}

impl Axis {
    /// `roll`, `pitch` or `yaw`.
    pub const fn name(self) -> &'static str {
        match self {
            Axis::Roll => "roll",
            Axis::Pitch => "pitch",
            Axis::Yaw => "yaw",
        }
    }
}

/// Parameters of a [`Sway`]: `angle(t) = angle0 + A·sin(2πt/T)` on one axis, the other angles
/// constant, feet fixed (seed 001 eq. 6–8), body centre fixed (`v_C = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwayParams {
    /// The robot.
    pub robot: Robot,
    /// The axis that oscillates.
    pub axis: Axis,
    /// Amplitude `A`, rad.
    pub amplitude_rad: f32,
    /// Period `T`, s.
    pub period_s: f32,
    /// Constant roll θ0, rad.
    pub roll0_rad: f32,
    /// Constant pitch γ0, rad.
    pub pitch0_rad: f32,
    /// Constant yaw ψ0, rad.
    pub yaw0_rad: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet on the ground (eq. 7: `x_K(t) = x_K(0)`, `y_K(t) = y_K(0)`), world frame, m.
    pub feet_in_world: [Vec3; 4],
}

impl SwayParams {
    /// Seed 001's values: [`Robot::fernando2025`], `A` = 0.2 rad, `T` = 20 s, θ0 = γ0 = ψ0 = 0,
    /// order `zxy`, feet at [`seed001_stance`]. `Axis::Roll` is eq. 6, `Axis::Pitch` eq. 8.
    pub fn seed001(axis: Axis) -> SwayParams {
        let robot = Robot::fernando2025();
        SwayParams {
            robot,
            axis,
            amplitude_rad: 0.2,
            period_s: 20.0,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            yaw0_rad: 0.0,
            order: RotationOrder::Zxy,
            feet_in_world: seed001_stance(&robot),
        }
    }

    /// Seed 000's pose sweep about `axis` (§3.1, Table 4: roll ±28°, pitch and yaw ±21°) with
    /// [`Robot::shahriar2023`] at [`SEED000_SWEEP_STANCE_HEIGHT_M`], order `zyx`, run as a sine of
    /// period 10 s (the paper steps 1° at a time; a sine covers the same range).
    pub fn seed000(axis: Axis) -> SwayParams {
        let robot = Robot::shahriar2023();
        let amplitude_deg: f32 = match axis {
            Axis::Roll => 28.0,
            Axis::Pitch | Axis::Yaw => 21.0,
        };
        SwayParams {
            robot,
            axis,
            amplitude_rad: amplitude_deg.to_radians(),
            period_s: 10.0,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            yaw0_rad: 0.0,
            order: RotationOrder::Zyx,
            feet_in_world: robot.stance_feet(SEED000_SWEEP_STANCE_HEIGHT_M),
        }
    }
}

impl SwayParams {
    /// The robot-free law of these parameters (all but the robot).
    pub const fn law(&self) -> SwayLaw {
        SwayLaw {
            axis: self.axis,
            amplitude_rad: self.amplitude_rad,
            period_s: self.period_s,
            roll0_rad: self.roll0_rad,
            pitch0_rad: self.pitch0_rad,
            yaw0_rad: self.yaw0_rad,
            order: self.order,
            feet_in_world: self.feet_in_world,
        }
    }
}

/// A sway's law without its robot: [`SwayParams`] but the robot, the frames' whole input. The
/// robot enters only the reach checks of [`Sway::new`] and the caller's IK; a device builds
/// this where it keeps it and checks it there ([`SwayLaw::check`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwayLaw {
    /// The axis that oscillates.
    pub axis: Axis,
    /// Amplitude `A`, rad.
    pub amplitude_rad: f32,
    /// Period `T`, s.
    pub period_s: f32,
    /// Constant roll θ0, rad.
    pub roll0_rad: f32,
    /// Constant pitch γ0, rad.
    pub pitch0_rad: f32,
    /// Constant yaw ψ0, rad.
    pub yaw0_rad: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet on the ground, world frame, m.
    pub feet_in_world: [Vec3; 4],
}

impl SwayLaw {
    /// The parameter checks of [`Sway::new`] without its reach checks: finite values, `T > 0`.
    pub fn check(&self) -> Result<(), Error> {
        finite(self.amplitude_rad, Param::AmplitudeRad)?;
        positive(self.period_s, Param::PeriodS)?;
        finite(self.roll0_rad, Param::Roll0Rad)?;
        finite(self.pitch0_rad, Param::Pitch0Rad)?;
        finite(self.yaw0_rad, Param::Yaw0Rad)?;
        finite_feet(&self.feet_in_world, Param::FeetInWorld)?;
        Ok(())
    }

    /// The oscillating angle's offset from its constant, `A·sin(2πt/T)`, rad.
    pub fn offset_rad<M: Math>(&self, t_s: f32) -> f32 {
        let phase = fract01(t_s / self.period_s);
        self.amplitude_rad * M::sin_cos(2.0 * PI * phase).0
    }

    /// [`Motion::frame`] written into `frame` (unchanged when `t_s` is not finite): no frame
    /// passed by value, for a caller that keeps one.
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        finite(t_s, Param::TS)?;
        frame.pose = self.pose_at(self.offset_rad::<M>(t_s));
        frame.feet_in_world = self.feet_in_world;
        frame.contact = [Contact::Stance; 4];
        Ok(())
    }

    fn pose_at(&self, offset_rad: f32) -> Pose {
        let (mut r, mut p, mut y) = (self.roll0_rad, self.pitch0_rad, self.yaw0_rad);
        match self.axis {
            Axis::Roll => r += offset_rad,
            Axis::Pitch => p += offset_rad,
            Axis::Yaw => y += offset_rad,
        }
        Pose::rotation(r, p, y)
    }
}

/// Seed 001's sway laws (eq. 6–8): one body angle oscillates, feet fixed, centre fixed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sway {
    robot: Robot,
    law: SwayLaw,
}

impl Sway {
    /// Validates the parameters: finite values, `T > 0`, and the feet reachable at `t = 0` and at
    /// both extremes `angle0 ± A` (a quick check; [`crate::preflight`] sweeps the whole motion).
    /// The reach checks run on the [`DefaultMath`] backend.
    pub fn new(p: SwayParams) -> Result<Sway, Error> {
        p.robot.validate()?;
        let s = Self::without_reach_check(p)?;
        let cfg = s.body_config();
        check_reach(
            &p.robot,
            &s.law.pose_at(0.0),
            &cfg,
            &p.feet_in_world,
            Param::FeetInWorld,
        )?;
        for sign in [1.0, -1.0] {
            check_reach(
                &p.robot,
                &s.law.pose_at(sign * p.amplitude_rad),
                &cfg,
                &p.feet_in_world,
                Param::AmplitudeRad,
            )?;
        }
        Ok(s)
    }

    /// [`Sway::new`]'s parameter checks without its reach checks and without validating
    /// `p.robot`, for a caller that validated its robot already and checks the reach itself.
    pub fn without_reach_check(p: SwayParams) -> Result<Sway, Error> {
        let law = p.law();
        law.check()?;
        Ok(Sway {
            robot: p.robot,
            law,
        })
    }

    /// The parameters.
    pub const fn params(&self) -> SwayParams {
        let l = &self.law;
        SwayParams {
            robot: self.robot,
            axis: l.axis,
            amplitude_rad: l.amplitude_rad,
            period_s: l.period_s,
            roll0_rad: l.roll0_rad,
            pitch0_rad: l.pitch0_rad,
            yaw0_rad: l.yaw0_rad,
            order: l.order,
            feet_in_world: l.feet_in_world,
        }
    }

    /// The robot-free law.
    pub const fn law(&self) -> &SwayLaw {
        &self.law
    }

    /// The oscillating angle's offset from its constant, `A·sin(2πt/T)`, rad.
    pub fn offset_rad<M: Math>(&self, t_s: f32) -> f32 {
        self.law.offset_rad::<M>(t_s)
    }

    /// [`Motion::frame`] written into `frame` ([`SwayLaw::frame_into`]).
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        self.law.frame_into::<M>(t_s, frame)
    }
}

impl Motion for Sway {
    fn robot(&self) -> &Robot {
        &self.robot
    }

    fn body_config(&self) -> BodyConfig {
        BodyConfig::about_centre(self.law.order)
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        let mut frame = Frame::ZERO;
        self.frame_into::<M>(t_s, &mut frame)?;
        Ok(frame)
    }

    fn period_s(&self) -> Option<f32> {
        Some(self.law.period_s)
    }
}

/// Parameters of seed 001's yaw turn (eq. 9–11): `ψ(t) = ψ0 + r·t` about the fixed body
/// centre, the crossed pairs (FL, RR) and (FR, RL) stepping alternately along the circles of
/// their feet. The yaw rate `r` counts counter-clockwise seen from above as positive (REP 103,
/// as the gaits' velocity command does); the paper's `ω_z` (eq. 9, `ψ = ψ0 − ω_z·t`) counts
/// clockwise: `r = −ω_z` (`docs/papers.md`, seed 001 errata).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawTurnParams {
    /// The robot.
    pub robot: Robot,
    /// Yaw rate `r = −ω_z`, rad/s; positive turns counter-clockwise seen from above (ψ
    /// increases).
    pub yaw_rate_rad_s: f32,
    /// Step period `T1` (one full cycle of both pairs), s.
    pub step_period_s: f32,
    /// Lift height `h_K` of the half-wave sine, m.
    pub lift_height_m: f32,
    /// Initial yaw ψ0, rad.
    pub yaw0_rad: f32,
    /// Constant roll θ0, rad.
    pub roll0_rad: f32,
    /// Constant pitch γ0, rad.
    pub pitch0_rad: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet at `t = 0` relative to the body, i.e. in the world frame of the pose with
    /// ψ = 0; each foot's `ρ_i`, `α_i` are taken from its `(x, y)`, m.
    pub stance_feet: [Vec3; 4],
}

impl YawTurnParams {
    /// Seed 001's values: [`Robot::fernando2025`], ω_z = 0.085 rad/s (clockwise: a yaw rate of
    /// −0.085 rad/s), T1 = 6 s, h_K = 0.3 m,
    /// ψ0 = θ0 = γ0 = 0, order `zxy`, feet at [`seed001_stance`].
    pub fn seed001() -> YawTurnParams {
        let robot = Robot::fernando2025();
        YawTurnParams {
            robot,
            yaw_rate_rad_s: -0.085,
            step_period_s: 6.0,
            lift_height_m: 0.3,
            yaw0_rad: 0.0,
            roll0_rad: 0.0,
            pitch0_rad: 0.0,
            order: RotationOrder::Zxy,
            stance_feet: seed001_stance(&robot),
        }
    }
}

/// True for the legs of seed 001's pair (1, 3) = (FL, RR), which swing in the first half of
/// each step period; (2, 4) = (FR, RL) swing in the second half.
pub const fn in_pair_13(leg: LegId) -> bool {
    matches!(leg, LegId::FL | LegId::RR)
}

impl YawTurnParams {
    /// These parameters but the robot.
    pub const fn law_params(&self) -> YawTurnLawParams {
        YawTurnLawParams {
            yaw_rate_rad_s: self.yaw_rate_rad_s,
            step_period_s: self.step_period_s,
            lift_height_m: self.lift_height_m,
            yaw0_rad: self.yaw0_rad,
            roll0_rad: self.roll0_rad,
            pitch0_rad: self.pitch0_rad,
            order: self.order,
            stance_feet: self.stance_feet,
        }
    }
}

/// [`YawTurnParams`] but the robot: a [`YawTurnLaw`]'s input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawTurnLawParams {
    /// Yaw rate `r = −ω_z`, rad/s; positive turns counter-clockwise seen from above.
    pub yaw_rate_rad_s: f32,
    /// Step period `T1` (one full cycle of both pairs), s.
    pub step_period_s: f32,
    /// Lift height `h_K` of the half-wave sine, m.
    pub lift_height_m: f32,
    /// Initial yaw ψ0, rad.
    pub yaw0_rad: f32,
    /// Constant roll θ0, rad.
    pub roll0_rad: f32,
    /// Constant pitch γ0, rad.
    pub pitch0_rad: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet at `t = 0` relative to the body, m.
    pub stance_feet: [Vec3; 4],
}

/// Seed 001's yaw turn without its robot ([`YawTurn`]'s law), eq. 9–11 as corrected in `docs/papers.md` ("Seed 001 eq. 10–11").
///
/// With `τ = t mod T1` and `k = ⌊t/T1⌋`:
/// - `Δ13 = k·T1 + (2τ if τ < T1/2 else T1)`, `Δ24 = k·T1 + (0 if τ < T1/2 else 2(τ − T1/2))`
///   (eq. 11 with a floored `mod`);
/// - foot `i` at `ρ_i·(cos a_i, sin a_i)` with `a_i = α_i + ψ0 + r·Δ_i` (`r = −ω_z`) and
///   `α_i = atan2(y_i, x_i)` of its stance position (eq. 10 corrected: atan2, cos/sin, sign);
/// - lift `h_K·max(0, sin(2πt/T1))` for (FL, RR) and `h_K·max(0, −sin(2πt/T1))` for (FR, RL)
///   above the stance height (eq. 10's half-wave).
///
/// A stance foot stays fixed while the body turns by `r·T1/2`; a swing foot moves by
/// `r·T1` along its circle in `T1/2`. The joint angles repeat with period `T1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawTurnLaw {
    p: YawTurnLawParams,
    rho_m: [f32; 4],
    alpha_rad: [f32; 4],
}

impl YawTurnLaw {
    /// [`YawTurn::new`]'s parameter checks without its reach checks, with the foot radii and
    /// angles on math backend `M`, for a caller that checks the reach itself by running the
    /// law's frames through its own IK (a device's start check).
    pub fn without_reach_check<M: Math>(p: YawTurnLawParams) -> Result<YawTurnLaw, Error> {
        Self::check(&p)?;
        Ok(YawTurnLaw {
            p,
            rho_m: p.stance_feet.map(|f| M::sqrt(f.x * f.x + f.y * f.y)),
            alpha_rad: p.stance_feet.map(|f| M::atan2(f.y, f.x)),
        })
    }

    /// The parameter checks of [`YawTurnLaw::without_reach_check`].
    fn check(p: &YawTurnLawParams) -> Result<(), Error> {
        finite(p.yaw_rate_rad_s, Param::YawRateRadS)?;
        positive(p.step_period_s, Param::StepPeriodS)?;
        non_negative(p.lift_height_m, Param::LiftHeightM)?;
        finite(p.yaw0_rad, Param::Yaw0Rad)?;
        finite(p.roll0_rad, Param::Roll0Rad)?;
        finite(p.pitch0_rad, Param::Pitch0Rad)?;
        finite_feet(&p.stance_feet, Param::StanceFeet)?;
        for f in &p.stance_feet {
            if !(f.z + p.lift_height_m < 0.0) {
                return Err(Error::OutOfRange {
                    parameter: Param::LiftHeightM,
                    expected: Expected::BelowStanceHeight,
                });
            }
        }
        Ok(())
    }

    /// The parameters.
    pub const fn params(&self) -> &YawTurnLawParams {
        &self.p
    }
    /// Radius `ρ_i` of each foot's circle, m (order FL, FR, RL, RR).
    pub const fn rho_m(&self) -> [f32; 4] {
        self.rho_m
    }

    /// Angle `α_i = atan2(y_i, x_i)` of each foot at `t = 0` relative to the body, rad.
    pub const fn alpha_rad(&self) -> [f32; 4] {
        self.alpha_rad
    }

    /// `(k, τ)` with `t = k·T1 + τ`, `τ ∈ [0, T1)`.
    fn split(&self, t_s: f32) -> (f32, f32) {
        let t1 = self.p.step_period_s;
        let mut k = crate::math::floor(t_s / t1);
        let mut tau = t_s - k * t1;
        if tau < 0.0 {
            k -= 1.0;
            tau += t1;
        }
        if tau >= t1 {
            k += 1.0;
            tau -= t1;
        }
        if !(tau >= 0.0 && tau < t1) {
            tau = 0.0;
        }
        (k, tau)
    }

    /// Eq. 11's `Δ13` and `Δ24` within the current step period (`Δ − k·T1`), s.
    pub fn deltas_in_period_s(&self, t_s: f32) -> (f32, f32) {
        let (_, tau) = self.split(t_s);
        Self::local_deltas(self.p.step_period_s, tau)
    }

    /// [`Motion::frame`] written into `frame` (unchanged when `t_s` is not finite): no frame
    /// passed by value, for a caller that keeps one.
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        finite(t_s, Param::TS)?;
        let p = &self.p;
        let t1 = p.step_period_s;
        let (k, tau) = self.split(t_s);
        // Yaw at the start of this step period, wrapped once so that body and feet share it.
        let base = wrap_pi(p.yaw0_rad + p.yaw_rate_rad_s * (k * t1));
        let yaw = wrap_pi(base + p.yaw_rate_rad_s * tau);
        let (d13, d24) = Self::local_deltas(t1, tau);
        let first_half = tau < 0.5 * t1;
        let wave = M::sin_cos(2.0 * PI * (tau / t1)).0;
        let lift13 = if first_half && wave > 0.0 { wave } else { 0.0 };
        let lift24 = if !first_half && wave < 0.0 {
            -wave
        } else {
            0.0
        };
        for leg in LegId::ALL {
            let i = leg.index();
            let (delta, lift, swing) = if in_pair_13(leg) {
                (d13, lift13, first_half)
            } else {
                (d24, lift24, !first_half)
            };
            let a = self.alpha_rad[i] + base + p.yaw_rate_rad_s * delta;
            let (s, c) = M::sin_cos(a);
            frame.feet_in_world[i] = Vec3::new(
                self.rho_m[i] * c,
                self.rho_m[i] * s,
                p.stance_feet[i].z + p.lift_height_m * lift,
            );
            frame.contact[i] = if swing {
                Contact::Swing
            } else {
                Contact::Stance
            };
        }
        frame.pose = Pose::rotation(p.roll0_rad, p.pitch0_rad, yaw);
        Ok(())
    }

    fn local_deltas(t1: f32, tau: f32) -> (f32, f32) {
        let half = 0.5 * t1;
        if tau < half {
            (2.0 * tau, 0.0)
        } else {
            (t1, 2.0 * (tau - half))
        }
    }
}

/// Seed 001's yaw turn ([`YawTurnLaw`] on a robot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawTurn {
    robot: Robot,
    law: YawTurnLaw,
}

impl YawTurn {
    /// Validates the parameters: finite values, `T1 > 0`, `h_K ≥ 0` and below the hips, and
    /// the feet reachable at `t = 0`, at both apexes and at the end of each swing (a quick check;
    /// [`crate::preflight`] sweeps the whole motion). The checks run on the [`DefaultMath`]
    /// backend.
    pub fn new(p: YawTurnParams) -> Result<YawTurn, Error> {
        p.robot.validate()?;
        let turn = Self::without_reach_check::<DefaultMath>(p)?;
        let cfg = turn.body_config();
        let t1 = p.step_period_s;
        for (t, name) in [
            (0.0, Param::StanceFeet),
            (0.25 * t1, Param::LiftHeightM),
            (0.75 * t1, Param::LiftHeightM),
            (0.499 * t1, Param::YawRateRadS),
            (0.999 * t1, Param::YawRateRadS),
        ] {
            let f = turn.frame::<DefaultMath>(t)?;
            check_reach(&p.robot, &f.pose, &cfg, &f.feet_in_world, name)?;
        }
        Ok(turn)
    }

    /// [`YawTurn::new`]'s parameter checks without its reach checks and without validating
    /// `p.robot` ([`YawTurnLaw::without_reach_check`]).
    pub fn without_reach_check<M: Math>(p: YawTurnParams) -> Result<YawTurn, Error> {
        Ok(YawTurn {
            robot: p.robot,
            law: YawTurnLaw::without_reach_check::<M>(p.law_params())?,
        })
    }

    /// The parameters.
    pub const fn params(&self) -> YawTurnParams {
        let l = &self.law.p;
        YawTurnParams {
            robot: self.robot,
            yaw_rate_rad_s: l.yaw_rate_rad_s,
            step_period_s: l.step_period_s,
            lift_height_m: l.lift_height_m,
            yaw0_rad: l.yaw0_rad,
            roll0_rad: l.roll0_rad,
            pitch0_rad: l.pitch0_rad,
            order: l.order,
            stance_feet: l.stance_feet,
        }
    }

    /// The robot-free law.
    pub const fn law(&self) -> &YawTurnLaw {
        &self.law
    }

    /// Radius `ρ_i` of each foot's circle, m (order FL, FR, RL, RR).
    pub const fn rho_m(&self) -> [f32; 4] {
        self.law.rho_m
    }

    /// Angle `α_i = atan2(y_i, x_i)` of each foot at `t = 0` relative to the body, rad.
    pub const fn alpha_rad(&self) -> [f32; 4] {
        self.law.alpha_rad
    }

    /// Eq. 11's `Δ13` and `Δ24` within the current step period (`Δ − k·T1`), s.
    pub fn deltas_in_period_s(&self, t_s: f32) -> (f32, f32) {
        self.law.deltas_in_period_s(t_s)
    }

    /// [`Motion::frame`] written into `frame` ([`YawTurnLaw::frame_into`]).
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        self.law.frame_into::<M>(t_s, frame)
    }
}

impl Motion for YawTurn {
    fn robot(&self) -> &Robot {
        &self.robot
    }

    fn body_config(&self) -> BodyConfig {
        BodyConfig::about_centre(self.law.p.order)
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        let mut frame = Frame::ZERO;
        self.frame_into::<M>(t_s, &mut frame)?;
        Ok(frame)
    }

    fn period_s(&self) -> Option<f32> {
        Some(self.law.p.step_period_s)
    }
}

/// Parameters of [`LegPaths`]: every foot follows a [`FootPath`] around its stance point while
/// the body is held at the nominal pose (seed 000 §3.2, where one leg traces a rectangle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPathsParams {
    /// The robot.
    pub robot: Robot,
    /// The path each foot follows (x along the body's x axis).
    pub path: AnyPath,
    /// Duration of one loop of the path, s.
    pub cycle_s: f32,
    /// Phase offset of each leg (order FL, FR, RL, RR), cycles.
    pub phase_offsets: [f32; 4],
    /// The stance point of each foot (path offset zero), world frame, m.
    pub stance_feet: [Vec3; 4],
}

impl LegPathsParams {
    /// Seed 000 Fig. 8: [`Robot::shahriar2023`], [`crate::motion::path::Rectangle::seed000`]
    /// (stride 0.1 m, lift 0.05 m) at stance height 0.2 m, 3 s per loop, all legs in phase.
    pub fn seed000() -> LegPathsParams {
        let robot = Robot::shahriar2023();
        LegPathsParams {
            robot,
            path: AnyPath::Rectangle(super::path::Rectangle::seed000()),
            cycle_s: 3.0,
            phase_offsets: [0.0; 4],
            stance_feet: robot.stance_feet(super::path::Rectangle::SEED000_STANCE_HEIGHT_M),
        }
    }
}

impl LegPathsParams {
    /// The robot-free law of these parameters (all but the robot).
    pub const fn law(&self) -> LegPathsLaw {
        LegPathsLaw {
            path: self.path,
            cycle_s: self.cycle_s,
            phase_offsets: self.phase_offsets,
            stance_feet: self.stance_feet,
        }
    }
}

/// Feet following a path under a held body, without the robot: [`LegPathsParams`] but the
/// robot (as [`SwayLaw`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPathsLaw {
    /// The path each foot follows (x along the body's x axis).
    pub path: AnyPath,
    /// Duration of one loop of the path, s.
    pub cycle_s: f32,
    /// Phase offset of each leg (order FL, FR, RL, RR), cycles.
    pub phase_offsets: [f32; 4],
    /// The stance point of each foot (path offset zero), world frame, m.
    pub stance_feet: [Vec3; 4],
}

impl LegPathsLaw {
    /// The parameter checks of [`LegPaths::new`] without its reach checks: finite values,
    /// `cycle_s > 0`.
    pub fn check(&self) -> Result<(), Error> {
        positive(self.cycle_s, Param::CycleS)?;
        for o in &self.phase_offsets {
            finite(*o, Param::PhaseOffsets)?;
        }
        finite_feet(&self.stance_feet, Param::StanceFeet)?;
        Ok(())
    }

    /// [`Motion::frame`] written into `frame` (unchanged when `t_s` is not finite): no frame
    /// passed by value, for a caller that keeps one.
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        finite(t_s, Param::TS)?;
        let base = fract01(t_s / self.cycle_s);
        frame.pose = Pose::default();
        for leg in LegId::ALL {
            let i = leg.index();
            let phase = Phase::wrap(base + self.phase_offsets[i]);
            frame.feet_in_world[i] = self.stance_feet[i] + self.path.offset::<M>(phase);
            frame.contact[i] = self.path.contact(phase);
        }
        Ok(())
    }
}

/// Feet following a path under a held body (the body does not move; stance feet slide).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPaths {
    robot: Robot,
    law: LegPathsLaw,
}

impl LegPaths {
    /// Number of phases per leg the constructor checks for reach.
    const REACH_SAMPLES: u16 = 64;

    /// Validates the parameters: finite values, `cycle_s > 0`, and the path reachable by every
    /// leg at 64 evenly spaced phases (a quick check; [`crate::preflight`] is exhaustive), on
    /// the [`DefaultMath`] backend.
    pub fn new(p: LegPathsParams) -> Result<LegPaths, Error> {
        p.robot.validate()?;
        let lp = Self::without_reach_check(p)?;
        let cfg = lp.body_config();
        for i in 0..Self::REACH_SAMPLES {
            let phase = Phase::wrap(f32::from(i) / f32::from(Self::REACH_SAMPLES));
            let feet = LegId::ALL
                .map(|leg| p.stance_feet[leg.index()] + p.path.offset::<DefaultMath>(phase));
            check_reach(&p.robot, &Pose::default(), &cfg, &feet, Param::Path)?;
        }
        Ok(lp)
    }

    /// [`LegPaths::new`]'s parameter checks without its reach checks and without validating
    /// `p.robot`, for a caller that validated its robot already and checks the reach itself.
    pub fn without_reach_check(p: LegPathsParams) -> Result<LegPaths, Error> {
        let law = p.law();
        law.check()?;
        Ok(LegPaths {
            robot: p.robot,
            law,
        })
    }

    /// The parameters.
    pub const fn params(&self) -> LegPathsParams {
        let l = &self.law;
        LegPathsParams {
            robot: self.robot,
            path: l.path,
            cycle_s: l.cycle_s,
            phase_offsets: l.phase_offsets,
            stance_feet: l.stance_feet,
        }
    }

    /// The robot-free law.
    pub const fn law(&self) -> &LegPathsLaw {
        &self.law
    }

    /// [`Motion::frame`] written into `frame` ([`LegPathsLaw::frame_into`]).
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        self.law.frame_into::<M>(t_s, frame)
    }
}

impl Motion for LegPaths {
    fn robot(&self) -> &Robot {
        &self.robot
    }

    fn body_config(&self) -> BodyConfig {
        BodyConfig::default()
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        let mut frame = Frame::ZERO;
        self.frame_into::<M>(t_s, &mut frame)?;
        Ok(frame)
    }

    fn period_s(&self) -> Option<f32> {
        Some(self.law.cycle_s)
    }
}

/// The order in which a [`StableTurn`] lifts its legs: around the body, so that the body's
/// shift from one support triangle to the next runs along a side of the feet's rectangle,
/// never across its diagonal.
pub const STABLE_TURN_ORDER: [LegId; 4] = [LegId::FL, LegId::FR, LegId::RR, LegId::RL];

/// Share of each leg's quarter of a [`StableTurn`] cycle in which the body shifts with all four
/// feet down; the leg swings in the rest.
pub const STABLE_TURN_SHIFT_SHARE: f32 = 0.5;

/// Parameters of a [`StableTurn`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableTurnParams {
    /// The robot.
    pub robot: Robot,
    /// Yaw of one cycle `Δψ` (each leg steps once), rad; positive turns counter-clockwise seen
    /// from above. `|Δψ| ≤ π/2`.
    pub yaw_per_cycle_rad: f32,
    /// Duration of one cycle `T`, s.
    pub cycle_s: f32,
    /// Swing apex above the ground, m.
    pub lift_height_m: f32,
    /// How far the body centre moves towards the centroid of the three feet that stay down,
    /// in (0, 1] (1: onto the centroid).
    pub shift_fraction: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet at `t = 0` relative to the body, world frame of the nominal pose, m. The world
    /// origin (the body centre of the stance) should be the centre of the four feet, as in
    /// [`Robot::stance_feet`].
    pub stance_feet: [Vec3; 4],
}

impl StableTurnParams {
    /// Default yaw of one cycle, rad (11.5°).
    pub const DEFAULT_YAW_PER_CYCLE_RAD: f32 = 0.2;
    /// Default cycle, s: each leg has 5 s, 2.5 s to shift the body and 2.5 s to swing. Slow
    /// enough for seed 001's 22 kg robot in the physics twin, which falls at 12 s
    /// (`docs/twin.md`).
    pub const DEFAULT_CYCLE_S: f32 = 20.0;
    /// Default swing apex, as a fraction of the stance height.
    pub const DEFAULT_LIFT_FRACTION: f32 = 0.15;
    /// Default shift: 0.8 of the way to the centroid of the support triangle. The physics
    /// twin's seed 001 robot, whose stance legs sag under load, falls with 0.6, 0.7 and 0.9
    /// (`docs/twin.md`).
    pub const DEFAULT_SHIFT_FRACTION: f32 = 0.8;

    /// The defaults above for `robot` at the stance of height `stance_height_m`
    /// ([`Robot::stance_feet`]), order `zyx`.
    pub fn new(robot: Robot, stance_height_m: f32) -> StableTurnParams {
        StableTurnParams {
            robot,
            yaw_per_cycle_rad: Self::DEFAULT_YAW_PER_CYCLE_RAD,
            cycle_s: Self::DEFAULT_CYCLE_S,
            lift_height_m: Self::DEFAULT_LIFT_FRACTION * stance_height_m,
            shift_fraction: Self::DEFAULT_SHIFT_FRACTION,
            order: RotationOrder::Zyx,
            stance_feet: robot.stance_feet(stance_height_m),
        }
    }
}

impl StableTurnParams {
    /// These parameters but the robot.
    pub const fn law_params(&self) -> StableTurnLawParams {
        StableTurnLawParams {
            yaw_per_cycle_rad: self.yaw_per_cycle_rad,
            cycle_s: self.cycle_s,
            lift_height_m: self.lift_height_m,
            shift_fraction: self.shift_fraction,
            order: self.order,
            stance_feet: self.stance_feet,
        }
    }
}

/// [`StableTurnParams`] but the robot: a [`StableTurnLaw`]'s input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableTurnLawParams {
    /// Yaw of one cycle `Δψ`, rad, counter-clockwise positive; `|Δψ| ≤ π/2`.
    pub yaw_per_cycle_rad: f32,
    /// Duration of one cycle `T`, s.
    pub cycle_s: f32,
    /// Swing apex above the ground, m.
    pub lift_height_m: f32,
    /// How far the body centre moves towards the centroid of the three feet that stay down,
    /// in (0, 1].
    pub shift_fraction: f32,
    /// Rotation order of the pose.
    pub order: RotationOrder,
    /// The feet at `t = 0` relative to the body, m.
    pub stance_feet: [Vec3; 4],
}

/// A statically stable yaw turn on the spot: one leg lifted at a time, in
/// [`STABLE_TURN_ORDER`], the body first shifted towards the centroid of the other three feet,
/// so that the centre of mass stays inside the support triangle while the leg is in the air
/// (unlike seed 001's crossed-pair [`YawTurn`], which holds the body on a diagonal pair).
///
/// With `k = ⌊t/T⌋`, `τ = t − kT`, the cycle is four slots of `T/4`, slot `j` for leg
/// `STABLE_TURN_ORDER[j]`, each with a local phase `u ∈ [0, 1)`:
/// - body yaw `ψ(t) = Δψ·t/T` (about the body centre), no roll or pitch, at the stance height;
/// - foot `i` at `ρ_i·(cos(α_i + a_i), sin(α_i + a_i))` with `ρ_i`, `α_i` of its stance
///   position and `a_i = kΔψ` before its step in cycle `k`, `(k + 1)Δψ` after it; during its
///   step (`u ≥ s`, `s` = [`STABLE_TURN_SHIFT_SHARE`], `v = (u − s)/(1 − s)`)
///   `a_i = kΔψ + Δψ·b(v)` and the foot is `h·(1 − cos 2πv)/2` above the ground, with
///   `b(v) = v − sin(2πv)/2π` (zero speed at lift-off and touch-down);
/// - body translation: in slot `j`, the target `g_j` is `shift_fraction` times the centroid
///   (ground plane, world frame) of the three feet other than leg `j`'s, which stand still
///   through the slot; for `u < s` the body moves from the previous slot's target to `g_j`
///   along `b(u/s)` with four feet down (in the first slot of cycle 0 it starts from the
///   stance's centre), and holds `g_j` while the leg swings.
///
/// From the end of the first shift on, the joint angles repeat with period `T`.
///
/// This is the law without its robot ([`StableTurn`] is the law on a robot), for a caller that
/// holds the robot itself (a device's solver).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableTurnLaw {
    p: StableTurnLawParams,
    rho_m: [f32; 4],
    alpha_rad: [f32; 4],
}

/// [`StableTurnLaw`] on a robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableTurn {
    robot: Robot,
    law: StableTurnLaw,
}

/// `v − sin(2πv)/2π`: 0 → 1 on `[0, 1]` with zero slope at both ends.
fn cycloid_blend<M: Math>(v: f32) -> f32 {
    v - M::sin_cos(2.0 * PI * v).0 / (2.0 * PI)
}

impl StableTurn {
    /// Validates the parameters: the robot, finite values, `|Δψ| ≤ π/2`, `T > 0`, the lift
    /// `≥ 0` and below the hips, `shift_fraction ∈ (0, 1]`, and the feet reachable at 64
    /// samples of each of the first two cycles (a quick check; [`crate::preflight`] sweeps
    /// the whole motion, with its static stability margin). The checks run on the
    /// [`DefaultMath`] backend.
    pub fn new(p: StableTurnParams) -> Result<StableTurn, Error> {
        p.robot.validate()?;
        let turn = Self::without_reach_check::<DefaultMath>(p)?;
        let cfg = turn.body_config();
        let f0 = turn.frame::<DefaultMath>(0.0)?;
        check_reach(
            &p.robot,
            &f0.pose,
            &cfg,
            &f0.feet_in_world,
            Param::StanceFeet,
        )?;
        const SAMPLES: u16 = 128;
        for i in 1..SAMPLES {
            let t = 2.0 * p.cycle_s * f32::from(i) / f32::from(SAMPLES);
            let f = turn.frame::<DefaultMath>(t)?;
            let any_swing = f.contact.contains(&Contact::Swing);
            let name = if any_swing {
                Param::YawPerCycleRad
            } else {
                Param::ShiftFraction
            };
            check_reach(&p.robot, &f.pose, &cfg, &f.feet_in_world, name)?;
        }
        Ok(turn)
    }

    /// [`StableTurn::new`]'s parameter checks without its reach checks and without validating
    /// `p.robot` ([`StableTurnLaw::without_reach_check`]).
    pub fn without_reach_check<M: Math>(p: StableTurnParams) -> Result<StableTurn, Error> {
        Ok(StableTurn {
            robot: p.robot,
            law: StableTurnLaw::without_reach_check::<M>(p.law_params())?,
        })
    }

    /// The parameters.
    pub const fn params(&self) -> StableTurnParams {
        let l = &self.law.p;
        StableTurnParams {
            robot: self.robot,
            yaw_per_cycle_rad: l.yaw_per_cycle_rad,
            cycle_s: l.cycle_s,
            lift_height_m: l.lift_height_m,
            shift_fraction: l.shift_fraction,
            order: l.order,
            stance_feet: l.stance_feet,
        }
    }

    /// The robot-free law.
    pub const fn law(&self) -> &StableTurnLaw {
        &self.law
    }

    /// [`Motion::frame`] written into `frame` ([`StableTurnLaw::frame_into`]).
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        self.law.frame_into::<M>(t_s, frame)
    }
}

impl StableTurnLaw {
    /// [`StableTurn::new`]'s parameter checks without its reach checks, with the foot radii
    /// and angles on backend `M`, for a caller that checks the reach itself by running the
    /// law's frames through its own IK (a device's start check).
    pub fn without_reach_check<M: Math>(p: StableTurnLawParams) -> Result<StableTurnLaw, Error> {
        if !(finite(p.yaw_per_cycle_rad, Param::YawPerCycleRad)?.abs() <= 0.5 * PI) {
            return Err(Error::OutOfRange {
                parameter: Param::YawPerCycleRad,
                expected: Expected::QuarterTurnPerCycle,
            });
        }
        positive(p.cycle_s, Param::CycleS)?;
        non_negative(p.lift_height_m, Param::LiftHeightM)?;
        let shift = finite(p.shift_fraction, Param::ShiftFraction)?;
        if !(shift > 0.0 && shift <= 1.0) {
            return Err(Error::OutOfRange {
                parameter: Param::ShiftFraction,
                expected: Expected::UnitIntervalOpenBelow,
            });
        }
        finite_feet(&p.stance_feet, Param::StanceFeet)?;
        for f in &p.stance_feet {
            if !(f.z + p.lift_height_m < 0.0) {
                return Err(Error::OutOfRange {
                    parameter: Param::LiftHeightM,
                    expected: Expected::BelowStanceHeight,
                });
            }
        }
        Ok(StableTurnLaw {
            p,
            rho_m: p.stance_feet.map(|f| M::sqrt(f.x * f.x + f.y * f.y)),
            alpha_rad: p.stance_feet.map(|f| M::atan2(f.y, f.x)),
        })
    }

    /// The parameters.
    pub const fn params(&self) -> &StableTurnLawParams {
        &self.p
    }

    /// The slot (index in [`STABLE_TURN_ORDER`]) of `leg`.
    pub fn slot(leg: LegId) -> usize {
        match leg {
            LegId::FL => 0,
            LegId::FR => 1,
            LegId::RR => 2,
            LegId::RL => 3,
        }
    }

    /// `(k, τ)` with `t = kT + τ`, `τ ∈ [0, T)`.
    fn split(&self, t_s: f32) -> (f32, f32) {
        let t1 = self.p.cycle_s;
        let mut k = crate::math::floor(t_s / t1);
        let mut tau = t_s - k * t1;
        if tau < 0.0 {
            k -= 1.0;
            tau += t1;
        }
        if tau >= t1 {
            k += 1.0;
            tau -= t1;
        }
        if !(tau >= 0.0 && tau < t1) {
            tau = 0.0;
        }
        (k, tau)
    }

    /// Foot `i` on its circle at angle `α_i + a`, in the ground plane (z of its stance).
    fn foot_at<M: Math>(&self, i: usize, a: f32) -> Vec3 {
        let (s, c) = M::sin_cos(self.alpha_rad[i] + a);
        Vec3::new(
            self.rho_m[i] * c,
            self.rho_m[i] * s,
            self.p.stance_feet[i].z,
        )
    }

    /// The body's target `(x, y)` in slot `j` of the cycle whose start yaw is `base`.
    fn target<M: Math>(&self, j: usize, base: f32) -> (f32, f32) {
        let (mut x, mut y) = (0.0, 0.0);
        for leg in LegId::ALL {
            let slot = Self::slot(leg);
            if slot == j {
                continue;
            }
            let a = if slot < j {
                base + self.p.yaw_per_cycle_rad
            } else {
                base
            };
            let f = self.foot_at::<M>(leg.index(), a);
            x += f.x;
            y += f.y;
        }
        let w = self.p.shift_fraction / 3.0;
        (w * x, w * y)
    }

    /// [`Motion::frame`] written into `frame` (unchanged when `t_s` is not finite).
    pub fn frame_into<M: Math>(&self, t_s: f32, frame: &mut Frame) -> Result<(), Error> {
        finite(t_s, Param::TS)?;
        let p = &self.p;
        let (k, tau) = self.split(t_s);
        let d = p.yaw_per_cycle_rad;
        // Yaw at the start of this cycle, wrapped once so that body and feet share it.
        let base = wrap_pi(d * k);
        let yaw = wrap_pi(base + d * (tau / p.cycle_s));
        let quarter = 4.0 * tau / p.cycle_s;
        let mut j = crate::math::floor(quarter) as usize;
        if j > 3 {
            j = 3;
        }
        let u = fract01(quarter - j as f32);
        let s = STABLE_TURN_SHIFT_SHARE;
        for leg in LegId::ALL {
            let i = leg.index();
            let slot = Self::slot(leg);
            let (a, lift, contact) = if slot < j {
                (base + d, 0.0, Contact::Stance)
            } else if slot > j || u < s {
                (base, 0.0, Contact::Stance)
            } else {
                let v = (u - s) / (1.0 - s);
                let lift = 0.5 * (1.0 - M::sin_cos(2.0 * PI * v).1);
                (base + d * cycloid_blend::<M>(v), lift, Contact::Swing)
            };
            let mut f = self.foot_at::<M>(i, a);
            f.z += p.lift_height_m * lift;
            frame.feet_in_world[i] = f;
            frame.contact[i] = contact;
        }
        let (x, y) = if u < s {
            let to = self.target::<M>(j, base);
            let from = if j > 0 {
                self.target::<M>(j - 1, base)
            } else if k == 0.0 {
                (0.0, 0.0)
            } else {
                self.target::<M>(3, wrap_pi(base - d))
            };
            let w = cycloid_blend::<M>(u / s);
            (from.0 + (to.0 - from.0) * w, from.1 + (to.1 - from.1) * w)
        } else {
            self.target::<M>(j, base)
        };
        let mut pose = Pose::rotation(0.0, 0.0, yaw);
        pose.x_m = x;
        pose.y_m = y;
        frame.pose = pose;
        Ok(())
    }
}

impl Motion for StableTurn {
    fn robot(&self) -> &Robot {
        &self.robot
    }

    fn body_config(&self) -> BodyConfig {
        BodyConfig::about_centre(self.law.p.order)
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        let mut frame = Frame::ZERO;
        self.frame_into::<M>(t_s, &mut frame)?;
        Ok(frame)
    }

    fn period_s(&self) -> Option<f32> {
        Some(self.law.p.cycle_s)
    }
}
