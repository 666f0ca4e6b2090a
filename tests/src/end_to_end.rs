//! The firmware's IK end to end: random body poses and foot targets over the whole workspace of
//! the preset the firmware carries (seed 000's robot), every rotation order and both reach
//! policies, solved by the firmware's solver (`body::Solver` on `AvrFast`, as the device
//! builds it) in simavr through the test harness firmware's pose batch (`P`), and compared with
//!
//! - the host's `SoftFloat` path (kin-core with the same kernels on the host): the same verdict
//!   (solved, refused, the legs clamped) and the share of bit-identical angles;
//! - an f64 reference for every solved target that was not clamped: Newton iterations on an
//!   f64 forward kinematics of the chain, independent of kin-core's closed form, to a foot
//!   residual below 1e-12 m. An error above [`TOLERANCE_RAD`] is an outlier.
//!
//! The CI runs a seeded share (`tests/avr_end_to_end.rs`); `cargo xtask kernel-campaign
//! --poses N` runs the long one.

use crate::avr_bench::{fk64, max_abs_diff, reference_leg_checked};
use crate::kernels::Harness;
use kin_core::math::SoftFloat;
use kin_core::{body, BodyConfig, LegId, Pose, ReachPolicy, Robot, RotationOrder, Vec3};
use nalgebra::{Matrix3, Vector3};
use seeded_rng::SplitMix64;

/// The bound of the angle error against f64: 0.01°, rad.
pub const TOLERANCE_RAD: f64 = 0.01 * std::f64::consts::PI / 180.0;

/// What is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A body pose at a stance height, m.
    Body(Pose, f32),
    /// One leg's foot in its hip frame, m.
    Leg(LegId, Vec3),
}

/// One case: a target, a rotation order (bodies), a reach policy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// The target.
    pub target: Target,
    /// The rotation order (body poses).
    pub order: RotationOrder,
    /// The reach policy.
    pub policy: ReachPolicy,
}

/// A solver's answer: `None` refused, else the angles (3 for a leg, 12 for a body) and the
/// legs clamped (bit per leg).
pub type Answer = Option<(Vec<f32>, u8)>;

/// A random case over the preset's workspace: body poses with rotations within ±45°
/// (each axis), translations within ±0.1 m and stance heights from 0.05 m to the leg's span;
/// foot targets anywhere in a box of the span around the hip; both kinds equally often.
pub fn random_case(robot: &Robot, rng: &mut SplitMix64) -> Case {
    let span = f64::from(robot.leg.femur_m + robot.leg.tibia_m + robot.leg.d_lat_m);
    let order = RotationOrder::ALL[(rng.next_u64() % 6) as usize];
    let policy = if rng.next_u64() & 1 == 0 {
        ReachPolicy::Reject
    } else {
        ReachPolicy::Clamp
    };
    let target = if rng.next_u64() & 1 == 0 {
        let quarter = std::f64::consts::FRAC_PI_4;
        let [r, p, y] = [0; 3].map(|_| rng.range(-quarter, quarter) as f32);
        let [x, yy, z] = [0; 3].map(|_| rng.range(-0.1, 0.1) as f32);
        let stance = rng.range(0.05, span) as f32;
        Target::Body(
            Pose {
                roll_rad: r,
                pitch_rad: p,
                yaw_rad: y,
                x_m: x,
                y_m: yy,
                z_m: z,
            },
            stance,
        )
    } else {
        let leg = LegId::ALL[(rng.next_u64() % 4) as usize];
        let [x, y, z] = [0; 3].map(|_| rng.range(-span, span) as f32);
        Target::Leg(leg, Vec3::new(x, y, z))
    };
    Case {
        target,
        order,
        policy,
    }
}

/// The host's `SoftFloat` answer to `case`.
pub fn host_answer(solver: &body::Solver<SoftFloat>, case: &Case) -> Answer {
    match case.target {
        Target::Body(pose, stance) => solver
            .inverse_at_stance(
                &pose,
                &BodyConfig::about_centre(case.order),
                stance,
                case.policy,
            )
            .ok()
            .map(|s| {
                let clamped = s
                    .clamped
                    .iter()
                    .enumerate()
                    .fold(0u8, |m, (i, c)| m | (u8::from(c.is_some()) << i));
                (s.angles_rad.to_vec(), clamped)
            }),
        Target::Leg(leg, foot) => solver
            .leg()
            .inverse(leg, foot, case.policy)
            .ok()
            .map(|s| (s.angles.to_array().to_vec(), u8::from(s.clamped.is_some()))),
    }
}

