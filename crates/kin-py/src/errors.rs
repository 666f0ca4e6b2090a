//! The Python exceptions of `quadkin`, and the conversion of the host's errors into them. Each
//! exception carries the facts as attributes (the device's nack reason and field, the port),
//! not only in its message.

use kin_core::IkError;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use quad_host::client;
use quad_host::link;
use quad_protocol::{Field, NackReason, ParamProblem, PreflightFault};

create_exception!(
    quadkin,
    QuadkinError,
    PyException,
    "Base class of the errors of quadkin."
);
create_exception!(
    quadkin,
    UnreachableError,
    QuadkinError,
    "A single-target solve that cannot be reached: `leg`, `code` (int) and `reason` (str)."
);
create_exception!(
    quadkin,
    DeviceError,
    QuadkinError,
    "Base class of the device client's errors."
);
create_exception!(
    quadkin,
    LinkError,
    DeviceError,
    "The link to the device could not be opened or failed: `port` names it (or `sim`, `emulator`)."
);
create_exception!(
    quadkin,
    NoAnswerError,
    DeviceError,
    "The device did not answer `request` after every retry."
);
create_exception!(
    quadkin,
    NackError,
    DeviceError,
    "The device refused `request`: `reason` (snake_case code), `detail` (its message), and where \
     it applies `leg`, `joint`, `field`, `param`, `problem`, `fault`."
);
create_exception!(
    quadkin,
    VersionError,
    DeviceError,
    "The device speaks another major protocol version: `device_version`."
);
create_exception!(
    quadkin,
    ProtocolError,
    DeviceError,
    "The device answered with an unexpected message, or runs another robot than asked."
);

/// `UnreachableError` of a single-target solve.
pub fn unreachable(e: IkError) -> PyErr {
    let err = UnreachableError::new_err(format!("{e}"));
    Python::attach(|py| {
        let v = err.value(py);
        let _ = v.setattr("leg", e.leg.name());
        let _ = v.setattr("code", crate::robot::code_of(e.kind));
        let _ = v.setattr("reason", e.kind.code());
    });
    err
}

/// A `ValueError` for a value refused before anything was sent.
pub fn value(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// The Python exception of a client error; `port` names the link.
pub fn device(e: client::Error, port: &str) -> PyErr {
    Python::attach(|py| {
        let (err, attrs): (PyErr, Vec<(&str, Py<PyAny>)>) = match &e {
            client::Error::Link(l) => (LinkError::new_err(link_text(l, port)), vec![]),
            client::Error::NoAnswer { request } => (
                NoAnswerError::new_err(format!("{port}: {e}")),
                vec![("request", str_obj(py, request))],
            ),
            client::Error::Refused { request, reason } => {
                let err = NackError::new_err(format!("{port}: {e}"));
                let mut attrs = nack_attrs(py, reason);
                attrs.push(("request", str_obj(py, request)));
                (err, attrs)
            }
            client::Error::Version { device } => (
                VersionError::new_err(format!("{port}: {e}")),
                vec![("device_version", int_obj(py, i64::from(*device)))],
            ),
            _ => (ProtocolError::new_err(format!("{port}: {e}")), vec![]),
        };
        let v = err.value(py);
        let _ = v.setattr("port", port);
        for (k, val) in attrs {
            let _ = v.setattr(k, val);
        }
        err
    })
}

/// The Python exception of a link that could not be opened.
pub fn link(e: &link::Error, port: &str) -> PyErr {
    let err = LinkError::new_err(link_text(e, port));
    Python::attach(|py| {
        let _ = err.value(py).setattr("port", port);
    });
    err
}

fn link_text(e: &link::Error, port: &str) -> String {
    let text = e.to_string();
    if text.contains(port) {
        text
    } else {
        format!("{port}: {text}")
    }
}

fn str_obj(py: Python<'_>, s: &str) -> Py<PyAny> {
    s.into_pyobject(py)
        .map(|o| o.into_any().unbind())
        .unwrap_or_else(|_| py.None())
}

fn int_obj(py: Python<'_>, i: i64) -> Py<PyAny> {
    i.into_pyobject(py)
        .map(|o| o.into_any().unbind())
        .unwrap_or_else(|_| py.None())
}

/// snake_case code of a nack reason.
pub fn nack_code(r: &NackReason) -> &'static str {
    match r {
        NackReason::UnknownVersion { .. } => "unknown_version",
        NackReason::BadCrc => "bad_crc",
        NackReason::BadFrame => "bad_frame",
        NackReason::Oversize => "oversize",
        NackReason::HelloRequired => "hello_required",
        NackReason::Unreachable { .. } => "unreachable",
        NackReason::JointLimit { .. } => "joint_limit",
        NackReason::ServoRange { .. } => "servo_range",
        NackReason::NonFinite => "non_finite",
        NackReason::BadCalibration(_) => "bad_calibration",
        NackReason::Busy => "busy",
        NackReason::OutputsDisabled => "outputs_disabled",
        NackReason::Storage => "storage",
        NackReason::InvalidArgument => "invalid_argument",
        NackReason::OutOfRange { .. } => "out_of_range",
        NackReason::InvalidParameter { .. } => "invalid_parameter",
        NackReason::Preflight { .. } => "preflight",
        NackReason::MotionRunning => "motion_running",
        NackReason::NotWalking => "not_walking",
        _ => "other",
    }
}

