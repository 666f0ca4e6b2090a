//! # kin-wasm — kin-core in the browser
//!
//! The panel served by `quadctl serve` previews every slider position with the same `no_std`
//! kin-core the device runs, compiled to `wasm32-unknown-unknown`. This crate is the thin
//! boundary: [`preview`] (full-body IK at the stance, with each leg's status and margins) and
//! [`points`] (every joint of the four legs in the world frame, for drawing) as safe functions,
//! and below them a handful of `extern "C"` exports that move numbers through two `f32`
//! buffers in the module's memory.
//!
//! Plain exports rather than wasm-bindgen: the interface is a few arrays of `f32`, which the
//! page reads as a `Float32Array` over the module's memory; wasm-bindgen would add a CLI tool
//! whose version must match the crate's and a generated JavaScript glue file for no gain here.
//!
//! ## Exports (all numbers in SI units, rad and m)
//! - `kin_input() -> *mut f32`, `kin_output() -> *const f32`: the buffers
//!   ([`INPUT_LEN`], [`OUTPUT_LEN`] floats).
//! - `kin_set_robot() -> i32`: the robot from `input[0..13]` (see [`robot_from`]); 0, or
//!   [`ERR_BAD_ROBOT`].
//! - `kin_preview(order) -> i32`: `input[0..7]` = roll, pitch, yaw, x, y, z, stance height;
//!   writes [`Preview::write`]'s layout; returns 0 when the device would accept the pose,
//!   1 + the first leg that cannot reach otherwise, [`ERR_NO_ROBOT`] before a robot is set,
//!   [`ERR_BAD_ORDER`] for an order index outside 0..6 ([`RotationOrder::ALL`]).
//! - `kin_points(order) -> i32`: `input[0..6]` = pose, `input[6..18]` = twelve angles;
//!   writes 4 legs × 4 points (hip mount, hip joint, knee, foot) × xyz in the world frame.

// `no_std` in the browser; the host build (tests, workspace lints) links std for its panic handler.
#![cfg_attr(target_arch = "wasm32", no_std)]
// The exports below need `#[no_mangle]` and the two static buffers; everything else is safe.
#![allow(unsafe_code)]

use kin_core::body::{self, Pose};
use kin_core::leg::{self, joint_points};
use kin_core::preflight::workspace_margin;
use kin_core::{
    rotation, BodyConfig, DefaultMath, Joint, JointAngles, JointLimits, KneeBend, LegGeometry,
    LegId, ReachPolicy, Robot, RotationOrder, Unreachable, Vec3,
};

/// Floats in the input buffer.
pub const INPUT_LEN: usize = 32;
/// Floats in the output buffer.
pub const OUTPUT_LEN: usize = 64;
/// `kin_preview` / `kin_points` before `kin_set_robot` succeeded.
pub const ERR_NO_ROBOT: i32 = -1;
/// `kin_set_robot` with a robot kin-core refuses.
pub const ERR_BAD_ROBOT: i32 = -2;
/// A rotation-order index outside 0..6.
pub const ERR_BAD_ORDER: i32 = -3;

/// Status code of a leg in [`Preview::status`]: 0 reachable, else the kin-core reason.
pub fn status_code(kind: Option<Unreachable>) -> f32 {
    match kind {
        None => 0.0,
        Some(Unreachable::TooFar) => 1.0,
        Some(Unreachable::TooClose) => 2.0,
        Some(Unreachable::InsideOffset) => 3.0,
        Some(Unreachable::JointLimit(_)) => 4.0,
        Some(Unreachable::NonFinite) => 5.0,
        Some(_) => 6.0,
    }
}

/// A robot from 13 floats: d_lat, d_ax, femur, tibia (m), body length, width (m), joint
/// minima and maxima `[abduction, hip, knee]` (rad, for the knee bend), knee bend (0 backward,
/// 1 forward).
///
/// # Errors
/// kin-core's [`kin_core::robot::RobotError`] for a robot it refuses.
pub fn robot_from(v: &[f32; 13]) -> Result<Robot, kin_core::robot::RobotError> {
    let robot = Robot {
        leg: LegGeometry {
            d_lat_m: v[0],
            d_ax_m: v[1],
            femur_m: v[2],
            tibia_m: v[3],
        },
        body_length_m: v[4],
        body_width_m: v[5],
        limits: JointLimits {
            min_rad: [v[6], v[7], v[8]],
            max_rad: [v[9], v[10], v[11]],
        },
        knee_bend: if v[12] == 1.0 {
            KneeBend::Forward
        } else {
            KneeBend::Backward
        },
    };
    robot.validate()?;
    Ok(robot)
}