/// The firmware's answers to `cases`, solved in simavr in batches.
pub fn firmware_answers(harness: &mut Harness, cases: &[Case]) -> Vec<Answer> {
    let records: Vec<[u32; 13]> = cases.iter().map(record).collect();
    harness
        .run_poses(&records)
        .into_iter()
        .zip(cases)
        .map(|(r, case)| {
            let status = r[0].to_le_bytes()[3];
            let n = match case.target {
                Target::Body(..) => 12,
                Target::Leg(..) => 3,
            };
            (status & 1 == 0).then(|| {
                (
                    r[1..1 + n].iter().map(|&w| f32::from_bits(w)).collect(),
                    status >> 4,
                )
            })
        })
        .collect()
}

fn record(case: &Case) -> [u32; 13] {
    let order = RotationOrder::ALL
        .iter()
        .position(|&o| o == case.order)
        .expect("an order") as u8;
    let policy = u8::from(case.policy == ReachPolicy::Clamp);
    let mut r = [0u32; 13];
    let floats: Vec<f32> = match case.target {
        Target::Body(p, stance) => {
            r[0] = u32::from_le_bytes([255, order, policy, 0]);
            let mut v = p.to_array().to_vec();
            v.push(stance);
            v
        }
        Target::Leg(leg, foot) => {
            r[0] = u32::from_le_bytes([leg.index() as u8, order, policy, 0]);
            foot.to_array().to_vec()
        }
    };
    for (w, f) in r[1..].iter_mut().zip(floats) {
        *w = f.to_bits();
    }
    r
}

/// The elementary rotation about `axis` (0 x, 1 y, 2 z) by `angle`, f64.
fn elementary(axis: u8, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    match axis {
        0 => Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c),
        1 => Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c),
        _ => Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
    }
}

/// The f64 targets of `case`: per leg solved, its foot in its hip frame (one leg, or the four
/// of a body pose in order FL, FR, RL, RR), computed in f64 from the case's f32 values.
pub fn targets(robot: &Robot, case: &Case) -> Vec<(LegId, Vector3<f64>)> {
    match case.target {
        Target::Leg(leg, foot) => vec![(
            leg,
            Vector3::new(f64::from(foot.x), f64::from(foot.y), f64::from(foot.z)),
        )],
        Target::Body(pose, stance) => {
            let angles = [
                f64::from(pose.roll_rad),
                f64::from(pose.pitch_rad),
                f64::from(pose.yaw_rad),
            ];
            let rot = case.order.axes().iter().fold(Matrix3::identity(), |m, &a| {
                m * elementary(a, angles[usize::from(a)])
            });
            let t = Vector3::new(
                f64::from(pose.x_m),
                f64::from(pose.y_m),
                f64::from(pose.z_m),
            );
            LegId::ALL
                .iter()
                .map(|&leg| {
                    let hip = robot.hip_in_body(leg);
                    let hip = Vector3::new(f64::from(hip.x), f64::from(hip.y), f64::from(hip.z));
                    let foot_world = hip
                        + Vector3::new(
                            0.0,
                            f64::from(leg.side()) * f64::from(robot.leg.d_lat_m),
                            -f64::from(stance),
                        );
                    (leg, rot.transpose() * (foot_world - t) - hip)
                })
                .collect()
        }
    }
}

/// The f64 angles of a solved, unclamped `case` from the firmware's `start`: `None` when the
/// reference does not converge (a target at a singularity).
pub fn reference(robot: &Robot, case: &Case, start: &[f32]) -> Option<Vec<f64>> {
    let mut out = Vec::with_capacity(start.len());
    for (i, (leg, foot)) in targets(robot, case).into_iter().enumerate() {
        let q = reference_leg_checked(
            robot,
            leg,
            foot,
            [start[3 * i], start[3 * i + 1], start[3 * i + 2]],
        )?;
        out.extend(q);
    }
    Some(out)
}

/// The largest distance, m, between the feet that `angles` put (f64 forward kinematics) and
/// the f64 targets of `case`; with it, the smallest depth of a foot below its abduction offset
/// (`√(y² + z² − d_lat²)` in the hip frame), m: the IK's abduction angle is ill-conditioned as
/// that depth goes to 0 (an angle error of about the foot's rounding divided by it).
pub fn foot_error(robot: &Robot, case: &Case, angles: &[f32]) -> (f64, f64) {
    let d_lat = f64::from(robot.leg.d_lat_m);
    targets(robot, case).into_iter().enumerate().fold(
        (0.0, f64::INFINITY),
        |(err, depth), (i, (leg, foot))| {
            let q = Vector3::new(
                f64::from(angles[3 * i]),
                f64::from(angles[3 * i + 1]),
                f64::from(angles[3 * i + 2]),
            );
            let e = (fk64(robot, leg, q) - foot).norm();
            let w = (foot.y * foot.y + foot.z * foot.z - d_lat * d_lat)
                .max(0.0)
                .sqrt();
            (err.max(e), depth.min(w))
        },
    )
}

