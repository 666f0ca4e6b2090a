//! One leg: forward kinematics (closed form and DH form), analytic inverse kinematics with
//! typed reachability, and the clamp policy.
//!
//! All positions are in the **hip frame** of the leg: origin at the hip (abduction-axis) mount,
//! axes parallel to the body frame (x forward, y left, z up), metres.
//!
//! ## Seed 000's IK (eq. 4.1–4.21) in this module
//!
//! [`Solver::inverse`] solves seed 000's geometry (`La` = `d_lat`, `Lb` = femur, `Lc` = tibia)
//! and seed 001's (`l0` = `d_ax`) in one chain, with the errata of `docs/papers.md` applied.
//! Every angle is one four-quadrant `atan2` of unnormalised arguments, so the paper's
//! quadrant cases, `sin⁻¹` and `cos⁻¹` collapse into the functions below (`s = ±1` the side
//! sign, `sd = s·d_lat`, `(x, y, z)` the foot in the hip frame):
//!
//! | paper step | equation (seed 000) | here |
//! |---|---|---|
//! | distance of the foot from the abduction axis, `A = √(y² + z²)` | 4.1 | [`Solver::inverse`]'s `r_sq` (`A²`), checked `A² ≥ La²` ([`Unreachable::InsideOffset`]) |
//! | α1, the direction of `A` (erratum 6a: measured from +y, one `atan2`) | 4.2–4.5 | `abduction_yx` |
//! | α2, α3 of the right triangle with legs `La`, `ℓ = √(A² − La²)` | 4.6–4.7 | `depth`: `w = −ℓ` |
//! | θ1 = α1 + (90° − α2) per quadrant (erratum 6c: wrapped on both sides) | 4.8–4.11 | `abduction_yx`: `atan2(sd·z − w·y, sd·y + w·z)` |
//! | `R = √(x² + z²)` in the tilted leg plane (its z is `w`, plus `d_ax`) | 4.12 | `Consts::leg_plane`: `R² = u² + v²`, checked against `(L1 ± L2)²` ([`Unreachable::TooFar`], [`Unreachable::TooClose`]) |
//! | R1, the direction of `R` (erratum 6b: by the sign of x, one `atan2`) | 4.13–4.14 | `hip_yx`: `angle(−v, −u)` |
//! | R2 by the law of cosines (erratum 1: `Lc²`) | 4.15 | `hip_yx`: `angle(L1 + L2·cos k, L2·sin k)` |
//! | R3 by the law of cosines | 4.16 | `Consts::knee_yx`: `cos k = (R² − L1² − L2²)/(2·L1·L2)` |
//! | θ2 = R1 − R2 | 4.17–4.20 | `hip_yx`: one `atan2` of the difference angle |
//! | θ3 = π − R3 | 4.21 | `Consts::knee_yx`: `atan2(sin k, cos k)`, `sin k` by the knee bend |
//! | `math_error_handler`, `angle_range_limiter` | Algorithm 1 | [`ReachPolicy`], [`JointLimits`] |
//!
//! The paper's angles θ1, θ2, θ3 relate to the crate's abduction, hip and knee as
//! [`crate::paper::to_seed000`] says (θ2 = 3π/2 − hip, θ3 = −knee).

use crate::math::{finite, interval_keys, DefaultMath, Math};
use crate::robot::{Joint, JointAngles, JointLimits, KneeBend, LegGeometry, LegId, Robot};
use crate::vec::Vec3;
use core::fmt;
use core::marker::PhantomData;

/// Why a foot target cannot be reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Unreachable {
    /// The hip-to-foot distance in the leg plane exceeds femur + tibia.
    TooFar,
    /// The hip-to-foot distance in the leg plane is below |femur − tibia|.
    TooClose,
    /// The foot lies within `d_lat` of the abduction axis: no leg plane passes through it.
    InsideOffset,
    /// The solution exists but this joint would leave its limits.
    JointLimit(Joint),
    /// An input coordinate or angle is NaN or infinite.
    NonFinite,
}

