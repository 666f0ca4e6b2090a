//! # quad-model — the quadruped as a physical model
//!
//! What a physics engine needs beyond the kinematics: masses, inertias, feet, servos, and the
//! robot description files that carry them.
//!
//! - [`Physical`] and its presets ([`Physical::shahriar2023`], [`Physical::fernando2025`]):
//!   masses, solid sizes, feet, the servo; every value an assumption documented in
//!   `docs/twin.md`. [`Model`] pairs it with a [`kin_core::Robot`] and validates both
//!   (non-positive masses and lengths are refused naming the field).
//! - [`servo`]: servo models ([`ServoModel::MG996R`], [`ServoModel::QDD17`]): stall torque,
//!   no-load speed, proportional band, deadband — the DC-motor law the twin simulates.
//! - [`mjcf`]: the MuJoCo model (a free body over a floor, the README's leg chain, the servos
//!   as actuators, an IMU site).
//! - [`urdf`]: the URDF (through `urdf-rs`), and a URDF back to a [`kin_core::Robot`] when its
//!   legs have this project's chain.
//! - [`venv`]: the twin's Python environment.
//!
//! Files are written whole or not at all ([`write_atomic`]).

pub mod inertia;
pub mod mjcf;
pub mod physical;
pub mod servo;
pub mod urdf;
pub mod venv;

pub use physical::{Error, Model, Physical};
pub use servo::{ServoModel, UnknownServo};

use std::io::Write as _;
use std::path::Path;

/// Writes `bytes` to `path` through a temporary file in the same directory, renamed over
/// `path` once written and flushed: a reader never sees a partial file, and a failure leaves
/// nothing behind (the temporary file is removed when dropped).
///
/// # Errors
/// [`Error::Write`] with the path.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let err = |source| Error::Write {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    // A temporary file is private (0600); the result is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644))
            .map_err(err)?;
    }
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}
