//! One leg: forward kinematics (closed form and DH form), analytic inverse kinematics with
//! typed reachability, and the clamp policy.
//!
//! All positions are in the **hip frame** of the leg: origin at the hip (abduction-axis) mount,
//! axes parallel to the body frame (x forward, y left, z up), metres.

use crate::math::{cmp, DefaultMath, Math};
use crate::robot::{Joint, JointAngles, JointLimits, KneeBend, LegGeometry, LegId, Robot};
use crate::vec::Vec3;
use core::fmt;

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

/// Forward kinematics, closed form:
/// `foot_in_hip = Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L_femur] + Ry(h+k)·[0,0,−L_tibia])`.
#[inline]
pub fn forward_with<M: Math>(g: &LegGeometry, leg: LegId, q: JointAngles) -> Vec3 {
    let (_, _, u, w) = planar::<M>(g, q.hip_rad, q.knee_rad);
    let (sa, ca) = M::sin_cos(q.abduction_rad);
    abduct(sa, ca, Vec3::new(u, leg.side() * g.d_lat_m, w))
}

/// [`forward_with`] on the [`DefaultMath`] backend.
#[inline]
pub fn forward(g: &LegGeometry, leg: LegId, q: JointAngles) -> Vec3 {
    forward_with::<DefaultMath>(g, leg, q)
}

/// Every joint position of the leg in its hip frame.
pub fn joint_points(g: &LegGeometry, leg: LegId, q: JointAngles) -> LegPoints {
    let (ku, kw, u, w) = planar::<DefaultMath>(g, q.hip_rad, q.knee_rad);
    let (sa, ca) = DefaultMath::sin_cos(q.abduction_rad);
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

/// The leg IK with the per-robot constants computed once: squared link lengths and reach
/// limits, `d_lat²`, the joint-limit interval. The free functions [`inverse_with`] and
/// [`inverse`] build one per call; a caller that solves many targets of one robot (a device's
/// control loop, the body IK) keeps one:
///
/// ```
/// use kin_core::{leg, LegId, ReachPolicy, Robot, Vec3};
/// let solver = leg::Solver::new(&Robot::shahriar2023());
/// let q = solver.inverse(LegId::FL, Vec3::new(0.05, 0.044, -0.45), ReachPolicy::Reject)?;
/// # Ok::<(), kin_core::IkError>(())
/// ```
///
/// Results are bit for bit those of the free functions. [`Solver::new`] is a `const fn`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solver {
    geometry: LegGeometry,
    limits: JointLimits,
    knee_bend: KneeBend,
    consts: Consts,
}

/// Constants of the leg IK derived from the link lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Consts {
    /// `d_lat²`.
    d_lat_sq: f32,
    /// `(L1 + L2)²` and `(L1 − L2)²`: the squared reach limits of the leg plane.
    far_sq: f32,
    near_sq: f32,
    /// `L1² + L2²` and `L1² − L2²`: the law of cosines.
    sum_sq: f32,
    diff_sq: f32,
    /// `d_ax = 0` (seed 000's leg): the hip-flexion joint lies on the abduction axis, and the
    /// planar distance needs no extra term.
    d_ax_zero: bool,
}

impl Consts {
    #[inline(always)]
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

/// What a solve reads: borrowed from a [`Solver`], or from a [`Robot`] with the constants
/// computed on the spot (the free functions), so that neither copies the robot.
#[derive(Clone, Copy)]
struct View<'a> {
    geometry: &'a LegGeometry,
    limits: &'a JointLimits,
    knee_bend: KneeBend,
    c: Consts,
}

/// Un-abducted depth of the foot: `w = −√(y² + z² − d_lat²)`, the branch with the foot below
/// the hip (0 when the foot lies on the offset circle), from `r² = y² + z²`; with `w²`.
#[inline(always)]
fn depth<M: Math>(d_lat_sq: f32, r_sq: f32) -> (f32, f32) {
    let w_sq = r_sq - d_lat_sq;
    let w_sq = if cmp::gt_zero(w_sq) { w_sq } else { 0.0 };
    (-M::sqrt(w_sq), w_sq)
}