/// snake_case name of a field of [`NackReason::OutOfRange`].
fn field_name(f: &Field) -> String {
    match f {
        Field::Foot(leg) => format!("foot_{leg}"),
        Field::JointAngle { leg, joint } => format!("angle_{leg}_{joint}"),
        other => other.to_string(),
    }
}

fn problem_name(p: &ParamProblem) -> &'static str {
    match p {
        ParamProblem::NonFinite => "non_finite",
        ParamProblem::NotPositive => "not_positive",
        ParamProblem::Negative => "negative",
        ParamProblem::OutOfRange => "out_of_range",
        ParamProblem::BeyondReach => "beyond_reach",
    }
}

/// snake_case of a `Debug` name (`AmplitudeRad` → `amplitude_rad`, `StandUp` → `stand_up`).
pub(crate) fn snake(debug: &str) -> String {
    let mut out = String::new();
    for (i, c) in debug.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// The attributes of a nack: `reason`, `detail`, and `leg`, `joint`, `field`, `param`,
/// `problem`, `fault` (None where they do not apply).
fn nack_attrs(py: Python<'_>, r: &NackReason) -> Vec<(&'static str, Py<PyAny>)> {
    let none = || py.None();
    let s = |v: &str| str_obj(py, v);
    let (mut leg, mut joint, mut field, mut param, mut problem, mut fault) =
        (none(), none(), none(), none(), none(), none());
    match r {
        NackReason::Unreachable { leg: l, fault: f } => {
            leg = s(l.name());
            fault = s(&f.to_string());
        }
        NackReason::JointLimit { leg: l, joint: j } => {
            leg = s(l.name());
            joint = s(j.name());
        }
        NackReason::ServoRange {
            leg: l,
            joint: j,
            fault: f,
        } => {
            leg = s(l.name());
            joint = s(j.name());
            fault = s(&snake(&format!("{f:?}")));
        }
        NackReason::BadCalibration(f) => fault = s(&snake(&format!("{f:?}"))),
        NackReason::OutOfRange { field: f } => {
            field = s(&field_name(f));
            if let Field::Foot(l) | Field::JointAngle { leg: l, .. } = f {
                leg = s(l.name());
            }
            if let Field::JointAngle { joint: j, .. } = f {
                joint = s(j.name());
            }
        }
        NackReason::InvalidParameter {
            param: p,
            problem: q,
        } => {
            param = s(&snake(&format!("{p:?}")));
            problem = s(problem_name(q));
        }
        NackReason::Preflight { leg: l, fault: f } => {
            leg = s(l.name());
            fault = s(&match f {
                PreflightFault::Reach(rf) => format!("reach_{rf}"),
                PreflightFault::JointLimit(j) => format!("joint_limit_{j}"),
                other => snake(&format!("{other:?}")),
            });
        }
        _ => {}
    }
    vec![
        ("reason", s(nack_code(r))),
        ("detail", s(&r.to_string())),
        ("leg", leg),
        ("joint", joint),
        ("field", field),
        ("param", param),
        ("problem", problem),
        ("fault", fault),
    ]
}

/// Registers the exception classes in the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("QuadkinError", py.get_type::<QuadkinError>())?;
    m.add("UnreachableError", py.get_type::<UnreachableError>())?;
    m.add("DeviceError", py.get_type::<DeviceError>())?;
    m.add("LinkError", py.get_type::<LinkError>())?;
    m.add("NoAnswerError", py.get_type::<NoAnswerError>())?;
    m.add("NackError", py.get_type::<NackError>())?;
    m.add("VersionError", py.get_type::<VersionError>())?;
    m.add("ProtocolError", py.get_type::<ProtocolError>())?;
    Ok(())
}