/// The preview of one body pose at the stance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Preview {
    /// kin-core's verdict on the whole pose (what the device answers): `Ok` or the first leg
    /// that cannot reach.
    pub result: Result<(), kin_core::IkError>,
    /// Angles to draw: the solution for a reachable leg, the clamped solution (nearest
    /// reachable point) for an unreachable one; zeros for a non-finite input. Canonical order.
    pub angles_rad: [f32; 12],
    /// Each leg's [`status_code`].
    pub status: [f32; 4],
    /// Each leg's distance to its workspace boundary, m (negative outside; NaN when not finite).
    pub workspace_margin_m: [f32; 4],
    /// Each leg's smallest distance to a joint limit at the drawn angles, rad (negative when
    /// the unclamped solution leaves them).
    pub joint_margin_rad: [f32; 4],
}

impl Preview {
    /// Writes `[angles(12), status(4), workspace margin(4), joint margin(4)]` to `out`.
    pub fn write(&self, out: &mut [f32; OUTPUT_LEN]) {
        out[..12].copy_from_slice(&self.angles_rad);
        out[12..16].copy_from_slice(&self.status);
        out[16..20].copy_from_slice(&self.workspace_margin_m);
        out[20..24].copy_from_slice(&self.joint_margin_rad);
    }
}

fn joint_margin(limits: &JointLimits, q: JointAngles) -> f32 {
    Joint::ALL
        .into_iter()
        .map(|j| limits.margin(j, q.get(j)))
        .fold(f32::INFINITY, f32::min)
}

/// Body pose `pose` with the feet at the stance of height `stance_height_m`: kin-core's
/// full-body IK (the reject policy, as the device runs it) and, per leg, its status and
/// margins.
pub fn preview(robot: &Robot, order: RotationOrder, pose: &Pose, stance_height_m: f32) -> Preview {
    let solver = body::Solver::new(robot);
    let config = BodyConfig {
        order,
        pivot_m: Vec3::ZERO,
    };
    let solution = solver.inverse_at_stance(pose, &config, stance_height_m, ReachPolicy::Reject);
    let result = solution.map(|_| ());
    let mut p = Preview {
        result,
        angles_rad: [0.0; 12],
        status: [0.0; 4],
        workspace_margin_m: [f32::NAN; 4],
        joint_margin_rad: [f32::NAN; 4],
    };
    if !(pose.is_finite() && stance_height_m.is_finite()) {
        p.status = [status_code(Some(Unreachable::NonFinite)); 4];
        return p;
    }
    // Per leg, through the general transform of the stance feet (the same feet as the body
    // solve's closed form up to f32 rounding); the angles of a reachable pose are the body
    // solve's own, below.
    let feet = solver.feet_in_hips(pose, &config, &robot.stance_feet(stance_height_m));
    for leg in LegId::ALL {
        let i = leg.index();
        let foot = feet[i];
        p.workspace_margin_m[i] = workspace_margin(robot, foot).map_or(f32::NAN, |(m, _)| m);
        let (angles, kind, margin) = match solver.leg().inverse(leg, foot, ReachPolicy::Reject) {
            Ok(s) => (s.angles, None, joint_margin(&robot.limits, s.angles)),
            Err(e) => {
                let clamped = solver.leg().inverse(leg, foot, ReachPolicy::Clamp).ok();
                let angles = clamped.map_or(JointAngles::new(0.0, 0.0, 0.0), |s| s.angles);
                // The margin of the unclamped angles when only a joint limit failed:
                // how far past the limit the slider asks.
                let margin = match e.kind {
                    Unreachable::JointLimit(_) => unclamped_joint_margin(robot, leg, foot),
                    _ => joint_margin(&robot.limits, angles),
                };
                (angles, Some(e.kind), margin)
            }
        };
        p.angles_rad[3 * i..3 * i + 3].copy_from_slice(&angles.to_array());
        p.status[i] = status_code(kind);
        p.joint_margin_rad[i] = margin;
    }
    if let Ok(s) = solution {
        p.angles_rad = s.flat();
    }
    p
}

