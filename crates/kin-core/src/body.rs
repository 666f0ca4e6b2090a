//! Full-body kinematics: body pose + four feet in the world frame ↔ twelve joint angles.
//!
//! The world frame coincides with the body frame in the nominal pose. A [`Pose`] gives the
//! body's roll, pitch, yaw (rad, combined in a [`RotationOrder`]) and its translation `t` (m).
//! With an optional pivot `c` (body frame; seed 000's code rotates about an offset centre):
//!
//! - `foot_in_hip = Rᵀ·(foot_in_world − t − c) + c − hip_in_body` (inverse)
//! - `foot_in_world = R·(hip_in_body + foot_in_hip − c) + c + t` (forward)

use crate::leg::{self, IkError, LegSolution, ReachPolicy};
use crate::math::{cmp, DefaultMath, Math};
use crate::robot::{JointAngles, LegId, Robot};
use crate::rotation::{self, RotationOrder};
use crate::vec::{Mat3, Vec3};

/// Body pose relative to the world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pose {
    /// Rotation about x, rad.
    pub roll_rad: f32,
    /// Rotation about y, rad.
    pub pitch_rad: f32,
    /// Rotation about z, rad.
    pub yaw_rad: f32,
    /// Translation x, m.
    pub x_m: f32,
    /// Translation y, m.
    pub y_m: f32,
    /// Translation z, m.
    pub z_m: f32,
}

impl Pose {
    /// A pure rotation.
    pub const fn rotation(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Pose {
        Pose {
            roll_rad,
            pitch_rad,
            yaw_rad,
            x_m: 0.0,
            y_m: 0.0,
            z_m: 0.0,
        }
    }

    /// `[roll, pitch, yaw, x, y, z]`.
    pub const fn to_array(self) -> [f32; 6] {
        [
            self.roll_rad,
            self.pitch_rad,
            self.yaw_rad,
            self.x_m,
            self.y_m,
            self.z_m,
        ]
    }

    /// From `[roll, pitch, yaw, x, y, z]`.
    pub const fn from_array(a: [f32; 6]) -> Pose {
        Pose {
            roll_rad: a[0],
            pitch_rad: a[1],
            yaw_rad: a[2],
            x_m: a[3],
            y_m: a[4],
            z_m: a[5],
        }
    }

    /// True when all six values are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.to_array().iter().all(|v| v.is_finite())
    }

    /// The translation `(x, y, z)`.
    pub const fn translation(self) -> Vec3 {
        Vec3::new(self.x_m, self.y_m, self.z_m)
    }
}

/// How a pose is interpreted.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BodyConfig {
    /// Rotation order.
    pub order: RotationOrder,
    /// Pivot of the rotation in the body frame, m (zero: the body centre).
    pub pivot_m: Vec3,
}

/// Twelve joint angles, in leg order FL, FR, RL, RR.
pub type BodyAngles = [JointAngles; 4];

/// Result of a full-body IK.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodySolution {
    /// Per-leg solutions in order FL, FR, RL, RR.
    pub legs: [LegSolution; 4],
}

impl BodySolution {
    /// The twelve angles.
    pub fn angles(&self) -> BodyAngles {
        self.legs.map(|l| l.angles)
    }

    /// The twelve angles flattened `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`.
    #[inline]
    pub fn flat(&self) -> [f32; 12] {
        let mut out = [0.0; 12];
        for (o, l) in out.chunks_exact_mut(3).zip(&self.legs) {
            o.copy_from_slice(&l.angles.to_array());
        }
        out
    }

    /// True when any leg was clamped.
    pub fn any_clamped(&self) -> bool {
        self.legs.iter().any(|l| l.clamped.is_some())
    }
}

/// Flattens four legs' angles into `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`.
pub fn flatten(angles: &BodyAngles) -> [f32; 12] {
    let mut out = [0.0; 12];
    for (i, a) in angles.iter().enumerate() {
        out[3 * i..3 * i + 3].copy_from_slice(&a.to_array());
    }
    out
}

/// Inverse of [`flatten`].
pub fn unflatten(flat: &[f32; 12]) -> BodyAngles {
    core::array::from_fn(|i| JointAngles::new(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]))
}

