//! Batch kinematics: leg IK, leg FK and body IK over many targets at once.
//!
//! The targets are taken in chunks of [`LANES`] (16 in the AVX-512 form, [`avx512`]); within a
//! chunk every stage of the solve runs over all lanes before the next (structure of arrays: one
//! array per coordinate), with no branch on a lane's value (unreachable lanes are computed along
//! and masked), so that the compiler vectorises each stage. The equations, their order of
//! operations and the branch choices (the knee bend, the abduction with the foot below the hip,
//! every quadrant in one `atan2`) are those of the scalar solve ([`leg::Solver::inverse`]):
//! **each result equals the scalar one bit for bit**, on every backend and in every form, which
//! the tests check over the workspace, at the reach and quadrant boundaries, on the backends'
//! kernel edges, on every tail length and around the row API's blocks ([`BLOCK_ROWS`]).
//! The [`Math`] backend supplies the lane forms of its kernels ([`Math::atan2_lanes`],
//! [`Math::sqrt_lanes`]; [`DefaultMath`](crate::DefaultMath)'s vectorise).
//!
//! Each target gets a reach code ([`code`]): the reason the scalar solve would give
//! ([`code_of`]). A target that fails holds **0.0** in every output (never NaN) and its code.
//! Under [`ReachPolicy::Clamp`] a target the chunk found unreachable is solved again by the
//! scalar solve (the clamp's projections are per target and rare), so it holds the clamped
//! angles and the code of why it was clamped, as [`leg::Solver::inverse`] reports it.
//!
//! On x86-64 the same solves are compiled for AVX2 ([`avx2`]) and AVX-512 ([`avx512`]), for a
//! host to call after checking the CPU: the same bits, more lanes per instruction.
//!
//! This module runs on one thread; a host splits a large batch into slices (multiples of 16
//! keep every slice's chunks full in every form) and hands them to its threads.
//!
//! ```
//! use kin_core::{batch, leg, LegId, ReachPolicy, Robot, Vec3};
//! let robot = Robot::shahriar2023();
//! let solver = leg::Solver::new(&robot);
//! let feet_in_hip_m = [[0.02, 0.05, -0.25], [0.0, 0.05, -0.9], [f32::NAN, 0.0, 0.0]];
//! let mut angles_rad = [[0.0f32; 3]; 3];
//! let mut codes = [0; 3];
//! batch::leg_inverse(
//!     &solver,
//!     LegId::FL,
//!     ReachPolicy::Reject,
//!     feet_in_hip_m.as_flattened(),
//!     angles_rad.as_flattened_mut(),
//!     &mut codes,
//! )?;
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

/// Targets per chunk of the portable solves (and of [`avx2`]): 8 f32 lanes, two SSE registers
/// or one AVX register per value.
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

/// A slice whose length does not fit the batch: an input not a whole number of rows, or an
/// output not as long as the input's rows need.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LengthMismatch {
    /// Which slice: `"angles_rad"`, `"codes"`, ….
    pub what: &'static str,
    /// The length it needs (for an input: the whole rows within its length).
    pub expected: usize,
    /// Its length.
    pub got: usize,
}

impl fmt::Display for LengthMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} elements, expected {}",
            self.what, self.got, self.expected
        )
    }
}

impl core::error::Error for LengthMismatch {}

/// The number of rows of `width` floats in `rows`, refused when `rows` is not whole rows.
fn row_count(what: &'static str, rows: &[f32], width: usize) -> Result<usize, LengthMismatch> {
    let n = rows.len() / width;
    check_len(what, n * width, rows.len())?;
    Ok(n)
}

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

impl<const N: usize> LegLanes<N> {
    /// Zero angles, [`code::OK`].
    const ZERO: Self = LegLanes {
        abduction_rad: [0.0; N],
        hip_rad: [0.0; N],
        knee_rad: [0.0; N],
        code: [code::OK; N],
    };
}