impl Unreachable {
    /// snake_case code used in CSV status cells: `too_far`, `too_close`, `inside_offset`,
    /// `joint_limit`, `non_finite`.
    pub const fn code(self) -> &'static str {
        match self {
            Unreachable::TooFar => "too_far",
            Unreachable::TooClose => "too_close",
            Unreachable::InsideOffset => "inside_offset",
            Unreachable::JointLimit(_) => "joint_limit",
            Unreachable::NonFinite => "non_finite",
        }
    }
}

impl fmt::Display for Unreachable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unreachable::JointLimit(j) => write!(f, "joint_limit ({j})"),
            other => f.write_str(other.code()),
        }
    }
}

/// An unreachable target of a given leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct IkError {
    /// The leg that cannot reach.
    pub leg: LegId,
    /// Why.
    pub kind: Unreachable,
}

impl fmt::Display for IkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.leg, self.kind)
    }
}

impl core::error::Error for IkError {}

/// What the IK does with an unreachable target (seed 000's `math_error_handler` and
/// `angle_range_limiter`, made explicit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ReachPolicy {
    /// Return an [`IkError`] (the default).
    #[default]
    Reject,
    /// Move the target to the nearest reachable point in its leg plane, clamp angles to the
    /// joint limits, and report it in [`LegSolution::clamped`]. Non-finite input is still
    /// rejected.
    Clamp,
}

/// A clamp applied under [`ReachPolicy::Clamp`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Clamp {
    /// The first reason the target was unreachable.
    pub kind: Unreachable,
    /// Distance between the requested foot and the foot the returned angles reach, m.
    pub distance_m: f32,
}

/// Result of a successful leg IK.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LegSolution {
    /// The joint angles.
    pub angles: JointAngles,
    /// `Some` when [`ReachPolicy::Clamp`] moved the target.
    pub clamped: Option<Clamp>,
}

/// Positions of every joint of a leg in its hip frame, for drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPoints {
    /// The abduction axis mount (always the origin of the hip frame).
    pub hip_mount: Vec3,
    /// The hip-flexion joint.
    pub hip_joint: Vec3,
    /// The knee joint.
    pub knee: Vec3,
    /// The foot.
    pub foot: Vec3,
}

/// In-plane coordinates of the foot before abduction: `p = [u, s·d_lat, w]`.
#[inline]
fn planar<M: Math>(g: &LegGeometry, hip_rad: f32, knee_rad: f32) -> (f32, f32, f32, f32) {
    let (sh, ch) = M::sin_cos(hip_rad);
    let (shk, chk) = M::sin_cos(hip_rad + knee_rad);
    let knee_u = -g.femur_m * sh;
    let knee_w = -g.d_ax_m - g.femur_m * ch;
    (
        knee_u,
        knee_w,
        knee_u - g.tibia_m * shk,
        knee_w - g.tibia_m * chk,
    )
}

#[inline]
fn abduct(s_a: f32, c_a: f32, v: Vec3) -> Vec3 {
    Vec3::new(v.x, c_a * v.y - s_a * v.z, s_a * v.y + c_a * v.z)
}

/// Forward kinematics on backend `M`, closed form.
#[inline]
pub(crate) fn forward_on<M: Math>(g: &LegGeometry, leg: LegId, q: JointAngles) -> Vec3 {
    let (_, _, u, w) = planar::<M>(g, q.hip_rad, q.knee_rad);
    let (sa, ca) = M::sin_cos(q.abduction_rad);
    abduct(sa, ca, Vec3::new(u, leg.side() * g.d_lat_m, w))
}

/// Forward kinematics, closed form:
/// `foot_in_hip = Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L_femur] + Ry(h+k)·[0,0,−L_tibia])`.
#[inline]
pub fn forward(g: &LegGeometry, leg: LegId, q: JointAngles) -> Vec3 {
    forward_on::<DefaultMath>(g, leg, q)
}

/// Every joint position of the leg in its hip frame.
pub fn joint_points(g: &LegGeometry, leg: LegId, q: JointAngles) -> LegPoints {
    joint_points_on::<DefaultMath>(g, leg, q)
}