/// Full-body IK with the robot's constants prepared once (the leg IK's [`leg::Solver`], the
/// hip mounts). The free functions ([`inverse_with`], [`inverse_at_stance_with`], …) build
/// one per call; a caller that solves many poses of one robot keeps one:
///
/// ```
/// use kin_core::{body, BodyConfig, Pose, ReachPolicy, Robot};
/// let solver = body::Solver::new(&Robot::shahriar2023());
/// let pose = Pose::rotation(0.1, -0.05, 0.2);
/// let q = solver.inverse_at_stance(&pose, &BodyConfig::default(), 0.277, ReachPolicy::Reject)?;
/// # Ok::<(), kin_core::IkError>(())
/// ```
///
/// Results are bit for bit those of the free functions. [`Solver::new`] is a `const fn`, so a
/// firmware can build its solver at compile time:
///
/// ```
/// use kin_core::{body, Robot};
/// const SOLVER: body::Solver = body::Solver::new(&Robot::shahriar2023());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solver {
    leg: leg::Solver,
    /// `length/2` and `width/2`: the hip mounts are `(±length/2, ±width/2, 0)`.
    half_length_m: f32,
    half_width_m: f32,
    /// `width/2 + d_lat`: the stance foot's lateral distance from the body's centre line.
    stance_lateral_m: f32,
}

/// True when `v` is (±0, ±0, ±0), from the bits (no float comparison).
#[inline(always)]
fn is_zero(v: Vec3) -> bool {
    const ABS: u32 = 0x7fff_ffff;
    (v.x.to_bits() | v.y.to_bits() | v.z.to_bits()) & ABS == 0
}

impl Solver {
    /// The constants of `robot`.
    #[inline]
    pub const fn new(robot: &Robot) -> Solver {
        let half_width_m = 0.5 * robot.body_width_m;
        Solver {
            leg: leg::Solver::new(robot),
            half_length_m: 0.5 * robot.body_length_m,
            half_width_m,
            stance_lateral_m: half_width_m + robot.leg.d_lat_m,
        }
    }

    /// The leg IK of this robot.
    #[inline]
    pub fn leg(&self) -> &leg::Solver {
        &self.leg
    }

    /// Hip mount of `leg` in the body frame, as [`Robot::hip_in_body`].
    #[inline(always)]
    fn hip_in_body(&self, leg: LegId) -> Vec3 {
        let x = if leg.is_front() {
            self.half_length_m
        } else {
            -self.half_length_m
        };
        let y = if leg.is_left() {
            self.half_width_m
        } else {
            -self.half_width_m
        };
        Vec3::new(x, y, 0.0)
    }

    /// Feet in the world frame → feet in each leg's hip frame:
    /// `Rᵀ·(foot_in_world − t − c) + c − hip_in_body`.
    #[inline]
    pub fn feet_in_hips_with<M: Math>(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
    ) -> [Vec3; 4] {
        let r: Mat3 =
            rotation::matrix_with::<M>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
        let c = config.pivot_m;
        let pivot = !is_zero(c);
        let offset = if pivot {
            pose.translation() + c
        } else {
            pose.translation()
        };
        // A plain loop rather than `LegId::ALL.map(..)`, whose closure the compiler may leave
        // as a call per leg that returns through memory.
        let mut out = [Vec3::ZERO; 4];
        for (i, leg) in LegId::ALL.into_iter().enumerate() {
            let mut p = r.transpose_mul_vec(feet_in_world[i] - offset);
            if pivot {
                p = p + c;
            }
            let hip = self.hip_in_body(leg);
            out[i] = Vec3::new(p.x - hip.x, p.y - hip.y, p.z);
        }
        out
    }

    /// The feet of the nominal stance of height `stance_height_m`
    /// (`foot_in_world = hip_in_body + (0, s·d_lat, −H)`) in each leg's hip frame: the
    /// transform of [`Solver::feet_in_hips_with`] in closed form. With `R`'s rows `r₀, r₁, r₂`,
    /// `foot_in_hip = sx·(L/2·r₀ − (L/2, 0, 0)) + s·((W/2 + d_lat)·r₁ − (0, W/2, 0)) − K` for the
    /// front/rear sign `sx`, the side sign `s` and `K = Rᵀ·(t + c + (0, 0, H)) − c`: 15
    /// multiplications and 27 additions for the four feet (9 and 20 without translation and
    /// pivot) instead of 36 and 60.
    #[inline]
    pub fn stance_feet_in_hips_with<M: Math>(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
    ) -> [Vec3; 4] {
        let r: Mat3 =
            rotation::matrix_with::<M>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
        let [r0, r1, r2] = r.rows.map(Vec3::from_array);
        let c = config.pivot_m;
        let pivot = !is_zero(c);
        let t = pose.translation();
        // K = Rᵀ·(t + c) + H·r₂ − c.
        // The ATmega2560 keeps only the general arm (-168 B of flash): the same feet, but for
        // the sign of a component that is zero in both.
        let k = if !cfg!(target_arch = "avr") && !pivot && is_zero(t) {
            r2 * stance_height_m
        } else {
            let g = if pivot { t + c } else { t };
            let k = r.transpose_mul_vec(Vec3::new(g.x, g.y, g.z + stance_height_m));
            if pivot {
                k - c
            } else {
                k
            }
        };
        let hl = self.half_length_m;
        let a = r0 * hl;
        let a = Vec3::new(a.x - hl, a.y, a.z);
        let b = r1 * self.stance_lateral_m;
        let b = Vec3::new(b.x, b.y - self.half_width_m, b.z);
        // Front: a − K ± b; rear: −(a + K) ± b (left +, right −).
        let front = a - k;
        let rear = -(a + k);
        [front + b, front - b, rear + b, rear - b]
    }

