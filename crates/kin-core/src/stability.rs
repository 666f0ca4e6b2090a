//! Static stability: the robot's centre of mass against the support polygon of its feet.
//!
//! A robot standing still (or moving slowly enough that its inertia does not matter) stays up
//! while the vertical projection of its centre of mass lies inside the convex hull of the feet
//! on the ground. The **static stability margin** is the signed distance, in the ground plane,
//! from that projection to the hull's boundary: positive inside, zero on an edge or a vertex,
//! negative outside. With fewer than three feet on the ground, or with the stance feet on one
//! line, the hull is a segment or a point and the margin is never positive (minus the distance
//! to it); with no foot on the ground it is `−∞`.
//!
//! ## Where the mass sits ([`MassModel`])
//! Per leg, as the physics twin's model has it (`crates/quad-model`, `docs/twin.md`): the
//! abduction servo in the body; the abduction link (the hip servo and its bracket) at the hip
//! joint; the femur structure at the femur's middle and the knee servo on the femur,
//! `knee_servo_offset_m` below the hip joint; the tibia (with the foot) at the tibia's middle.
//! The body's mass sits at the body frame's origin (the body centre).
//!
//! ## Frames
//! The ground plane is horizontal in the world frame (`z` up); the margin is taken on the
//! `(x, y)` of the world frame, whatever the body's roll and pitch.

use crate::body::{BodyConfig, Pose};
use crate::leg;
use crate::math::Math;
use crate::motion::{Contact, Frame};
use crate::robot::{JointAngles, LegId, Robot};
use crate::rotation;
use crate::vec::Vec3;
use core::fmt;

/// Where a robot's mass sits (kg, m), for its centre of mass. See the module docs for the
/// layout; the presets are the physics twin's assumed masses (`docs/twin.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MassModel {
    /// The body with everything it carries (frame, battery, electronics, the four abduction
    /// servos), at the body centre, kg.
    pub body_kg: f32,
    /// Mass turning with each abduction joint (the hip servo and its bracket), at the hip
    /// joint, kg.
    pub abduction_link_kg: f32,
    /// Each femur's structure, at the femur's middle, kg.
    pub femur_kg: f32,
    /// Each knee servo, on the femur at `knee_servo_offset_m` from the hip joint, kg.
    pub knee_servo_kg: f32,
    /// Distance of the knee servo below the hip joint along the femur, m (≤ the femur).
    pub knee_servo_offset_m: f32,
    /// Each tibia with its foot, at the tibia's middle, kg.
    pub tibia_kg: f32,
}

/// Why a [`MassModel`] was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MassError {
    /// The named mass or offset is negative or not finite.
    Negative(&'static str),
    /// The masses add up to zero.
    NoMass,
    /// The knee servo sits beyond the femur (`knee_servo_offset_m` > `femur_m`).
    KneeServoBeyondFemur,
}

impl fmt::Display for MassError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MassError::Negative(field) => write!(f, "`{field}` must be finite and not negative"),
            MassError::NoMass => f.write_str("the masses must not all be zero"),
            MassError::KneeServoBeyondFemur => {
                f.write_str("`knee_servo_offset_m` must not exceed `femur_m`")
            }
        }
    }
}

impl core::error::Error for MassError {}

impl MassModel {
    /// Seed 000's robot with DS3235-class servos (the twin's preset): 1.8 kg body, 0.085 kg
    /// abduction links, 0.06 kg femurs, 0.065 kg knee servos 0.04 m below the hip, 0.05 kg
    /// tibias; 2.84 kg in all.
    pub const fn shahriar2023() -> MassModel {
        MassModel {
            body_kg: 1.8,
            abduction_link_kg: 0.085,
            femur_kg: 0.06,
            knee_servo_kg: 0.065,
            knee_servo_offset_m: 0.04,
            tibia_kg: 0.05,
        }
    }

    /// Seed 001's robot with A1-class actuators (the twin's preset): 12 kg body, 1.0 kg
    /// abduction links, 0.6 kg femurs, 0.605 kg knee actuators 0.05 m below the hip, 0.3 kg
    /// tibias; 22.02 kg in all.
    pub const fn fernando2025() -> MassModel {
        MassModel {
            body_kg: 12.0,
            abduction_link_kg: 1.0,
            femur_kg: 0.6,
            knee_servo_kg: 0.605,
            knee_servo_offset_m: 0.05,
            tibia_kg: 0.3,
        }
    }

