//! `quadkin.motion`: a motion law or gait sampled to arrays, as `quadctl motion` samples it
//! into its CSV (the same parameters, defaults, validation and solve).

use crate::robot::{code_of, OK};
use kin_core::motion::path::PathKind;
use kin_core::motion::Motion;
use kin_core::{body, DefaultMath, ReachPolicy};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quad_host::ops::motion::{self, Law, Params};
use quad_host::robot_file;

fn motion_err(e: motion::Error) -> PyErr {
    match e {
        motion::Error::Robot(robot_file::Error::Read { .. }) => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// Samples a motion law at ``rate_hz`` from t = 0 to ``duration_s`` (``quadctl motion``'s
/// laws: ``roll-sway``, ``pitch-sway``, ``yaw-sway``, ``yaw-turn``, ``rect-path``, ``trot``,
/// ``walk``; the parameters left ``None`` take the papers' defaults, as the command's).
/// ``robot`` is a preset name or a TOML robot file.
///
/// Returns a dict of arrays over the N samples: ``t_s`` (N,) float64, s; ``angles_rad``
/// (N, 4, 3) float32, rad (zeros where unreachable); ``feet_in_world_m`` (N, 4, 3) float32,
/// m; ``pose`` (N, 6) float32 ``[roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m]``; ``code``
/// (N,) int8, the reach code of the first failing leg; ``leg`` (N,) int8 (−1 when solved);
/// and ``rotation_order`` (str). Raises ``ValueError`` naming the refused parameter.
#[pyfunction]
#[pyo3(signature = (
    law, robot = "shahriar2023", duration_s = 2.0, rate_hz = 100.0, *,
    stance_height_m = None, rotation_order = None, amplitude_rad = None, period_s = None,
    yaw_rate_rad_s = None, step_period_s = None, lift_height_m = None, path = None,
    stride_m = None, step_height_m = None, duty_factor = None, cycle_s = None,
    forward_m_s = None, lateral_m_s = None, yaw_rad_s = None
))]
#[allow(clippy::too_many_arguments)]
pub fn sample_motion<'py>(
    py: Python<'py>,
    law: &str,
    robot: &str,
    duration_s: f32,
    rate_hz: f32,
    stance_height_m: Option<f32>,
    rotation_order: Option<&str>,
    amplitude_rad: Option<f32>,
    period_s: Option<f32>,
    yaw_rate_rad_s: Option<f32>,
    step_period_s: Option<f32>,
    lift_height_m: Option<f32>,
    path: Option<&str>,
    stride_m: Option<f32>,
    step_height_m: Option<f32>,
    duty_factor: Option<f32>,
    cycle_s: Option<f32>,
    forward_m_s: Option<f32>,
    lateral_m_s: Option<f32>,
    yaw_rad_s: Option<f32>,
) -> PyResult<Bound<'py, PyDict>> {
    let law_id = Law::parse(law).ok_or_else(|| {
        let names: Vec<_> = Law::ALL.iter().map(|l| l.name()).collect();
        PyValueError::new_err(format!("law {law:?}: expected one of {}", names.join(", ")))
    })?;
    let params = Params {
        robot: robot.to_owned(),
        stance_height_m,
        rotation_order: rotation_order
            .map(|o| crate::robot::order_arg(Some(o)))
            .transpose()?,
        amplitude_rad,
        period_s,
        yaw_rate_rad_s,
        step_period_s,
        lift_height_m,
        path: path
            .map(|p| {
                PathKind::parse(p).ok_or_else(|| {
                    PyValueError::new_err(format!(
                        "path {p:?}: expected rectangle, semicircle, ellipse, cycloid or bezier"
                    ))
                })
            })
            .transpose()?,
        stride_m,
        step_height_m,
        duty_factor,
        cycle_s,
        forward_m_s,
        lateral_m_s,
        yaw_rad_s,
        yaw_per_cycle_rad: None,
        shift_fraction: None,
    };
    let m = params.build(law_id).map_err(motion_err)?;
    let sweep = motion::sweep(duration_s, rate_hz).map_err(motion_err)?;
    let n = sweep.samples() as usize;
    let config = m.body_config();
    let solver = body::Solver::new(m.robot());
    let rate = f64::from(sweep.rate_hz());
    let result = py.detach(|| -> Result<_, motion::Error> {
        let mut t = Vec::with_capacity(n);
        let mut angles = vec![0.0f32; n * 12];
        let mut feet = Vec::with_capacity(n * 12);
        let mut pose = Vec::with_capacity(n * 6);
        let mut code = vec![OK; n];
        let mut leg = vec![-1i8; n];
        for k in 0..n {
            let frame = m
                .frame::<DefaultMath>(sweep.time_s(k as u32))
                .map_err(motion::param_err)?;
            t.push(k as f64 / rate);
            match solver.inverse(
                &frame.pose,
                &config,
                &frame.feet_in_world,
                ReachPolicy::Reject,
            ) {
                Ok(s) => angles[12 * k..12 * k + 12].copy_from_slice(&s.flat()),
                Err(e) => {
                    code[k] = code_of(e.kind);
                    leg[k] = e.leg.index() as i8;
                }
            }
            feet.extend(frame.feet_in_world.iter().flat_map(|f| f.to_array()));
            pose.extend(frame.pose.to_array());
        }
        Ok((t, angles, feet, pose, code, leg))
    });
    let (t, angles, feet, pose, code, leg) = result.map_err(motion_err)?;
    let d = PyDict::new(py);
    d.set_item("t_s", PyArray1::from_vec(py, t))?;
    d.set_item(
        "angles_rad",
        PyArray1::from_vec(py, angles).reshape([n, 4, 3])?,
    )?;
    d.set_item(
        "feet_in_world_m",
        PyArray1::from_vec(py, feet).reshape([n, 4, 3])?,
    )?;
    d.set_item("pose", PyArray1::from_vec(py, pose).reshape([n, 6])?)?;
    d.set_item("code", PyArray1::from_vec(py, code))?;
    d.set_item("leg", PyArray1::from_vec(py, leg))?;
    d.set_item("rotation_order", config.order.name())?;
    Ok(d)
}

/// The motion laws' names.
#[pyfunction]
pub fn motion_laws() -> Vec<&'static str> {
    Law::ALL.iter().map(|l| l.name()).collect()
}
