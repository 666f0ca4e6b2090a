//! The wire protocol from Python: a message's JSON form (quad-protocol's `text` feature, the
//! same declaration as its bytes) to its frame and back, for clients in other languages and
//! for replaying the conformance kit (docs/conformance.md).

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use quad_protocol::{
    Accumulator, DeviceToHost, Feed, HostToDevice, MAX_DECODED_LEN, MAX_FRAME_LEN,
};

/// The frame (COBS, CRC and both delimiters) of a host-to-device message given in its JSON
/// form, e.g. ``'{"seq": 1, "request": "get_state"}'``. Raises ``ValueError`` naming what is
/// wrong with the JSON.
#[pyfunction]
pub fn encode_request<'py>(py: Python<'py>, message_json: &str) -> PyResult<Bound<'py, PyBytes>> {
    let msg: HostToDevice = serde_json::from_str(message_json)
        .map_err(|e| PyValueError::new_err(format!("not a host-to-device message: {e}")))?;
    let mut buf = [0u8; MAX_FRAME_LEN];
    let frame = quad_protocol::encode_frame(&msg, &mut buf)
        .map_err(|e| PyValueError::new_err(format!("cannot encode {message_json}: {e:?}")))?;
    Ok(PyBytes::new(py, frame))
}

/// The JSON form of the device-to-host message in ``frame`` (one whole frame, both
/// delimiters included). Raises ``ValueError`` when the bytes are not one readable frame.
#[pyfunction]
pub fn decode_answer(frame: &[u8]) -> PyResult<String> {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    match acc.feed::<DeviceToHost>(frame) {
        Feed::Frame { msg, remaining } if remaining.iter().all(|&b| b == 0) => {
            serde_json::to_string(&msg)
                .map_err(|e| PyValueError::new_err(format!("no JSON form: {e}")))
        }
        Feed::Frame { .. } => Err(PyValueError::new_err("bytes after the frame")),
        Feed::NeedMore => Err(PyValueError::new_err("not a whole frame")),
        other => Err(PyValueError::new_err(format!(
            "unreadable frame: {other:?}"
        ))),
    }
}