    /// The mass model of a robot preset name (see [`Robot::preset`]).
    pub fn preset(name: &str) -> Option<MassModel> {
        match name {
            "shahriar2023" => Some(MassModel::shahriar2023()),
            "fernando2025" => Some(MassModel::fernando2025()),
            _ => None,
        }
    }

    /// Total mass, kg.
    pub fn total_kg(&self) -> f32 {
        self.body_kg + 4.0 * self.leg_kg()
    }

    /// Mass of one leg (abduction link, femur, knee servo, tibia), kg.
    pub fn leg_kg(&self) -> f32 {
        self.abduction_link_kg + self.femur_kg + self.knee_servo_kg + self.tibia_kg
    }

    /// Checks: every mass and the knee-servo offset finite and ≥ 0, a positive total, the knee
    /// servo on the femur of `robot`.
    pub fn validate(&self, robot: &Robot) -> Result<(), MassError> {
        for (v, name) in [
            (self.body_kg, "body_kg"),
            (self.abduction_link_kg, "abduction_link_kg"),
            (self.femur_kg, "femur_kg"),
            (self.knee_servo_kg, "knee_servo_kg"),
            (self.knee_servo_offset_m, "knee_servo_offset_m"),
            (self.tibia_kg, "tibia_kg"),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(MassError::Negative(name));
            }
        }
        if !(self.total_kg() > 0.0) {
            return Err(MassError::NoMass);
        }
        if self.knee_servo_offset_m > robot.leg.femur_m {
            return Err(MassError::KneeServoBeyondFemur);
        }
        Ok(())
    }
}

/// The centre of mass in the body frame (m) with the legs at `angles` (order FL, FR, RL, RR),
/// on backend `M`. `mass` is assumed valid ([`MassModel::validate`]).
pub fn centre_of_mass_in_body<M: Math>(
    robot: &Robot,
    mass: &MassModel,
    angles: &[JointAngles; 4],
) -> Vec3 {
    let femur = robot.leg.femur_m;
    let servo_at = if femur > 0.0 {
        mass.knee_servo_offset_m / femur
    } else {
        0.0
    };
    let mut moment = Vec3::ZERO;
    for leg in LegId::ALL {
        let p = leg::joint_points_on::<M>(&robot.leg, leg, angles[leg.index()]);
        let hip = robot.hip_in_body(leg);
        let femur_mid = (p.hip_joint + p.knee) * 0.5;
        let knee_servo = p.hip_joint + (p.knee - p.hip_joint) * servo_at;
        let tibia_mid = (p.knee + p.foot) * 0.5;
        moment = moment
            + (hip + p.hip_joint) * mass.abduction_link_kg
            + (hip + femur_mid) * mass.femur_kg
            + (hip + knee_servo) * mass.knee_servo_kg
            + (hip + tibia_mid) * mass.tibia_kg;
    }
    // The body's own mass sits at the origin: no moment.
    moment * (1.0 / mass.total_kg())
}

/// The centre of mass in the world frame (m): [`centre_of_mass_in_body`] moved by the body
/// `pose` under `config` (`R·(c − pivot) + pivot + t`).
pub fn centre_of_mass<M: Math>(
    robot: &Robot,
    mass: &MassModel,
    pose: &Pose,
    config: &BodyConfig,
    angles: &[JointAngles; 4],
) -> Vec3 {
    let c = centre_of_mass_in_body::<M>(robot, mass, angles);
    let r = rotation::matrix::<M>(config.order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
    r.mul_vec(c - config.pivot_m) + config.pivot_m + pose.translation()
}

/// 2-D cross product `(b − a) × (p − a)`: positive when `p` is left of `a → b`.
fn cross(a: (f32, f32), b: (f32, f32), p: (f32, f32)) -> f32 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// Distance from `p` to the segment `a b` (a point when `a == b`), m.
fn distance_to_segment<M: Math>(a: (f32, f32), b: (f32, f32), p: (f32, f32)) -> f32 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let u = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (p.0 - (a.0 + u * dx), p.1 - (a.1 + u * dy));
    M::sqrt(ex * ex + ey * ey)
}

