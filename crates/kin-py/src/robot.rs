//! `quadkin.Robot`: a robot description (preset, TOML robot file, URDF) and its kinematics on
//! numpy arrays: leg IK/FK, body IK/FK, the leg Jacobian and the singularity measure.

use crate::arrays::{self, for_rows};
use kin_core::batch::code;
use kin_core::body::{self, BodyConfig, Pose};
use kin_core::jacobian;
use kin_core::{
    leg, JointAngles, KneeBend, LegId, ReachPolicy, Robot as KinRobot, RotationOrder, Unreachable,
    Vec3,
};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use quad_host::robot_file;

/// `(values (N, 3), codes (N,))`.
type Rows3<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray1<i8>>);
/// `(values (N, a, b), codes (N,))`.
type Rows3d<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray1<i8>>);
/// `(values (N,), codes (N,))`.
type Rows1<'py> = (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<i8>>);
/// `(angles (N, 4, 3), codes (N,), legs (N,))`.
type BodyRows<'py> = (
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray1<i8>>,
    Bound<'py, PyArray1<i8>>,
);

// The reach codes are kin-core's batch codes (`kin_core::batch::code`), as numpy's int8.
/// Reach code of a row that was solved exactly.
pub const OK: i8 = code::OK as i8;
/// Reach code: the foot is farther than femur + tibia.
pub const TOO_FAR: i8 = code::TOO_FAR as i8;
/// Reach code: the foot is closer than |femur − tibia|.
pub const TOO_CLOSE: i8 = code::TOO_CLOSE as i8;
/// Reach code: the foot lies within `d_lat` of the abduction axis.
pub const INSIDE_OFFSET: i8 = code::INSIDE_OFFSET as i8;
/// Reach code: a joint would leave its limits.
pub const JOINT_LIMIT: i8 = code::JOINT_LIMIT as i8;
/// Reach code: an input value is NaN or infinite.
pub const NON_FINITE: i8 = code::NON_FINITE as i8;
/// The names of the reach codes, indexed by code.
pub const CODE_NAMES: [&str; 6] = code::NAMES;

/// The reach code of kin-core's reason.
pub fn code_of(kind: Unreachable) -> i8 {
    match kind {
        Unreachable::TooFar => TOO_FAR,
        Unreachable::TooClose => TOO_CLOSE,
        Unreachable::InsideOffset => INSIDE_OFFSET,
        Unreachable::JointLimit(_) => JOINT_LIMIT,
        _ => NON_FINITE,
    }
}

/// A leg argument: `"FL"`, `"FR"`, `"RL"`, `"RR"` or 0–3.
pub fn leg_arg(obj: &Bound<'_, PyAny>) -> PyResult<LegId> {
    if let Ok(i) = obj.extract::<usize>() {
        return LegId::from_index(i)
            .ok_or_else(|| PyValueError::new_err(format!("leg {i}: expected 0..=3")));
    }
    let s: String = obj.extract().map_err(|_| {
        PyValueError::new_err("leg: expected \"FL\", \"FR\", \"RL\", \"RR\" or 0..=3")
    })?;
    LegId::parse(&s).ok_or_else(|| {
        PyValueError::new_err(format!(
            "leg {s:?}: expected \"FL\", \"FR\", \"RL\", \"RR\" or 0..=3"
        ))
    })
}

/// A reach policy argument: `"reject"` or `"clamp"`.
pub fn policy_arg(name: &str) -> PyResult<ReachPolicy> {
    quad_host::names::reach_policy(name).ok_or_else(|| {
        PyValueError::new_err(format!("policy {name:?}: expected \"reject\" or \"clamp\""))
    })
}

/// A rotation order argument (`"zyx"`, …); `None`: kin-core's default.
pub fn order_arg(name: Option<&str>) -> PyResult<RotationOrder> {
    match name {
        None => Ok(RotationOrder::default()),
        Some(n) => RotationOrder::parse(n).ok_or_else(|| {
            PyValueError::new_err(format!(
                "rotation_order {n:?}: expected one of xyz, xzy, yxz, yzx, zxy, zyx"
            ))
        }),
    }
}

