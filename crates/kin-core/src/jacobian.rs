//! Leg velocity kinematics (seed 001 eq. 4): the analytic 3×3 Jacobian `∂foot_in_hip/∂q`,
//! joint rates from a foot velocity, and a singularity measure.
//!
//! Columns, for `foot = Rx(a)·p(h, k)` with `p = [u, s·d_lat, w]`:
//! - `∂/∂a = e_x × foot`
//! - `∂/∂h = Rx(a)·[−L1·cos h − L2·cos(h+k), 0, L1·sin h + L2·sin(h+k)]`
//! - `∂/∂k = Rx(a)·[−L2·cos(h+k), 0, L2·sin(h+k)]`
//!
//! `det J = −w·L1·L2·sin k` up to sign: singular when the knee is straight or folded
//! (`sin k = 0`) or when the un-abducted foot is level with the abduction axis (`w = 0`).

use crate::math::{DefaultMath, Math};
use crate::robot::{JointAngles, LegGeometry, LegId};
use crate::vec::{Mat3, Vec3};
use core::fmt;

/// Below this inverse condition number a configuration counts as near-singular.
///
/// At 0.05 a foot-velocity error is amplified up to 20× more along the worst joint direction
/// than along the best one. seed 001's initial pose (hip 30°, knee −60°) has ≈ 0.215.
pub const SINGULARITY_THRESHOLD: f32 = 0.05;

/// The Jacobian cannot be inverted at this configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Singular {
    /// The inverse condition number found (below [`SINGULARITY_THRESHOLD`] or zero).
    pub inverse_condition: f32,
}

impl fmt::Display for Singular {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "singular configuration (inverse condition number {:.3e} < {})",
            self.inverse_condition, SINGULARITY_THRESHOLD
        )
    }
}

impl core::error::Error for Singular {}

/// Analytic leg Jacobian `∂foot_in_hip/∂(abduction, hip, knee)`, m/rad.
pub fn leg_jacobian(g: &LegGeometry, leg: LegId, q: JointAngles) -> Mat3 {
    leg_jacobian_on::<DefaultMath>(g, leg, q)
}

/// [`leg_jacobian`] on backend `M` (reached through [`crate::leg::Solver::inverse_condition`]).
#[inline(never)]
pub(crate) fn leg_jacobian_on<M: Math>(g: &LegGeometry, leg: LegId, q: JointAngles) -> Mat3 {
    let (sa, ca) = M::sin_cos(q.abduction_rad);
    let (sh, ch) = M::sin_cos(q.hip_rad);
    let (shk, chk) = M::sin_cos(q.hip_rad + q.knee_rad);
    let (l1, l2) = (g.femur_m, g.tibia_m);
    let u = -l1 * sh - l2 * shk;
    let w = -g.d_ax_m - l1 * ch - l2 * chk;
    let y0 = leg.side() * g.d_lat_m;
    let rx = |v: Vec3| Vec3::new(v.x, ca * v.y - sa * v.z, sa * v.y + ca * v.z);
    let foot = rx(Vec3::new(u, y0, w));
    let d_a = Vec3::new(0.0, -foot.z, foot.y);
    let d_h = rx(Vec3::new(-l1 * ch - l2 * chk, 0.0, l1 * sh + l2 * shk));
    let d_k = rx(Vec3::new(-l2 * chk, 0.0, l2 * shk));
    Mat3::from_columns(d_a, d_h, d_k)
}

/// Manipulability `√det(J·Jᵀ) = |det J|`, m³/rad³.
pub fn manipulability(j: &Mat3) -> f32 {
    libm::fabsf(j.determinant())
}

/// Inverse condition number `σ_min / σ_max` of `j` ∈ [0, 1] (1 = isotropic, 0 = singular),
/// from the closed-form eigenvalues of the symmetric `JᵀJ`, on the [`DefaultMath`] backend.
pub fn inverse_condition(j: &Mat3) -> f32 {
    inverse_condition_on::<DefaultMath>(j)
}