/// Figures of an end-to-end run.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Figures {
    /// Cases run.
    pub cases: u64,
    /// Body poses among them.
    pub bodies: u64,
    /// Cases the firmware solved (clamped included).
    pub solved: u64,
    /// Of those, clamped.
    pub clamped: u64,
    /// Cases whose verdict (solved, refused, clamped legs) differs from the host's.
    pub verdict_differences: u64,
    /// Solved cases whose angles are the host's bits.
    pub bit_identical: u64,
    /// Largest angle difference to the host, rad.
    pub max_host_difference_rad: f64,
    /// Solved unclamped cases compared with the f64 reference.
    pub referenced: u64,
    /// Of the solved unclamped ones, those whose reference did not converge.
    pub reference_failures: u64,
    /// Largest error against the f64 reference, rad.
    pub max_error_rad: f64,
    /// Errors above [`TOLERANCE_RAD`].
    pub outliers: u64,
    /// Largest distance between the feet the firmware's angles put (f64 forward kinematics)
    /// and the f64 targets, over the referenced cases, m.
    pub max_foot_error_m: f64,
    /// The first differences and outliers, described.
    pub first_findings: Vec<String>,
}

impl Figures {
    /// The share of solved cases that are bit-identical to the host's.
    pub fn bit_identical_share(&self) -> f64 {
        self.bit_identical as f64 / self.solved.max(1) as f64
    }

    fn note(&mut self, s: String) {
        if self.first_findings.len() < 20 {
            self.first_findings.push(s);
        }
    }
}

/// Runs `n` seeded random cases (seed `seed`) through the firmware and the host, in chunks,
/// calling `progress` after each chunk.
pub fn run(
    harness: &mut Harness,
    n: u64,
    seed: u64,
    mut progress: impl FnMut(&Figures),
) -> Figures {
    let robot = Robot::shahriar2023();
    let host = body::Solver::<SoftFloat>::with_math(&robot);
    let mut rng = SplitMix64::new(seed);
    let mut fig = Figures::default();
    let mut left = n;
    while left > 0 {
        let chunk = left.min(4096);
        left -= chunk;
        let cases: Vec<Case> = (0..chunk).map(|_| random_case(&robot, &mut rng)).collect();
        let answers = firmware_answers(harness, &cases);
        for (case, avr) in cases.iter().zip(answers) {
            fig.cases += 1;
            fig.bodies += u64::from(matches!(case.target, Target::Body(..)));
            let want = host_answer(&host, case);
            let same_verdict = match (&avr, &want) {
                (None, None) => true,
                (Some((_, ca)), Some((_, cw))) => ca == cw,
                _ => false,
            };
            if !same_verdict {
                fig.verdict_differences += 1;
                fig.note(format!("verdict {case:?}: firmware {avr:?}, host {want:?}"));
            }
            let Some((angles, clamped)) = avr else {
                continue;
            };
            fig.solved += 1;
            fig.clamped += u64::from(clamped != 0);
            if let Some((host_angles, _)) = &want {
                if angles
                    .iter()
                    .zip(host_angles)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
                {
                    fig.bit_identical += 1;
                }
                let d = angles
                    .iter()
                    .zip(host_angles)
                    .map(|(a, b)| f64::from((a - b).abs()))
                    .fold(0.0, f64::max);
                fig.max_host_difference_rad = fig.max_host_difference_rad.max(d);
            }
            if clamped != 0 {
                continue;
            }
            match reference(&robot, case, &angles) {
                Some(q) => {
                    fig.referenced += 1;
                    let e = max_abs_diff(&angles, &q);
                    fig.max_error_rad = fig.max_error_rad.max(e);
                    let (foot_err, depth) = foot_error(&robot, case, &angles);
                    fig.max_foot_error_m = fig.max_foot_error_m.max(foot_err);
                    if e > TOLERANCE_RAD {
                        fig.outliers += 1;
                        fig.note(format!(
                            "error {e:e} rad (feet within {foot_err:e} m of their targets, the \
                             shallowest {depth:e} m below its abduction offset) {case:?}: \
                             firmware {angles:?}, f64 {q:?}"
                        ));
                    }
                }
                None => fig.reference_failures += 1,
            }
        }
        progress(&fig);
    }
    fig
}
