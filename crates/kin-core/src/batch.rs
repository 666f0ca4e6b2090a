//! Batch kinematics: leg IK, leg FK and body IK over many targets at once.
//!
//! The targets are taken in chunks of [`LANES`]; within a chunk every stage of the solve runs
//! over all lanes before the next (structure of arrays: one array per coordinate), with no
//! branch on a lane's value (unreachable lanes are computed along and masked), so that the
//! compiler vectorises each stage. The equations, their order of operations and the branch
//! choices (the knee bend, the abduction with the foot below the hip, every quadrant in one
//! `atan2`) are those of the scalar solve ([`leg::Solver::inverse`]): **each result equals the
//! scalar one bit for bit**, on every backend, which the tests check over the workspace, at
//! the reach and quadrant boundaries, on the backends' kernel edges and on every tail length.
//! The [`Math`] backend supplies the lane forms of its kernels ([`Math::atan2_lanes`],
//! [`Math::sqrt_lanes`]; [`DefaultMath`](crate::DefaultMath)'s vectorise).
//!
//! Each target gets a reach code ([`code`]): the reason the scalar solve would give
//! ([`code_of`]). A target that fails holds **0.0** in every output (never NaN) and its code.
//! Under [`ReachPolicy::Clamp`] a target the chunk found unreachable is solved again by the
//! scalar solve (the clamp's projections are per target and rare), so it holds the clamped
//! angles and the code of why it was clamped, as [`leg::Solver::inverse`] reports it.
//!
//! This module runs on one thread; a host splits a large batch into slices (multiples of
//! [`LANES`] keep every slice's chunks full) and hands them to its threads.
//!
//! ```
//! use kin_core::{batch, leg, LegId, ReachPolicy, Robot, Vec3};
//! let robot = Robot::shahriar2023();
//! let solver = leg::Solver::new(&robot);
//! let feet_in_hip_m = [[0.02, 0.05, -0.25], [0.0, 0.05, -0.9], [f32::NAN, 0.0, 0.0]];
//! let mut angles_rad = [[0.0; 3]; 3];
//! let mut codes = [0; 3];
//! batch::leg_inverse(&solver, LegId::FL, ReachPolicy::Reject, &feet_in_hip_m, &mut angles_rad, &mut codes)?;
//! assert_eq!(codes, [batch::code::OK, batch::code::TOO_FAR, batch::code::NON_FINITE]);
//! let one = solver.inverse(LegId::FL, Vec3::from_array(feet_in_hip_m[0]), ReachPolicy::Reject)?;
//! assert_eq!(angles_rad[0], one.angles.to_array());
//! assert_eq!(angles_rad[1], [0.0; 3]);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use crate::body::{self, BodyConfig, BodySolution, Pose};
use crate::leg::{self, abduction_yx, hip_yx, Unreachable};
use crate::math::{finite, Math};
use crate::robot::{JointAngles, KneeBend, LegGeometry, LegId};
use crate::vec::Vec3;
use crate::ReachPolicy;
use core::fmt;

/// Targets per chunk: 8 f32 lanes, two SSE registers or one AVX register per value.
pub const LANES: usize = 8;

/// The reach codes of the batch solves, one byte per target (the same numbers as the Python
/// package's `quadkin.OK`, …).
pub mod code {
    /// Solved exactly (or, under [`ReachPolicy::Clamp`](crate::ReachPolicy::Clamp), not moved).
    pub const OK: u8 = 0;
    /// [`Unreachable::TooFar`](crate::Unreachable::TooFar).
    pub const TOO_FAR: u8 = 1;
    /// [`Unreachable::TooClose`](crate::Unreachable::TooClose).
    pub const TOO_CLOSE: u8 = 2;
    /// [`Unreachable::InsideOffset`](crate::Unreachable::InsideOffset).
    pub const INSIDE_OFFSET: u8 = 3;
    /// [`Unreachable::JointLimit`](crate::Unreachable::JointLimit), any joint.
    pub const JOINT_LIMIT: u8 = 4;
    /// [`Unreachable::NonFinite`](crate::Unreachable::NonFinite).
    pub const NON_FINITE: u8 = 5;
    /// The codes' snake_case names, indexed by code ([`Unreachable::code`](crate::Unreachable::code)
    /// for the failures).
    pub const NAMES: [&str; 6] = [
        "ok",
        "too_far",
        "too_close",
        "inside_offset",
        "joint_limit",
        "non_finite",
    ];
}

