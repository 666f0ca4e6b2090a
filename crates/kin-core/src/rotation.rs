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

    /// True for the cyclic orders (`xyz`, `yzx`, `zxy`): the even permutations of the axes.
    const fn is_even(self) -> bool {
        matches!(
            self,
            RotationOrder::Xyz | RotationOrder::Yzx | RotationOrder::Zxy
        )
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

/// `(sin, cos)` of roll, pitch and yaw on backend `M`.
fn sin_cos3<M: Math>(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> [(f32, f32); 3] {
    [
        M::sin_cos(roll_rad),
        M::sin_cos(pitch_rad),
        M::sin_cos(yaw_rad),
    ]
}

/// Body rotation matrix for `roll`, `pitch`, `yaw` (rad) in `order`, on backend `M`
/// (`rotation::matrix::<kin_core::DefaultMath>(…)` on a host): three `sin_cos`, then the
/// general Tait–Bryan closed form with the order's axes, which for the
/// papers' orders is their entry-by-entry form ([`zyx`], [`zxy`]), bit for bit.
///
/// ```
/// use kin_core::{rotation::{self, RotationOrder}, DefaultMath, Mat3};
/// let (roll, pitch, yaw) = (0.3, -0.2, 0.7);
/// let product = rotation::rot_z(yaw).mul_mat(&rotation::rot_x(roll)).mul_mat(&rotation::rot_y(pitch));
/// let m = rotation::matrix::<DefaultMath>(RotationOrder::Zxy, roll, pitch, yaw);
/// for (a, b) in m.rows.iter().flatten().zip(product.rows.iter().flatten()) {
///     assert!((a - b).abs() < 1e-6);
/// }
/// ```
pub fn matrix<M: Math>(order: RotationOrder, roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Mat3 {
    let mut m = Mat3::ZERO;
    matrix_into::<M>(order, roll_rad, pitch_rad, yaw_rad, &mut m);
    m
}

/// [`matrix`] written into `out` (every entry), where the caller keeps it: on CPUs that
/// return a matrix through memory, no temporary and no copy.
pub fn matrix_into<M: Math>(
    order: RotationOrder,
    roll_rad: f32,
    pitch_rad: f32,
    yaw_rad: f32,
    out: &mut Mat3,
) {
    let sc = sin_cos3::<M>(roll_rad, pitch_rad, yaw_rad);
    let [i, j, k] = order.axes();
    closed_form(
        usize::from(i),
        usize::from(j),
        usize::from(k),
        order.is_even(),
        &sc,
        &mut out.rows,
    );
}

/// Seed 000's default order ([`RotationOrder::Zyx`], seed 000 eq. 5.1–5.3 and Algorithm 2 with
/// erratum 3): `R = Rz(ψ)·Ry(θ)·Rx(φ)` for roll φ, pitch θ, yaw ψ, entry by entry
/// (`c`, `s`: cosine, sine), on backend `M`:
///
/// ```text
/// ⎡ cψ·cθ   cψ·sθ·sφ − sψ·cφ   cψ·sθ·cφ + sψ·sφ ⎤
/// ⎢ sψ·cθ   sψ·sθ·sφ + cψ·cφ   sψ·sθ·cφ − cψ·sφ ⎥
/// ⎣ −sθ     cθ·sφ              cθ·cφ            ⎦
/// ```
///
/// ```
/// use kin_core::{rotation::{self, RotationOrder}, DefaultMath};
/// let (roll, pitch, yaw) = (0.3, -0.2, 0.7);
/// let product = rotation::rot_z(yaw).mul_mat(&rotation::rot_y(pitch)).mul_mat(&rotation::rot_x(roll));
/// let m = rotation::zyx::<DefaultMath>(roll, pitch, yaw);
/// for (a, b) in m.rows.iter().flatten().zip(product.rows.iter().flatten()) {
///     assert!((a - b).abs() < 1e-6);
/// }
/// // The general closed form of the order gives the same matrix.
/// assert_eq!(m, rotation::matrix::<DefaultMath>(RotationOrder::Zyx, roll, pitch, yaw));
/// ```
pub fn zyx<M: Math>(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Mat3 {
    let [(s_phi, c_phi), (s_theta, c_theta), (s_psi, c_psi)] =
        sin_cos3::<M>(roll_rad, pitch_rad, yaw_rad);
    // The shared products first (the same roundings as the general closed form).
    let (s_psi_s_theta, c_psi_s_theta) = (s_psi * s_theta, c_psi * s_theta);
    Mat3 {
        rows: [
            [
                c_psi * c_theta,
                c_psi_s_theta * s_phi - s_psi * c_phi,
                c_psi_s_theta * c_phi + s_psi * s_phi,
            ],
            [
                s_psi * c_theta,
                s_psi_s_theta * s_phi + c_psi * c_phi,
                s_psi_s_theta * c_phi - c_psi * s_phi,
            ],
            [-s_theta, c_theta * s_phi, c_theta * c_phi],
        ],
    }
}

/// Seed 001's order ([`RotationOrder::Zxy`], seed 001 eq. 1–2 with erratum 6g):
/// `Γψθγ = Γψ·Γθ·Γγ` for course ψ (yaw, about z), roll θ (about x) and pitch γ (about y), entry
/// by entry, on backend `M`:
///
/// ```text
/// ⎡ cψ·cγ − sψ·sθ·sγ   −sψ·cθ   cψ·sγ + sψ·sθ·cγ ⎤
/// ⎢ sψ·cγ + cψ·sθ·sγ    cψ·cθ   sψ·sγ − cψ·sθ·cγ ⎥
/// ⎣ −cθ·sγ              sθ      cθ·cγ            ⎦
/// ```
///
/// ```
/// use kin_core::{rotation::{self, RotationOrder}, DefaultMath};
/// let (roll, pitch, yaw) = (0.3, -0.2, 0.7);
/// let product = rotation::rot_z(yaw).mul_mat(&rotation::rot_x(roll)).mul_mat(&rotation::rot_y(pitch));
/// let m = rotation::zxy::<DefaultMath>(roll, pitch, yaw);
/// for (a, b) in m.rows.iter().flatten().zip(product.rows.iter().flatten()) {
///     assert!((a - b).abs() < 1e-6);
/// }
/// assert_eq!(m, rotation::matrix::<DefaultMath>(RotationOrder::Zxy, roll, pitch, yaw));
/// ```
pub fn zxy<M: Math>(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Mat3 {
    let [(s_theta, c_theta), (s_gamma, c_gamma), (s_psi, c_psi)] =
        sin_cos3::<M>(roll_rad, pitch_rad, yaw_rad);
    let (s_psi_s_theta, c_psi_s_theta) = (s_psi * s_theta, c_psi * s_theta);
    Mat3 {
        rows: [
            [
                c_psi * c_gamma - s_psi_s_theta * s_gamma,
                -(s_psi * c_theta),
                c_psi * s_gamma + s_psi_s_theta * c_gamma,
            ],
            [
                s_psi * c_gamma + c_psi_s_theta * s_gamma,
                c_psi * c_theta,
                s_psi * s_gamma - c_psi_s_theta * c_gamma,
            ],
            [-(c_theta * s_gamma), s_theta, c_theta * c_gamma],
        ],
    }
}

/// `E_i(a)·E_j(b)·E_k(c)` for the elementary rotations about the distinct axes `i`, `j`, `k`
/// (0 = x, 1 = y, 2 = z; `even`: `(i, j, k)` is a cyclic permutation of `(x, y, z)`), with
/// `(sin, cos)` of the roll, pitch and yaw angles in `sc` (`a`, `b`, `c` are the angles of axes
/// `i`, `j`, `k`). The general Tait–Bryan closed form, with `ε = ±1` by the parity of the
/// order (for zyx and zxy it is [`zyx`] and [`zxy`], bit for bit), written into `rows` (all
/// nine entries, the axes being distinct):
///
/// | | column i | column j | column k |
/// |---|---|---|---|
/// | row i | cb·cc | −ε·cb·sc | ε·sb |
/// | row j | ε·ca·sc + sa·sb·cc | ca·cc − ε·sa·sb·sc | −ε·sa·cb |
/// | row k | sa·sc − ε·ca·sb·cc | ε·sa·cc + ca·sb·sc | ca·cb |
// Always inlined into its one caller (`BENCHMARKS.md`, the AVR body pose).
#[inline(always)]
fn closed_form(
    i: usize,
    j: usize,
    k: usize,
    even: bool,
    sc: &[(f32, f32); 3],
    rows: &mut [[f32; 3]; 3],
) {
    let ((sa, ca), (sb, cb), (s_c, c_c)) = (sc[i], sc[j], sc[k]);
    let e = |x: f32| if even { x } else { -x };
    let (sa_sb, ca_sb) = (sa * sb, ca * sb);
    rows[i][i] = cb * c_c;
    rows[i][j] = e(-(cb * s_c));
    rows[i][k] = e(sb);
    rows[j][i] = e(ca * s_c) + sa_sb * c_c;
    rows[j][j] = ca * c_c - e(sa_sb * s_c);
    rows[j][k] = e(-(sa * cb));
    rows[k][i] = sa * s_c - e(ca_sb * c_c);
    rows[k][j] = e(sa * c_c) + ca_sb * s_c;
    rows[k][k] = ca * cb;
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
    use crate::math::{Fast, SoftFloat};

    /// [`closed_form`] with the axes of `order` as run-time values.
    fn closed_form_at_run_time(order: RotationOrder, sc: &[(f32, f32); 3]) -> Mat3 {
        let [i, j, k] = order.axes();
        // Cyclic orders (xyz, yzx, zxy) are the even permutations.
        let even = (j + 3 - i) % 3 == 1;
        let mut m = Mat3::ZERO;
        closed_form(i as usize, j as usize, k as usize, even, sc, &mut m.rows);
        m
    }

    /// Every order's matrix (the written-out [`zyx`] and [`zxy`] included) equals the general
    /// closed form with the order's axes found at run time, bit for bit, on the default and the
    /// soft-float kernels, and the product of the elementary rotations.
    #[test]
    fn every_order_equals_the_general_closed_form_and_the_product() {
        fn check<M: Math>() {
            for order in RotationOrder::ALL {
                for (r, p, y) in [
                    (0.3f32, -0.2f32, 0.7f32),
                    (-2.0, 1.1, -0.4),
                    (0.0, 0.0, 0.0),
                ] {
                    let sc = [M::sin_cos(r), M::sin_cos(p), M::sin_cos(y)];
                    let m = matrix::<M>(order, r, p, y);
                    assert_eq!(m, closed_form_at_run_time(order, &sc), "{order}");
                    let angles = [r, p, y];
                    let mut product = Mat3::IDENTITY;
                    for axis in order.axes() {
                        let (s, c) = sc[axis as usize];
                        product = product.mul_mat(&elementary(axis, s, c));
                    }
                    for (a, b) in m.rows.iter().flatten().zip(product.rows.iter().flatten()) {
                        assert!((a - b).abs() < 1e-6, "{order} {angles:?}");
                    }
                }
            }
        }
        check::<Fast>();
        check::<SoftFloat>();
    }
}
