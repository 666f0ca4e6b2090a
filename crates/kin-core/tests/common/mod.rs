//! Shared test support: an independent f64 oracle of the leg chain (nalgebra rotations, not the
//! crate's formulas), an f64 analytic IK used to classify targets, a seeded RNG and the named
//! tolerances every test file uses.
#![allow(dead_code)]

use kin_core::{JointAngles, KneeBend, LegGeometry, LegId, Robot};
use nalgebra::{Rotation3, Vector3};
use std::f64::consts::PI;

/// Largest allowed distance between a target foot and the f64 FK of the angles the f32 IK
/// returned for it (the 1 µm requirement).
pub const FOOT_TOL_M: f64 = 1.0e-6;
/// Largest allowed difference between the f32 IK's angles and the exact (f64) angles of the same
/// target, away from singular configurations.
pub const ANGLE_TOL_RAD: f64 = 2.0e-5;
/// Targets whose distance to a reachability boundary is below this (in the boundary's own
/// metric: metres for lengths, radians for joint limits) may be classified either way by f32
/// rounding; tests accept either of the neighbouring outcomes there.
pub const BOUNDARY_BAND: f64 = 1.0e-5;
/// A configuration counts as "away from singularities" when the un-abducted foot is at least this
/// far from the abduction axis level (|w| in metres) ...
pub const SINGULAR_W_MARGIN_M: f64 = 0.01;
/// ... and |sin knee| exceeds this.
pub const SINGULAR_SIN_KNEE_MARGIN: f64 = 0.1;

/// Both presets with their names.
pub fn presets() -> [(&'static str, Robot); 2] {
    [
        ("shahriar2023", Robot::shahriar2023()),
        ("fernando2025", Robot::fernando2025()),
    ]
}

/// `v` as an f64 vector.
pub fn v64(v: kin_core::Vec3) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// Angles as f64 `[abduction, hip, knee]`.
pub fn q64(q: JointAngles) -> [f64; 3] {
    q.to_array().map(|a| a as f64)
}

/// Independent f64 forward kinematics of the canonical chain, built from nalgebra rotations:
/// `Rx(a)·([0, s·d_lat, −d_ax] + Ry(h)·[0,0,−L1] + Ry(h+k)·[0,0,−L2])`.
pub fn fk64(g: &LegGeometry, leg: LegId, q: [f64; 3]) -> Vector3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), q[0]);
    let ry_h = Rotation3::from_axis_angle(&Vector3::y_axis(), q[1]);
    let ry_hk = Rotation3::from_axis_angle(&Vector3::y_axis(), q[1] + q[2]);
    let side = leg.side() as f64;
    let offset = Vector3::new(0.0, side * g.d_lat_m as f64, -(g.d_ax_m as f64));
    rx * (offset
        + ry_h * Vector3::new(0.0, 0.0, -(g.femur_m as f64))
        + ry_hk * Vector3::new(0.0, 0.0, -(g.tibia_m as f64)))
}

/// Wraps into (−π, π].
pub fn wrap_pi64(a: f64) -> f64 {
    let mut r = a.rem_euclid(2.0 * PI);
    if r > PI {
        r -= 2.0 * PI;
    }
    r
}

/// Wraps into [0, 2π).
pub fn wrap_2pi64(a: f64) -> f64 {
    let r = a.rem_euclid(2.0 * PI);
    if r >= 2.0 * PI {
        0.0
    } else {
        r
    }
}

/// Absolute difference of two angles on the circle, in [0, π].
pub fn ang_diff(a: f64, b: f64) -> f64 {
    wrap_pi64(a - b).abs()
}

/// Reachability verdict of the f64 oracle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind64 {
    /// Foot within d_lat of the abduction axis.
    InsideOffset,
    /// Planar distance beyond L1 + L2.
    TooFar,
    /// Planar distance below |L1 − L2|.
    TooClose,
    /// Joint `0..3` outside its limits.
    JointLimit(usize),
}

/// What the f64 oracle says about a target.
#[derive(Debug, Clone, Copy)]
pub struct Verdict {
    /// The exact angles (when geometrically reachable) or the first reason it is not.
    pub result: Result<[f64; 3], Kind64>,
    /// Smallest distance to any decision boundary met on the way (m or rad).
    pub margin: f64,
    /// Un-abducted foot height `w` (m), when defined.
    pub w_m: f64,
}

