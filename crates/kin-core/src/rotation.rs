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

/// Body rotation matrix for `roll`, `pitch`, `yaw` (rad) in `order`, on backend `M`: three
/// `sin_cos`, then the closed form of the order (14 multiplications, 4 additions).
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
    // Hosts: one arm per order with the axes as constants, so that each compiles to its own
    // closed form without index arithmetic. The ATmega2560: one copy with the axes at run
    // time (a sixth of the flash; the indexing costs little next to software floats).
    #[cfg(not(target_arch = "avr"))]
    match order {
        RotationOrder::Xyz => closed_form(0, 1, 2, true, &sc),
        RotationOrder::Xzy => closed_form(0, 2, 1, false, &sc),
        RotationOrder::Yxz => closed_form(1, 0, 2, false, &sc),
        RotationOrder::Yzx => closed_form(1, 2, 0, true, &sc),
        RotationOrder::Zxy => closed_form(2, 0, 1, true, &sc),
        RotationOrder::Zyx => closed_form(2, 1, 0, false, &sc),
    }
    #[cfg(target_arch = "avr")]
    {
        closed_form_at_run_time(order, &sc)
    }
}

/// [`closed_form`] with the axes of `order` as run-time values.
#[cfg_attr(not(any(test, target_arch = "avr")), allow(dead_code))]
#[inline(always)]
fn closed_form_at_run_time(order: RotationOrder, sc: &[(f32, f32); 3]) -> Mat3 {
    let [i, j, k] = order.axes();
    // Cyclic orders (xyz, yzx, zxy) are the even permutations.
    let even = (j + 3 - i) % 3 == 1;
    closed_form(i as usize, j as usize, k as usize, even, sc)
}

/// `E_i(a)·E_j(b)·E_k(c)` for the elementary rotations about the distinct axes `i`, `j`, `k`
/// (0 = x, 1 = y, 2 = z; `even`: `(i, j, k)` is a cyclic permutation of `(x, y, z)`), with
/// `(sin, cos)` of the roll, pitch and yaw angles in `sc` (`a`, `b`, `c` are the angles of axes
/// `i`, `j`, `k`). The Tait–Bryan closed form, with `ε = ±1` by the parity of the order:
///
/// | | column i | column j | column k |
/// |---|---|---|---|
/// | row i | cb·cc | −ε·cb·sc | ε·sb |
/// | row j | ε·ca·sc + sa·sb·cc | ca·cc − ε·sa·sb·sc | −ε·sa·cb |
/// | row k | sa·sc − ε·ca·sb·cc | ε·sa·cc + ca·sb·sc | ca·cb |
#[inline(always)]
fn closed_form(i: usize, j: usize, k: usize, even: bool, sc: &[(f32, f32); 3]) -> Mat3 {
    let ((sa, ca), (sb, cb), (s_c, c_c)) = (sc[i], sc[j], sc[k]);
    let e = |x: f32| if even { x } else { -x };
    let (sa_sb, ca_sb) = (sa * sb, ca * sb);
    let mut rows = [[0.0f32; 3]; 3];
    rows[i][i] = cb * c_c;
    rows[i][j] = e(-(cb * s_c));
    rows[i][k] = e(sb);
    rows[j][i] = e(ca * s_c) + sa_sb * c_c;
    rows[j][j] = ca * c_c - e(sa_sb * s_c);
    rows[j][k] = e(-(sa * cb));
    rows[k][i] = sa * s_c - e(ca_sb * c_c);
    rows[k][j] = e(sa * c_c) + ca_sb * s_c;
    rows[k][k] = ca * cb;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Fast;

    /// The ATmega2560's form (axes at run time) gives the hosts' matrices bit for bit, and
    /// both equal the product of the elementary rotations.
    #[test]
    fn run_time_axes_equal_constant_axes() {
        for order in RotationOrder::ALL {
            for (r, p, y) in [
                (0.3f32, -0.2f32, 0.7f32),
                (-2.0, 1.1, -0.4),
                (0.0, 0.0, 0.0),
            ] {
                let sc = [Fast::sin_cos(r), Fast::sin_cos(p), Fast::sin_cos(y)];
                let host = matrix_with::<Fast>(order, r, p, y);
                let avr = closed_form_at_run_time(order, &sc);
                assert_eq!(host, avr, "{order}");
                let angles = [r, p, y];
                let mut product = Mat3::IDENTITY;
                for axis in order.axes() {
                    let (s, c) = sc[axis as usize];
                    product = product.mul_mat(&elementary(axis, s, c));
                }
                for (a, b) in host
                    .rows
                    .iter()
                    .flatten()
                    .zip(product.rows.iter().flatten())
                {
                    assert!((a - b).abs() < 1e-6, "{order} {angles:?}");
                }
            }
        }
    }
}