/// The joint margin of the leg's IK without joint limits (negative past a limit).
fn unclamped_joint_margin(robot: &Robot, leg: LegId, foot: Vec3) -> f32 {
    let free = Robot {
        limits: JointLimits::FULL_TURN,
        ..*robot
    };
    match leg::Solver::new(&free).inverse(leg, foot, ReachPolicy::Reject) {
        Ok(s) => joint_margin(&robot.limits, s.angles),
        Err(_) => f32::NAN,
    }
}

/// Every joint of the four legs in the world frame, for drawing: per leg (FL, FR, RL, RR) the
/// hip mount, hip joint, knee and foot, each `[x, y, z]`, m.
pub fn points(
    robot: &Robot,
    order: RotationOrder,
    pose: &Pose,
    angles_rad: &[f32; 12],
) -> [f32; 48] {
    let r = rotation::matrix::<DefaultMath>(order, pose.roll_rad, pose.pitch_rad, pose.yaw_rad);
    let t = pose.translation();
    let mut out = [0.0; 48];
    for leg in LegId::ALL {
        let i = leg.index();
        let q = JointAngles::new(
            angles_rad[3 * i],
            angles_rad[3 * i + 1],
            angles_rad[3 * i + 2],
        );
        let lp = joint_points(&robot.leg, leg, q);
        let hip = robot.hip_in_body(leg);
        for (k, p) in [lp.hip_mount, lp.hip_joint, lp.knee, lp.foot]
            .into_iter()
            .enumerate()
        {
            let w = r.mul_vec(hip + p) + t;
            out[12 * i + 3 * k..12 * i + 3 * k + 3].copy_from_slice(&[w.x, w.y, w.z]);
        }
    }
    out
}

/// The two buffers and the robot: the module's whole state. WebAssembly without threads runs
/// one call at a time, so the exports are never re-entered.
struct State {
    input: [f32; INPUT_LEN],
    output: [f32; OUTPUT_LEN],
    robot: Option<Robot>,
}

static mut STATE: State = State {
    input: [0.0; INPUT_LEN],
    output: [0.0; OUTPUT_LEN],
    robot: None,
};

/// The module's state.
fn state() -> &'static mut State {
    // SAFETY: single-threaded WebAssembly (and single-threaded host tests of these exports);
    // each export takes this reference once and drops it before returning.
    unsafe { &mut *core::ptr::addr_of_mut!(STATE) }
}

fn order_of(index: u32) -> Option<RotationOrder> {
    RotationOrder::ALL.get(index as usize).copied()
}

/// What a pose export starts with: the state, the robot set, the rotation order of `order` and
/// the pose of `input[0..6]`; else the export's error code.
fn call(order: u32) -> Result<(&'static mut State, Robot, RotationOrder, Pose), i32> {
    let s = state();
    let robot = s.robot.ok_or(ERR_NO_ROBOT)?;
    let order = order_of(order).ok_or(ERR_BAD_ORDER)?;
    let i = &s.input;
    let pose = Pose::from_array([i[0], i[1], i[2], i[3], i[4], i[5]]);
    Ok((s, robot, order, pose))
}

/// The input buffer ([`INPUT_LEN`] floats).
#[no_mangle]
pub extern "C" fn kin_input() -> *mut f32 {
    state().input.as_mut_ptr()
}

/// The output buffer ([`OUTPUT_LEN`] floats).
#[no_mangle]
pub extern "C" fn kin_output() -> *const f32 {
    state().output.as_ptr()
}

/// Sets the robot from `input[0..13]` ([`robot_from`]).
#[no_mangle]
pub extern "C" fn kin_set_robot() -> i32 {
    let s = state();
    let mut v = [0.0; 13];
    v.copy_from_slice(&s.input[..13]);
    match robot_from(&v) {
        Ok(r) => {
            s.robot = Some(r);
            0
        }
        Err(_) => ERR_BAD_ROBOT,
    }
}