/// A robot: link lengths, body size, joint limits and knee bend, with its kinematics over
/// numpy arrays.
///
/// Build it from a preset name (``Robot("shahriar2023")``, ``Robot("fernando2025")``), a
/// TOML robot file or a URDF file (``Robot("robot.toml")``, ``Robot("robot.urdf")``, as
/// quadctl's ``--robot``), or TOML text (``Robot.from_toml(text)``).
///
/// Array methods take float32 or float64 arrays (or nested sequences) and return float32
/// arrays (kin-core computes in f32) with an int8 reach code per row (``quadkin.OK``,
/// ``TOO_FAR``, ``TOO_CLOSE``, ``INSIDE_OFFSET``, ``JOINT_LIMIT``, ``NON_FINITE``): a row that
/// fails gets its code and zeros, never NaN and never an exception. A wrong shape raises
/// ``ValueError``, a wrong dtype ``TypeError``, both naming the expected shape.
#[pyclass(module = "quadkin", frozen)]
pub struct Robot {
    pub(crate) robot: KinRobot,
    /// What it was built from: a preset name or a file path; `None` for TOML text.
    pub(crate) spec: Option<String>,
}

impl Robot {
    fn leg_solver(&self) -> leg::Solver {
        leg::Solver::new(&self.robot)
    }
}

