//! Full-body kinematics: body pose + four feet in the world frame ↔ twelve joint angles.
//!
//! The world frame coincides with the body frame in the nominal pose. A [`Pose`] gives the
//! body's roll, pitch, yaw (rad, combined in a [`RotationOrder`]) and its translation `t` (m).
//! With an optional pivot `c` (body frame; seed 000's code rotates about an offset centre):
//!
//! - `foot_in_hip = Rᵀ·(foot_in_world − t − c) + c − hip_in_body` (inverse)
//! - `foot_in_world = R·(hip_in_body + foot_in_hip − c) + c + t` (forward)

use crate::leg::{self, Clamp, IkError, LegSolution, ReachPolicy};
use crate::math::{finite, DefaultMath, Math};
use crate::robot::{JointAngles, LegId, Robot};
use crate::rotation::{self, RotationOrder};
use crate::vec::{Mat3, Vec3};

/// Body pose relative to the world frame. In self-describing formats (JSON) a field it does not
/// have is an error, not ignored.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

impl BodyConfig {
    /// Rotations in `order` about the body centre (no pivot).
    pub const fn about_centre(order: RotationOrder) -> BodyConfig {
        BodyConfig {
            order,
            pivot_m: Vec3::ZERO,
        }
    }
}

/// Twelve joint angles, in leg order FL, FR, RL, RR.
pub type BodyAngles = [JointAngles; 4];

/// Result of a full-body IK, stored flat: the twelve angles in the order the servos take them
/// (the solve writes each leg's angles straight into its place, and a consumer reads them there
/// without a copy), and each leg's clamp. [`BodySolution::default`] (all zero, no clamp) is an
/// empty one for [`Solver::inverse_into`] and [`Solver::inverse_at_stance_into`] to fill.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodySolution {
    /// The twelve angles `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`, rad (legs in
    /// order FL, FR, RL, RR).
    pub angles_rad: [f32; 12],
    /// Per leg in order FL, FR, RL, RR: `Some` when [`ReachPolicy::Clamp`] moved its target.
    pub clamped: [Option<Clamp>; 4],
}

impl BodySolution {
    /// The solution of leg `leg`.
    pub fn leg(&self, leg: LegId) -> LegSolution {
        let i = leg.index();
        let a = &self.angles_rad;
        LegSolution {
            angles: JointAngles::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]),
            clamped: self.clamped[i],
        }
    }

    /// The four legs' solutions, in order FL, FR, RL, RR.
    pub fn legs(&self) -> [LegSolution; 4] {
        LegId::ALL.map(|leg| self.leg(leg))
    }

    /// The twelve angles, per leg.
    pub fn angles(&self) -> BodyAngles {
        unflatten(&self.angles_rad)
    }

    /// The twelve angles flattened `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`: a copy
    /// of [`BodySolution::angles_rad`] (which a caller that only reads them reads in place).
    #[inline]
    pub fn flat(&self) -> [f32; 12] {
        self.angles_rad
    }

    /// True when any leg was clamped.
    pub fn any_clamped(&self) -> bool {
        self.clamped.iter().any(Option::is_some)
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

/// Full-body IK on math backend `M` with the robot's constants prepared once (the leg IK's
/// [`leg::Solver`], the hip mounts). A caller that solves many poses of one robot keeps one:
///
/// ```
/// use kin_core::{body, BodyConfig, Pose, ReachPolicy, Robot};
/// let solver = body::Solver::new(&Robot::shahriar2023());
/// let pose = Pose::rotation(0.1, -0.05, 0.2);
/// let q = solver.inverse_at_stance(&pose, &BodyConfig::default(), 0.277, ReachPolicy::Reject)?;
/// # Ok::<(), kin_core::IkError>(())
/// ```
///
/// [`Solver::new`] takes the [`DefaultMath`] backend, [`Solver::with_math`] any other; both
/// are `const fn`, so a firmware can build its solver at compile time:
///
/// ```
/// use kin_core::{body, math::SoftFloat, Robot};
/// const SOLVER: body::Solver<SoftFloat> = body::Solver::with_math(&Robot::shahriar2023());
/// ```
pub struct Solver<M: Math = DefaultMath> {
    leg: leg::Solver<M>,
    /// The front left hip mount `(length/2, width/2, 0)`; the others by [`LegId::at_corner`].
    hip_fl_m: Vec3,
    /// `width/2 + d_lat`: the stance foot's lateral distance from the body's centre line.
    stance_lateral_m: f32,
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
        (self.leg, self.hip_fl_m) == (other.leg, other.hip_fl_m)
    }
}
impl<M: Math> core::fmt::Debug for Solver<M> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Solver")
            .field("leg", &self.leg)
            .field("hip_fl_m", &self.hip_fl_m)
            .finish()
    }
}