/// Every joint position of the leg in its hip frame, on backend `M` ([`joint_points`]).
pub fn joint_points_on<M: Math>(g: &LegGeometry, leg: LegId, q: JointAngles) -> LegPoints {
    let (ku, kw, u, w) = planar::<M>(g, q.hip_rad, q.knee_rad);
    let (sa, ca) = M::sin_cos(q.abduction_rad);
    let y = leg.side() * g.d_lat_m;
    LegPoints {
        hip_mount: Vec3::ZERO,
        hip_joint: abduct(sa, ca, Vec3::new(0.0, y, -g.d_ax_m)),
        knee: abduct(sa, ca, Vec3::new(ku, y, kw)),
        foot: abduct(sa, ca, Vec3::new(u, y, w)),
    }
}

/// Standard Denavit–Hartenberg parameters of one joint: `T = Rz(θ)·Tz(d)·Tx(a)·Rx(α)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhRow {
    /// Joint angle θ, rad.
    pub theta_rad: f32,
    /// Offset along the previous z axis, m.
    pub d_m: f32,
    /// Length along the new x axis, m.
    pub a_m: f32,
    /// Twist about the new x axis, rad.
    pub alpha_rad: f32,
}

/// The DH form of the canonical chain (the correction of seed 000 eq. 3.1–3.6, see
/// `docs/papers.md`). Base frame: `x0 = −z_hip`, `y0 = y_hip`, `z0 = x_hip` (the abduction axis).
///
/// | joint | θ | d | a | α |
/// |---|---|---|---|---|
/// | abduction | a | 0 | d_ax | −π/2 |
/// | hip | h | s·d_lat | L_femur | 0 |
/// | knee | k | 0 | L_tibia | 0 |
pub fn dh_table(g: &LegGeometry, leg: LegId, q: JointAngles) -> [DhRow; 3] {
    [
        DhRow {
            theta_rad: q.abduction_rad,
            d_m: 0.0,
            a_m: g.d_ax_m,
            alpha_rad: -core::f32::consts::FRAC_PI_2,
        },
        DhRow {
            theta_rad: q.hip_rad,
            d_m: leg.side() * g.d_lat_m,
            a_m: g.femur_m,
            alpha_rad: 0.0,
        },
        DhRow {
            theta_rad: q.knee_rad,
            d_m: 0.0,
            a_m: g.tibia_m,
            alpha_rad: 0.0,
        },
    ]
}

/// Forward kinematics by chaining the homogeneous DH transforms of [`dh_table`] (slower than
/// [`forward`]; kept to show the two forms agree).
pub fn forward_dh(g: &LegGeometry, leg: LegId, q: JointAngles) -> Vec3 {
    // Base rotation: columns x0 = (0,0,-1), y0 = (0,1,0), z0 = (1,0,0) in the hip frame.
    let mut rot = crate::vec::Mat3::from_columns(
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    );
    let mut pos = Vec3::ZERO;
    for row in dh_table(g, leg, q) {
        let (st, ct) = DefaultMath::sin_cos(row.theta_rad);
        let (sa, ca) = DefaultMath::sin_cos(row.alpha_rad);
        let local = crate::vec::Mat3 {
            rows: [
                [ct, -st * ca, st * sa],
                [st, ct * ca, -ct * sa],
                [0.0, sa, ca],
            ],
        };
        let t = Vec3::new(row.a_m * ct, row.a_m * st, row.d_m);
        pos = pos + rot.mul_vec(t);
        rot = rot.mul_mat(&local);
    }
    pos
}