/// The signed static stability margin (m) of `point` against the support polygon of the feet
/// with `stance[i]` true, taken in the world's ground plane (`x`, `y`; the `z` are ignored).
///
/// The support polygon is the convex hull of the stance feet. Inside it the margin is the
/// distance to the nearest edge (> 0); on an edge or a vertex it is 0; outside it is minus the
/// distance to the hull. One or two stance feet, or stance feet on one line, make a point or a
/// segment: the margin is minus the distance to it (0 on it, never positive). No stance foot:
/// `−∞`.
pub fn support_margin<M: Math>(feet_in_world: &[Vec3; 4], stance: [bool; 4], point: Vec3) -> f32 {
    // The stance feet, sorted by (x, y) (an insertion sort of at most four).
    let mut pts = [(0.0f32, 0.0f32); 4];
    let mut n = 0;
    for (foot, on_ground) in feet_in_world.iter().zip(stance) {
        if on_ground {
            let q = (foot.x, foot.y);
            let mut j = n;
            while j > 0 && (pts[j - 1].0 > q.0 || (pts[j - 1].0 == q.0 && pts[j - 1].1 > q.1)) {
                pts[j] = pts[j - 1];
                j -= 1;
            }
            pts[j] = q;
            n += 1;
        }
    }
    if n == 0 {
        return f32::NEG_INFINITY;
    }
    // Andrew's monotone chain: the hull counter-clockwise, collinear points dropped.
    let mut hull = [(0.0f32, 0.0f32); 8];
    let mut h = 0;
    for &q in &pts[..n] {
        while h >= 2 && cross(hull[h - 2], hull[h - 1], q) <= 0.0 {
            h -= 1;
        }
        hull[h] = q;
        h += 1;
    }
    let lower = h + 1;
    for &q in pts[..n].iter().rev().skip(1) {
        while h >= lower && cross(hull[h - 2], hull[h - 1], q) <= 0.0 {
            h -= 1;
        }
        hull[h] = q;
        h += 1;
    }
    // The last point repeats the first (for n ≥ 2).
    let h = if n >= 2 { h - 1 } else { h };
    let p = (point.x, point.y);
    if h < 3 {
        // A point or a segment: the first and the last point of the sorted feet bound it.
        return -distance_to_segment::<M>(pts[0], pts[n - 1], p);
    }
    let mut inside = true;
    let mut nearest_edge = f32::INFINITY;
    let mut nearest_boundary = f32::INFINITY;
    for i in 0..h {
        let (a, b) = (hull[i], hull[(i + 1) % h]);
        let c = cross(a, b, p);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = M::sqrt(dx * dx + dy * dy);
        if c < 0.0 {
            inside = false;
        }
        let d = c / len;
        if d < nearest_edge {
            nearest_edge = d;
        }
        let s = distance_to_segment::<M>(a, b, p);
        if s < nearest_boundary {
            nearest_boundary = s;
        }
    }
    if inside {
        nearest_edge
    } else {
        -nearest_boundary
    }
}

