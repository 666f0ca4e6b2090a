//! One leg: forward kinematics (closed form and DH form), analytic inverse kinematics with
//! typed reachability, and the clamp policy.
//!
//! All positions are in the **hip frame** of the leg: origin at the hip (abduction-axis) mount,
//! axes parallel to the body frame (x forward, y left, z up), metres.

use crate::math::{DefaultMath, Math};
use crate::robot::{Joint, JointAngles, KneeBend, LegGeometry, LegId, Robot};
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

/// Intermediate values of the analytic IK, before limits.
#[derive(Clone, Copy)]
struct Raw {
    angles: JointAngles,
}

/// Un-abducted depth of the foot: `w = −√(y² + z² − d_lat²)`, the branch with the foot below
/// the hip (0 when the foot lies on the offset circle).
#[inline(always)]
fn depth<M: Math>(d2: f32, y: f32, z: f32) -> f32 {
    let w_sq = y * y + z * z - d2;
    -M::sqrt(if w_sq > 0.0 { w_sq } else { 0.0 })
}

/// a = angle(y, z) − angle(s·d_lat, w), as one atan2 of cross and dot.
#[inline(always)]
fn abduction_angle<M: Math>(sd: f32, y: f32, z: f32, w: f32) -> f32 {
    M::atan2(sd * z - w * y, sd * y + w * z)
}

/// `((L1+L2)², (L1−L2)²)`: the squared reach limits of the two-link leg plane.
#[inline(always)]
fn reach2(g: &LegGeometry) -> (f32, f32) {
    let (l1, l2) = (g.femur_m, g.tibia_m);
    ((l1 + l2) * (l1 + l2), (l1 - l2) * (l1 - l2))
}

/// The law of cosines for the foot at `(u, v)` in the leg plane, relative to the hip-flexion
/// joint, with `(L1−L2)² ≤ u² + v² ≤ (L1+L2)²` up to rounding (`moved`: after a projection).
/// Returns `(D², c, s)` with `c = 2·L1·L2·cos k` and `s = 2·L1·L2·sin k`, for
/// [`planar_angles`].
#[inline(always)]
fn planar_sides<M: Math>(
    g: &LegGeometry,
    bend: KneeBend,
    u: f32,
    v: f32,
    moved: bool,
) -> (f32, f32, f32) {
    let (l1, l2) = (g.femur_m, g.tibia_m);
    let (far2, near2) = reach2(g);
    let dist2 = u * u + v * v;
    // Scaled by 2·L1·L2 (no division; atan2 is scale-invariant): c = D² − L1² − L2², and
    // s² = (D² − (L1−L2)²)·((L1+L2)² − D²), the factored form that stays accurate near a
    // folded or straight knee, where (2·L1·L2)² − c² loses the digits that set the foot's
    // distance.
    let two_l1l2 = 2.0 * l1 * l2;
    let mut c = dist2 - (l1 * l1 + l2 * l2);
    // Only rounding can push a projected point past ±2·L1·L2 here.
    if moved {
        c = c.clamp(-two_l1l2, two_l1l2);
    }
    let s_sq = (dist2 - near2) * (far2 - dist2);
    let s_abs = M::sqrt(if s_sq > 0.0 { s_sq } else { 0.0 });
    let s = match bend {
        KneeBend::Backward => -s_abs,
        KneeBend::Forward => s_abs,
    };
    (dist2, c, s)
}

/// `(hip, knee)` from [`planar_sides`].
#[inline(always)]
fn planar_angles<M: Math>(g: &LegGeometry, u: f32, v: f32, sides: (f32, f32, f32)) -> (f32, f32) {
    let (l1, l2) = (g.femur_m, g.tibia_m);
    let (dist2, c, s) = sides;
    let knee = M::atan2(s, c);
    // hip = angle(−v, −u) − angle(L1 + L2·cos k, L2·sin k), the second vector scaled by 2·L1:
    // (D² + L1² − L2², s).
    let (bx, by) = (dist2 + (l1 * l1 - l2 * l2), s);
    let (ax, ay) = (-v, -u);
    let hip = M::atan2(bx * ay - by * ax, bx * ax + by * ay);
    (hip, knee)
}

