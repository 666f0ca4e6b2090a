//! Full-body kinematics: body pose + four feet in the world frame ↔ twelve joint angles.
//!
//! The world frame coincides with the body frame in the nominal pose. A [`Pose`] gives the
//! body's roll, pitch, yaw (rad, combined in a [`RotationOrder`]) and its translation `t` (m).
//! With an optional pivot `c` (body frame; seed 000's code rotates about an offset centre):
//!
//! - `foot_in_hip = Rᵀ·(foot_in_world − t − c) + c − hip_in_body` (inverse)
//! - `foot_in_world = R·(hip_in_body + foot_in_hip − c) + c + t` (forward)

use crate::leg::{self, IkError, LegSolution, ReachPolicy};
use crate::math::{DefaultMath, Math};
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
    pub fn flat(&self) -> [f32; 12] {
        flatten(&self.angles())
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

/// Feet in the world frame → feet in each leg's hip frame.
#[inline]
pub fn feet_in_hips_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
) -> [Vec3; 4] {
    let r: Mat3 =
        rotation::matrix_with::<M>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
    let offset = pose.translation() + config.pivot_m;
    // A plain loop rather than `LegId::ALL.map(..)`, whose closure the compiler may leave as a
    // call per leg that returns through memory.
    let mut out = [Vec3::ZERO; 4];
    for (i, leg) in LegId::ALL.into_iter().enumerate() {
        out[i] = r.transpose_mul_vec(feet_in_world[i] - offset) + config.pivot_m
            - robot.hip_in_body(leg);
    }
    out
}

/// Full-body IK: all-or-nothing. The first leg (in order FL, FR, RL, RR) that cannot reach
/// rejects the pose and is named in the error.
#[inline]
pub fn inverse_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    if !pose.is_finite() || !config.pivot_m.is_finite() {
        return Err(IkError {
            leg: LegId::FL,
            kind: leg::Unreachable::NonFinite,
        });
    }
    let local = feet_in_hips_with::<M>(robot, pose, config, feet_in_world);
    // Hosts run the four legs interleaved (out-of-order CPUs overlap their dependency chains);
    // the in-order AVR would gain nothing and carry a second copy of the leg solver (≈ 4 KB
    // of flash), so it solves them one by one (the same results, bit for bit).
    #[cfg(not(target_arch = "avr"))]
    if policy == ReachPolicy::Reject {
        if let Some(angles) = leg::inverse_all_reject::<M>(robot, &local) {
            return Ok(BodySolution {
                legs: angles.map(|angles| LegSolution {
                    angles,
                    clamped: None,
                }),
            });
        }
    }
    let mut legs = [LegSolution {
        angles: JointAngles::default(),
        clamped: None,
    }; 4];
    for leg in LegId::ALL {
        legs[leg.index()] = leg::inverse_with::<M>(robot, leg, local[leg.index()], policy)?;
    }
    Ok(BodySolution { legs })
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

/// Body pose with the feet held at the nominal stance of height `stance_height_m`.
#[inline]
pub fn inverse_at_stance_with<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    stance_height_m: f32,
    policy: ReachPolicy,
) -> Result<BodySolution, IkError> {
    inverse_with::<M>(
        robot,
        pose,
        config,
        &robot.stance_feet(stance_height_m),
        policy,
    )
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
