//! Running documented command lines as a user types them: in a fresh directory that sees the
//! repository's files (so `examples/...` resolves) and keeps every output file (`yaw.csv`,
//! `cal.toml`, ...) out of the repository, with `quadctl` on the `PATH` being this build's.

use super::repo_root;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// What one command line printed and how it exited.
pub struct Shell {
    /// The line as run (after the documented substitutions).
    pub line: String,
    /// Everything written to stdout.
    pub stdout: String,
    /// Everything written to stderr.
    pub stderr: String,
    /// The exit code (`-1` when killed by a signal).
    pub code: i32,
}

/// A fresh directory under the test target's temporary directory in which every top-level
/// entry of the repository except `target/` and `.git` is a symbolic link: documented relative
/// paths (`examples/poses.csv`, `scripts/flash.sh`) work, outputs land in this directory.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).expect("old scratch directory removed");
    }
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let root = repo_root();
    for entry in std::fs::read_dir(&root).expect("repository root") {
        let entry = entry.expect("directory entry");
        let file_name = entry.file_name();
        if file_name == "target" || file_name == ".git" {
            continue;
        }
        std::os::unix::fs::symlink(entry.path(), dir.join(&file_name)).expect("symlink");
    }
    dir
}

/// Runs `line` with `bash -o pipefail` in `dir`, `quadctl` being the binary under test.
pub fn run_line(line: &str, dir: &Path) -> Shell {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_quadctl"))
        .parent()
        .expect("binary directory")
        .to_owned();
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![bin_dir];
    paths.extend(std::env::split_paths(&path));
    let out = Command::new("bash")
        .args(["-o", "pipefail", "-c", line])
        .current_dir(dir)
        .env("PATH", std::env::join_paths(paths).expect("PATH"))
        .stdin(Stdio::null())
        .output()
        .expect("bash runs");
    Shell {
        line: line.to_owned(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        code: out.status.code().unwrap_or(-1),
    }
}