/// The reach code of a scalar solve's reason.
pub const fn code_of(kind: Unreachable) -> u8 {
    match kind {
        Unreachable::TooFar => code::TOO_FAR,
        Unreachable::TooClose => code::TOO_CLOSE,
        Unreachable::InsideOffset => code::INSIDE_OFFSET,
        Unreachable::JointLimit(_) => code::JOINT_LIMIT,
        Unreachable::NonFinite => code::NON_FINITE,
    }
}

/// An output slice whose length differs from the input's number of targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LengthMismatch {
    /// Which slice: `"angles_rad"`, `"codes"`, ….
    pub what: &'static str,
    /// The number of targets.
    pub expected: usize,
    /// The slice's length.
    pub got: usize,
}

impl fmt::Display for LengthMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} elements for {} targets",
            self.what, self.got, self.expected
        )
    }
}

impl core::error::Error for LengthMismatch {}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), LengthMismatch> {
    if expected == got {
        Ok(())
    } else {
        Err(LengthMismatch {
            what,
            expected,
            got,
        })
    }
}

/// One chunk's leg IK under [`ReachPolicy::Reject`]: the angles (0.0 where the code is not
/// [`code::OK`]) and the codes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegLanes<const N: usize> {
    pub(crate) abduction_rad: [f32; N],
    pub(crate) hip_rad: [f32; N],
    pub(crate) knee_rad: [f32; N],
    pub(crate) code: [u8; N],
}

/// The leg IK of `N` targets `(x, y, z)` (hip frames), lane `i` of the leg with
/// `s·d_lat = sd[i]`, under [`ReachPolicy::Reject`]: the scalar solve's steps
/// ([`leg::Solver::inverse`]: `depth`, `Consts::leg_plane`, `abduction_yx`,
/// `Consts::knee_yx`, `hip_yx`, one `atan2` per angle, the limits), each stage over all lanes.
/// The scalar solve returns at the first failing check; here every lane runs every stage and
/// the code keeps the first failure in the scalar order (non-finite, inside the offset, too
/// far, too close, a joint limit).
#[inline]
pub(crate) fn leg_lanes<M: Math, const N: usize>(
    s: &leg::Solver<M>,
    sd: &[f32; N],
    x: &[f32; N],
    y: &[f32; N],
    z: &[f32; N],
) -> LegLanes<N> {
    let (g, c) = (&s.geometry, &s.c);
    // depth: w² = max(A² − La², 0), A² = y² + z².
    let mut r_sq = [0.0f32; N];
    let mut w_sq = [0.0f32; N];
    for i in 0..N {
        r_sq[i] = y[i] * y[i] + z[i] * z[i];
        let d = r_sq[i] - c.d_lat_sq;
        w_sq[i] = if M::gt_zero(d) { d } else { 0.0 };
    }
    let root = M::sqrt_lanes(&w_sq);
    // The leg plane, the reach checks, the abduction's arguments and the knee's sin² k.
    let mut code = [code::OK; N];
    let (mut v, mut dist2, mut s_sq) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    let (mut abd_y, mut abd_x, mut knee_x) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        let w = -root[i];
        let (vi, v_sq) = c.leg_plane(g.d_ax_m, (w, w_sq[i]));
        let d2 = x[i] * x[i] + v_sq;
        (v[i], dist2[i]) = (vi, d2);
        (abd_y[i], abd_x[i]) = abduction_yx(sd[i], y[i], z[i], w);
        knee_x[i] = d2 - c.sum_sq;
        let q = (d2 - c.near_sq) * (c.far_sq - d2);
        s_sq[i] = if M::gt_zero(q) { q } else { 0.0 };
        let non_finite = !(finite(x[i]) & finite(y[i]) & finite(z[i]));
        let inside = M::lt_nonneg(r_sq[i], c.d_lat_sq);
        let far = M::lt_nonneg(c.far_sq, d2);
        let close = M::lt_nonneg(d2, c.near_sq);
        // The first failure in the scalar order, by selects.
        let mut k = if close { code::TOO_CLOSE } else { code::OK };
        k = if far { code::TOO_FAR } else { k };
        k = if inside { code::INSIDE_OFFSET } else { k };
        code[i] = if non_finite { code::NON_FINITE } else { k };
    }
    let s_abs = M::sqrt_lanes(&s_sq);
    let (mut knee_y, mut hip_y, mut hip_x) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        let sk = match s.knee_bend {
            KneeBend::Backward => -s_abs[i],
            KneeBend::Forward => s_abs[i],
        };
        knee_y[i] = sk;
        (hip_y[i], hip_x[i]) = hip_yx(x[i], v[i], dist2[i], c.diff_sq, sk);
    }
    let abduction = M::atan2_lanes(&abd_y, &abd_x);
    let knee = M::atan2_lanes(&knee_y, &knee_x);
    let hip = M::atan2_lanes(&hip_y, &hip_x);
    let mut out = LegLanes {
        abduction_rad: [0.0; N],
        hip_rad: [0.0; N],
        knee_rad: [0.0; N],
        code,
    };
    for i in 0..N {
        let within = s.admits_all(JointAngles::new(abduction[i], hip[i], knee[i]));
        let k = out.code[i];
        let k = if k == code::OK && !within {
            code::JOINT_LIMIT
        } else {
            k
        };
        out.code[i] = k;
        let ok = k == code::OK;
        out.abduction_rad[i] = if ok { abduction[i] } else { 0.0 };
        out.hip_rad[i] = if ok { hip[i] } else { 0.0 };
        out.knee_rad[i] = if ok { knee[i] } else { 0.0 };
    }
    out
}