/// Solves the abduction and planar problem exactly for a point known to be reachable (after
/// optional projection). Returns the angles and the foot actually reached when projecting.
#[inline]
fn solve<M: Math>(
    g: &LegGeometry,
    side: f32,
    bend: KneeBend,
    target: Vec3,
    policy: ReachPolicy,
) -> Result<(Raw, Option<(Unreachable, Vec3)>), Unreachable> {
    let (l1, l2) = (g.femur_m, g.tibia_m);
    let sd = side * g.d_lat_m;
    let (mut y, mut z) = (target.y, target.z);
    let mut first: Option<Unreachable> = None;

    // Abduction: the foot's (y, z) must lie at distance ≥ d_lat from the abduction axis.
    let r2 = y * y + z * z;
    let d2 = g.d_lat_m * g.d_lat_m;
    if r2 < d2 {
        if policy == ReachPolicy::Reject {
            return Err(Unreachable::InsideOffset);
        }
        first = Some(Unreachable::InsideOffset);
        let r = M::sqrt(r2);
        if r > 0.0 {
            let k = g.d_lat_m / r;
            y *= k;
            z *= k;
        } else {
            y = sd;
            z = 0.0;
        }
    }
    let w = depth::<M>(d2, y, z);
    let abduction = abduction_angle::<M>(sd, y, z, w);

    // Planar two-link problem from the hip-flexion joint: (u, v) = (x, w + d_ax).
    let mut u = target.x;
    let mut v = w + g.d_ax_m;
    let dist2 = u * u + v * v;
    let (far2, near2) = reach2(g);
    let planar_fault = if dist2 > far2 {
        Some((Unreachable::TooFar, l1 + l2))
    } else if dist2 < near2 {
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
        if dist > 0.0 {
            let k = radius / dist;
            u *= k;
            v *= k;
        } else {
            u = 0.0;
            v = -radius;
        }
    }
    let sides = planar_sides::<M>(g, bend, u, v, moved);
    let (hip, knee) = planar_angles::<M>(g, u, v, sides);

    let raw = Raw {
        angles: JointAngles::new(abduction, hip, knee),
    };
    let reached = if moved {
        let (sa, ca) = M::sin_cos(abduction);
        Some((
            first.unwrap_or(Unreachable::TooFar),
            abduct(sa, ca, Vec3::new(u, sd, v - g.d_ax_m)),
        ))
    } else {
        None
    };
    Ok((raw, reached))
}

/// Under [`ReachPolicy::Clamp`], targets farther than this along any axis (m) are first
/// shrunk towards the hip to this distance.
const FAR_M: f32 = 1.0e6;

