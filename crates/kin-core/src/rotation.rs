//! Body rotation matrices (seed 000 eq. 5.1–5.3 and Algorithm 2, seed 001 eq. 2) in all six
//! orders.
//!
//! Elementary rotations (active, right-handed): `Rx(roll)`, `Ry(pitch)`, `Rz(yaw)`. An order
//! names the matrix product **left to right**: [`RotationOrder::Zyx`] is
//! `R = Rz(yaw)·Ry(pitch)·Rx(roll)`; [`RotationOrder::Zxy`] is `Rz·Rx·Ry` (seed 001's
//! `Γψ·Γθ·Γγ`). `R` maps body-frame vectors into the world frame.

use crate::math::{DefaultMath, Math};
use crate::vec::{Mat3, Vec3};
use core::fmt;

/// The order of the elementary rotations, named by the matrix product left to right.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum RotationOrder {
    /// `Rx·Ry·Rz`.
    Xyz,
    /// `Rx·Rz·Ry`.
    Xzy,
    /// `Ry·Rx·Rz`.
    Yxz,
    /// `Ry·Rz·Rx`.
    Yzx,
    /// `Rz·Rx·Ry` (seed 001).
    Zxy,
    /// `Rz·Ry·Rx` (the default; seed 000's published default, which that code calls 'xyz').
    #[default]
    Zyx,
}

impl RotationOrder {
    /// All six orders.
    pub const ALL: [RotationOrder; 6] = [
        RotationOrder::Xyz,
        RotationOrder::Xzy,
        RotationOrder::Yxz,
        RotationOrder::Yzx,
        RotationOrder::Zxy,
        RotationOrder::Zyx,
    ];

    /// The axes of the product, left to right (0 = x/roll, 1 = y/pitch, 2 = z/yaw).
    pub const fn axes(self) -> [u8; 3] {
        match self {
            RotationOrder::Xyz => [0, 1, 2],
            RotationOrder::Xzy => [0, 2, 1],
            RotationOrder::Yxz => [1, 0, 2],
            RotationOrder::Yzx => [1, 2, 0],
            RotationOrder::Zxy => [2, 0, 1],
            RotationOrder::Zyx => [2, 1, 0],
        }
    }

    /// Lower-case name: `xyz`, …, `zyx`.
    pub const fn name(self) -> &'static str {
        match self {
            RotationOrder::Xyz => "xyz",
            RotationOrder::Xzy => "xzy",
            RotationOrder::Yxz => "yxz",
            RotationOrder::Yzx => "yzx",
            RotationOrder::Zxy => "zxy",
            RotationOrder::Zyx => "zyx",
        }
    }

    /// Parses a name as printed by [`RotationOrder::name`] (case-insensitive).
    pub fn parse(s: &str) -> Option<RotationOrder> {
        RotationOrder::ALL
            .into_iter()
            .find(|o| o.name().eq_ignore_ascii_case(s.trim()))
    }
}

