//! Where the physics twin's Python lives: the project's virtual environment `.venv-twin`
//! (created by `scripts/install-deps.sh` from the pinned `twin/requirements.txt`) and the
//! `twin/` package directory, both at the workspace root.

use core::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The virtual environment's directory name, at the workspace root.
pub const VENV_DIR: &str = ".venv-twin";

/// The Python package's directory, at the workspace root.
pub const PACKAGE_DIR: &str = "twin";

/// The workspace root of this source tree (two levels above this crate's manifest).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The environment is not set up.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Missing {
    /// The interpreter looked for.
    pub python: PathBuf,
}

impl fmt::Display for Missing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the physics twin's Python `{}` is missing: run `bash scripts/install-deps.sh` \
             (creates {VENV_DIR} from twin/requirements.txt)",
            self.python.display()
        )
    }
}

impl std::error::Error for Missing {}

/// A command running `python -m quadtwin.<module>` in the twin's environment, with the
/// package on `PYTHONPATH` and offscreen rendering through EGL unless `MUJOCO_GL` is set.
///
/// # Errors
/// [`Missing`] when the environment has not been created.
pub fn python_module(root: &Path, module: &str) -> Result<Command, Missing> {
    let python = root.join(VENV_DIR).join("bin").join("python");
    if !python.is_file() {
        return Err(Missing { python });
    }
    let mut cmd = Command::new(python);
    cmd.arg("-m")
        .arg(format!("quadtwin.{module}"))
        .env("PYTHONPATH", root.join(PACKAGE_DIR))
        .env("PYTHONDONTWRITEBYTECODE", "1");
    if std::env::var_os("MUJOCO_GL").is_none() {
        cmd.env("MUJOCO_GL", "egl");
    }
    Ok(cmd)
}