/// The leg IK of `N` targets `(x, y, z)` (hip frames), lane `i` of the leg with
/// `s·d_lat = sd[i]`, under [`ReachPolicy::Reject`]: the scalar solve's steps
/// ([`leg::Solver::inverse`]: `depth`, `Consts::leg_plane`, `abduction_yx`,
/// `Consts::knee_yx`, `hip_yx`, one `atan2` per angle, the limits), each stage over all lanes.
/// The scalar solve returns at the first failing check; here every lane runs every stage and
/// the code keeps the first failure in the scalar order (non-finite, inside the offset, too
/// far, too close, a joint limit).
// Always inlined: into the entry points compiled for CPU features too, which compile it for
// theirs.
#[inline(always)]
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
    // The codes as 32-bit lanes beside the f32 values (one vector width), bytes at the end.
    let mut code = [u32::from(code::OK); N];
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
        let mut k = select(close, code::TOO_CLOSE, u32::from(code::OK));
        k = select(far, code::TOO_FAR, k);
        k = select(inside, code::INSIDE_OFFSET, k);
        code[i] = select(non_finite, code::NON_FINITE, k);
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
    // The joint limits, one angle over all lanes at a time (`admits_all` per lane).
    let (lo, hi, keys) = (&s.limits.min_rad, &s.limits.max_rad, &s.limit_keys);
    let mut outside = [0u32; N];
    for (j, angle) in [&abduction, &hip, &knee].into_iter().enumerate() {
        for i in 0..N {
            outside[i] |= u32::from(!M::within_keys(angle[i], lo[j], hi[j], keys[j]));
        }
    }
    let mut out = LegLanes::ZERO;
    for i in 0..N {
        let k = code[i];
        let k = select(
            (k == u32::from(code::OK)) & (outside[i] != 0),
            code::JOINT_LIMIT,
            k,
        );
        // All ones where solved, zero elsewhere: the angles or +0.0.
        let keep = 0u32.wrapping_sub(u32::from(k == u32::from(code::OK)));
        out.abduction_rad[i] = f32::from_bits(abduction[i].to_bits() & keep);
        out.hip_rad[i] = f32::from_bits(hip[i].to_bits() & keep);
        out.knee_rad[i] = f32::from_bits(knee[i].to_bits() & keep);
        code[i] = k;
    }
    for (o, k) in out.code.iter_mut().zip(code) {
        *o = k as u8;
    }
    out
}

/// `code` where `cond`, else `other`, as a 32-bit lane (by a mask: no branch).
// Always inlined: a select inside the lanes' loops, which must stay branch-free.
#[inline(always)]
fn select(cond: bool, code: u8, other: u32) -> u32 {
    let m = 0u32.wrapping_sub(u32::from(cond));
    (m & u32::from(code)) | (!m & other)
}

/// [`leg_lanes`] of one chunk under `policy`: under [`ReachPolicy::Clamp`] a lane the chunk
/// found unreachable (not [`code::NON_FINITE`]) is solved again by the scalar solve: its
/// clamped angles and the code of why it was clamped.
// Always inlined: into its public form and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
fn leg_chunk<M: Math, const W: usize>(
    s: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    sd: &[f32; W],
    x: &[f32; W],
    y: &[f32; W],
    z: &[f32; W],
) -> LegLanes<W> {
    let mut r = leg_lanes(s, sd, x, y, z);
    if policy == ReachPolicy::Clamp {
        let mut redo = false;
        for k in r.code {
            redo |= (k != code::OK) & (k != code::NON_FINITE);
        }
        if redo {
            clamp_lanes(s, leg, x, y, z, &mut r);
        }
    }
    r
}

