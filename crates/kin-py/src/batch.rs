//! The batch kinematics of `kin_core::batch` on the host: large batches split into slices of
//! [`CHUNK_ROWS`] rows over rayon's threads, each slice solved by the widest form compiled for
//! this CPU ([`Form`]: `kin_core::batch::avx512`, `kin_core::batch::avx2` or the portable one;
//! all give the same bits).
//!
//! Rows are flat slices: `width` floats per row, one row after the other (numpy's C order).

use crate::arrays::CHUNK_ROWS;
use kin_core::batch::{self, BodyFeet, LengthMismatch};
use kin_core::{body, leg, BodyConfig, DefaultMath, LegGeometry, LegId, ReachPolicy};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, Ordering};

/// A form of kin-core's batch solves, the widest first (all give the same bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Form {
    /// `kin_core::batch::avx512`: 16 lanes.
    Avx512,
    /// `kin_core::batch::avx2`: 8 lanes.
    Avx2,
    /// The portable solves (x86-64's baseline SSE2, or any other CPU).
    Portable,
}

/// The form chosen by [`Form::choose`]: 0 for none (the widest the CPU runs), else 1 + the
/// form's index in [`Form::ALL`].
static CHOSEN: AtomicU8 = AtomicU8::new(0);

impl Form {
    /// Every form, the widest first.
    pub const ALL: [Form; 3] = [Form::Avx512, Form::Avx2, Form::Portable];