/// The leg IK of one robot on math backend `M`, with the per-robot constants computed once:
/// squared link lengths and reach limits, `d_lat²`. A caller that solves many targets of one
/// robot (a device's control loop, the body IK) keeps one:
///
/// ```
/// use kin_core::{leg, LegId, ReachPolicy, Robot, Vec3};
/// let solver = leg::Solver::new(&Robot::shahriar2023());
/// let q = solver.inverse(LegId::FL, Vec3::new(0.05, 0.044, -0.45), ReachPolicy::Reject)?;
/// # Ok::<(), kin_core::IkError>(())
/// ```
///
/// [`Solver::new`] takes the [`DefaultMath`] backend, [`Solver::with_math`] any other
/// (`leg::Solver::<kin_core::math::Libm>::with_math(&robot)`); both are `const fn`.
pub struct Solver<M: Math = DefaultMath> {
    pub(crate) geometry: LegGeometry,
    pub(crate) limits: JointLimits,
    /// The limits' [`crate::math::interval_keys`], computed once for [`Math::within_keys`].
    pub(crate) limit_keys: [(i32, i32); 3],
    pub(crate) knee_bend: KneeBend,
    pub(crate) c: Consts,
    math: PhantomData<M>,
}

// By hand: derives would ask the backend type (never a value here) for the same traits.
impl<M: Math> Clone for Solver<M> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<M: Math> Copy for Solver<M> {}
impl<M: Math> PartialEq for Solver<M> {
    fn eq(&self, other: &Self) -> bool {
        (self.geometry, self.limits, self.knee_bend)
            == (other.geometry, other.limits, other.knee_bend)
    }
}
impl<M: Math> fmt::Debug for Solver<M> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Solver")
            .field("geometry", &self.geometry)
            .field("limits", &self.limits)
            .field("knee_bend", &self.knee_bend)
            .field("math", &core::any::type_name::<M>())
            .finish()
    }
}

/// Constants of the leg IK derived from the link lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Consts {
    /// `d_lat²` (seed 000's `La²`).
    pub(crate) d_lat_sq: f32,
    /// `(L1 + L2)²` and `(L1 − L2)²`: the squared reach limits of the leg plane.
    pub(crate) far_sq: f32,
    pub(crate) near_sq: f32,
    /// `L1² + L2²` and `L1² − L2²`: the law of cosines.
    pub(crate) sum_sq: f32,
    pub(crate) diff_sq: f32,
    /// `d_ax = 0` (seed 000's leg): the hip-flexion joint lies on the abduction axis, and the
    /// planar distance needs no extra term.
    pub(crate) d_ax_zero: bool,
}

impl Consts {
    const fn of(g: &LegGeometry) -> Consts {
        let (l1, l2) = (g.femur_m, g.tibia_m);
        Consts {
            d_lat_sq: g.d_lat_m * g.d_lat_m,
            far_sq: (l1 + l2) * (l1 + l2),
            near_sq: (l1 - l2) * (l1 - l2),
            sum_sq: l1 * l1 + l2 * l2,
            diff_sq: l1 * l1 - l2 * l2,
            d_ax_zero: g.d_ax_m.to_bits() & 0x7fff_ffff == 0,
        }
    }
}

/// Seed 000 eq. 4.6–4.7: the right triangle of the coxa `La` (= `d_lat`) and the leg plane's
/// line `ℓ` to the foot at distance `A` from the abduction axis, `ℓ = √(A² − La²)`. Returns
/// the un-abducted depth of the foot `w = −ℓ` (the branch with the foot below the hip; 0 when
/// the foot lies on the offset circle) and `w²`, from `r_sq = A² = y² + z²` (eq. 4.1).
fn depth<M: Math>(d_lat_sq: f32, r_sq: f32) -> (f32, f32) {
    let w_sq = r_sq - d_lat_sq;
    // max(w², 0) without a float comparison on the backends that avoid them.
    let w_sq = if M::gt_zero(w_sq) { w_sq } else { 0.0 };
    (-M::sqrt(w_sq), w_sq)
}

/// Seed 000 eq. 4.2–4.11 (errata 6a, 6c): the abduction θ1 = α1 + α3, the direction of the
/// foot's `(y, z)` less that of the leg's own `(s·d_lat, w)` (`sd = s·d_lat`, `w` from
/// [`depth`]), as the arguments `(y, x)` of one `atan2` of their cross and dot products: every
/// quadrant of the abduction circle in one formula, in `(−π, π]`.
pub(crate) fn abduction_yx(sd: f32, y: f32, z: f32, w: f32) -> (f32, f32) {
    (sd * z - w * y, sd * y + w * z)
}