/// The lanes of `r` that [`leg_lanes`] found unreachable (not non-finite), solved again by
/// the scalar solve under [`ReachPolicy::Clamp`]: their angles (zeros when it still fails)
/// and codes.
// Out of line: rare, and the chunk's vector code stays small.
#[inline(never)]
fn clamp_lanes<M: Math, const N: usize>(
    s: &leg::Solver<M>,
    leg: LegId,
    x: &[f32; N],
    y: &[f32; N],
    z: &[f32; N],
    r: &mut LegLanes<N>,
) {
    for i in 0..N {
        if r.code[i] == code::OK || r.code[i] == code::NON_FINITE {
            continue;
        }
        let (a, k) = match s.inverse(leg, Vec3::new(x[i], y[i], z[i]), ReachPolicy::Clamp) {
            Ok(sol) => (
                sol.angles.to_array(),
                sol.clamped.map_or(code::OK, |c| code_of(c.kind)),
            ),
            Err(e) => ([0.0; 3], code_of(e.kind)),
        };
        (r.abduction_rad[i], r.hip_rad[i], r.knee_rad[i]) = (a[0], a[1], a[2]);
        r.code[i] = k;
    }
}

/// Leg IK of many feet of one leg: `feet_in_hip_m`, rows `[x, y, z]` (the hip frame of
/// `leg`, m) one after the other (`rows.as_flattened()` of `&[[f32; 3]]`) → `angles_rad`,
/// rows `[abduction, hip, knee]` (rad), and one reach code per row in `codes`, each row equal
/// to what `solver.inverse(leg, foot, policy)` returns (a failure: zeros and its code). See
/// the [module docs](self).
///
/// # Errors
/// [`LengthMismatch`] when `feet_in_hip_m` is not whole rows of 3, or `angles_rad` or `codes`
/// does not fit its rows (nothing is written).
// Never inlined: inlined into a caller's closure (the Python package's threads) it ran 1.6×
// slower than as a function of its own.
#[inline(never)]
pub fn leg_inverse<M: Math>(
    solver: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    feet_in_hip_m: &[f32],
    angles_rad: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    leg_inverse_impl::<M, LANES>(solver, leg, policy, feet_in_hip_m, angles_rad, codes)
}

// Always inlined: into its public form and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
fn leg_inverse_impl<M: Math, const W: usize>(
    solver: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    feet_in_hip_m: &[f32],
    angles_rad: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let n = row_count("feet_in_hip_m", feet_in_hip_m, 3)?;
    check_len("angles_rad", 3 * n, angles_rad.len())?;
    check_len("codes", n, codes.len())?;
    // A block of rows at a time: the rows taken apart into one array per coordinate (a loop
    // the compiler turns into shuffles), the chunks solved over them, the angles put back
    // together into rows.
    for ((f, a), c) in feet_in_hip_m
        .chunks(3 * BLOCK_ROWS)
        .zip(angles_rad.chunks_mut(3 * BLOCK_ROWS))
        .zip(codes.chunks_mut(BLOCK_ROWS))
    {
        let m = c.len();
        let (mut x, mut y, mut z) = (
            [0.0f32; BLOCK_ROWS],
            [0.0f32; BLOCK_ROWS],
            [0.0f32; BLOCK_ROWS],
        );
        for (i, row) in f.chunks_exact(3).enumerate() {
            (x[i], y[i], z[i]) = (row[0], row[1], row[2]);
        }
        let (mut abduction, mut hip, mut knee) = (
            [0.0f32; BLOCK_ROWS],
            [0.0f32; BLOCK_ROWS],
            [0.0f32; BLOCK_ROWS],
        );
        leg_columns::<M, W>(
            solver,
            leg,
            policy,
            [&x[..m], &y[..m], &z[..m]],
            [&mut abduction[..m], &mut hip[..m], &mut knee[..m]],
            c,
        );
        for (i, row) in a.chunks_exact_mut(3).enumerate() {
            row.copy_from_slice(&[abduction[i], hip[i], knee[i]]);
        }
    }
    Ok(())
}

/// Rows per block of [`leg_inverse`] (taken apart into one array per coordinate, solved, put
/// back together): a multiple of every form's lanes.
pub const BLOCK_ROWS: usize = 128;