/// True when `v` is (±0, ±0, ±0), from the bits (no float comparison).
fn is_zero(v: Vec3) -> bool {
    const ABS: u32 = 0x7fff_ffff;
    (v.x.to_bits() | v.y.to_bits() | v.z.to_bits()) & ABS == 0
}

impl Solver<DefaultMath> {
    /// The body IK of `robot` on the [`DefaultMath`] backend.
    #[inline]
    pub const fn new(robot: &Robot) -> Solver {
        Solver::with_math(robot)
    }
}

impl<M: Math> Solver<M> {
    /// The body IK of `robot` on backend `M`.
    #[inline]
    pub const fn with_math(robot: &Robot) -> Solver<M> {
        let hip_fl_m = robot.hip_in_body(LegId::FL);
        Solver {
            leg: leg::Solver::with_math(robot),
            hip_fl_m,
            stance_lateral_m: hip_fl_m.y + robot.leg.d_lat_m,
        }
    }

    /// The leg IK of this robot.
    #[inline]
    pub fn leg(&self) -> &leg::Solver<M> {
        &self.leg
    }

    /// Feet in the world frame → feet in each leg's hip frame:
    /// `Rᵀ·(foot_in_world − t − c) + c − hip_in_body`.
    pub fn feet_in_hips(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
    ) -> [Vec3; 4] {
        let r = rotation::matrix::<M>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
        let c = config.pivot_m;
        let offset = pose.translation() + c;
        let mut out = [Vec3::ZERO; 4];
        for ((foot_in_hip, foot), leg) in out.iter_mut().zip(feet_in_world).zip(LegId::ALL) {
            let p = r.transpose_mul_vec(*foot - offset);
            // The hip mounts lie in the body's plane z = 0.
            let hip = leg.at_corner(self.hip_fl_m);
            *foot_in_hip = Vec3::new(p.x + c.x - hip.x, p.y + c.y - hip.y, p.z + c.z);
        }
        out
    }

    /// The feet of the nominal stance of height `stance_height_m`
    /// (`foot_in_world = hip_in_body + (0, s·d_lat, −H)`) in each leg's hip frame, written into
    /// `out`: the transform of [`Solver::feet_in_hips`] in closed form. With `R`'s rows
    /// `r₀, r₁, r₂`, `foot_in_hip = sx·(L/2·r₀ − (L/2, 0, 0)) + s·((W/2 + d_lat)·r₁ − (0, W/2, 0)) − K`
    /// for the front/rear sign `sx`, the side sign `s` and `K = Rᵀ·(g + (0, 0, H)) − c`,
    /// `g = t + c`: 9 multiplications and 27 additions (15 and 33 with a horizontal
    /// translation or pivot) where the general transform of the four stance feet takes 36 and
    /// 59.
    pub(crate) fn stance_feet_in_hips(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
        out: &mut [Vec3; 4],
    ) {
        let c = &config.pivot_m;
        let g = pose.translation() + *c;
        let mut r = Mat3::ZERO;
        rotation::matrix_into::<M>(
            config.order,
            pose.roll_rad,
            pose.pitch_rad,
            pose.yaw_rad,
            &mut r,
        );
        // The four feet are built in place, the slots holding the shared terms on the way.
        let [fl, fr, rl, rr] = out;
        // −K = Rᵀ·(−g − (0, 0, H)) + c to FR, as the rows of R scaled by the components:
        // −(g_z + H)·r₂ (−H·r₂ without translation and pivot), −g_x·r₀, −g_y·r₁ and c added.
        *fr = Vec3::from_array(r.rows[2]) * -(g.z + stance_height_m);
        if !is_zero(Vec3::new(g.x, g.y, 0.0)) {
            *fr = *fr + Vec3::from_array(r.rows[0]) * -g.x;
            *fr = *fr + Vec3::from_array(r.rows[1]) * -g.y;
        }
        *fr = *fr + *c;
        // a = L/2·r₀ − (L/2, 0, 0) to FL, −a to RL; then the front's a − K and the rear's −a − K.
        let hl = self.hip_fl_m.x;
        *fl = Vec3::from_array(r.rows[0]) * hl;
        fl.x -= hl;
        *rl = -*fl;
        *fl = *fl + *fr;
        *rl = *rl + *fr;
        // ± b, b = (W/2 + d_lat)·r₁ − (0, W/2, 0): the right feet (a − K − b, −a − K − b)
        // from the left ones before these take theirs (+ b), so that no vector is copied.
        let mut b = Vec3::from_array(r.rows[1]) * self.stance_lateral_m;
        b.y -= self.hip_fl_m.y;
        *fr = *fl + -b;
        *rr = *rl + -b;
        *fl = *fl + b;
        *rl = *rl + b;
    }