/// A failed lane under [`ReachPolicy::Clamp`] solved by the scalar solve: its angles (zeros
/// when it still fails) and code.
fn clamp_one<M: Math>(s: &leg::Solver<M>, leg: LegId, foot: Vec3) -> ([f32; 3], u8) {
    match s.inverse(leg, foot, ReachPolicy::Clamp) {
        Ok(sol) => (
            sol.angles.to_array(),
            sol.clamped.map_or(code::OK, |c| code_of(c.kind)),
        ),
        Err(e) => ([0.0; 3], code_of(e.kind)),
    }
}

/// The lanes of chunk `k` of `n` targets read by `at(i)`; lanes past `n` hold the first
/// target of the chunk (their results are dropped).
#[inline(always)]
fn gather<const N: usize>(
    first: usize,
    n: usize,
    at: impl Fn(usize) -> [f32; 3],
) -> ([f32; N], [f32; N], [f32; N]) {
    let (mut x, mut y, mut z) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    let pad = at(first);
    for i in 0..N {
        let [a, b, c] = if first + i < n { at(first + i) } else { pad };
        (x[i], y[i], z[i]) = (a, b, c);
    }
    (x, y, z)
}

/// Leg IK of many feet of one leg: `feet_in_hip_m[i]` (the hip frame of `leg`, m) → the
/// joint angles `angles_rad[i]` (`[abduction, hip, knee]`, rad) and the reach code
/// `codes[i]`, each equal to what `solver.inverse(leg, feet_in_hip_m[i], policy)` returns
/// (a failure: zeros and its code). See the [module docs](self).
///
/// # Errors
/// [`LengthMismatch`] when `angles_rad` or `codes` is not as long as `feet_in_hip_m` (nothing
/// is written).
pub fn leg_inverse<M: Math>(
    solver: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    feet_in_hip_m: &[[f32; 3]],
    angles_rad: &mut [[f32; 3]],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let n = feet_in_hip_m.len();
    check_len("angles_rad", n, angles_rad.len())?;
    check_len("codes", n, codes.len())?;
    let sd = [solver.side_d_lat(leg); LANES];
    for first in (0..n).step_by(LANES) {
        let (x, y, z) = gather::<LANES>(first, n, |i| feet_in_hip_m[i]);
        let r = leg_lanes(solver, &sd, &x, &y, &z);
        let m = LANES.min(n - first);
        for i in 0..m {
            let (mut a, mut k) = ([r.abduction_rad[i], r.hip_rad[i], r.knee_rad[i]], r.code[i]);
            if policy == ReachPolicy::Clamp && k != code::OK && k != code::NON_FINITE {
                (a, k) = clamp_one(solver, leg, Vec3::new(x[i], y[i], z[i]));
            }
            angles_rad[first + i] = a;
            codes[first + i] = k;
        }
    }
    Ok(())
}