impl Consts {
    /// Seed 000 eq. 4.12 in the tilted leg plane (`docs/papers.md`): the foot's height
    /// `v = w + d_ax` below the hip-flexion joint and `v²`, from [`depth`]'s `(w, w²)`;
    /// `(w, w²)` itself when `d_ax = 0` (a multiplication and an addition fewer). The planar
    /// distance is then `R² = x² + v²`.
    pub(crate) fn leg_plane(&self, d_ax_m: f32, (w, w_sq): (f32, f32)) -> (f32, f32) {
        if self.d_ax_zero {
            (w, w_sq)
        } else {
            let v = w + d_ax_m;
            (v, v * v)
        }
    }

    /// Seed 000 eq. 4.16 and 4.21: the knee `k = −θ3 = R3 − π` as the arguments `(sin k, cos k)`
    /// of one `atan2`, both scaled by `2·L1·L2` (no division; `atan2` is scale-invariant), for
    /// the planar distance `dist2 = R²` within the reach up to rounding (`moved`: after a
    /// projection). `cos k = (R² − L1² − L2²)/(2·L1·L2)` (eq. 4.16's `−cos R3`), and
    /// `sin² k` in the factored form `(R² − (L1−L2)²)·((L1+L2)² − R²)`, which stays accurate
    /// near a folded or straight knee, where `(2·L1·L2)² − cos²` loses the digits that set the
    /// foot's distance; the sign of `sin k` is the knee bend.
    fn knee_yx<M: Math>(
        &self,
        g: &LegGeometry,
        bend: KneeBend,
        dist2: f32,
        moved: bool,
    ) -> (f32, f32) {
        let mut c = dist2 - self.sum_sq;
        // Only rounding can push a projected point past ±2·L1·L2 here.
        if moved {
            // `c.clamp(−2·L1·L2, 2·L1·L2)` by the magnitude's comparison of the backend and
            // the sign bit (a NaN stays NaN): no float comparison calls on CPUs without
            // floating-point hardware.
            let two_l1l2 = 2.0 * g.femur_m * g.tibia_m;
            const SIGN: u32 = 0x8000_0000;
            if M::lt_nonneg(two_l1l2, f32::from_bits(c.to_bits() & !SIGN)) {
                c = f32::from_bits(two_l1l2.to_bits() | (c.to_bits() & SIGN));
            }
        }
        let s_sq = (dist2 - self.near_sq) * (self.far_sq - dist2);
        let s_abs = M::sqrt(if M::gt_zero(s_sq) { s_sq } else { 0.0 });
        let s = match bend {
            KneeBend::Backward => -s_abs,
            KneeBend::Forward => s_abs,
        };
        (s, c)
    }
}

/// Seed 000 eq. 4.13–4.15 and 4.17–4.20 (errata 1, 6b): the hip θ2 = R1 − R2 as the arguments
/// of one `atan2`: R1 = `angle(−v, −u)`, the direction of the line R to the foot at `(u, v)`
/// in the leg plane, less R2 = `angle(L1 + L2·cos k, L2·sin k)`, the femur's angle from R by
/// the law of cosines; the second vector scaled by `2·L1` is `(R² + L1² − L2², 2·L1·L2·sin k)`
/// (`diff_sq` = `L1² − L2²`, `s` from [`Consts::knee_yx`]).
// Always inlined: out of line, its fifth float argument goes on the stack, and LLVM's AVR
// backend miscompiled that call (wrong hip angles in `cargo xtask avr-bench`).
#[inline(always)]
pub(crate) fn hip_yx(u: f32, v: f32, dist2: f32, diff_sq: f32, s: f32) -> (f32, f32) {
    let (bx, by) = (dist2 + diff_sq, s);
    let (ax, ay) = (-v, -u);
    (bx * ay - by * ax, bx * ax + by * ay)
}