/// Exact f64 analytic IK with the crate's branch rules (knee bend, `w ≤ 0`) and its order of
/// checks (inside offset, too far / too close, then limits in order abduction, hip, knee).
pub fn ik64(robot: &Robot, leg: LegId, p: [f64; 3]) -> Verdict {
    let g = &robot.leg;
    let (d, dax) = (g.d_lat_m as f64, g.d_ax_m as f64);
    let (l1, l2) = (g.femur_m as f64, g.tibia_m as f64);
    let s = leg.side() as f64;
    let [x, y, z] = p;
    let r = (y * y + z * z).sqrt();
    let mut margin = (r - d).abs();
    if r < d {
        return Verdict {
            result: Err(Kind64::InsideOffset),
            margin,
            w_m: f64::NAN,
        };
    }
    let w = -(r * r - d * d).max(0.0).sqrt();
    let a = wrap_pi64(z.atan2(y) - w.atan2(s * d));
    let (u, v) = (x, w + dax);
    let dist = u.hypot(v);
    margin = margin
        .min((dist - (l1 + l2)).abs())
        .min((dist - (l1 - l2).abs()).abs());
    if dist > l1 + l2 {
        return Verdict {
            result: Err(Kind64::TooFar),
            margin,
            w_m: w,
        };
    }
    if dist < (l1 - l2).abs() {
        return Verdict {
            result: Err(Kind64::TooClose),
            margin,
            w_m: w,
        };
    }
    let ck = ((dist * dist - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
    let k = match robot.knee_bend {
        KneeBend::Backward => -ck.acos(),
        KneeBend::Forward => ck.acos(),
    };
    let h = wrap_pi64((-u).atan2(-v) - (l2 * k.sin()).atan2(l1 + l2 * k.cos()));
    let q = [a, h, k];
    let limits = |j: usize| {
        (
            robot.limits.min_rad[j] as f64,
            robot.limits.max_rad[j] as f64,
        )
    };
    for (j, &qj) in q.iter().enumerate() {
        let (lo, hi) = limits(j);
        margin = margin.min((qj - lo).abs()).min((qj - hi).abs());
    }
    for (j, &qj) in q.iter().enumerate() {
        let (lo, hi) = limits(j);
        if qj < lo || qj > hi {
            return Verdict {
                result: Err(Kind64::JointLimit(j)),
                margin,
                w_m: w,
            };
        }
    }
    Verdict {
        result: Ok(q),
        margin,
        w_m: w,
    }
}

/// The crate's error kind in the oracle's vocabulary.
pub fn kind_of(u: kin_core::Unreachable) -> Option<Kind64> {
    use kin_core::{Joint, Unreachable as U};
    Some(match u {
        U::InsideOffset => Kind64::InsideOffset,
        U::TooFar => Kind64::TooFar,
        U::TooClose => Kind64::TooClose,
        U::JointLimit(Joint::Abduction) => Kind64::JointLimit(0),
        U::JointLimit(Joint::Hip) => Kind64::JointLimit(1),
        U::JointLimit(Joint::Knee) => Kind64::JointLimit(2),
        _ => return None,
    })
}

/// Un-abducted foot height `w` of a configuration (f64).
pub fn w_of(g: &LegGeometry, q: [f64; 3]) -> f64 {
    -(g.d_ax_m as f64) - (g.femur_m as f64) * q[1].cos() - (g.tibia_m as f64) * (q[1] + q[2]).cos()
}

/// The seeded generator of the deterministic (non-proptest) sweeps.
pub use seeded_rng::SplitMix64;

/// Uniform joint angles within the robot's limits, shrunk by `inset_rad` at each end.
pub fn random_angles(rng: &mut SplitMix64, robot: &Robot, inset_rad: f64) -> JointAngles {
    let l = robot.limits;
    let pick = |rng: &mut SplitMix64, j: usize| {
        rng.range(
            l.min_rad[j] as f64 + inset_rad,
            l.max_rad[j] as f64 - inset_rad,
        ) as f32
    };
    let a = pick(rng, 0);
    let h = pick(rng, 1);
    let k = pick(rng, 2);
    JointAngles::new(a, h, k)
}