fn robot_err(e: robot_file::Error) -> PyErr {
    match e {
        robot_file::Error::Read { .. } => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

#[pymethods]
impl Robot {
    /// Resolves ``spec`` as quadctl's ``--robot``: a preset name, a ``.urdf`` file or a TOML
    /// robot file. Raises ``OSError`` for an unreadable file, ``ValueError`` for an invalid
    /// one (naming the line).
    #[new]
    fn new(spec: &str) -> PyResult<Robot> {
        let d = robot_file::resolve_description(spec).map_err(robot_err)?;
        Ok(Robot {
            robot: d.robot,
            spec: Some(spec.to_owned()),
        })
    }

    /// A robot from the text of a TOML robot file. Raises ``ValueError`` naming the line.
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Robot> {
        let robot = robot_file::parse(text).map_err(robot_err)?;
        Ok(Robot { robot, spec: None })
    }

    /// The preset names.
    #[staticmethod]
    fn presets() -> Vec<&'static str> {
        KinRobot::PRESETS.to_vec()
    }

    /// The preset name or file path this robot was built from (``None`` for TOML text).
    #[getter]
    fn spec(&self) -> Option<String> {
        self.spec.clone()
    }

    /// Lateral offset of the leg plane from the abduction axis (seed 000's ``La``), m.
    #[getter]
    fn d_lat_m(&self) -> f32 {
        self.robot.leg.d_lat_m
    }

    /// Offset of the hip joint below the abduction axis (seed 001's ``l0``), m.
    #[getter]
    fn d_ax_m(&self) -> f32 {
        self.robot.leg.d_ax_m
    }

    /// Hip-to-knee length, m.
    #[getter]
    fn femur_m(&self) -> f32 {
        self.robot.leg.femur_m
    }

    /// Knee-to-foot length, m.
    #[getter]
    fn tibia_m(&self) -> f32 {
        self.robot.leg.tibia_m
    }

    /// Distance between front and rear hip mounts, m.
    #[getter]
    fn body_length_m(&self) -> f32 {
        self.robot.body_length_m
    }

    /// Distance between left and right hip mounts, m.
    #[getter]
    fn body_width_m(&self) -> f32 {
        self.robot.body_width_m
    }

    /// Lower joint limits ``[abduction, hip, knee]``, rad, shape (3,).
    #[getter]
    fn joint_min_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.robot.limits.min_rad)
    }

    /// Upper joint limits ``[abduction, hip, knee]``, rad, shape (3,).
    #[getter]
    fn joint_max_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.robot.limits.max_rad)
    }

    /// ``"backward"`` or ``"forward"``.
    #[getter]
    fn knee_bend(&self) -> &'static str {
        quad_host::names::knee_bend_name(self.robot.knee_bend)
    }

    /// This robot with the other knee solution (``"backward"`` or ``"forward"``; the knee
    /// limits mirrored as kin-core does).
    fn with_knee_bend(&self, knee_bend: &str) -> PyResult<Robot> {
        let bend: KneeBend = quad_host::names::knee_bend(knee_bend).ok_or_else(|| {
            PyValueError::new_err(format!(
                "knee_bend {knee_bend:?}: expected \"backward\" or \"forward\""
            ))
        })?;
        Ok(Robot {
            robot: self.robot.with_knee_bend(bend),
            spec: None,
        })
    }

    /// The hip mount of ``leg`` in the body frame, m, shape (3,).
    fn hip_in_body_m<'py>(
        &self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let leg = leg_arg(leg)?;
        Ok(PyArray1::from_slice(
            py,
            &self.robot.hip_in_body(leg).to_array(),
        ))
    }

    /// The nominal stance feet at height ``stance_height_m`` (world frame of the zero pose,
    /// FL, FR, RL, RR), m, shape (4, 3).
    fn stance_feet_m<'py>(
        &self,
        py: Python<'py>,
        stance_height_m: f32,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        if !(stance_height_m.is_finite() && stance_height_m > 0.0) {
            return Err(PyValueError::new_err(format!(
                "stance_height_m {stance_height_m}: expected a finite height > 0"
            )));
        }
        let feet = self.robot.stance_feet(stance_height_m);
        let flat: Vec<f32> = feet.iter().flat_map(|f| f.to_array()).collect();
        PyArray1::from_vec(py, flat).reshape([4, 3])
    }

    /// Leg IK of many foot targets of one leg: ``foot_in_hip_m`` (N, 3), the feet in the hip
    /// frame of ``leg``, m → ``(angles_rad, code)``: the joint angles ``[abduction, hip,
    /// knee]`` (N, 3) float32, rad, and the reach code (N,) int8. Under ``policy="clamp"`` an
    /// unreachable row holds the clamped angles and the code of why it was clamped; a
    /// non-finite row is ``NON_FINITE`` under both policies. The GIL is released.
    #[pyo3(signature = (leg, foot_in_hip_m, policy = "reject"))]
    fn leg_ik<'py>(
        &self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        foot_in_hip_m: &Bound<'py, PyAny>,
        policy: &str,
    ) -> PyResult<Rows3<'py>> {
        let leg = leg_arg(leg)?;
        let policy = policy_arg(policy)?;
        let rows = arrays::read(foot_in_hip_m, &[3], "foot_in_hip_m")?;
        let solver = self.leg_solver();
        let n = rows.n;
        let input = rows.slice();
        let (out, codes) = py
            .detach(|| {
                let feet = input.to_f32();
                let mut out = vec![0.0f32; n * 3];
                let mut codes = vec![0u8; n];
                crate::batch::leg_inverse(&solver, leg, policy, &feet, &mut out, &mut codes)?;
                Ok((out, codes))
            })
            .map_err(length_err)?;
        finish2(py, out, n, 3, signed(codes))
    }

    /// One leg IK: the foot ``(x_m, y_m, z_m)`` in the hip frame of ``leg`` → ``(abduction_rad,
    /// hip_rad, knee_rad)``. Raises ``quadkin.UnreachableError`` (with ``code`` and
    /// ``reason``) for a target the leg cannot reach. For many targets, :meth:`leg_ik` is
    /// far faster.
    #[pyo3(signature = (leg, x_m, y_m, z_m, policy = "reject"))]
    fn leg_ik_one(
        &self,
        leg: &Bound<'_, PyAny>,
        x_m: f32,
        y_m: f32,
        z_m: f32,
        policy: &str,
    ) -> PyResult<(f32, f32, f32)> {
        let leg = leg_arg(leg)?;
        let policy = policy_arg(policy)?;
        match self
            .leg_solver()
            .inverse(leg, Vec3::new(x_m, y_m, z_m), policy)
        {
            Ok(s) => Ok((s.angles.abduction_rad, s.angles.hip_rad, s.angles.knee_rad)),
            Err(e) => Err(crate::errors::unreachable(e)),
        }
    }

    /// Leg FK of many joint-angle rows of one leg: ``angles_rad`` (N, 3) ``[abduction, hip,
    /// knee]``, rad → ``(foot_in_hip_m, code)``: the feet in the hip frame (N, 3) float32, m,
    /// and the code (N,) int8 (``NON_FINITE`` for a row with a NaN or infinite angle, else
    /// ``OK``; the joint limits are not checked). The GIL is released.
    fn leg_fk<'py>(
        &self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        angles_rad: &Bound<'py, PyAny>,
    ) -> PyResult<Rows3<'py>> {
        let leg = leg_arg(leg)?;
        let rows = arrays::read(angles_rad, &[3], "angles_rad")?;
        let g = self.robot.leg;
        let n = rows.n;
        let input = rows.slice();
        let (out, codes) = py
            .detach(|| {
                let q = input.to_f32();
                let mut out = vec![0.0f32; n * 3];
                let mut codes = vec![0u8; n];
                crate::batch::leg_forward(&g, leg, &q, &mut out, &mut codes)?;
                Ok((out, codes))
            })
            .map_err(length_err)?;
        finish2(py, out, n, 3, signed(codes))
    }

    /// The leg Jacobian ``∂foot_in_hip/∂(abduction, hip, knee)`` at many joint-angle rows:
    /// ``angles_rad`` (N, 3), rad → ``(jacobian_m_per_rad, code)``: (N, 3, 3) float32, m/rad
    /// (row: foot axis x, y, z; column: joint), and the code (N,) int8 (``NON_FINITE`` for
    /// a non-finite row). The GIL is released.
    fn leg_jacobian<'py>(
        &self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        angles_rad: &Bound<'py, PyAny>,
    ) -> PyResult<Rows3d<'py>> {
        let leg = leg_arg(leg)?;
        let rows = arrays::read(angles_rad, &[3], "angles_rad")?;
        let g = self.robot.leg;
        let n = rows.n;
        let input = rows.slice();
        let (out, codes) = py.detach(|| {
            let mut out = vec![0.0f32; n * 9];
            let mut codes = vec![OK; n];
            for_rows(n, 9, &mut out, &mut codes, |i, o| {
                let q = JointAngles::from_array(input.row::<3>(3 * i));
                if !q.is_finite() {
                    return NON_FINITE;
                }
                let j = jacobian::leg_jacobian(&g, leg, q);
                for r in 0..3 {
                    for c in 0..3 {
                        o[3 * r + c] = j.column(c).to_array()[r];
                    }
                }
                OK
            });
            (out, codes)
        });
        let arr = PyArray1::from_vec(py, out).reshape([n, 3, 3])?;
        Ok((arr, PyArray1::from_vec(py, codes)))
    }

    /// The singularity measure at many joint-angle rows: the inverse condition number
    /// ``σ_min/σ_max`` of the leg Jacobian in [0, 1] (below ``quadkin.SINGULARITY_THRESHOLD``
    /// counts as near-singular; the device's preflight uses the same measure). ``angles_rad``
    /// (N, 3), rad → ``(inverse_condition, code)``: (N,) float32 and (N,) int8. The GIL is
    /// released.
    fn singularity<'py>(
        &self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        angles_rad: &Bound<'py, PyAny>,
    ) -> PyResult<Rows1<'py>> {
        let leg = leg_arg(leg)?;
        let rows = arrays::read(angles_rad, &[3], "angles_rad")?;
        let solver = self.leg_solver();
        let n = rows.n;
        let input = rows.slice();
        let (out, codes) = py.detach(|| {
            let mut out = vec![0.0f32; n];
            let mut codes = vec![OK; n];
            for_rows(n, 1, &mut out, &mut codes, |i, o| {
                let q = JointAngles::from_array(input.row::<3>(3 * i));
                if !q.is_finite() {
                    return NON_FINITE;
                }
                o[0] = solver.inverse_condition(leg, q);
                OK
            });
            (out, codes)
        });
        Ok((PyArray1::from_vec(py, out), PyArray1::from_vec(py, codes)))
    }

    /// Full-body IK of many body poses: ``pose`` (N, 6) ``[roll_rad, pitch_rad, yaw_rad, x_m,
    /// y_m, z_m]`` in the world frame, the feet either ``feet_in_world_m`` (N, 4, 3) or (4, 3)
    /// for every row, m, or the nominal stance at ``stance_height_m``; rotations in
    /// ``rotation_order`` about the body centre. → ``(angles_rad, code, leg)``: (N, 4, 3)
    /// float32 rad (legs FL, FR, RL, RR; joints abduction, hip, knee), the code (N,) int8 of
    /// the first leg that fails (all-or-nothing, as the device), and that leg (N,) int8
    /// (0–3, −1 for a solved row). The GIL is released.
    #[pyo3(signature = (pose, feet_in_world_m = None, stance_height_m = None, rotation_order = None, policy = "reject"))]
    fn body_ik<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        feet_in_world_m: Option<&Bound<'py, PyAny>>,
        stance_height_m: Option<f32>,
        rotation_order: Option<&str>,
        policy: &str,
    ) -> PyResult<BodyRows<'py>> {
        let policy = policy_arg(policy)?;
        let config = BodyConfig::about_centre(order_arg(rotation_order)?);
        let poses = arrays::read(pose, &[6], "pose")?;
        let n = poses.n;
        let feet = feet_arg(feet_in_world_m, stance_height_m, n)?;
        let solver = body::Solver::new(&self.robot);
        let input = poses.slice();
        let feet = match &feet {
            Feet::Stance(h) => FeetSlice::Stance(*h),
            Feet::Rows(r) => FeetSlice::Rows(r.slice()),
        };
        let (out, c, l) = py
            .detach(|| {
                let poses = input.to_f32();
                let feet_rows = match &feet {
                    FeetSlice::Stance(_) => None,
                    FeetSlice::Rows(f) => Some(f.to_f32()),
                };
                let same: Option<[Vec3; 4]> = match (&feet, &feet_rows) {
                    (FeetSlice::Rows(f), Some(rows)) if f_len(f) == 12 => {
                        Some(core::array::from_fn(|k| {
                            Vec3::new(rows[3 * k], rows[3 * k + 1], rows[3 * k + 2])
                        }))
                    }
                    _ => None,
                };
                let form = match (&feet, &same, &feet_rows) {
                    (FeetSlice::Stance(h), _, _) => crate::batch::Feet::Stance(*h),
                    (_, Some(same), _) => crate::batch::Feet::Same(same),
                    (_, None, Some(rows)) => crate::batch::Feet::PerPose(rows),
                    (_, None, None) => crate::batch::Feet::PerPose(&[]),
                };
                let mut out = vec![0.0f32; n * 12];
                let (mut codes, mut legs) = (vec![0u8; n], vec![0i8; n]);
                crate::batch::body_inverse(
                    &solver, &config, policy, &poses, form, &mut out, &mut codes, &mut legs,
                )?;
                Ok((out, codes, legs))
            })
            .map_err(length_err)?;
        let c = signed(c);
        let arr = PyArray1::from_vec(py, out).reshape([n, 4, 3])?;
        Ok((arr, PyArray1::from_vec(py, c), PyArray1::from_vec(py, l)))
    }

    /// Full-body FK: ``pose`` (N, 6) as :meth:`body_ik` and ``angles_rad`` (N, 4, 3), rad →
    /// ``(feet_in_world_m, code)``: (N, 4, 3) float32, m, and (N,) int8 (``NON_FINITE`` for a
    /// row with a non-finite value).
    #[pyo3(signature = (pose, angles_rad, rotation_order = None))]
    fn body_fk<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        angles_rad: &Bound<'py, PyAny>,
        rotation_order: Option<&str>,
    ) -> PyResult<Rows3d<'py>> {
        let config = BodyConfig::about_centre(order_arg(rotation_order)?);
        let poses = arrays::read(pose, &[6], "pose")?;
        let angles = arrays::read(angles_rad, &[4, 3], "angles_rad")?;
        if angles.n != poses.n {
            return Err(PyValueError::new_err(format!(
                "angles_rad has {} rows, pose {}: expected the same N",
                angles.n, poses.n
            )));
        }
        let robot = self.robot;
        let n = poses.n;
        let (p, a) = (poses.slice(), angles.slice());
        let (out, codes) = py.detach(|| {
            let mut out = vec![0.0f32; n * 12];
            let mut codes = vec![OK; n];
            for_rows(n, 12, &mut out, &mut codes, |i, o| {
                let pose = Pose::from_array(p.row::<6>(6 * i));
                let q: [JointAngles; 4] =
                    core::array::from_fn(|k| JointAngles::from_array(a.row::<3>(12 * i + 3 * k)));
                if !pose.is_finite() || !q.iter().all(|q| q.is_finite()) {
                    return NON_FINITE;
                }
                let feet = body::forward(&robot, &pose, &config, &q);
                for (k, f) in feet.iter().enumerate() {
                    o[3 * k..3 * k + 3].copy_from_slice(&f.to_array());
                }
                OK
            });
            (out, codes)
        });
        let arr = PyArray1::from_vec(py, out).reshape([n, 4, 3])?;
        Ok((arr, PyArray1::from_vec(py, codes)))
    }

    fn __repr__(&self) -> String {
        match &self.spec {
            Some(s) => format!("Robot({s:?})"),
            None => format!(
                "Robot(femur_m={}, tibia_m={}, d_lat_m={}, d_ax_m={})",
                self.robot.leg.femur_m,
                self.robot.leg.tibia_m,
                self.robot.leg.d_lat_m,
                self.robot.leg.d_ax_m
            ),
        }
    }
}