impl Solver<DefaultMath> {
    /// The leg IK of `robot` (all legs are alike) on the [`DefaultMath`] backend.
    #[inline]
    pub const fn new(robot: &Robot) -> Solver {
        Solver::with_math(robot)
    }
}

impl<M: Math> Solver<M> {
    /// The leg IK of `robot` (all legs are alike) on backend `M`.
    #[inline]
    pub const fn with_math(robot: &Robot) -> Solver<M> {
        Solver {
            geometry: robot.leg,
            limits: robot.limits,
            limit_keys: {
                let (lo, hi) = (&robot.limits.min_rad, &robot.limits.max_rad);
                [
                    interval_keys(lo[0], hi[0]),
                    interval_keys(lo[1], hi[1]),
                    interval_keys(lo[2], hi[2]),
                ]
            },
            knee_bend: robot.knee_bend,
            c: Consts::of(&robot.leg),
            math: PhantomData,
        }
    }

    /// The singularity measure of `leg` at `q`: the inverse condition number of its Jacobian
    /// ([`crate::jacobian::leg_inverse_condition`], the host preflight's measure) on this
    /// solver's backend, in `[0, 1]`; below [`crate::jacobian::SINGULARITY_THRESHOLD`] counts
    /// as near-singular.
    pub fn inverse_condition(&self, leg: LegId, q: JointAngles) -> f32 {
        crate::jacobian::leg_inverse_condition_on::<M>(&self.geometry, leg, q)
    }

    /// The leg geometry.
    #[inline]
    pub fn geometry(&self) -> &LegGeometry {
        &self.geometry
    }

    /// True when all three angles lie within their limits (false for any NaN), compared by
    /// the backend with the limits' keys computed once ([`Math::within_keys`]).
    pub(crate) fn admits_all(&self, q: JointAngles) -> bool {
        let (lo, hi, k) = (&self.limits.min_rad, &self.limits.max_rad, &self.limit_keys);
        M::within_keys(q.abduction_rad, lo[0], hi[0], k[0])
            & M::within_keys(q.hip_rad, lo[1], hi[1], k[1])
            & M::within_keys(q.knee_rad, lo[2], hi[2], k[2])
    }

    /// `s·d_lat`: the leg plane's offset with the side sign of `leg`.
    pub(crate) fn side_d_lat(&self, leg: LegId) -> f32 {
        if leg.is_left() {
            self.geometry.d_lat_m
        } else {
            -self.geometry.d_lat_m
        }
    }

    /// Analytic leg IK: the foot target in the hip frame → joint angles (the steps of seed 000
    /// eq. 4.1–4.21 in the [module docs](self)).
    ///
    /// Branches: the knee bend of the robot's `knee_bend`, and the abduction whose un-abducted
    /// foot lies below the hip (`w ≤ 0`). Every quadrant of the abduction circle is covered
    /// (seed 000 §2.2, Algorithm 1): the abduction angle is one four-quadrant `atan2` in
    /// `(−π, π]`.
    ///
    /// Never returns NaN: non-finite input gives [`Unreachable::NonFinite`]; out-of-workspace
    /// targets give a typed error under [`ReachPolicy::Reject`] or a reported clamp under
    /// [`ReachPolicy::Clamp`].
    #[inline]
    pub fn inverse(
        &self,
        leg: LegId,
        foot_in_hip: Vec3,
        policy: ReachPolicy,
    ) -> Result<LegSolution, IkError> {
        let (mut angles_rad, mut clamped) = ([0.0; 3], None);
        self.inverse_into(leg, &foot_in_hip, policy, &mut angles_rad, &mut clamped)?;
        let [abduction, hip, knee] = angles_rad;
        Ok(LegSolution {
            angles: JointAngles::new(abduction, hip, knee),
            clamped,
        })
    }