impl Consts {
    /// `(v, v²)` of the in-plane foot height `v = w + d_ax` below the hip-flexion joint, from
    /// [`depth`]'s `(w, w²)`: `(w, w²)` itself when `d_ax = 0` (a multiplication and an addition
    /// fewer).
    #[inline(always)]
    fn height(&self, d_ax_m: f32, (w, w_sq): (f32, f32)) -> (f32, f32) {
        if self.d_ax_zero {
            (w, w_sq)
        } else {
            let v = w + d_ax_m;
            (v, v * v)
        }
    }
}

impl Solver {
    /// The constants of `robot`'s legs (all legs are alike).
    #[inline]
    pub const fn new(robot: &Robot) -> Solver {
        Solver {
            geometry: robot.leg,
            limits: robot.limits,
            knee_bend: robot.knee_bend,
            consts: Consts::of(&robot.leg),
        }
    }

    /// The leg geometry.
    #[inline]
    pub fn geometry(&self) -> &LegGeometry {
        &self.geometry
    }

    #[inline(always)]
    fn view(&self) -> View<'_> {
        View {
            geometry: &self.geometry,
            limits: &self.limits,
            knee_bend: self.knee_bend,
            c: self.consts,
        }
    }

    /// Analytic leg IK: the foot target in the hip frame → joint angles; see
    /// [`inverse_with`](fn@inverse_with), which this is with the constants prepared.
    #[inline]
    pub fn inverse_with<M: Math>(
        &self,
        leg: LegId,
        foot_in_hip: Vec3,
        policy: ReachPolicy,
    ) -> Result<LegSolution, IkError> {
        self.view().inverse_with::<M>(leg, foot_in_hip, policy)
    }

    /// [`Solver::inverse_with`] on the [`DefaultMath`] backend.
    #[inline]
    pub fn inverse(
        &self,
        leg: LegId,
        foot_in_hip: Vec3,
        policy: ReachPolicy,
    ) -> Result<LegSolution, IkError> {
        self.inverse_with::<DefaultMath>(leg, foot_in_hip, policy)
    }

    /// The four legs of [`LegId::ALL`] at once under [`ReachPolicy::Reject`], for the
    /// full-body IK: the arithmetic of [`Solver::inverse_with`] leg by leg (bit-identical
    /// results), written stage by stage across the legs so that the four independent solves
    /// interleave instead of running one after the other. `None` when any leg is not cleanly
    /// solvable (non-finite input, outside the workspace, beyond a joint limit): the caller
    /// then solves the legs in order to name the first failure.
    #[cfg(not(target_arch = "avr"))]
    #[inline]
    pub(crate) fn inverse_all_reject<M: Math>(
        &self,
        feet_in_hip: &[Vec3; 4],
    ) -> Option<[JointAngles; 4]> {
        self.view().inverse_all_reject::<M>(feet_in_hip)
    }
}

/// `lo <= x && x <= hi` by integer keys (no software-float comparison).
#[cfg(target_arch = "avr")]
#[inline(always)]
fn within_limit(x: f32, lo: f32, hi: f32) -> bool {
    cmp::bits::within(x, cmp::bits::interval(lo, hi))
}

