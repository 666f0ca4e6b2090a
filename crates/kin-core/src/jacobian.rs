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
    type M = DefaultMath;
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
    let c = |k: usize| j.column(k);
    let (c0, c1, c2) = (c(0), c(1), c(2));
    gram_inverse_condition::<DefaultMath>(&Gram {
        diagonal: [c0.dot(c0), c1.dot(c1), c2.dot(c2)],
        off: [c0.dot(c1), c0.dot(c2), c1.dot(c2)],
    })
}

/// The singularity measure of a leg: [`inverse_condition`] of its [`leg_jacobian`], on the
/// [`DefaultMath`] backend. The host's preflight and the device's start check
/// ([`crate::leg::Solver::inverse_condition`]) both use this one computation.
///
/// `JᵀJ` does not depend on the abduction (`J = Rx(a)·J₀`, `Rx(a)` orthogonal), so it is
/// formed from the un-abducted columns `J₀ = [e_x × p, ∂p/∂h, ∂p/∂k]` of the foot
/// `p = [u, s·d_lat, w]`: `e_x × p = (0, −w, s·d_lat)` and the planar columns
/// `(h_x, 0, h_z)`, `(k_x, 0, k_z)`, six entries from a few products, no abduction sine.
pub fn leg_inverse_condition(g: &LegGeometry, leg: LegId, q: JointAngles) -> f32 {
    leg_inverse_condition_on::<DefaultMath>(g, leg, q)
}

/// [`leg_inverse_condition`] on backend `M` (reached through
/// [`crate::leg::Solver::inverse_condition`]).
pub(crate) fn leg_inverse_condition_on<M: Math>(
    g: &LegGeometry,
    leg: LegId,
    q: JointAngles,
) -> f32 {
    let (sh, ch) = M::sin_cos(q.hip_rad);
    let (shk, chk) = M::sin_cos(q.hip_rad + q.knee_rad);
    let (l1, l2) = (g.femur_m, g.tibia_m);
    // ∂p/∂k = (k_x, 0, k_z), ∂p/∂h = (h_x, 0, h_z) = ∂p/∂k + L1·(−cos h, 0, sin h).
    let (kx, kz) = (-l2 * chk, l2 * shk);
    let (hx, hz) = (kx - l1 * ch, kz + l1 * sh);
    // The foot's un-abducted depth w = −d_ax − L1·cos h − L2·cos(h+k) = h_x − d_ax.
    let w = hx - g.d_ax_m;
    let y0 = leg.side() * g.d_lat_m;
    gram_inverse_condition::<M>(&Gram {
        diagonal: [w * w + y0 * y0, hx * hx + hz * hz, kx * kx + kz * kz],
        off: [y0 * hz, y0 * kz, hx * kx + hz * kz],
    })
}

/// A symmetric 3×3 matrix by its distinct entries.
struct Gram {
    /// `[a₀₀, a₁₁, a₂₂]`.
    diagonal: [f32; 3],
    /// `[a₀₁, a₀₂, a₁₂]`.
    off: [f32; 3],
}

/// `√(λ_min / λ_max)` of the symmetric positive semi-definite `a` (0 when `λ_max ≤ 0`): the
/// inverse condition number of a matrix whose Gram matrix `a` is. Eigenvalues in the
/// trigonometric closed form: with `q = tr(a)/3`, `p = √(tr((a − qI)²)/6)` and
/// `r = det(a − qI)/(2p³)`, `φ = acos(r)/3`, the largest is `q + 2p·cos φ` and the smallest
/// `q + 2p·cos(φ + 2π/3) = q − p·(cos φ + √3·sin φ)` (one sine and cosine); `p = 0` is
/// `a = q·I`.
fn gram_inverse_condition<M: Math>(a: &Gram) -> f32 {
    let [a00, a11, a22] = a.diagonal;
    let [a01, a02, a12] = a.off;
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let tr = a00 + a11 + a22;
    let q = tr / 3.0;
    let (d0, d1, d2) = (a00 - q, a11 - q, a22 - q);
    let p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
    if !M::gt_zero(p2) {
        // a = q·I: isotropic when q > 0 (else zero, or not finite).
        return if M::gt_zero(q) { 1.0 } else { 0.0 };
    }
    let p = M::sqrt(p2 / 6.0);
    let det =
        d0 * (d1 * d2 - a12 * a12) - a01 * (a01 * d2 - a12 * a02) + a02 * (a01 * a12 - d1 * a02);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    // acos r = atan2(√(1 − r²), r) for r in [−1, 1]: the backend's own functions.
    let phi = M::atan2(M::sqrt((1.0 - r) * (1.0 + r)), r) / 3.0;
    let (sin, cos) = M::sin_cos(phi);
    const SQRT_3: f32 = 1.732_050_8;
    let (lo, hi) = (q - p * (cos + SQRT_3 * sin), q + 2.0 * p * cos);
    // `max(0.0)` by comparison (NaN and −0 give +0 as with `f32::max`): `max` links a libm
    // routine on the AVR.
    let non_negative = |x: f32| if x > 0.0 { x } else { 0.0 };
    let (lo, hi) = (non_negative(lo), non_negative(hi));
    if hi <= 0.0 {
        return 0.0;
    }
    M::sqrt(lo / hi)
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
