//! # kin-core — kinematics of a 12-DoF quadruped, `no_std`, f32
//!
//! Leg forward and inverse kinematics, body rotation and full-body IK/FK, the leg Jacobian and
//! adapters to the conventions of the two source papers:
//!
//! - **seed 000**: A. Shahriar, *A Balanced Positional Control Architecture for a 12-DoF
//!   Quadruped Robot through Simulation-validation and Hardware Testing*.
//! - **seed 001**: M. J. Fernando, G. R. Saypulaev, M. R. Saypulaev, *Analysis of a Four-Legged
//!   Robot Kinematics during Rotational Movements of Its Body*, 2025.
//!
//! The same code runs on the host and on the ATmega2560 firmware. No allocation, no panics on
//! any input, and never a NaN out: unreachable targets are typed errors ([`leg::IkError`]) or
//! explicitly reported clamps ([`leg::Clamp`]).
//!
//! ## Conventions
//! - SI units everywhere (m, rad, s); names carry units (`x_m`, `hip_rad`).
//! - **Body frame**: origin at the body's geometric centre, x forward, y left, z up (REP 103).
//!   Legs [`LegId::FL`], `FR`, `RL`, `RR`; hip (abduction-axis) mount of each leg at
//!   `(±length/2, ±width/2, 0)`.
//! - **Hip frame** of a leg: origin at its hip mount, axes parallel to the body frame. Side sign
//!   `s = +1` for left legs, `−1` for right legs.
//! - **Joint angles** (abduction, hip, knee), rad; one chain covers both papers:
//!   `foot_in_hip = Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L_femur] + Ry(h+k)·[0,0,−L_tibia])`
//!   with `Rx(a) = [[1,0,0],[0,cos a,−sin a],[0,sin a,cos a]]`,
//!   `Ry(a) = [[cos a,0,sin a],[0,1,0],[−sin a,0,cos a]]`. `d_lat` is seed 000's lateral coxa
//!   offset `La` (perpendicular to the leg plane); `d_ax` is seed 001's abduction link `l0`
//!   (in the leg plane, hanging down). All angles zero: leg straight down.
//! - **IK branch**: knee ≤ 0 by default ([`KneeBend::Backward`]; [`KneeBend::Forward`] gives
//!   knee ≥ 0), and the abduction whose un-abducted foot lies below the hip.
//! - **Body pose** ([`body::Pose`]): roll, pitch, yaw (rad) and translation x, y, z (m) of the
//!   body in the world frame, which coincides with the body frame in the nominal pose. The
//!   [`RotationOrder`] names the matrix product left to right: `zyx` is
//!   `R = Rz(yaw)·Ry(pitch)·Rx(roll)` (the default), `zxy` is seed 001's `Γψ·Γθ·Γγ`.
//!   With pivot `c`: `foot_in_hip = Rᵀ·(foot_in_world − t − c) + c − hip_in_body`.
//! - **Nominal stance** of height `H`: `foot_in_world = hip_in_body + (0, s·d_lat, −H)`.
//!
//! ## Modules
//! - [`robot`]: [`Robot`] description and the presets [`Robot::shahriar2023`],
//!   [`Robot::fernando2025`].
//! - [`leg`]: FK (closed form and DH form), IK, reachability, [`ReachPolicy`].
//! - [`rotation`], [`body`]: body rotation in six orders, full-body IK/FK.
//! - [`batch`]: leg IK/FK and body IK over many targets, in fixed-width chunks of lanes that
//!   the compiler vectorises; each result the scalar solve's, bit for bit.
//! - [`attitude`]: roll and pitch from a six-axis inertial sensor (Mahony's filter).
//! - [`jacobian`]: velocity kinematics and the singularity measure.
//! - [`paper`]: seed 000 (θ1, θ2, θ3) and seed 001 (β, α, φ) angle adapters.
//! - [`math`]: the [`Math`] backend trait (`libm`, fast polynomials, the soft-float choices of
//!   CPUs without floating-point hardware, or a firmware's own).
//! - [`motion`]: foot paths, seed 001's body-motion laws, trot / walk gaits.
//! - [`preflight`]: sweep a motion and report reach, margins, singularity, joint speeds.
//! - [`stability`]: the centre of mass against the support polygon (static stability margin).
//!
//! ## Why not nalgebra inside
//! On the ATmega2560, a program that builds the zyx body rotation and rotates four vectors
//! links to about three times the flash with nalgebra's `Rotation3::from_euler_angles` than
//! with this crate's [`rotation::matrix`] (measured in `docs/benchmark-journal.md`, "nalgebra
//! on the ATmega2560"). The gap is nalgebra's sine/cosine, which goes through libm's f64
//! `sincosf` and cannot be swapped for a cheaper backend; the matrix code itself is the same
//! size either way.
//! So the hand-written [`Vec3`]/[`Mat3`] stay — they also keep every operation visible and
//! every backend swappable — and nalgebra (f64) is the independent oracle of the tests.

#![no_std]
// `deny`, not `forbid`: the exceptions are the AVR's flash tables of `math` (their
// `link_section`), which only the `Math` backend's reads can reach, the x86-64 square root of
// the batch solves' lanes (`math::lanes`, SSE's `sqrtps`), and the entry points of
// `batch::avx2` and `batch::avx512` (unsafe to call: the CPU must have the features).
#![deny(unsafe_code)]

pub mod attitude;
pub mod batch;
pub mod body;
pub mod jacobian;
pub mod leg;
pub mod math;
pub mod motion;
pub mod paper;
pub mod preflight;
pub mod robot;
pub mod rotation;
pub mod stability;
pub mod vec;

pub use body::{BodyConfig, BodySolution, Pose};
pub use leg::{Clamp, IkError, LegSolution, ReachPolicy, Unreachable};
pub use math::{DefaultMath, Math};
pub use robot::{Joint, JointAngles, JointLimits, KneeBend, LegGeometry, LegId, Robot};
pub use rotation::RotationOrder;
pub use vec::{Mat3, Vec3};