impl View<'_> {
    /// True when all three angles lie within the joint limits (false for any NaN).
    #[inline(always)]
    fn admits(&self, q: JointAngles) -> bool {
        #[cfg(target_arch = "avr")]
        {
            let (lo, hi) = (&self.limits.min_rad, &self.limits.max_rad);
            within_limit(q.abduction_rad, lo[0], hi[0])
                && within_limit(q.hip_rad, lo[1], hi[1])
                && within_limit(q.knee_rad, lo[2], hi[2])
        }
        #[cfg(not(target_arch = "avr"))]
        {
            let (lo, hi) = (&self.limits.min_rad, &self.limits.max_rad);
            let a = q.to_array();
            (a[0] >= lo[0])
                & (a[0] <= hi[0])
                & (a[1] >= lo[1])
                & (a[1] <= hi[1])
                & (a[2] >= lo[2])
                & (a[2] <= hi[2])
        }
    }

    /// The arguments of the abduction's `atan2`: a = angle(y, z) − angle(s·d_lat, w), as one
    /// atan2 of cross and dot (the foot's `(y, z)` lies at least `d_lat` from the abduction
    /// axis, `w` is its depth from [`depth`], `sd = s·d_lat`).
    #[inline(always)]
    fn abduction_yx(sd: f32, y: f32, z: f32, w: f32) -> (f32, f32) {
        (sd * z - w * y, sd * y + w * z)
    }

    /// The arguments of the knee's and the hip's `atan2`, `([knee_y, hip_y], [knee_x, hip_x])`,
    /// for the foot at `(u, v)` in the leg plane (`dist2 = u² + v²`) within the reach up to
    /// rounding (`moved`: after a projection).
    #[inline(always)]
    fn planar_yx<M: Math>(&self, u: f32, v: f32, dist2: f32, moved: bool) -> ([f32; 2], [f32; 2]) {
        // The law of cosines, scaled by 2·L1·L2 (no division; atan2 is scale-invariant):
        // c = D² − L1² − L2², and s² = (D² − (L1−L2)²)·((L1+L2)² − D²), the factored form that
        // stays accurate near a folded or straight knee, where (2·L1·L2)² − c² loses the digits
        // that set the foot's distance.
        let mut c = dist2 - self.c.sum_sq;
        // Only rounding can push a projected point past ±2·L1·L2 here.
        if moved {
            let two_l1l2 = 2.0 * self.geometry.femur_m * self.geometry.tibia_m;
            c = c.clamp(-two_l1l2, two_l1l2);
        }
        let s_sq = (dist2 - self.c.near_sq) * (self.c.far_sq - dist2);
        let s_abs = M::sqrt(if cmp::gt_zero(s_sq) { s_sq } else { 0.0 });
        let s = match self.knee_bend {
            KneeBend::Backward => -s_abs,
            KneeBend::Forward => s_abs,
        };
        // hip = angle(−v, −u) − angle(L1 + L2·cos k, L2·sin k), the second vector scaled by
        // 2·L1: (D² + L1² − L2², s).
        let (bx, by) = (dist2 + self.c.diff_sq, s);
        let (ax, ay) = (-v, -u);
        ([s, bx * ay - by * ax], [c, bx * ax + by * ay])
    }

    /// Solves the abduction and planar problem exactly for a point known to be reachable
    /// (after optional projection), for the leg with `sd = s·d_lat`. Returns the angles and,
    /// when projecting, the first reason and the foot actually reached.
    #[inline(always)]
    fn solve<M: Math>(
        &self,
        sd: f32,
        target: Vec3,
        policy: ReachPolicy,
    ) -> Result<(JointAngles, Option<(Unreachable, Vec3)>), Unreachable> {
        let g = &self.geometry;
        let (mut y, mut z) = (target.y, target.z);
        let mut first: Option<Unreachable> = None;

        // Abduction: the foot's (y, z) must lie at distance ≥ d_lat from the abduction axis.
        let mut r_sq = y * y + z * z;
        if cmp::lt_nonneg(r_sq, self.c.d_lat_sq) {
            if policy == ReachPolicy::Reject {
                return Err(Unreachable::InsideOffset);
            }
            first = Some(Unreachable::InsideOffset);
            let r = M::sqrt(r_sq);
            if cmp::gt_zero(r) {
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

        // Planar two-link problem from the hip-flexion joint: (u, v) = (x, w + d_ax).
        let mut u = target.x;
        let (mut v, v_sq) = self.c.height(g.d_ax_m, depth);
        let mut dist2 = u * u + v_sq;
        let (l1, l2) = (g.femur_m, g.tibia_m);
        let planar_fault = if cmp::lt_nonneg(self.c.far_sq, dist2) {
            Some((Unreachable::TooFar, l1 + l2))
        } else if cmp::lt_nonneg(dist2, self.c.near_sq) {
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
            if cmp::gt_zero(dist) {
                let k = radius / dist;
                u *= k;
                v *= k;
            } else {
                u = 0.0;
                v = -radius;
            }
            dist2 = u * u + v * v;
        }
        let (abd_y, abd_x) = Self::abduction_yx(sd, y, z, w);
        let ([knee_y, hip_y], [knee_x, hip_x]) = self.planar_yx::<M>(u, v, dist2, moved);
        let [abduction, knee, hip] = M::atan2_3([abd_y, knee_y, hip_y], [abd_x, knee_x, hip_x]);
        let angles = JointAngles::new(abduction, hip, knee);
        let reached = if moved {
            let (sa, ca) = M::sin_cos(abduction);
            Some((
                first.unwrap_or(Unreachable::TooFar),
                abduct(sa, ca, Vec3::new(u, sd, v - g.d_ax_m)),
            ))
        } else {
            None
        };
        Ok((angles, reached))
    }

    /// The first joint of `q` outside its limits (any joint for a NaN angle).
    #[inline(always)]
    fn first_violation(&self, q: JointAngles) -> Option<Joint> {
        if self.admits(q) {
            return None;
        }
        Joint::ALL.into_iter().find(|&j| {
            #[cfg(target_arch = "avr")]
            let ok = within_limit(
                q.get(j),
                self.limits.min_rad[j as usize],
                self.limits.max_rad[j as usize],
            );
            #[cfg(not(target_arch = "avr"))]
            let ok = self.limits.admits(j, q.get(j));
            !ok
        })
    }

    /// [`Solver::inverse_with`].
    #[cfg_attr(not(target_arch = "avr"), inline(always))]
    #[cfg_attr(target_arch = "avr", inline(never))]
    fn inverse_with<M: Math>(
        &self,
        leg: LegId,
        foot_in_hip: Vec3,
        policy: ReachPolicy,
    ) -> Result<LegSolution, IkError> {
        let err = |kind| IkError { leg, kind };
        if !(cmp::finite(foot_in_hip.x) && cmp::finite(foot_in_hip.y) && cmp::finite(foot_in_hip.z))
        {
            return Err(err(Unreachable::NonFinite));
        }
        // Far outside the workspace a clamped answer depends only on the target's direction;
        // shrinking such a target keeps its squares clear of f32 overflow (|p| ≳ 1.8e19 m),
        // which would otherwise turn a finite target into NaN angles. (Computed only under
        // Clamp: the Reject path, the hot one, stays free of it.)
        let target = match policy {
            ReachPolicy::Clamp => {
                let m = libm::fmaxf(
                    libm::fabsf(foot_in_hip.x),
                    libm::fmaxf(libm::fabsf(foot_in_hip.y), libm::fabsf(foot_in_hip.z)),
                );
                if m > FAR_M {
                    foot_in_hip * (FAR_M / m)
                } else {
                    foot_in_hip
                }
            }
            ReachPolicy::Reject => foot_in_hip,
        };
        let side_d_lat = if leg.is_left() {
            self.geometry.d_lat_m
        } else {
            -self.geometry.d_lat_m
        };
        let (mut angles, reached) = self.solve::<M>(side_d_lat, target, policy).map_err(err)?;
        let Some(joint) = self.first_violation(angles) else {
            // Within the limits also means finite: a NaN fails every comparison.
            return Ok(LegSolution {
                angles,
                clamped: reached.map(|(kind, p)| Clamp {
                    kind,
                    distance_m: distance::<M>(p, foot_in_hip),
                }),
            });
        };
        if policy == ReachPolicy::Reject {
            return Err(err(Unreachable::JointLimit(joint)));
        }
        let mut a = angles.to_array();
        for (i, v) in a.iter_mut().enumerate() {
            *v = v.clamp(self.limits.min_rad[i], self.limits.max_rad[i]);
        }
        angles = JointAngles::from_array(a);
        let foot = forward_with::<M>(self.geometry, leg, angles);
        let clamped = Some(Clamp {
            kind: reached.map_or(Unreachable::JointLimit(joint), |(kind, _)| kind),
            distance_m: distance::<M>(foot, foot_in_hip),
        });
        if !angles.is_finite() {
            // Unreachable by construction; kept so that no NaN can ever leave this function.
            return Err(err(Unreachable::NonFinite));
        }
        Ok(LegSolution { angles, clamped })
    }

    /// [`Solver::inverse_all_reject`].
    #[cfg(not(target_arch = "avr"))]
    #[inline]
    fn inverse_all_reject<M: Math>(&self, feet_in_hip: &[Vec3; 4]) -> Option<[JointAngles; 4]> {
        let g = &self.geometry;
        let mut ok = true;
        // One plain array per quantity (not arrays of structs), which the compiler keeps in
        // registers.
        let mut w = [0.0f32; 4];
        let mut w_sq = [0.0f32; 4];
        let mut v = [0.0f32; 4];
        let mut dist2 = [0.0f32; 4];
        let mut abduction = [0.0f32; 4];
        for (i, p) in feet_in_hip.iter().enumerate() {
            // Non-short-circuit `&` and float arithmetic: no branch per lane. `q·0` is ±0 for a
            // finite q and NaN otherwise.
            let finite = p.x * 0.0 + p.y * 0.0 + p.z * 0.0 == 0.0;
            let r_sq = p.y * p.y + p.z * p.z;
            ok &= finite & !(r_sq < self.c.d_lat_sq);
            (w[i], w_sq[i]) = depth::<M>(self.c.d_lat_sq, r_sq);
        }
        for (i, p) in feet_in_hip.iter().enumerate() {
            let sd = if LegId::ALL[i].is_left() {
                g.d_lat_m
            } else {
                -g.d_lat_m
            };
            let (abd_y, abd_x) = Self::abduction_yx(sd, p.y, p.z, w[i]);
            abduction[i] = M::atan2(abd_y, abd_x);
            let v_sq;
            (v[i], v_sq) = self.c.height(g.d_ax_m, (w[i], w_sq[i]));
            dist2[i] = p.x * p.x + v_sq;
            ok &= !(dist2[i] > self.c.far_sq) & !(dist2[i] < self.c.near_sq);
        }
        // Stage by stage across the legs (square roots, then angles), so that the independent
        // dependency chains sit next to each other in the instruction stream; the abductions
        // above start as soon as their depths are known. (The same `atan2` calls as
        // `Math::atan2_3` makes: bit for bit the leg-by-leg results.)
        let mut planar = [([0.0f32; 2], [0.0f32; 2]); 4];
        for (i, p) in feet_in_hip.iter().enumerate() {
            planar[i] = self.planar_yx::<M>(p.x, v[i], dist2[i], false);
        }
        let mut out = [JointAngles::default(); 4];
        for (i, ([knee_y, hip_y], [knee_x, hip_x])) in planar.iter().enumerate() {
            let knee = M::atan2(*knee_y, *knee_x);
            let hip = M::atan2(*hip_y, *hip_x);
            out[i] = JointAngles::new(abduction[i], hip, knee);
        }
        // Within the limits (a NaN fails every comparison, so this also rejects non-finite
        // angles).
        for a in &out {
            ok &= self.admits(*a);
        }
        if ok {
            Some(out)
        } else {
            None
        }
    }
}

/// Under [`ReachPolicy::Clamp`], targets farther than this along any axis (m) are first
/// shrunk towards the hip to this distance.
const FAR_M: f32 = 1.0e6;

/// `|a − b|` without overflowing the squares of far targets, with the backend's square root
/// (on the ATmega2560 that keeps a second one, libm's, out of the firmware).
#[inline]
fn distance<M: Math>(a: Vec3, b: Vec3) -> f32 {
    let d = a - b;
    let m = libm::fmaxf(
        libm::fabsf(d.x),
        libm::fmaxf(libm::fabsf(d.y), libm::fabsf(d.z)),
    );
    if m > FAR_M {
        m * M::sqrt((d * (1.0 / m)).norm_squared())
    } else {
        M::sqrt(d.norm_squared())
    }
}

/// Analytic leg IK: the foot target in the hip frame → joint angles.
///
/// Branches: the knee bend of `robot.knee_bend`, and the abduction whose un-abducted foot lies
/// below the hip (`w ≤ 0`). Every quadrant of the abduction circle is covered (seed 000 §2.2,
/// Algorithm 1): the abduction angle is one four-quadrant `atan2` in `(−π, π]`.
///
/// Never returns NaN: non-finite input gives [`Unreachable::NonFinite`]; out-of-workspace
/// targets give a typed error under [`ReachPolicy::Reject`] or a reported clamp under
/// [`ReachPolicy::Clamp`]. Computes the robot's constants each call; [`Solver`] keeps them.
#[inline]
pub fn inverse_with<M: Math>(
    robot: &Robot,
    leg: LegId,
    foot_in_hip: Vec3,
    policy: ReachPolicy,
) -> Result<LegSolution, IkError> {
    let view = View {
        geometry: &robot.leg,
        limits: &robot.limits,
        knee_bend: robot.knee_bend,
        c: Consts::of(&robot.leg),
    };
    view.inverse_with::<M>(leg, foot_in_hip, policy)
}

/// [`inverse_with`] on the [`DefaultMath`] backend.
#[inline]
pub fn inverse(
    robot: &Robot,
    leg: LegId,
    foot_in_hip: Vec3,
    policy: ReachPolicy,
) -> Result<LegSolution, IkError> {
    inverse_with::<DefaultMath>(robot, leg, foot_in_hip, policy)
}