/// [`leg_inverse`] on a structure of arrays: the feet's coordinates `x_m`, `y_m`, `z_m` (one
/// slice each) → the angles `abduction_rad`, `hip_rad`, `knee_rad` and `codes`.
///
/// # Errors
/// [`LengthMismatch`] when the slices differ in length from `x_m` (nothing is written).
#[allow(clippy::too_many_arguments)] // Three coordinates in, three angles and a code out.
pub fn leg_inverse_soa<M: Math>(
    solver: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    [x_m, y_m, z_m]: [&[f32]; 3],
    abduction_rad: &mut [f32],
    hip_rad: &mut [f32],
    knee_rad: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let n = x_m.len();
    check_len("y_m", n, y_m.len())?;
    check_len("z_m", n, z_m.len())?;
    check_len("abduction_rad", n, abduction_rad.len())?;
    check_len("hip_rad", n, hip_rad.len())?;
    check_len("knee_rad", n, knee_rad.len())?;
    check_len("codes", n, codes.len())?;
    let sd = [solver.side_d_lat(leg); LANES];
    for first in (0..n).step_by(LANES) {
        let (x, y, z) = gather::<LANES>(first, n, |i| [x_m[i], y_m[i], z_m[i]]);
        let r = leg_lanes(solver, &sd, &x, &y, &z);
        let m = LANES.min(n - first);
        for i in 0..m {
            let (mut a, mut k) = ([r.abduction_rad[i], r.hip_rad[i], r.knee_rad[i]], r.code[i]);
            if policy == ReachPolicy::Clamp && k != code::OK && k != code::NON_FINITE {
                (a, k) = clamp_one(solver, leg, Vec3::new(x[i], y[i], z[i]));
            }
            (
                abduction_rad[first + i],
                hip_rad[first + i],
                knee_rad[first + i],
            ) = (a[0], a[1], a[2]);
            codes[first + i] = k;
        }
    }
    Ok(())
}

/// Leg FK of many joint-angle rows of one leg on backend `M`: `angles_rad[i]`
/// (`[abduction, hip, knee]`, rad) → `feet_in_hip_m[i]` (the hip frame, m), equal to
/// [`leg::forward`] on the same backend (`DefaultMath`: bit for bit), and `codes[i]`:
/// [`code::NON_FINITE`] (and zeros) for a row with a NaN or infinite angle, else
/// [`code::OK`] (the joint limits are not checked).
///
/// # Errors
/// [`LengthMismatch`] when `feet_in_hip_m` or `codes` is not as long as `angles_rad`.
pub fn leg_forward<M: Math>(
    geometry: &LegGeometry,
    leg: LegId,
    angles_rad: &[[f32; 3]],
    feet_in_hip_m: &mut [[f32; 3]],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let n = angles_rad.len();
    check_len("feet_in_hip_m", n, feet_in_hip_m.len())?;
    check_len("codes", n, codes.len())?;
    for first in (0..n).step_by(LANES) {
        let (a, h, k) = gather::<LANES>(first, n, |i| angles_rad[i]);
        let mut out = [[0.0f32; 3]; LANES];
        let mut ok = [false; LANES];
        for i in 0..LANES {
            ok[i] = finite(a[i]) & finite(h[i]) & finite(k[i]);
            let q = JointAngles::new(a[i], h[i], k[i]);
            let f = leg::forward_on::<M>(geometry, leg, q);
            out[i] = if ok[i] { f.to_array() } else { [0.0; 3] };
        }
        let m = LANES.min(n - first);
        for i in 0..m {
            feet_in_hip_m[first + i] = out[i];
            codes[first + i] = if ok[i] { code::OK } else { code::NON_FINITE };
        }
    }
    Ok(())
}