/// The static stability margin (m) of a motion frame with the legs at `angles`: the centre of
/// mass ([`centre_of_mass`]) against the feet of `frame` in [`Contact::Stance`]
/// ([`support_margin`]).
pub fn frame_margin<M: Math>(
    robot: &Robot,
    mass: &MassModel,
    config: &BodyConfig,
    frame: &Frame,
    angles: &[JointAngles; 4],
) -> f32 {
    let com = centre_of_mass::<M>(robot, mass, &frame.pose, config, angles);
    support_margin::<M>(
        &frame.feet_in_world,
        frame.contact.map(|c| c == Contact::Stance),
        com,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::Solver;
    use crate::math::DefaultMath;
    use crate::rotation::RotationOrder;
    use crate::ReachPolicy;

    /// Float tolerance of the margins, m.
    const TOL_M: f32 = 1e-5;

    fn m(feet: &[Vec3; 4], stance: [bool; 4], x: f32, y: f32) -> f32 {
        support_margin::<DefaultMath>(feet, stance, Vec3::new(x, y, 0.0))
    }

    /// A 2 × 1 m rectangle of feet around the origin, order FL, FR, RL, RR.
    fn rectangle() -> [Vec3; 4] {
        [
            Vec3::new(1.0, 0.5, -0.3),
            Vec3::new(1.0, -0.5, -0.3),
            Vec3::new(-1.0, 0.5, -0.3),
            Vec3::new(-1.0, -0.5, -0.3),
        ]
    }

    const ALL: [bool; 4] = [true; 4];

    #[test]
    fn inside_the_rectangle_the_margin_is_the_nearest_edge() {
        let f = rectangle();
        assert!((m(&f, ALL, 0.0, 0.0) - 0.5).abs() < TOL_M);
        assert!((m(&f, ALL, 0.8, 0.1) - 0.2).abs() < TOL_M);
        assert!((m(&f, ALL, -0.9, -0.2) - 0.1).abs() < TOL_M);
    }

    #[test]
    fn on_an_edge_or_a_vertex_the_margin_is_zero() {
        let f = rectangle();
        assert!(m(&f, ALL, 0.3, 0.5).abs() < TOL_M);
        assert!(m(&f, ALL, -1.0, 0.0).abs() < TOL_M);
        assert!(m(&f, ALL, 1.0, -0.5).abs() < TOL_M);
        assert!(m(&f, ALL, -1.0, 0.5).abs() < TOL_M);
    }

    #[test]
    fn outside_the_margin_is_minus_the_distance_to_the_polygon() {
        let f = rectangle();
        // Beside an edge.
        assert!((m(&f, ALL, 0.0, 0.8) + 0.3).abs() < TOL_M);
        // Beyond a vertex: the distance to the vertex.
        assert!((m(&f, ALL, 1.3, 0.9) + 0.5).abs() < TOL_M);
    }

    #[test]
    fn three_feet_make_a_triangle() {
        let f = rectangle();
        // FL lifted: the triangle FR, RL, RR; its long edge is the FR–RL diagonal.
        let s = [false, true, true, true];
        assert!(
            m(&f, s, 0.0, 0.0).abs() < TOL_M,
            "the centre is on the diagonal"
        );
        let diag_len = (4.0f32 + 1.0).sqrt();
        // (−0.5, −0.1): distance to the line x + 2y = 0 is |−0.5 − 0.2|/√5; the nearest edge.
        let expect = (0.7 / diag_len).min(0.4);
        assert!((m(&f, s, -0.5, -0.1) - expect).abs() < TOL_M);
        // On the lifted foot's side of the diagonal: outside.
        assert!(m(&f, s, 0.2, 0.1) < 0.0);
        // The triangle's vertex.
        assert!(m(&f, s, -1.0, -0.5).abs() < TOL_M);
    }

    #[test]
    fn two_feet_make_a_line_with_a_margin_of_at_most_zero() {
        let f = rectangle();
        let diagonal = [true, false, false, true];
        assert!(m(&f, diagonal, 0.0, 0.0).abs() < TOL_M);
        assert!(m(&f, diagonal, 0.5, 0.25) <= 0.0);
        let off = m(&f, diagonal, 0.0, 0.5);
        assert!((off + 0.5 * 2.0 / 5.0f32.sqrt()).abs() < TOL_M, "{off}");
        // Beyond an end of the segment: the distance to that foot.
        assert!((m(&f, diagonal, 1.3, 0.9) + 0.5).abs() < TOL_M);
        // One foot: a point.
        let one = [false, false, true, false];
        assert!((m(&f, one, -1.0, 0.2) + 0.3).abs() < TOL_M);
    }

    #[test]
    fn collinear_feet_make_a_segment() {
        let f = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(5.0, 5.0, 0.0),
        ];
        let s = [true, true, true, false];
        assert!(m(&f, s, 0.5, 0.0).abs() < TOL_M);
        assert!((m(&f, s, 0.0, 0.25) + 0.25).abs() < TOL_M);
        assert!((m(&f, s, 2.0, 0.0) + 1.0).abs() < TOL_M);
    }

    #[test]
    fn coincident_feet_and_no_feet() {
        let f = [Vec3::new(0.3, 0.4, 0.0); 4];
        assert!((m(&f, ALL, 0.0, 0.0) + 0.5).abs() < TOL_M);
        assert_eq!(m(&f, [false; 4], 0.0, 0.0), f32::NEG_INFINITY);
    }

    #[test]
    fn a_non_convex_quadrilateral_uses_its_hull() {
        let mut f = rectangle();
        // RR pulled inside: the hull is the triangle FL, FR, RL. (0, 0.05) lies below RR, out
        // of the quadrilateral FL, FR, RR, RL but inside the hull, 0.1/√5 from its FR–RL edge.
        f[3] = Vec3::new(0.0, 0.1, 0.0);
        let inside_hull = m(&f, ALL, 0.0, 0.05);
        assert!(
            (inside_hull - 0.1 / 5.0f32.sqrt()).abs() < TOL_M,
            "{inside_hull}"
        );
    }

    fn stance_angles(robot: &Robot, h: f32) -> [JointAngles; 4] {
        let feet = robot.stance_feet(h);
        let sol = Solver::new(robot)
            .inverse(
                &Pose::rotation(0.0, 0.0, 0.0),
                &BodyConfig::default(),
                &feet,
                ReachPolicy::Reject,
            )
            .expect("the stance is reachable");
        sol.angles()
    }

    #[test]
    fn the_nominal_stance_has_its_centre_of_mass_below_the_body_centre() {
        for (robot, mass, h) in [
            (Robot::shahriar2023(), MassModel::shahriar2023(), 0.4),
            (Robot::fernando2025(), MassModel::fernando2025(), 0.9),
        ] {
            mass.validate(&robot).unwrap();
            let q = stance_angles(&robot, h);
            let c = centre_of_mass_in_body::<DefaultMath>(&robot, &mass, &q);
            // Left and right mirror each other; the knees bend backwards, behind the hips.
            assert!(c.y.abs() < TOL_M, "{c:?}");
            assert!(c.x < 0.0 && c.x > -0.1 * robot.body_length_m, "{c:?}");
            assert!(c.z < 0.0, "the legs hang below the body");
            let feet = robot.stance_feet(h);
            let margin = support_margin::<DefaultMath>(&feet, ALL, c);
            let half_width = 0.5 * robot.body_width_m + robot.leg.d_lat_m;
            let expect = half_width.min(0.5 * robot.body_length_m + c.x);
            assert!((margin - expect).abs() < TOL_M, "{margin} vs {expect}");
        }
    }

    #[test]
    fn rolling_the_body_moves_its_centre_of_mass_sideways() {
        let robot = Robot::fernando2025();
        let mass = MassModel::fernando2025();
        let q = stance_angles(&robot, 0.9);
        let c = centre_of_mass_in_body::<DefaultMath>(&robot, &mass, &q);
        let cfg = BodyConfig::about_centre(RotationOrder::Zyx);
        let roll = 0.2f32;
        let pose = Pose::rotation(roll, 0.0, 0.0);
        let w = centre_of_mass::<DefaultMath>(&robot, &mass, &pose, &cfg, &q);
        // Rx(roll)·(c.x, 0, c.z): y = −sin(roll)·c.z.
        assert!((w.y + roll.sin() * c.z).abs() < TOL_M, "{w:?}");
        let pitch = 0.15f32;
        let pose = Pose::rotation(0.0, pitch, 0.0);
        let w = centre_of_mass::<DefaultMath>(&robot, &mass, &pose, &cfg, &q);
        // Ry(pitch)·(c.x, 0, c.z): x = cos(pitch)·c.x + sin(pitch)·c.z.
        assert!(
            (w.x - (pitch.cos() * c.x + pitch.sin() * c.z)).abs() < TOL_M,
            "{w:?}"
        );
    }

    #[test]
    fn a_folded_leg_raises_the_centre_of_mass() {
        let robot = Robot::shahriar2023();
        let mass = MassModel::shahriar2023();
        let mut q = stance_angles(&robot, 0.4);
        let base = centre_of_mass_in_body::<DefaultMath>(&robot, &mass, &q);
        // Fold the FL leg: its knee and foot come up.
        q[0].hip_rad += 0.5;
        q[0].knee_rad -= 1.0;
        let lifted = centre_of_mass_in_body::<DefaultMath>(&robot, &mass, &q);
        assert!(lifted.z > base.z);
    }

    #[test]
    fn bad_masses_are_refused_by_name() {
        let robot = Robot::shahriar2023();
        let mut m = MassModel::shahriar2023();
        m.femur_kg = -0.1;
        assert_eq!(m.validate(&robot), Err(MassError::Negative("femur_kg")));
        let mut m = MassModel::shahriar2023();
        m.knee_servo_offset_m = 1.0;
        assert_eq!(m.validate(&robot), Err(MassError::KneeServoBeyondFemur));
        let zero = MassModel {
            body_kg: 0.0,
            abduction_link_kg: 0.0,
            femur_kg: 0.0,
            knee_servo_kg: 0.0,
            knee_servo_offset_m: 0.0,
            tibia_kg: 0.0,
        };
        assert_eq!(zero.validate(&robot), Err(MassError::NoMass));
        assert!((MassModel::shahriar2023().total_kg() - 2.84).abs() < 1e-4);
        assert!((MassModel::fernando2025().total_kg() - 22.02).abs() < 1e-3);
    }
}