impl fmt::Display for RotationOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Elementary rotation about axis `axis` (0 = x, 1 = y, 2 = z) from `(sin, cos)`.
#[inline(always)]
fn elementary(axis: u8, s: f32, c: f32) -> Mat3 {
    match axis {
        0 => Mat3 {
            rows: [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        },
        1 => Mat3 {
            rows: [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        },
        _ => Mat3 {
            rows: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        },
    }
}

/// `Rx(angle)` (seed 000 eq. 5.1, seed 001 Γθ and Γβ).
pub fn rot_x(angle_rad: f32) -> Mat3 {
    let (s, c) = DefaultMath::sin_cos(angle_rad);
    elementary(0, s, c)
}

/// `Ry(angle)` (seed 000 eq. 5.2, seed 001 Γγ).
pub fn rot_y(angle_rad: f32) -> Mat3 {
    let (s, c) = DefaultMath::sin_cos(angle_rad);
    elementary(1, s, c)
}

/// `Rz(angle)` (seed 000 eq. 5.3, seed 001 Γψ).
pub fn rot_z(angle_rad: f32) -> Mat3 {
    let (s, c) = DefaultMath::sin_cos(angle_rad);
    elementary(2, s, c)
}

/// Body rotation matrix for `roll`, `pitch`, `yaw` (rad) in `order`, on backend `M`.
#[inline]
pub fn matrix_with<M: Math>(
    order: RotationOrder,
    roll_rad: f32,
    pitch_rad: f32,
    yaw_rad: f32,
) -> Mat3 {
    let sc = [
        M::sin_cos(roll_rad),
        M::sin_cos(pitch_rad),
        M::sin_cos(yaw_rad),
    ];
    // One monomorphic product per order: the axes are constants, so each arm compiles to the
    // closed-form matrix of its order (no runtime dispatch inside the product).
    match order {
        RotationOrder::Xyz => product::<0, 1, 2>(&sc),
        RotationOrder::Xzy => product::<0, 2, 1>(&sc),
        RotationOrder::Yxz => product::<1, 0, 2>(&sc),
        RotationOrder::Yzx => product::<1, 2, 0>(&sc),
        RotationOrder::Zxy => product::<2, 0, 1>(&sc),
        RotationOrder::Zyx => product::<2, 1, 0>(&sc),
    }
}

/// `E(A)·E(B)·E(C)` for elementary rotations about the axes `A`, `B`, `C` (0 = x, 1 = y,
/// 2 = z) with `(sin, cos)` of the roll, pitch and yaw angles in `sc`.
#[inline(always)]
fn product<const A: u8, const B: u8, const C: u8>(sc: &[(f32, f32); 3]) -> Mat3 {
    let (s, co) = sc[C as usize];
    let m = elementary(C, s, co);
    let (s, co) = sc[B as usize];
    let m = rotate_rows(B, s, co, &m);
    let (s, co) = sc[A as usize];
    rotate_rows(A, s, co, &m)
}

/// `elementary(axis, s, c) · m`, touching only the two rows the rotation mixes (a third of the
/// multiplications of a full matrix product).
#[inline(always)]
fn rotate_rows(axis: u8, s: f32, c: f32, m: &Mat3) -> Mat3 {
    let mix = |p: &[f32; 3], q: &[f32; 3]| -> ([f32; 3], [f32; 3]) {
        (
            core::array::from_fn(|j| c * p[j] - s * q[j]),
            core::array::from_fn(|j| s * p[j] + c * q[j]),
        )
    };
    let [r0, r1, r2] = &m.rows;
    let rows = match axis {
        0 => {
            let (n1, n2) = mix(r1, r2);
            [*r0, n1, n2]
        }
        1 => {
            // Ry mixes z and x: row0 = c·r0 + s·r2, row2 = −s·r0 + c·r2.
            let (n2, n0) = mix(r2, r0);
            [n0, *r1, n2]
        }
        _ => {
            let (n0, n1) = mix(r0, r1);
            [n0, n1, *r2]
        }
    };
    Mat3 { rows }
}

/// [`matrix_with`] on the [`DefaultMath`] backend.
#[inline]
pub fn matrix(order: RotationOrder, roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Mat3 {
    matrix_with::<DefaultMath>(order, roll_rad, pitch_rad, yaw_rad)
}

/// Angular velocity of the body, in the world frame, for Euler-angle rates in `order`:
/// for `R = R₁(q₁)·R₂(q₂)·R₃(q₃)`, `ω = q̇₁·e₁ + R₁·q̇₂·e₂ + R₁·R₂·q̇₃·e₃`.
pub fn angular_velocity(order: RotationOrder, angles_rad: [f32; 3], rates_rad_s: [f32; 3]) -> Vec3 {
    let axes = order.axes();
    let unit = |axis: u8| match axis {
        0 => Vec3::new(1.0, 0.0, 0.0),
        1 => Vec3::new(0.0, 1.0, 0.0),
        _ => Vec3::new(0.0, 0.0, 1.0),
    };
    let mut acc = Mat3::IDENTITY;
    let mut omega = Vec3::ZERO;
    for axis in axes {
        let i = axis as usize;
        omega = omega + acc.mul_vec(unit(axis)) * rates_rad_s[i];
        let (s, c) = DefaultMath::sin_cos(angles_rad[i]);
        acc = acc.mul_mat(&elementary(axis, s, c));
    }
    omega
}