/// The feet of a body IK batch.
enum Feet<'py> {
    /// The nominal stance at this height, m.
    Stance(f32),
    /// (N, 4, 3) or (4, 3) for every row.
    Rows(arrays::Rows<'py>),
}

/// [`Feet`] as the solve reads it.
enum FeetSlice<'a> {
    Stance(f32),
    Rows(arrays::Slice<'a>),
}

fn f_len(s: &arrays::Slice<'_>) -> usize {
    match s {
        arrays::Slice::F32(v) => v.len(),
        arrays::Slice::F64(v) => v.len(),
    }
}

fn feet_arg<'py>(
    feet: Option<&Bound<'py, PyAny>>,
    stance_height_m: Option<f32>,
    n: usize,
) -> PyResult<Feet<'py>> {
    match (feet, stance_height_m) {
        (Some(_), Some(_)) => Err(PyValueError::new_err(
            "give feet_in_world_m or stance_height_m, not both",
        )),
        (None, None) => Err(PyValueError::new_err(
            "give feet_in_world_m (N, 4, 3) or (4, 3), m, or stance_height_m, m",
        )),
        (None, Some(h)) => Ok(Feet::Stance(h)),
        (Some(f), None) => {
            let shape: Option<Vec<usize>> = f
                .getattr("shape")
                .ok()
                .and_then(|s| s.extract::<Vec<usize>>().ok());
            let rows = if shape.as_deref() == Some(&[4, 3]) {
                let one = arrays::read(
                    &f.call_method1("reshape", ((1, 4, 3),))?,
                    &[4, 3],
                    "feet_in_world_m",
                )?;
                return Ok(Feet::Rows(one));
            } else {
                arrays::read(f, &[4, 3], "feet_in_world_m")?
            };
            if rows.n != n {
                return Err(PyValueError::new_err(format!(
                    "feet_in_world_m has {} rows, pose {n}: expected shape ({n}, 4, 3) or (4, 3)",
                    rows.n
                )));
            }
            Ok(Feet::Rows(rows))
        }
    }
}

/// kin-core's reach codes (0–5) as the int8 codes of the Python API (the same numbers).
fn signed(codes: Vec<u8>) -> Vec<i8> {
    codes.into_iter().map(|c| c as i8).collect()
}

/// A batch whose slices do not fit (never for the arrays built here): `ValueError`.
fn length_err(e: kin_core::batch::LengthMismatch) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// `(out reshaped (n, w), codes)` as numpy arrays.
fn finish2(
    py: Python<'_>,
    out: Vec<f32>,
    n: usize,
    w: usize,
    codes: Vec<i8>,
) -> PyResult<Rows3<'_>> {
    let arr = PyArray1::from_vec(py, out).reshape([n, w])?;
    Ok((arr, PyArray1::from_vec(py, codes)))
}