    /// Full-body IK: all-or-nothing. The first leg (in order FL, FR, RL, RR) that cannot reach
    /// rejects the pose and is named in the error.
    #[inline]
    pub fn inverse_with<M: Math>(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        check_finite(pose, config)?;
        let local = self.feet_in_hips_with::<M>(pose, config, feet_in_world);
        self.legs::<M>(&local, policy)
    }

    /// [`Solver::inverse_with`] on the [`DefaultMath`] backend.
    #[inline]
    pub fn inverse(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        self.inverse_with::<DefaultMath>(pose, config, feet_in_world, policy)
    }

    /// Body pose with the feet held at the nominal stance of height `stance_height_m`
    /// (through [`Solver::stance_feet_in_hips_with`]).
    #[inline]
    pub fn inverse_at_stance_with<M: Math>(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        check_finite(pose, config)?;
        let local = self.stance_feet_in_hips_with::<M>(pose, config, stance_height_m);
        self.legs::<M>(&local, policy)
    }

    /// [`Solver::inverse_at_stance_with`] on the [`DefaultMath`] backend.
    #[inline]
    pub fn inverse_at_stance(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        self.inverse_at_stance_with::<DefaultMath>(pose, config, stance_height_m, policy)
    }

    /// The four leg solves of feet already in their hips' frames (from
    /// [`Solver::feet_in_hips_with`] or [`Solver::stance_feet_in_hips_with`]):
    /// [`Solver::inverse_with`] is [`check_finite`], [`Solver::feet_in_hips_with`] and this.
    #[inline]
    pub fn inverse_in_hips_with<M: Math>(
        &self,
        feet_in_hips: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        self.legs::<M>(feet_in_hips, policy)
    }

    /// The four leg solves of a body pose.
    #[inline(always)]
    fn legs<M: Math>(
        &self,
        local: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        // Hosts run the four legs interleaved (out-of-order CPUs overlap their dependency
        // chains); the in-order AVR would gain nothing and carry a second copy of the leg
        // solver (≈ 4 KB of flash), so it solves them one by one (the same results, bit for
        // bit).
        #[cfg(not(target_arch = "avr"))]
        if policy == ReachPolicy::Reject {
            if let Some(angles) = self.leg.inverse_all_reject::<M>(local) {
                return Ok(BodySolution {
                    legs: angles.map(|angles| LegSolution {
                        angles,
                        clamped: None,
                    }),
                });
            }
        }
        self.legs_one_by_one::<M>(local, policy)
    }

    /// The four leg solves in order FL, FR, RL, RR, stopping at the first failure (on hosts,
    /// the fallback of the interleaved path that names the failing leg).
    #[inline]
    fn legs_one_by_one<M: Math>(
        &self,
        local: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        // One expression, so that each leg's solution is written in place (no copies of the
        // 64-byte result through memory).
        let solve = |leg: LegId| self.leg.inverse_with::<M>(leg, local[leg.index()], policy);
        Ok(BodySolution {
            legs: [
                solve(LegId::FL)?,
                solve(LegId::FR)?,
                solve(LegId::RL)?,
                solve(LegId::RR)?,
            ],
        })
    }
}