    /// Full-body IK: all-or-nothing. The first leg (in order FL, FR, RL, RR) that cannot reach
    /// rejects the pose and is named in the error; a non-finite pose or pivot is
    /// [`leg::Unreachable::NonFinite`] named on FL. ([`Solver::inverse_into`] writes the
    /// solution into a caller's.)
    #[inline]
    pub fn inverse(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        by_value(|out| self.inverse_into(pose, config, feet_in_world, policy, out))
    }

    /// [`Solver::inverse`] written into `out`, where the caller reads it in place: no solution
    /// built in a temporary and copied out (a returned solution goes through memory on CPUs
    /// such as the AVR, and is copied there once more). The same results; on an error `out`
    /// may hold some legs of this solve and is to be ignored.
    ///
    /// ```
    /// use kin_core::{body, BodyConfig, BodySolution, Pose, ReachPolicy, Robot};
    /// let robot = Robot::shahriar2023();
    /// let solver = body::Solver::new(&robot);
    /// let (pose, config) = (Pose::rotation(0.1, 0.0, 0.0), BodyConfig::default());
    /// let feet = robot.stance_feet(0.277);
    /// let mut solution = BodySolution::default();
    /// solver.inverse_into(&pose, &config, &feet, ReachPolicy::Reject, &mut solution)?;
    /// assert_eq!(Ok(solution), solver.inverse(&pose, &config, &feet, ReachPolicy::Reject));
    /// # Ok::<(), kin_core::IkError>(())
    /// ```
    #[inline]
    pub fn inverse_into(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        feet_in_world: &[Vec3; 4],
        policy: ReachPolicy,
        out: &mut BodySolution,
    ) -> Result<(), IkError> {
        check_finite(pose, config)?;
        let local = self.feet_in_hips(pose, config, feet_in_world);
        self.legs(&local, policy, out)
    }

    /// Body pose with the feet held at the nominal stance of height `stance_height_m`
    /// ([`Robot::stance_feet`]), through the closed-form transform of the stance feet (the
    /// same angles as [`Solver::inverse`] with those feet up to f32 rounding). Errors as
    /// [`Solver::inverse`]. ([`Solver::inverse_at_stance_into`] writes the solution into a
    /// caller's.)
    #[inline]
    pub fn inverse_at_stance(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        by_value(|out| self.inverse_at_stance_into(pose, config, stance_height_m, policy, out))
    }