    /// The widest form this CPU runs (the standard library caches the checks).
    pub fn widest() -> Form {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx512f")
                && std::is_x86_feature_detected!("avx512vl")
                && std::is_x86_feature_detected!("avx512bw")
                && std::is_x86_feature_detected!("avx512dq")
            {
                return Form::Avx512;
            }
            if std::is_x86_feature_detected!("avx2") {
                return Form::Avx2;
            }
        }
        Form::Portable
    }

    /// The form the batch calls use: the one chosen ([`Form::choose`]), else the widest this
    /// CPU runs. Never a form the CPU cannot run.
    pub fn current() -> Form {
        match CHOSEN.load(Ordering::Relaxed) {
            0 => Form::widest(),
            k => Form::ALL[usize::from(k - 1)],
        }
    }

    /// Makes the batch calls use `form` (`None`: the widest this CPU runs again).
    ///
    /// # Errors
    /// The form's name and the widest the CPU runs, when the CPU cannot run `form`.
    pub fn choose(form: Option<Form>) -> Result<(), String> {
        let widest = Form::widest();
        match form {
            None => CHOSEN.store(0, Ordering::Relaxed),
            Some(f) if f < widest => {
                return Err(format!(
                    "this CPU cannot run the {} form; the widest it runs is {}",
                    f.name(),
                    widest.name()
                ));
            }
            // The discriminants are the indices in `Form::ALL`.
            Some(f) => CHOSEN.store(f as u8 + 1, Ordering::Relaxed),
        }
        Ok(())
    }

    /// The form's name, as `quadkin.batch_form()` gives it.
    pub fn name(self) -> &'static str {
        match self {
            Form::Avx512 => "avx512",
            Form::Avx2 => "avx2",
            Form::Portable => "portable",
        }
    }

    /// The form of a name of [`Form::name`].
    pub fn from_name(name: &str) -> Option<Form> {
        Form::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// Calls `kin_core::batch::$f` in the form `$form` ([`Form`]) with `$args`.
macro_rules! in_form {
    ($form:expr, $f:ident $(::<$m:ty>)? ($($args:expr),* $(,)?)) => {{
        match $form {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Form::current` is never a form the CPU cannot run.
            #[allow(unsafe_code)]
            Form::Avx512 => unsafe { batch::avx512::$f $(::<$m>)? ($($args),*) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            #[allow(unsafe_code)]
            Form::Avx2 => unsafe { batch::avx2::$f $(::<$m>)? ($($args),*) },
            _ => batch::$f $(::<$m>)? ($($args),*),
        }
    }};
}

/// Runs `solve(input, out, codes)` on the whole batch of `codes.len()` rows, or on slices of
/// [`CHUNK_ROWS`] rows in parallel when there are at least two of them. `input` has `in_w`
/// floats per row, `out` `out_w` (other lengths: one call, which refuses them).
fn split<F>(
    input: &[f32],
    in_w: usize,
    out: &mut [f32],
    out_w: usize,
    codes: &mut [u8],
    solve: F,
) -> Result<(), LengthMismatch>
where
    F: Fn(&[f32], &mut [f32], &mut [u8]) -> Result<(), LengthMismatch> + Sync,
{
    let n = codes.len();
    if n < 2 * CHUNK_ROWS || input.len() != in_w * n || out.len() != out_w * n {
        return solve(input, out, codes);
    }
    input
        .par_chunks(in_w * CHUNK_ROWS)
        .zip(out.par_chunks_mut(out_w * CHUNK_ROWS))
        .zip(codes.par_chunks_mut(CHUNK_ROWS))
        .try_for_each(|((i, o), c)| solve(i, o, c))
}

/// Leg IK of `feet_in_hip_m` (rows of 3) into `angles_rad` (rows of 3) and `codes`, as
/// `kin_core::batch::leg_inverse`.
///
/// # Errors
/// As `kin_core::batch::leg_inverse`.
pub fn leg_inverse(
    solver: &leg::Solver,
    leg: LegId,
    policy: ReachPolicy,
    feet_in_hip_m: &[f32],
    angles_rad: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let form = Form::current();
    split(feet_in_hip_m, 3, angles_rad, 3, codes, |f, a, c| {
        in_form!(form, leg_inverse(solver, leg, policy, f, a, c))
    })
}

/// Leg FK of `angles_rad` (rows of 3) into `feet_in_hip_m` (rows of 3) and `codes`, as
/// `kin_core::batch::leg_forward` on the default backend.
///
/// # Errors
/// As `kin_core::batch::leg_forward`.
pub fn leg_forward(
    geometry: &LegGeometry,
    leg: LegId,
    angles_rad: &[f32],
    feet_in_hip_m: &mut [f32],
    codes: &mut [u8],
) -> Result<(), LengthMismatch> {
    let form = Form::current();
    split(angles_rad, 3, feet_in_hip_m, 3, codes, |q, f, c| {
        in_form!(form, leg_forward::<DefaultMath>(geometry, leg, q, f, c))
    })
}

/// The feet of a body batch: the stance, one set for every pose (12 floats), or one per pose
/// (rows of 12).
#[derive(Clone, Copy)]
pub enum Feet<'a> {
    /// The nominal stance of this height, m.
    Stance(f32),
    /// The same four feet for every pose.
    Same(&'a [kin_core::Vec3; 4]),
    /// Four feet per pose, rows of 12.
    PerPose(&'a [f32]),
}

/// Body IK of `poses` (rows of 6) with `feet` into `angles_rad` (rows of 12), `codes` and
/// `legs`, as `kin_core::batch::body_inverse`.
///
/// # Errors
/// As `kin_core::batch::body_inverse`.
#[allow(clippy::too_many_arguments)] // Poses and feet in, angles, codes and legs out.
pub fn body_inverse(
    solver: &body::Solver,
    config: &BodyConfig,
    policy: ReachPolicy,
    poses: &[f32],
    feet: Feet<'_>,
    angles_rad: &mut [f32],
    codes: &mut [u8],
    legs: &mut [i8],
) -> Result<(), LengthMismatch> {
    let form = Form::current();
    // Per-pose feet are split with the poses: their slice of rows goes with each slice.
    let n = codes.len();
    let per_pose = match feet {
        Feet::PerPose(f) => Some(f),
        _ => None,
    };
    let solve = |first_row: usize, p: &[f32], a: &mut [f32], c: &mut [u8], l: &mut [i8]| {
        let f = match feet {
            Feet::Stance(h) => BodyFeet::Stance { height_m: h },
            Feet::Same(f) => BodyFeet::Same(f),
            Feet::PerPose(f) => {
                let end = (12 * (first_row + c.len())).min(f.len());
                BodyFeet::PerPose(&f[(12 * first_row).min(end)..end])
            }
        };
        in_form!(form, body_inverse(solver, config, policy, p, f, a, c, l))
    };
    if let Some(f) = per_pose {
        if f.len() != 12 * n {
            return Err(LengthMismatch {
                what: "feet_in_world_m",
                expected: 12 * n,
                got: f.len(),
            });
        }
    }
    if n < 2 * CHUNK_ROWS || poses.len() != 6 * n || angles_rad.len() != 12 * n {
        return solve(0, poses, angles_rad, codes, legs);
    }
    poses
        .par_chunks(6 * CHUNK_ROWS)
        .zip(angles_rad.par_chunks_mut(12 * CHUNK_ROWS))
        .zip(codes.par_chunks_mut(CHUNK_ROWS))
        .zip(legs.par_chunks_mut(CHUNK_ROWS))
        .enumerate()
        .try_for_each(|(k, (((p, a), c), l))| solve(k * CHUNK_ROWS, p, a, c, l))
}