/// [`inverse_condition`] on backend `M` (reached through
/// [`crate::leg::Solver::inverse_condition`]).
#[inline(never)]
pub(crate) fn inverse_condition_on<M: Math>(j: &Mat3) -> f32 {
    let jt = j.transpose();
    let a = jt.mul_mat(j); // symmetric positive semi-definite
    let e = symmetric_eigenvalues::<M>(&a.rows);
    let (lo, hi) = (e[0].max(0.0), e[2].max(0.0));
    if hi <= 0.0 {
        return 0.0;
    }
    M::sqrt(lo / hi)
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (trigonometric closed form).
#[inline(never)]
fn symmetric_eigenvalues<M: Math>(a: &[[f32; 3]; 3]) -> [f32; 3] {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let tr = a[0][0] + a[1][1] + a[2][2];
    let q = tr / 3.0;
    if p1 <= f32::EPSILON * (q * q) {
        let (x, y, z) = (a[0][0], a[1][1], a[2][2]);
        let lo = x.min(y).min(z);
        let hi = x.max(y).max(z);
        return [lo, x + y + z - lo - hi, hi];
    }
    let p2 = (a[0][0] - q) * (a[0][0] - q)
        + (a[1][1] - q) * (a[1][1] - q)
        + (a[2][2] - q) * (a[2][2] - q)
        + 2.0 * p1;
    let p = M::sqrt(p2 / 6.0);
    let inv_p = 1.0 / p;
    let b = [
        [(a[0][0] - q) * inv_p, a[0][1] * inv_p, a[0][2] * inv_p],
        [a[1][0] * inv_p, (a[1][1] - q) * inv_p, a[1][2] * inv_p],
        [a[2][0] * inv_p, a[2][1] * inv_p, (a[2][2] - q) * inv_p],
    ];
    let det_b = Mat3 { rows: b }.determinant();
    let r = (det_b / 2.0).clamp(-1.0, 1.0);
    // acos r = atan2(√(1 − r²), r) for r in [−1, 1]: the backend's own functions.
    let phi = M::atan2(M::sqrt((1.0 - r) * (1.0 + r)), r) / 3.0;
    let e_hi = q + 2.0 * p * M::sin_cos(phi).1;
    let e_lo = q + 2.0 * p * M::sin_cos(phi + 2.0 * core::f32::consts::PI / 3.0).1;
    let e_mid = tr - e_hi - e_lo;
    [e_lo, e_mid, e_hi]
}

/// Joint rates `q̇ = J⁻¹·v` for a foot velocity `v` in the hip frame (m/s → rad/s).
///
/// Refuses (typed [`Singular`]) when the inverse condition number is below
/// [`SINGULARITY_THRESHOLD`].
pub fn joint_rates(
    g: &LegGeometry,
    leg: LegId,
    q: JointAngles,
    foot_velocity_in_hip: Vec3,
) -> Result<[f32; 3], Singular> {
    let j = leg_jacobian(g, leg, q);
    let ic = inverse_condition(&j);
    if !(ic >= SINGULARITY_THRESHOLD) {
        return Err(Singular {
            inverse_condition: if ic.is_finite() { ic } else { 0.0 },
        });
    }
    // Cramer's rule.
    let (c0, c1, c2) = (j.column(0), j.column(1), j.column(2));
    let det = c0.dot(c1.cross(c2));
    let v = foot_velocity_in_hip;
    Ok([
        v.dot(c1.cross(c2)) / det,
        c0.dot(v.cross(c2)) / det,
        c0.dot(c1.cross(v)) / det,
    ])
}

/// Velocity of a foot in its hip frame when the foot moves at `foot_velocity_in_world` and the
/// body translates at `body_velocity` (world) and turns at `body_angular_velocity` (world), for
/// body rotation `r` and the foot's world position relative to the (translated) pivot
/// `foot_rel_pivot_world = foot_in_world − t − pivot`:
/// `v_hip = Rᵀ·(v_foot − v_body − ω × foot_rel_pivot_world)` (seed 001 eq. 4 solved for the leg).
pub fn foot_velocity_in_hip(
    r: &Mat3,
    foot_rel_pivot_world: Vec3,
    foot_velocity_in_world: Vec3,
    body_velocity: Vec3,
    body_angular_velocity: Vec3,
) -> Vec3 {
    r.transpose_mul_vec(
        foot_velocity_in_world - body_velocity - body_angular_velocity.cross(foot_rel_pivot_world),
    )
}