    /// [`Solver::inverse`] with its solution written into `angles_rad` (`[abduction, hip,
    /// knee]`) and `clamped`, the leg's places in the body IK's flat solution, where the caller
    /// reads them (a returned solution would be copied once more on CPUs that return it
    /// through memory). On an error neither place is written.
    // Out of line: the body IK's loop over the legs then keeps a small stack frame (inlined
    // there, the AVR's `SetBodyPose` took longer: `BENCHMARKS.md`).
    #[inline(never)]
    pub(crate) fn inverse_into(
        &self,
        leg: LegId,
        foot_in_hip: &Vec3,
        policy: ReachPolicy,
        angles_rad: &mut [f32; 3],
        clamped: &mut Option<Clamp>,
    ) -> Result<(), IkError> {
        let foot_in_hip = *foot_in_hip;
        let err = |kind| IkError { leg, kind };
        if !(finite(foot_in_hip.x) && finite(foot_in_hip.y) && finite(foot_in_hip.z)) {
            return Err(err(Unreachable::NonFinite));
        }
        // Far outside the workspace a clamped answer depends only on the target's direction;
        // shrinking such a target keeps its squares clear of f32 overflow (|p| ≳ 1.8e19 m),
        // which would otherwise turn a finite target into NaN angles. (Computed only under
        // Clamp: the Reject path, the hot one, stays free of it.)
        let target = match policy {
            ReachPolicy::Clamp => {
                let m = max_abs(foot_in_hip);
                if M::lt_nonneg(FAR_M, m) {
                    foot_in_hip * (FAR_M / m)
                } else {
                    foot_in_hip
                }
            }
            ReachPolicy::Reject => foot_in_hip,
        };
        let (angles, projected) = self
            .solve(self.side_d_lat(leg), target, policy)
            .map_err(err)?;
        // Within the limits also means finite: a NaN fails every comparison.
        let within = self.admits_all(angles);
        if within && projected.is_none() {
            *angles_rad = angles.to_array();
            *clamped = None;
            return Ok(());
        }
        let s = self.beyond(leg, &foot_in_hip, policy, &angles, within, projected)?;
        *angles_rad = s.angles.to_array();
        *clamped = s.clamped;
        Ok(())
    }

    /// [`Solver::inverse_into`] for the angles of a target that was projected onto the
    /// workspace or whose angles lie beyond a joint limit (`within` false): the error under
    /// [`ReachPolicy::Reject`], the clamped angles and the reported [`Clamp`] under
    /// [`ReachPolicy::Clamp`].
    // Out of line: the common path's stack frame then stays within the AVR's short
    // displacement (`BENCHMARKS.md`, leg IK and body pose).
    #[inline(never)]
    fn beyond(
        &self,
        leg: LegId,
        foot_in_hip: &Vec3,
        policy: ReachPolicy,
        angles: &JointAngles,
        within: bool,
        projected: Option<Unreachable>,
    ) -> Result<LegSolution, IkError> {
        let err = |kind| IkError { leg, kind };
        let mut angles = *angles;
        let kind = if within {
            // Within the limits: the target was projected.
            projected.unwrap_or(Unreachable::TooFar)
        } else {
            // Some joint is outside (any for a NaN angle).
            let joint = self
                .limits
                .first_violation(angles)
                .unwrap_or(Joint::Abduction);
            if policy == ReachPolicy::Reject {
                return Err(err(Unreachable::JointLimit(joint)));
            }
            angles = self.limits.clamp(angles);
            projected.unwrap_or(Unreachable::JointLimit(joint))
        };
        // Under Clamp, moved: the distance of the foot the returned angles reach.
        let foot = forward_on::<M>(&self.geometry, leg, angles);
        if !angles.is_finite() {
            // Unreachable by construction; kept so that no NaN can ever leave this function.
            return Err(err(Unreachable::NonFinite));
        }
        Ok(LegSolution {
            angles,
            clamped: Some(Clamp {
                kind,
                distance_m: distance::<M>(foot, *foot_in_hip),
            }),
        })
    }