/// The feet of a batch of body poses.
#[derive(Debug, Clone, Copy)]
pub enum BodyFeet<'a> {
    /// The nominal stance of this height, m, for every pose
    /// ([`body::Solver::inverse_at_stance`]).
    Stance {
        /// The stance height, m.
        height_m: f32,
    },
    /// The same four feet in the world frame (FL, FR, RL, RR), m, for every pose
    /// ([`body::Solver::inverse`]).
    Same(&'a [Vec3; 4]),
    /// Four feet per pose in the world frame, `[FL, FR, RL, RR]` of `[x, y, z]`, m, one entry
    /// per pose ([`body::Solver::inverse`]).
    PerPose(&'a [[[f32; 3]; 4]]),
}

/// No leg named in a body code: the pose was solved (`legs[i]` of [`body_inverse`]).
pub const NO_LEG: i8 = -1;

/// Full-body IK of many poses: `poses[i]` (`[roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m]`,
/// [`Pose::from_array`]) with the feet of `feet` → `angles_rad[i]` (the twelve angles in the
/// order of [`BodySolution::angles_rad`]), `codes[i]` and `legs[i]`, equal to what the scalar
/// body IK returns for that pose, all-or-nothing as it is: a pose that fails holds zeros, the
/// code of the first leg (FL, FR, RL, RR) that fails and that leg's index (a non-finite pose:
/// [`code::NON_FINITE`] on FL); under [`ReachPolicy::Clamp`] a clamped pose holds its angles,
/// the code and index of its first clamped leg. A solved pose: [`code::OK`] and [`NO_LEG`].
///
/// The feet are carried into each leg's hip frame pose by pose by the scalar transform; the
/// four legs' IK runs over [`LANES`] poses at a time.
///
/// # Errors
/// [`LengthMismatch`] when `angles_rad`, `codes`, `legs` or the feet of
/// [`BodyFeet::PerPose`] are not as long as `poses`.
#[allow(clippy::too_many_arguments)] // Poses and feet in, angles, codes and legs out.
pub fn body_inverse<M: Math>(
    solver: &body::Solver<M>,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[[f32; 6]],
    feet: BodyFeet<'_>,
    angles_rad: &mut [[f32; 12]],
    codes: &mut [u8],
    legs: &mut [i8],
) -> Result<(), LengthMismatch> {
    let n = poses.len();
    check_len("angles_rad", n, angles_rad.len())?;
    check_len("codes", n, codes.len())?;
    check_len("legs", n, legs.len())?;
    if let BodyFeet::PerPose(f) = feet {
        check_len("feet_in_world_m", n, f.len())?;
    }
    let leg_solver = solver.leg();
    let sd: [[f32; LANES]; 4] = LegId::ALL.map(|leg| [leg_solver.side_d_lat(leg); LANES]);
    for first in (0..n).step_by(LANES) {
        let m = LANES.min(n - first);
        // The feet in the hip frames, per leg a structure of arrays over the chunk's poses.
        let mut local = [[[0.0f32; LANES]; 3]; 4];
        let mut pose_ok = [false; LANES];
        for i in 0..m {
            let pose = Pose::from_array(poses[first + i]);
            pose_ok[i] = body::check_finite(&pose, config).is_ok();
            if !pose_ok[i] {
                continue;
            }
            let mut hips = [Vec3::ZERO; 4];
            match feet {
                BodyFeet::Stance { height_m } => {
                    solver.stance_feet_in_hips(&pose, config, height_m, &mut hips)
                }
                BodyFeet::Same(f) => hips = solver.feet_in_hips(&pose, config, f),
                BodyFeet::PerPose(f) => {
                    let f = f[first + i].map(Vec3::from_array);
                    hips = solver.feet_in_hips(&pose, config, &f);
                }
            }
            for (k, h) in hips.iter().enumerate() {
                (local[k][0][i], local[k][1][i], local[k][2][i]) = (h.x, h.y, h.z);
            }
        }
        let solved: [LegLanes<LANES>; 4] = core::array::from_fn(|k| {
            let [x, y, z] = &local[k];
            leg_lanes(leg_solver, &sd[k], x, y, z)
        });
        for i in 0..m {
            let j = first + i;
            let failed = (0..4).find(|&k| solved[k].code[i] != code::OK);
            let (out, code, leg) = match (pose_ok[i], failed) {
                (false, _) => ([0.0; 12], code::NON_FINITE, 0),
                (true, None) => {
                    let mut a = [0.0f32; 12];
                    for (k, s) in solved.iter().enumerate() {
                        a[3 * k..3 * k + 3].copy_from_slice(&[
                            s.abduction_rad[i],
                            s.hip_rad[i],
                            s.knee_rad[i],
                        ]);
                    }
                    (a, code::OK, NO_LEG)
                }
                (true, Some(k)) if policy == ReachPolicy::Reject => {
                    ([0.0; 12], solved[k].code[i], k as i8)
                }
                (true, Some(_)) => body_scalar(solver, config, poses[j], feet, j),
            };
            (angles_rad[j], codes[j], legs[j]) = (out, code, leg);
        }
    }
    Ok(())
}

/// Pose `j` of [`body_inverse`] under [`ReachPolicy::Clamp`] by the scalar body IK.
fn body_scalar<M: Math>(
    solver: &body::Solver<M>,
    config: &BodyConfig,
    pose: [f32; 6],
    feet: BodyFeet<'_>,
    j: usize,
) -> ([f32; 12], u8, i8) {
    let pose = Pose::from_array(pose);
    let policy = ReachPolicy::Clamp;
    let mut sol = BodySolution::default();
    let r = match feet {
        BodyFeet::Stance { height_m } => {
            solver.inverse_at_stance_into(&pose, config, height_m, policy, &mut sol)
        }
        BodyFeet::Same(f) => solver.inverse_into(&pose, config, f, policy, &mut sol),
        BodyFeet::PerPose(f) => {
            let f = f[j].map(Vec3::from_array);
            solver.inverse_into(&pose, config, &f, policy, &mut sol)
        }
    };
    match r {
        Ok(()) => match sol.clamped.iter().position(Option::is_some) {
            Some(k) => (
                sol.angles_rad,
                sol.clamped[k].map_or(code::OK, |c| code_of(c.kind)),
                k as i8,
            ),
            None => (sol.angles_rad, code::OK, NO_LEG),
        },
        Err(e) => ([0.0; 12], code_of(e.kind), e.leg.index() as i8),
    }
}
