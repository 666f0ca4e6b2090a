//! Adapters between the canonical joint angles and the two papers' conventions.
//!
//! See `docs/papers.md` for the derivations and the errata these adapters correct.

use crate::math::{wrap_pi, wrap_two_pi};
use crate::robot::{JointAngles, LegId};
use core::f32::consts::{FRAC_PI_2, PI};

/// Seed 000 (Shahriar 2023) joint angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed000Angles {
    /// θ1 ∈ [0, 2π): angle of the coxa link `La` (hip mount → hip joint) measured from the
    /// hip frame's +y axis towards +z (counter-clockwise seen from the front, +x towards the
    /// viewer). Left legs: θ1 = abduction; right legs: θ1 = abduction + π.
    pub theta1_rad: f32,
    /// θ2 ∈ [0, 2π): angle of the femur in the leg plane, measured from the leg's +x axis
    /// towards its +z (seed 000's R1 − R2): θ2 = 3π/2 − hip.
    pub theta2_rad: f32,
    /// θ3: the knee's deflection from the femur's extension, seed 000's π − R3: θ3 = −knee
    /// (≥ 0 for the backward knee).
    pub theta3_rad: f32,
}

/// Canonical → seed 000.
pub fn to_seed000(leg: LegId, q: JointAngles) -> Seed000Angles {
    let offset = if leg.is_left() { 0.0 } else { PI };
    Seed000Angles {
        theta1_rad: wrap_two_pi(q.abduction_rad + offset),
        theta2_rad: wrap_two_pi(3.0 * FRAC_PI_2 - q.hip_rad),
        theta3_rad: -q.knee_rad,
    }
}

/// Seed 000 → canonical (abduction and hip wrapped to (−π, π]).
pub fn from_seed000(leg: LegId, a: Seed000Angles) -> JointAngles {
    let offset = if leg.is_left() { 0.0 } else { PI };
    JointAngles::new(
        wrap_pi(a.theta1_rad - offset),
        wrap_pi(3.0 * FRAC_PI_2 - a.theta2_rad),
        -a.theta3_rad,
    )
}

/// Seed 001 (Fernando 2025) joint angles, with φ absolute (measured from the body's −x axis,
/// like α), as in its eq. 3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed001Angles {
    /// β: rotation of the leg plane about the body x axis (Γβ = Rx(β)) = abduction.
    pub beta_rad: f32,
    /// α: femur angle below the body's −x axis: `r_AB = (−l1·cos α, 0, −l1·sin α)`;
    /// α = π/2 − hip.
    pub alpha_rad: f32,
    /// φ: tibia angle below the body's −x axis: `r_BK = (−l2·cos φ, 0, −l2·sin φ)`;
    /// φ = π/2 − hip − knee.
    pub phi_rad: f32,
}

/// Canonical → seed 001.
pub fn to_seed001(q: JointAngles) -> Seed001Angles {
    Seed001Angles {
        beta_rad: q.abduction_rad,
        alpha_rad: FRAC_PI_2 - q.hip_rad,
        phi_rad: FRAC_PI_2 - q.hip_rad - q.knee_rad,
    }
}

/// Seed 001 → canonical.
pub fn from_seed001(a: Seed001Angles) -> JointAngles {
    JointAngles::new(a.beta_rad, FRAC_PI_2 - a.alpha_rad, a.alpha_rad - a.phi_rad)
}

/// Seed 001's initial pose (eq. 5): φ = 120°, α = 60°, β = 0.
pub const SEED001_INITIAL: Seed001Angles = Seed001Angles {
    beta_rad: 0.0,
    alpha_rad: PI / 3.0,
    phi_rad: 2.0 * PI / 3.0,
};