/// `NonFinite` (named on FL) when the pose or the pivot is not finite: the first check of
/// [`Solver::inverse_with`] and [`Solver::inverse_at_stance_with`].
///
/// # Errors
/// `NonFinite` on [`LegId::FL`].
#[inline(always)]
pub fn check_finite(pose: &Pose, config: &BodyConfig) -> Result<(), IkError> {
    let p = config.pivot_m;
    let finite = pose.to_array().iter().all(|&v| cmp::finite(v))
        && cmp::finite(p.x)
        && cmp::finite(p.y)
        && cmp::finite(p.z);
    if finite {
        Ok(())
    } else {
        Err(IkError {
            leg: LegId::FL,
            kind: leg::Unreachable::NonFinite,
        })
    }
}

/// Feet in the world frame → feet in each leg's hip frame ([`Solver::feet_in_hips_with`]).
#[inline]
pub fn feet_in_hips_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
) -> [Vec3; 4] {
    Solver::new(robot).feet_in_hips_with::<M>(pose, config, feet_in_world)
}

/// Full-body IK: all-or-nothing. The first leg (in order FL, FR, RL, RR) that cannot reach
/// rejects the pose and is named in the error. Computes the robot's constants each call;
/// [`Solver`] keeps them.
#[inline]
pub fn inverse_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    Solver::new(robot).inverse_with::<M>(pose, config, feet_in_world, policy)
}

/// [`inverse_with`] on the [`DefaultMath`] backend.
#[inline]
pub fn inverse(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    inverse_with::<DefaultMath>(robot, pose, config, feet_in_world, policy)
}

/// Body pose with the feet held at the nominal stance of height `stance_height_m`
/// ([`Robot::stance_feet`]), through the closed-form transform of
/// [`Solver::stance_feet_in_hips_with`] (the same angles as [`inverse_with`] with those feet
/// up to f32 rounding).
#[inline]
pub fn inverse_at_stance_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    stance_height_m: f32,
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    Solver::new(robot).inverse_at_stance_with::<M>(pose, config, stance_height_m, policy)
}

/// [`inverse_at_stance_with`] on the [`DefaultMath`] backend.
#[inline]
pub fn inverse_at_stance(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    stance_height_m: f32,
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    inverse_at_stance_with::<DefaultMath>(robot, pose, config, stance_height_m, policy)
}