    /// [`Solver::inverse_at_stance`] written into `out`, where the caller reads it in place (as
    /// [`Solver::inverse_into`]; on an error `out` is to be ignored).
    #[inline]
    pub fn inverse_at_stance_into(
        &self,
        pose: &Pose,
        config: &BodyConfig,
        stance_height_m: f32,
        policy: ReachPolicy,
        out: &mut BodySolution,
    ) -> Result<(), IkError> {
        check_finite(pose, config)?;
        // Four zeros written out, not a repeat expression: the compiler then sees that the
        // stance transform writes every foot before it reads one and drops the zeroing.
        let mut local = [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        self.stance_feet_in_hips(pose, config, stance_height_m, &mut local);
        self.legs(&local, policy, out)
    }

    /// The body at the zero pose with its feet at `feet_in_body` (body frame, m): each foot
    /// less its hip mount, then the leg solves, all-or-nothing as [`Solver::inverse`] (a
    /// non-finite foot is [`leg::Unreachable::NonFinite`] of its leg).
    #[inline]
    pub fn inverse_feet_in_body(
        &self,
        feet_in_body: &[Vec3; 4],
        policy: ReachPolicy,
    ) -> Result<BodySolution, IkError> {
        let mut local = *feet_in_body;
        for (p, leg) in local.iter_mut().zip(LegId::ALL) {
            *p = *p - leg.at_corner(self.hip_fl_m);
        }
        by_value(|out| self.legs(&local, policy, out))
    }

    /// The four leg solves ([`leg::Solver::inverse`]) of feet in their hips' frames, in the
    /// order of [`LegId::ALL`], each leg's angles written straight into their place in `out`;
    /// the first leg that fails rejects the pose and is named in the error.
    fn legs(
        &self,
        local: &[Vec3; 4],
        policy: ReachPolicy,
        out: &mut BodySolution,
    ) -> Result<(), IkError> {
        // Hosts: the four legs as the four lanes of the batch solve (`crate::batch`, the
        // scalar solve's bits), whose stages the compiler interleaves across the legs; a pose
        // with a leg that fails goes through the scalar loop below for its error or clamps.
        // Not on the AVR, which gains nothing from it (in order, no vector unit).
        #[cfg(not(target_arch = "avr"))]
        {
            let x = [local[0].x, local[1].x, local[2].x, local[3].x];
            let y = [local[0].y, local[1].y, local[2].y, local[3].y];
            let z = [local[0].z, local[1].z, local[2].z, local[3].z];
            let sd = LegId::ALL.map(|leg| self.leg.side_d_lat(leg));
            let r = crate::batch::leg_lanes(&self.leg, &sd, &x, &y, &z);
            if u32::from_ne_bytes(r.code) == 0 {
                for (k, a) in out.angles_rad.chunks_exact_mut(3).enumerate() {
                    a.copy_from_slice(&[r.abduction_rad[k], r.hip_rad[k], r.knee_rad[k]]);
                }
                out.clamped = [None; 4];
                return Ok(());
            }
        }
        let legs = out.angles_rad.chunks_exact_mut(3).zip(&mut out.clamped);
        for ((angles, clamped), (foot, leg)) in legs.zip(local.iter().zip(&LegId::ALL)) {
            // Chunks of exactly three: the conversion cannot fail (and compiles to nothing).
            if let Ok(angles) = angles.try_into() {
                self.leg.inverse_into(*leg, foot, policy, angles, clamped)?;
            }
        }
        Ok(())
    }
}

/// The solution that `solve` writes into an empty one ([`BodySolution::default`]), by value:
/// the by-value forms of the solves that write into a caller's.
// Always inlined, early: the reach policy its closure captures then stays a constant that the
// compiler propagates into the solve and drops the other policy's code (`BENCHMARKS.md`).
#[inline(always)]
fn by_value(
    solve: impl FnOnce(&mut BodySolution) -> Result<(), IkError>,
) -> Result<BodySolution, IkError> {
    let mut out = BodySolution::default();
    solve(&mut out)?;
    Ok(out)
}

/// `NonFinite` (named on FL) when the pose or the pivot is not finite: the first check of
/// [`Solver::inverse`] and [`Solver::inverse_at_stance`].
pub(crate) fn check_finite(pose: &Pose, config: &BodyConfig) -> Result<(), IkError> {
    let p = &config.pivot_m;
    // Field by field, without copying the pose into an array first; all nine checked
    // together (`&`, no branch per value).
    let ok = finite(pose.roll_rad)
        & finite(pose.pitch_rad)
        & finite(pose.yaw_rad)
        & finite(pose.x_m)
        & finite(pose.y_m)
        & finite(pose.z_m)
        & finite(p.x)
        & finite(p.y)
        & finite(p.z);
    if ok {
        Ok(())
    } else {
        Err(IkError {
            leg: LegId::FL,
            kind: leg::Unreachable::NonFinite,
        })
    }
}

/// Full-body FK: pose + twelve angles → the four feet in the world frame.
pub fn forward(robot: &Robot, pose: &Pose, config: &BodyConfig, angles: &BodyAngles) -> [Vec3; 4] {
    let r =
        rotation::matrix::<DefaultMath>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
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
    use crate::math::SoftFloat;
    use crate::robot::KneeBend;
    use seeded_rng::SplitMix64;

    /// Seeded test inputs, uniform in `[lo, hi)`.
    struct Rng(SplitMix64);
    impl Rng {
        fn new(seed: u64) -> Rng {
            Rng(SplitMix64::new(seed))
        }
        fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
            self.0.range(lo as f64, hi as f64) as f32
        }
    }

