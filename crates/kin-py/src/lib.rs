//! `quadkin`: the quadruped's kinematics and device client for Python (PyO3, built into a
//! wheel by maturin; see the package's README section in the repository's README.md).
//!
//! - [`robot::Robot`]: presets, TOML robot files, URDF; leg IK/FK, body IK/FK, the leg
//!   Jacobian and the singularity measure over numpy arrays, with a reach code per row;
//! - [`motion::sample_motion`]: the motion laws and gaits sampled to arrays, as `quadctl
//!   motion`;
//! - [`device::Device`]: the device client over the simulated controller, the firmware in
//!   simavr (through the `quad-link-bridge` process, [`bridge`]) or a serial port, with typed
//!   exceptions ([`errors`]).
//!
//! Batch calls run with the GIL released, over rayon's threads for large batches: leg IK/FK
//! and body IK through kin-core's batch solves (`kin_core::batch`, the widest form the CPU
//! runs: AVX-512, AVX2 or the portable one; [`batch`]), the others row by row ([`arrays::for_rows`]). No Rust panic is
//! meant to reach Python; PyO3 would turn one into `pyo3_runtime.PanicException`.

pub mod arrays;
pub mod batch;
pub mod bridge;
pub mod device;
pub mod errors;
pub mod motion;
pub mod protocol;
pub mod robot;

use pyo3::prelude::*;

/// The form of kin-core's batch solves that the batch calls use: the widest this CPU runs,
/// `"avx512"` (16 lanes), `"avx2"` (8 lanes) or `"portable"`, unless `set_batch_form` chose
/// another. All give the same bits.
#[pyfunction]
fn batch_form() -> &'static str {
    batch::Form::current().name()
}

/// Makes the batch calls use the form `form` (`"avx512"`, `"avx2"` or `"portable"`; `None`:
/// the widest this CPU runs again), to compare the forms or to measure one. Raises
/// `ValueError` for another name or a form this CPU cannot run.
#[pyfunction]
#[pyo3(signature = (form))]
fn set_batch_form(form: Option<&str>) -> PyResult<()> {
    let chosen = match form {
        None => None,
        Some(name) => Some(batch::Form::from_name(name).ok_or_else(|| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "form {name:?}: expected \"avx512\", \"avx2\", \"portable\" or None"
            ))
        })?),
    };
    batch::Form::choose(chosen).map_err(pyo3::exceptions::PyValueError::new_err)
}

/// The Python module `quadkin._quadkin` (re-exported by the `quadkin` package).
#[pymodule]
fn _quadkin(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<robot::Robot>()?;
    m.add_class::<device::Device>()?;
    m.add_function(wrap_pyfunction!(motion::sample_motion, m)?)?;
    m.add_function(wrap_pyfunction!(motion::motion_laws, m)?)?;
    m.add_function(wrap_pyfunction!(protocol::encode_request, m)?)?;
    m.add_function(wrap_pyfunction!(protocol::decode_answer, m)?)?;
    m.add_function(wrap_pyfunction!(batch_form, m)?)?;
    m.add_function(wrap_pyfunction!(set_batch_form, m)?)?;
    m.add("OK", robot::OK)?;
    m.add("TOO_FAR", robot::TOO_FAR)?;
    m.add("TOO_CLOSE", robot::TOO_CLOSE)?;
    m.add("INSIDE_OFFSET", robot::INSIDE_OFFSET)?;
    m.add("JOINT_LIMIT", robot::JOINT_LIMIT)?;
    m.add("NON_FINITE", robot::NON_FINITE)?;
    m.add("CODE_NAMES", robot::CODE_NAMES.to_vec())?;
    m.add(
        "SINGULARITY_THRESHOLD",
        kin_core::jacobian::SINGULARITY_THRESHOLD,
    )?;
    m.add("LEGS", ["FL", "FR", "RL", "RR"].to_vec())?;
    m.add("JOINTS", ["abduction", "hip", "knee"].to_vec())?;
    errors::register(m)?;
    Ok(())
}