/// The leg IK of the targets `x`, `y`, `z` (one slice per coordinate, of equal lengths) into
/// `angles` (abduction, hip, knee) and `codes` (as long), [`leg_chunk`] over chunks of `W`; a
/// tail is padded with its first target, whose results are dropped.
// Always inlined: into the public forms and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
fn leg_columns<M: Math, const W: usize>(
    solver: &leg::Solver<M>,
    leg: LegId,
    policy: ReachPolicy,
    [x, y, z]: [&[f32]; 3],
    [abduction, hip, knee]: [&mut [f32]; 3],
    codes: &mut [u8],
) {
    let sd = [solver.side_d_lat(leg); W];
    let n = codes.len();
    for first in (0..n).step_by(W) {
        let m = W.min(n - first);
        let lanes = |v: &[f32]| -> [f32; W] {
            let v = &v[first..first + m];
            match v.try_into() {
                Ok(full) => full,
                Err(_) => {
                    let mut padded = [v[0]; W];
                    padded[..m].copy_from_slice(v);
                    padded
                }
            }
        };
        let r = leg_chunk::<M, W>(solver, leg, policy, &sd, &lanes(x), &lanes(y), &lanes(z));
        put(&mut abduction[first..first + m], &r.abduction_rad);
        put(&mut hip[first..first + m], &r.hip_rad);
        put(&mut knee[first..first + m], &r.knee_rad);
        put(&mut codes[first..first + m], &r.code);
    }
}

/// `dst` (at most `W` long) from the first lanes of `src`: a full chunk as one fixed-size copy
/// (a copy of a length the compiler does not know is a call).
// Always inlined: inside the chunk loops, compiled for the entry points' CPU features.
#[inline(always)]
fn put<T: Copy, const W: usize>(dst: &mut [T], src: &[T; W]) {
    let m = dst.len();
    if let Ok(full) = <&mut [T; W]>::try_from(&mut *dst) {
        *full = *src;
    } else {
        dst.copy_from_slice(&src[..m]);
    }
}

/// [`leg_inverse`] on a structure of arrays: the feet's coordinates `x_m`, `y_m`, `z_m` (one
/// slice each) → the angles `abduction_rad`, `hip_rad`, `knee_rad` and `codes`.
///
/// # Errors
/// [`LengthMismatch`] when the slices differ in length from `x_m` (nothing is written).
#[allow(clippy::too_many_arguments)] // Three coordinates in, three angles and a code out.
#[inline]
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
    leg_inverse_soa_impl::<M, LANES>(
        solver,
        leg,
        policy,
        [x_m, y_m, z_m],
        abduction_rad,
        hip_rad,
        knee_rad,
        codes,
    )
}

// Always inlined: into its public form and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn leg_inverse_soa_impl<M: Math, const W: usize>(
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
    leg_columns::<M, W>(
        solver,
        leg,
        policy,
        [x_m, y_m, z_m],
        [abduction_rad, hip_rad, knee_rad],
        codes,
    );
    Ok(())
}

/// Leg FK of many joint-angle rows of one leg on backend `M`: `angles_rad`, rows
/// `[abduction, hip, knee]` (rad) one after the other → `feet_in_hip_m`, rows `[x, y, z]`
/// (the hip frame, m), equal to [`leg::forward`] on the same backend (`DefaultMath`: bit for
/// bit), and one code per row in `codes`: [`code::NON_FINITE`] (and zeros) for a row with a
/// NaN or infinite angle, else [`code::OK`] (the joint limits are not checked).
///
/// # Errors
/// [`LengthMismatch`] when `angles_rad` is not whole rows of 3, or `feet_in_hip_m` or `codes`
/// does not fit its rows (nothing is written).
#[inline]
pub fn leg_forward<M: Math>(
    geometry: &LegGeometry,
    leg: LegId,
    angles_rad: &[f32],
    feet_in_hip_m: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    leg_forward_impl::<M, LANES>(geometry, leg, angles_rad, feet_in_hip_m, codes)
}