    /// Solves the abduction and planar problem exactly for a point known to be reachable
    /// (after optional projection), for the leg with `sd = s·d_lat`. Returns the angles and,
    /// when projecting, the first reason.
    fn solve(
        &self,
        sd: f32,
        target: Vec3,
        policy: ReachPolicy,
    ) -> Result<(JointAngles, Option<Unreachable>), Unreachable> {
        let g = &self.geometry;
        let (mut y, mut z) = (target.y, target.z);
        let mut first: Option<Unreachable> = None;

        // Eq. 4.1: the foot must lie at A ≥ La from the abduction axis (A² < La²: inside).
        let mut r_sq = y * y + z * z;
        if M::lt_nonneg(r_sq, self.c.d_lat_sq) {
            if policy == ReachPolicy::Reject {
                return Err(Unreachable::InsideOffset);
            }
            first = Some(Unreachable::InsideOffset);
            let r = M::sqrt(r_sq);
            if M::gt_zero(r) {
                let k = g.d_lat_m / r;
                y *= k;
                z *= k;
            } else {
                y = sd;
                z = 0.0;
            }
            r_sq = y * y + z * z;
        }
        let depth = depth::<M>(self.c.d_lat_sq, r_sq);
        let w = depth.0;

        // Eq. 4.12: the planar two-link problem from the hip-flexion joint, (u, v) = (x, w + d_ax),
        // R² = u² + v² within [(L1 − L2)², (L1 + L2)²].
        let mut u = target.x;
        let (mut v, v_sq) = self.c.leg_plane(g.d_ax_m, depth);
        let mut dist2 = u * u + v_sq;
        let (l1, l2) = (g.femur_m, g.tibia_m);
        let planar_fault = if M::lt_nonneg(self.c.far_sq, dist2) {
            Some((Unreachable::TooFar, l1 + l2))
        } else if M::lt_nonneg(dist2, self.c.near_sq) {
            Some((Unreachable::TooClose, libm::fabsf(l1 - l2)))
        } else {
            None
        };
        let mut moved = first.is_some();
        if let Some((kind, radius)) = planar_fault {
            if policy == ReachPolicy::Reject {
                return Err(kind);
            }
            first.get_or_insert(kind);
            moved = true;
            let dist = M::sqrt(dist2);
            if M::gt_zero(dist) {
                let k = radius / dist;
                u *= k;
                v *= k;
            } else {
                u = 0.0;
                v = -radius;
            }
            dist2 = u * u + v * v;
        }
        let (abd_y, abd_x) = abduction_yx(sd, y, z, w);
        let (knee_y, knee_x) = self.c.knee_yx::<M>(g, self.knee_bend, dist2, moved);
        let (hip_y, hip_x) = hip_yx(u, v, dist2, self.c.diff_sq, knee_y);
        let [abduction, knee, hip] = M::atan2_3([abd_y, knee_y, hip_y], [abd_x, knee_x, hip_x]);
        let angles = JointAngles::new(abduction, hip, knee);
        let projected = if moved {
            Some(first.unwrap_or(Unreachable::TooFar))
        } else {
            None
        };
        Ok((angles, projected))
    }
}

/// Under [`ReachPolicy::Clamp`], targets farther than this along any axis (m) are first
/// shrunk towards the hip to this distance.
const FAR_M: f32 = 1.0e6;

/// The largest absolute coordinate of `v` (its maximum norm): what decides whether squaring
/// `v`'s coordinates could overflow. From the bits, which order as the magnitudes do (no
/// software-float comparison on CPUs without floating-point hardware); a NaN coordinate
/// (never passed here: the targets are checked finite first) would count as the largest.
fn max_abs(v: Vec3) -> f32 {
    const ABS: u32 = 0x7fff_ffff;
    let (x, y, z) = (
        v.x.to_bits() & ABS,
        v.y.to_bits() & ABS,
        v.z.to_bits() & ABS,
    );
    f32::from_bits(x.max(y).max(z))
}

/// `|a − b|` without overflowing the squares of far targets, with the backend's square root
/// (a firmware then links one square root, its backend's).
fn distance<M: Math>(a: Vec3, b: Vec3) -> f32 {
    let d = a - b;
    let m = max_abs(d);
    if M::lt_nonneg(FAR_M, m) {
        m * M::sqrt((d * (1.0 / m)).norm_squared())
    } else {
        M::sqrt(d.norm_squared())
    }
}