    /// The closed-form stance transform equals the general transform of the stance feet (f32
    /// rounding apart), with and without translation and pivot, in every order.
    #[test]
    fn stance_transform_equals_general_transform() {
        /// Largest difference, m: a few f32 ulp of half-metre coordinates.
        const TOL_M: f32 = 2e-7;
        let mut rng = Rng::new(11);
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
                    let mut fast = [Vec3::ZERO; 4];
                    solver.stance_feet_in_hips(&pose, &config, height_m, &mut fast);
                    let general = solver.feet_in_hips(&pose, &config, &feet);
                    for (a, b) in fast.iter().zip(&general) {
                        let d = *a - *b;
                        let worst = d.x.abs().max(d.y.abs()).max(d.z.abs());
                        assert!(worst < TOL_M, "{order} {pose:?} {config:?}: {a:?} vs {b:?}");
                    }
                }
            }
        }
    }

    /// A kept [`Solver`] gives exactly the results of one built per call.
    #[test]
    fn kept_solver_equals_solver_per_call() {
        let mut rng = Rng::new(5);
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
                        Solver::new(&robot).inverse_at_stance(&pose, &config, height_m, policy)
                    );
                    let feet = robot.stance_feet(height_m);
                    assert_eq!(
                        solver.inverse(&pose, &config, &feet, policy),
                        Solver::new(&robot).inverse(&pose, &config, &feet, policy)
                    );
                    let foot = Vec3::new(
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.6, 0.6),
                        rng.uniform(-0.9, 0.1),
                    );
                    for leg in LegId::ALL {
                        assert_eq!(
                            solver.leg().inverse(leg, foot, policy),
                            leg::Solver::new(&robot).inverse(leg, foot, policy)
                        );
                    }
                }
            }
        }
    }

    /// The body IK (Reject) gives exactly the per-leg results, and the same first error when a
    /// leg cannot reach.
    #[test]
    fn body_ik_equals_leg_by_leg_ik_bit_for_bit() {
        let mut rng = Rng::new(7);
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
                        let local = Solver::new(&robot).feet_in_hips(&pose, &config, &feet);
                        let one_by_one: Result<[LegSolution; 4], IkError> = (|| {
                            let mut legs = [LegSolution {
                                angles: JointAngles::default(),
                                clamped: None,
                            }; 4];
                            for leg in LegId::ALL {
                                legs[leg.index()] = leg::Solver::new(&robot).inverse(
                                    leg,
                                    local[leg.index()],
                                    ReachPolicy::Reject,
                                )?;
                            }
                            Ok(legs)
                        })(
                        );
                        let body =
                            Solver::new(&robot).inverse(&pose, &config, &feet, ReachPolicy::Reject);
                        match (body, one_by_one) {
                            (Ok(b), Ok(l)) => {
                                solved += 1;
                                for (x, y) in b.legs().iter().zip(&l) {
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

    /// The body at the zero pose with feet given in the body frame equals the general body IK
    /// of those feet at the zero pose, on the default and the soft-float backend.
    #[test]
    fn feet_in_body_equals_the_general_inverse_at_the_zero_pose() {
        let mut rng = Rng::new(13);
        let (mut solved, mut rejected) = (0, 0);
        for robot in [Robot::shahriar2023(), Robot::fernando2025()] {
            let height_m = 0.75 * (robot.leg.femur_m + robot.leg.tibia_m);
            for policy in [ReachPolicy::Reject, ReachPolicy::Clamp] {
                for _ in 0..200 {
                    let feet = robot.stance_feet(height_m).map(|f| {
                        f + Vec3::new(
                            rng.uniform(-0.3, 0.3),
                            rng.uniform(-0.3, 0.3),
                            rng.uniform(-0.3, 0.3),
                        )
                    });
                    let zero = (Pose::default(), BodyConfig::default());
                    let a = Solver::new(&robot).inverse_feet_in_body(&feet, policy);
                    let b = Solver::new(&robot).inverse(&zero.0, &zero.1, &feet, policy);
                    let c =
                        Solver::<SoftFloat>::with_math(&robot).inverse_feet_in_body(&feet, policy);
                    match (&a, &b, &c) {
                        (Ok(a), Ok(b), Ok(c)) => {
                            solved += 1;
                            for ((x, y), z) in a.flat().iter().zip(b.flat()).zip(c.flat()) {
                                assert!((x - y).abs() < 1e-5 && (x - z).abs() < 5e-5);
                            }
                        }
                        (Err(a), Err(b), Err(c)) => {
                            rejected += 1;
                            assert_eq!((a, a), (b, c));
                        }
                        _ => panic!("{a:?} vs {b:?} vs {c:?}"),
                    }
                }
            }
        }
        assert!(
            solved > 100 && rejected > 10,
            "solved {solved}, rejected {rejected}"
        );
    }
}