// Always inlined: into its public form and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
fn leg_forward_impl<M: Math, const W: usize>(
    geometry: &LegGeometry,
    leg: LegId,
    angles_rad: &[f32],
    feet_in_hip_m: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let n = row_count("angles_rad", angles_rad, 3)?;
    check_len("feet_in_hip_m", 3 * n, feet_in_hip_m.len())?;
    check_len("codes", n, codes.len())?;
    for first in (0..n).step_by(W) {
        let m = W.min(n - first);
        let at = |i: usize, k: usize| {
            let i = if i < m { first + i } else { first };
            angles_rad[3 * i + k]
        };
        let a: [f32; W] = core::array::from_fn(|i| at(i, 0));
        let h: [f32; W] = core::array::from_fn(|i| at(i, 1));
        let k: [f32; W] = core::array::from_fn(|i| at(i, 2));
        let mut out = [[0.0f32; 3]; W];
        let mut ok = [false; W];
        for i in 0..W {
            ok[i] = finite(a[i]) & finite(h[i]) & finite(k[i]);
            let q = JointAngles::new(a[i], h[i], k[i]);
            let f = leg::forward_on::<M>(geometry, leg, q);
            out[i] = if ok[i] { f.to_array() } else { [0.0; 3] };
        }
        for i in 0..m {
            feet_in_hip_m[3 * (first + i)..3 * (first + i) + 3].copy_from_slice(&out[i]);
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
    /// Four feet per pose in the world frame, m: per pose `[FL, FR, RL, RR]` of `[x, y, z]`,
    /// 12 floats, one pose after the other ([`body::Solver::inverse`]).
    PerPose(&'a [f32]),
}

/// No leg named in a body code: the pose was solved (`legs[i]` of [`body_inverse`]).
pub const NO_LEG: i8 = -1;

/// Full-body IK of many poses: `poses`, rows `[roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m]`
/// ([`Pose::from_array`]) one after the other, with the feet of `feet` → `angles_rad`, rows of
/// the twelve angles in the order of [`BodySolution::angles_rad`], and per pose `codes[i]` and
/// `legs[i]`, equal to what the scalar
/// body IK returns for that pose, all-or-nothing as it is: a pose that fails holds zeros, the
/// code of the first leg (FL, FR, RL, RR) that fails and that leg's index (a non-finite pose:
/// [`code::NON_FINITE`] on FL); under [`ReachPolicy::Clamp`] a clamped pose holds its angles,
/// the code and index of its first clamped leg. A solved pose: [`code::OK`] and [`NO_LEG`].
///
/// The feet are carried into each leg's hip frame pose by pose by the scalar transform; the
/// four legs' IK runs over [`LANES`] poses at a time.
///
/// # Errors
/// [`LengthMismatch`] when `poses` is not whole rows of 6, or `angles_rad`, `codes`, `legs`
/// or the feet of [`BodyFeet::PerPose`] do not fit its rows (nothing is written).
#[allow(clippy::too_many_arguments)] // Poses and feet in, angles, codes and legs out.
#[inline]
pub fn body_inverse<M: Math>(
    solver: &body::Solver<M>,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[f32],
    feet: BodyFeet<'_>,
    angles_rad: &mut [f32],
    codes: &mut [u8],
    legs: &mut [i8],
) -> Result<(), LengthMismatch> {
    body_inverse_impl::<M, LANES>(solver, config, policy, poses, feet, angles_rad, codes, legs)
}

// Always inlined: into its public form and the entry points compiled for CPU features (a
// call out of line would run the portable code).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn body_inverse_impl<M: Math, const W: usize>(
    solver: &body::Solver<M>,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[f32],
    feet: BodyFeet<'_>,
    angles_rad: &mut [f32],
    codes: &mut [u8],
    legs: &mut [i8],
) -> Result<(), LengthMismatch> {
    let n = row_count("poses", poses, 6)?;
    check_len("angles_rad", 12 * n, angles_rad.len())?;
    check_len("codes", n, codes.len())?;
    check_len("legs", n, legs.len())?;
    if let BodyFeet::PerPose(f) = feet {
        check_len("feet_in_world_m", 12 * n, f.len())?;
    }
    let leg_solver = solver.leg();
    let sd: [[f32; W]; 4] = LegId::ALL.map(|leg| [leg_solver.side_d_lat(leg); W]);
    for first in (0..n).step_by(W) {
        let m = W.min(n - first);
        // The feet in the hip frames, per leg a structure of arrays over the chunk's poses.
        let mut local = [[[0.0f32; W]; 3]; 4];
        let mut pose_ok = [false; W];
        for i in 0..m {
            let pose = Pose::from_array(pose_at(poses, first + i));
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
                    hips = solver.feet_in_hips(&pose, config, &feet_at(f, first + i));
                }
            }
            for (k, h) in hips.iter().enumerate() {
                (local[k][0][i], local[k][1][i], local[k][2][i]) = (h.x, h.y, h.z);
            }
        }
        // A loop rather than `array::from_fn`: its closure is called through core's generic
        // code, which is not compiled for the entry points' CPU features.
        let mut solved = [LegLanes::<W>::ZERO; 4];
        for (k, out) in solved.iter_mut().enumerate() {
            let [x, y, z] = &local[k];
            *out = leg_lanes(leg_solver, &sd[k], x, y, z);
        }
        for (i, &ok) in pose_ok.iter().enumerate().take(m) {
            let j = first + i;
            let failed = (0..4).find(|&k| solved[k].code[i] != code::OK);
            let (out, code, leg) = match (ok, failed) {
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
                (true, Some(_)) => body_scalar(solver, config, pose_at(poses, j), feet, j),
            };
            angles_rad[12 * j..12 * j + 12].copy_from_slice(&out);
            (codes[j], legs[j]) = (code, leg);
        }
    }
    Ok(())
}