/// Full-body FK: pose + twelve angles → the four feet in the world frame.
pub fn forward(robot: &Robot, pose: &Pose, config: &BodyConfig, angles: &BodyAngles) -> [Vec3; 4] {
    let r = rotation::matrix(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
    LegId::ALL.map(|leg| {
        let foot_in_hip = leg::forward(&robot.leg, leg, angles[leg.index()]);
        r.mul_vec(robot.hip_in_body(leg) + foot_in_hip - config.pivot_m)
            + config.pivot_m
            + pose.translation()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::KneeBend;

    /// A tiny seeded generator for test inputs (SplitMix64), uniform in `[lo, hi)`.
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            lo + (hi - lo) * ((z >> 40) as f32 / (1u64 << 24) as f32)
        }
    }

    /// The closed-form stance transform equals the general transform of the stance feet (f32
    /// rounding apart), with and without translation and pivot, in every order.
    #[test]
    fn stance_transform_equals_general_transform() {
        /// Largest difference, m: a few f32 ulp of half-metre coordinates.
        const TOL_M: f32 = 2e-7;
        let mut rng = Rng(11);
        for robot in [Robot::shahriar2023(), Robot::fernando2025()] {
            let solver = Solver::new(&robot);
            let height_m = 0.75 * (robot.leg.femur_m + robot.leg.tibia_m);
            let feet = robot.stance_feet(height_m);
            for order in RotationOrder::ALL {
                for case in 0..100 {
                    let mut pose = Pose::rotation(
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.6, 0.6),
                    );
                    let mut config = BodyConfig {
                        order,
                        pivot_m: Vec3::ZERO,
                    };
                    if case % 2 == 1 {
                        (pose.x_m, pose.y_m, pose.z_m) = (
                            rng.uniform(-0.3, 0.3),
                            rng.uniform(-0.3, 0.3),
                            rng.uniform(-0.3, 0.3),
                        );
                    }
                    if case % 4 >= 2 {
                        config.pivot_m =
                            Vec3::new(rng.uniform(-0.1, 0.1), 0.0, rng.uniform(-0.1, 0.1));
                    }
                    let fast =
                        solver.stance_feet_in_hips_with::<DefaultMath>(&pose, &config, height_m);
                    let general = solver.feet_in_hips_with::<DefaultMath>(&pose, &config, &feet);
                    for (a, b) in fast.iter().zip(&general) {
                        let d = *a - *b;
                        let worst = d.x.abs().max(d.y.abs()).max(d.z.abs());
                        assert!(worst < TOL_M, "{order} {pose:?} {config:?}: {a:?} vs {b:?}");
                    }
                }
            }
        }
    }

    /// A kept [`Solver`] gives exactly the free functions' results.
    #[test]
    fn solver_equals_free_functions() {
        let mut rng = Rng(5);
        for robot in [Robot::shahriar2023(), Robot::fernando2025()] {
            let solver = Solver::new(&robot);
            let height_m = 0.75 * (robot.leg.femur_m + robot.leg.tibia_m);
            for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
                for _ in 0..200 {
                    let pose = Pose {
                        roll_rad: rng.uniform(-0.6, 0.6),
                        pitch_rad: rng.uniform(-0.6, 0.6),
                        yaw_rad: rng.uniform(-0.6, 0.6),
                        x_m: rng.uniform(-0.3, 0.3),
                        y_m: rng.uniform(-0.3, 0.3),
                        z_m: rng.uniform(-0.3, 0.3),
                    };
                    let config = BodyConfig::default();
                    assert_eq!(
                        solver.inverse_at_stance(&pose, &config, height_m, policy),
                        inverse_at_stance(&robot, &pose, &config, height_m, policy)
                    );
                    let feet = robot.stance_feet(height_m);
                    assert_eq!(
                        solver.inverse(&pose, &config, &feet, policy),
                        inverse(&robot, &pose, &config, &feet, policy)
                    );
                    let foot = Vec3::new(
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.9, 0.1),
                    );
                    for leg in LegId::ALL {
                        assert_eq!(
                            solver.leg().inverse(leg, foot, policy),
                            leg::inverse(&robot, leg, foot, policy)
                        );
                    }
                }
            }
        }
    }

    /// The four-leg fast path of the body IK (Reject) gives exactly the per-leg results, and
    /// the same first error when a leg cannot reach.
    #[test]
    fn body_ik_equals_leg_by_leg_ik_bit_for_bit() {
        let mut rng = Rng(7);
        let (mut solved, mut rejected) = (0, 0);
        for robot in [Robot::shahriar2023(), Robot::fernando2025()] {
            for bend in [KneeBend::Backward, KneeBend::Forward] {
                let robot = robot.with_knee_bend(bend);
                let height_m = 0.75 * (robot.leg.femur_m + robot.leg.tibia_m);
                for order in RotationOrder::ALL {
                    for _ in 0..200 {
                        let pose = Pose {
                            roll_rad: rng.uniform(-0.6, 0.6),
                            pitch_rad: rng.uniform(-0.6, 0.6),
                            yaw_rad: rng.uniform(-0.6, 0.6),
                            x_m: rng.uniform(-0.3, 0.3),
                            y_m: rng.uniform(-0.3, 0.3),
                            z_m: rng.uniform(-0.3, 0.3),
                        };
                        let config = BodyConfig {
                            order,
                            pivot_m: Vec3::new(rng.uniform(-0.1, 0.1), 0.0, rng.uniform(-0.1, 0.1)),
                        };
                        let feet = robot.stance_feet(height_m);
                        let local = feet_in_hips_with::<DefaultMath>(&robot, &pose, &config, &feet);
                        let one_by_one: Result<[LegSolution; 4], IkError> = (|| {
                            let mut legs = [LegSolution {
                                angles: JointAngles::default(),
                                clamped: None,
                            }; 4];
                            for leg in LegId::ALL {
                                legs[leg.index()] = leg::inverse(
                                    &robot,
                                    leg,
                                    local[leg.index()],
                                    ReachPolicy::Reject,
                                )?;
                            }
                            Ok(legs)
                        })(
                        );
                        let body = inverse(&robot, &pose, &config, &feet, ReachPolicy::Reject);
                        match (body, one_by_one) {
                            (Ok(b), Ok(l)) => {
                                solved += 1;
                                for (x, y) in b.legs.iter().zip(&l) {
                                    assert_eq!(
                                        x.angles.to_array().map(f32::to_bits),
                                        y.angles.to_array().map(f32::to_bits)
                                    );
                                }
                            }
                            (Err(b), Err(l)) => {
                                rejected += 1;
                                assert_eq!(b, l);
                            }
                            (b, l) => panic!("body {b:?} vs legs {l:?}"),
                        }
                    }
                }
            }
        }
        assert!(
            solved > 1000 && rejected > 100,
            "solved {solved}, rejected {rejected}"
        );
    }
}