/// `|a − b|` without overflowing the squares of far targets.
#[inline]
fn distance(a: Vec3, b: Vec3) -> f32 {
    let d = a - b;
    let m = libm::fmaxf(
        libm::fabsf(d.x),
        libm::fmaxf(libm::fabsf(d.y), libm::fabsf(d.z)),
    );
    if m > FAR_M {
        m * (d * (1.0 / m)).norm()
    } else {
        d.norm()
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
/// [`ReachPolicy::Clamp`].
#[inline]
pub fn inverse_with<M: Math>(
    robot: &Robot,
    leg: LegId,
    foot_in_hip: Vec3,
    policy: ReachPolicy,
) -> Result<LegSolution, IkError> {
    let err = |kind| IkError { leg, kind };
    if !foot_in_hip.is_finite() {
        return Err(err(Unreachable::NonFinite));
    }
    let g = &robot.leg;
    // Far outside the workspace a clamped answer depends only on the target's direction;
    // shrinking such a target keeps its squares clear of f32 overflow (|p| ≳ 1.8e19 m), which
    // would otherwise turn a finite target into NaN angles.
    // (Computed only under Clamp: the Reject path, the hot one, stays free of it.)
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
    let (raw, reached) = solve::<M>(g, leg.side(), robot.knee_bend, target, policy).map_err(err)?;
    let mut angles = raw.angles;
    let mut clamped = reached.map(|(kind, p)| Clamp {
        kind,
        distance_m: distance(p, foot_in_hip),
    });
    if let Some(joint) = robot.limits.first_violation(angles) {
        if policy == ReachPolicy::Reject {
            return Err(err(Unreachable::JointLimit(joint)));
        }
        let mut a = angles.to_array();
        for (i, v) in a.iter_mut().enumerate() {
            *v = v.clamp(robot.limits.min_rad[i], robot.limits.max_rad[i]);
        }
        angles = JointAngles::from_array(a);
        let reached = forward_with::<M>(g, leg, angles);
        clamped = Some(Clamp {
            kind: clamped.map_or(Unreachable::JointLimit(joint), |c| c.kind),
            distance_m: distance(reached, foot_in_hip),
        });
    }
    if !angles.is_finite() {
        // Unreachable by construction; kept so that no NaN can ever leave this function.
        return Err(err(Unreachable::NonFinite));
    }
    Ok(LegSolution { angles, clamped })
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

/// The four legs of [`LegId::ALL`] at once under [`ReachPolicy::Reject`], for the full-body
/// IK: the arithmetic of [`inverse_with`] leg by leg (bit-identical results), written lane by
/// lane so that the four independent solves interleave instead of running one after the
/// other. `None` when any leg is not cleanly solvable (non-finite input, outside the
/// workspace, beyond a joint limit): the caller then solves the legs in order to name the
/// first failure.
#[cfg(not(target_arch = "avr"))]
#[inline]
pub(crate) fn inverse_all_reject<M: Math>(
    robot: &Robot,
    feet_in_hip: &[Vec3; 4],
) -> Option<[JointAngles; 4]> {
    let g = &robot.leg;
    let d2 = g.d_lat_m * g.d_lat_m;
    let (far2, near2) = reach2(g);
    let mut ok = true;
    // One plain array per quantity (not arrays of structs), which the compiler keeps in
    // registers.
    let mut w = [0.0f32; 4];
    let mut abduction = [0.0f32; 4];
    let mut dist2 = [0.0f32; 4];
    let mut c = [0.0f32; 4];
    let mut s = [0.0f32; 4];
    for (i, p) in feet_in_hip.iter().enumerate() {
        // Non-short-circuit `&` and float arithmetic: no branch per lane. `q·0` is ±0 for a
        // finite q and NaN otherwise.
        let finite = p.x * 0.0 + p.y * 0.0 + p.z * 0.0 == 0.0;
        ok &= finite & !(p.y * p.y + p.z * p.z < d2);
        w[i] = depth::<M>(d2, p.y, p.z);
    }
    for (i, p) in feet_in_hip.iter().enumerate() {
        let sd = LegId::ALL[i].side() * g.d_lat_m;
        abduction[i] = abduction_angle::<M>(sd, p.y, p.z, w[i]);
        let v = w[i] + g.d_ax_m;
        let d = p.x * p.x + v * v;
        ok &= !(d > far2) & !(d < near2);
    }
    // Stage by stage across the legs (square roots, then angles), so that the independent
    // dependency chains sit next to each other in the instruction stream.
    for (i, p) in feet_in_hip.iter().enumerate() {
        (dist2[i], c[i], s[i]) = planar_sides::<M>(g, robot.knee_bend, p.x, w[i] + g.d_ax_m, false);
    }
    let mut out = [JointAngles::default(); 4];
    for (i, p) in feet_in_hip.iter().enumerate() {
        let (hip, knee) = planar_angles::<M>(g, p.x, w[i] + g.d_ax_m, (dist2[i], c[i], s[i]));
        out[i] = JointAngles::new(abduction[i], hip, knee);
    }
    // Within the limits (a NaN fails every comparison, so this also rejects non-finite angles).
    let (lo, hi) = (&robot.limits.min_rad, &robot.limits.max_rad);
    for a in &out {
        let a = a.to_array();
        ok &= (a[0] >= lo[0]) & (a[0] <= hi[0]) & (a[1] >= lo[1]) & (a[1] <= hi[1]);
        ok &= (a[2] >= lo[2]) & (a[2] <= hi[2]);
    }
    if ok {
        Some(out)
    } else {
        None
    }
}