/// Row `j` of the poses.
fn pose_at(poses: &[f32], j: usize) -> [f32; 6] {
    core::array::from_fn(|k| poses[6 * j + k])
}

/// The four feet of pose `j` of [`BodyFeet::PerPose`].
fn feet_at(feet: &[f32], j: usize) -> [Vec3; 4] {
    core::array::from_fn(|k| {
        let b = 12 * j + 3 * k;
        Vec3::new(feet[b], feet[b + 1], feet[b + 2])
    })
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
            solver.inverse_into(&pose, config, &feet_at(f, j), policy, &mut sol)
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

/// Defines a module of entry points: the batch solves compiled for one set of x86-64 CPU
/// features, with `$lanes` targets per chunk. A `#[target_feature]` function must be a
/// function of its own (and is unsafe to call: the CPU must have the features), so each public
/// solve has one per feature set; they all inline the same generic solve.
#[cfg(target_arch = "x86_64")]
macro_rules! compiled_for {
    ($(#[$doc:meta])* $name:ident, $features:literal, $lanes:literal, $needs:literal) => {
        $(#[$doc])*
        #[allow(unsafe_code)] // `#[target_feature]` functions are unsafe to call.
        pub mod $name {
            use super::*;

            /// Targets per chunk of these entry points.
            pub const LANES: usize = $lanes;

            #[doc = concat!("[`super::leg_inverse`] compiled for ", $needs, ".")]
            ///
            /// # Safety
            #[doc = concat!("The CPU must support ", $needs, ".")]
            ///
            /// # Errors
            /// As [`super::leg_inverse`].
            #[target_feature(enable = $features)]
            pub unsafe fn leg_inverse<M: Math>(
                solver: &leg::Solver<M>,
                leg: LegId,
                policy: ReachPolicy,
                feet_in_hip_m: &[f32],
                angles_rad: &mut [f32],
                codes: &mut [u8],
            ) -> Result<(), LengthMismatch> {
                leg_inverse_impl::<M, LANES>(solver, leg, policy, feet_in_hip_m, angles_rad, codes)
            }

            #[doc = concat!("[`super::leg_inverse_soa`] compiled for ", $needs, ".")]
            ///
            /// # Safety
            #[doc = concat!("The CPU must support ", $needs, ".")]
            ///
            /// # Errors
            /// As [`super::leg_inverse_soa`].
            #[target_feature(enable = $features)]
            #[allow(clippy::too_many_arguments)]
            pub unsafe fn leg_inverse_soa<M: Math>(
                solver: &leg::Solver<M>,
                leg: LegId,
                policy: ReachPolicy,
                feet_in_hip_m: [&[f32]; 3],
                abduction_rad: &mut [f32],
                hip_rad: &mut [f32],
                knee_rad: &mut [f32],
                codes: &mut [u8],
            ) -> Result<(), LengthMismatch> {
                leg_inverse_soa_impl::<M, LANES>(
                    solver,
                    leg,
                    policy,
                    feet_in_hip_m,
                    abduction_rad,
                    hip_rad,
                    knee_rad,
                    codes,
                )
            }

            #[doc = concat!("[`super::leg_forward`] compiled for ", $needs, ".")]
            ///
            /// # Safety
            #[doc = concat!("The CPU must support ", $needs, ".")]
            ///
            /// # Errors
            /// As [`super::leg_forward`].
            #[target_feature(enable = $features)]
            pub unsafe fn leg_forward<M: Math>(
                geometry: &LegGeometry,
                leg: LegId,
                angles_rad: &[f32],
                feet_in_hip_m: &mut [f32],
                codes: &mut [u8],
            ) -> Result<(), LengthMismatch> {
                leg_forward_impl::<M, LANES>(geometry, leg, angles_rad, feet_in_hip_m, codes)
            }

            #[doc = concat!("[`super::body_inverse`] compiled for ", $needs, ".")]
            ///
            /// # Safety
            #[doc = concat!("The CPU must support ", $needs, ".")]
            ///
            /// # Errors
            /// As [`super::body_inverse`].
            #[target_feature(enable = $features)]
            #[allow(clippy::too_many_arguments)]
            pub unsafe fn body_inverse<M: Math>(
                solver: &body::Solver<M>,
                config: &BodyConfig,
                policy: ReachPolicy,
                poses: &[f32],
                feet: BodyFeet<'_>,
                angles_rad: &mut [f32],
                codes: &mut [u8],
                legs: &mut [i8],
            ) -> Result<(), LengthMismatch> {
                body_inverse_impl::<M, LANES>(
                    solver, config, policy, poses, feet, angles_rad, codes, legs,
                )
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
compiled_for!(
    /// The batch solves compiled for x86-64 CPUs with AVX2: the same functions, each value in
    /// one 256-bit register of 8 lanes and three-operand instructions instead of two SSE
    /// registers and the moves between them. The results are the same bits: the same
    /// operations in the same order (the compiler never contracts a multiplication and an
    /// addition into a fused one). A host checks the CPU once
    /// (`std::is_x86_feature_detected!("avx2")`) and calls these, else the portable ones.
    avx2,
    "avx2",
    8,
    "AVX2"
);

#[cfg(target_arch = "x86_64")]
compiled_for!(
    /// The batch solves compiled for x86-64 CPUs with AVX-512 (F, VL, BW, DQ): the same
    /// functions over chunks of 16 targets, each value in one 512-bit register, the lanes'
    /// comparisons in mask registers. The same bits as the portable ones, as [`avx2`]'s. A host
    /// checks the CPU once (`std::is_x86_feature_detected!` for each of the four) and calls
    /// these where it can.
    avx512,
    "avx512f,avx512vl,avx512bw,avx512dq",
    16,
    "AVX-512 F, VL, BW and DQ"
);