/// [`preview`] of `input[0..7]`; see the crate docs for the codes.
#[no_mangle]
pub extern "C" fn kin_preview(order: u32) -> i32 {
    let (s, robot, order, pose) = match call(order) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let i = &s.input;
    let p = preview(&robot, order, &pose, i[6]);
    p.write(&mut s.output);
    match p.result {
        Ok(()) => 0,
        Err(e) => 1 + e.leg.index() as i32,
    }
}

/// [`points`] of `input[0..18]`; see the crate docs.
#[no_mangle]
pub extern "C" fn kin_points(order: u32) -> i32 {
    let (s, robot, order, pose) = match call(order) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let i = &s.input;
    let mut angles = [0.0; 12];
    angles.copy_from_slice(&i[6..18]);
    s.output[..48].copy_from_slice(&points(&robot, order, &pose, &angles));
    0
}

#[cfg(all(target_arch = "wasm32", not(test)))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    core::arch::wasm32::unreachable()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shahriar() -> [f32; 13] {
        let r = Robot::shahriar2023();
        let l = r.limits;
        [
            r.leg.d_lat_m,
            r.leg.d_ax_m,
            r.leg.femur_m,
            r.leg.tibia_m,
            r.body_length_m,
            r.body_width_m,
            l.min_rad[0],
            l.min_rad[1],
            l.min_rad[2],
            l.max_rad[0],
            l.max_rad[1],
            l.max_rad[2],
            0.0,
        ]
    }

    #[test]
    fn robot_round_trips() {
        assert_eq!(robot_from(&shahriar()).unwrap(), Robot::shahriar2023());
        let mut bad = shahriar();
        bad[2] = -1.0;
        assert!(robot_from(&bad).is_err());
    }

    #[test]
    fn preview_agrees_with_kin_core() {
        let robot = Robot::shahriar2023();
        let config = BodyConfig::default();
        let pose = Pose::rotation(0.1, -0.05, 0.2);
        let p = preview(&robot, config.order, &pose, 0.4);
        let want = body::Solver::new(&robot)
            .inverse_at_stance(&pose, &config, 0.4, ReachPolicy::Reject)
            .unwrap()
            .flat();
        assert_eq!(p.result, Ok(()));
        assert_eq!(p.angles_rad, want);
        assert_eq!(p.status, [0.0; 4]);
        assert!(p.workspace_margin_m.iter().all(|&m| m > 0.0));
        assert!(p.joint_margin_rad.iter().all(|&m| m >= 0.0));
        // FK of the drawn angles puts each foot where the body FK puts it.
        let pts = points(&robot, config.order, &pose, &p.angles_rad);
        let feet = body::forward(&robot, &pose, &config, &body::unflatten(&p.angles_rad));
        for (i, f) in feet.iter().enumerate() {
            let got = &pts[12 * i + 9..12 * i + 12];
            assert!(
                (got[0] - f.x).abs() < 1e-6
                    && (got[1] - f.y).abs() < 1e-6
                    && (got[2] - f.z).abs() < 1e-6
            );
        }
    }

    #[test]
    fn unreachable_pose_is_reported_per_leg() {
        let robot = Robot::shahriar2023();
        // Stance deeper than the stretched leg: every leg too far.
        let p = preview(
            &robot,
            RotationOrder::Zyx,
            &Pose::rotation(0.0, 0.0, 0.0),
            0.7,
        );
        assert_eq!(p.result.unwrap_err().leg, LegId::FL);
        assert_eq!(p.status, [1.0; 4]);
        assert!(p.workspace_margin_m.iter().all(|&m| m < 0.0));
        let p = preview(
            &robot,
            RotationOrder::Zyx,
            &Pose::rotation(f32::NAN, 0.0, 0.0),
            0.4,
        );
        assert!(p.result.is_err());
        assert_eq!(p.status, [5.0; 4]);
    }

    #[test]
    fn exports_use_the_buffers() {
        let s = state();
        s.input[..13].copy_from_slice(&shahriar());
        assert_eq!(kin_set_robot(), 0);
        s.input[..7].copy_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.4]);
        assert_eq!(kin_preview(5), 0);
        assert_eq!(kin_preview(6), ERR_BAD_ORDER);
        s.input[6] = 0.7;
        assert_eq!(kin_preview(5), 1);
        assert_eq!(state().output[12], 1.0);
    }
}
