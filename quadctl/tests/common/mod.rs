//! What the `quadctl` black-box tests share: running the binary and reading what it printed.

// Each test binary uses its own part of this module.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// What one run of `quadctl` printed, and how it exited.
pub struct Run {
    /// Everything written to stdout.
    pub stdout: String,
    /// Everything written to stderr.
    pub stderr: String,
    /// The exit code.
    pub code: i32,
}

/// Runs `quadctl` from the workspace root with `args`, feeding it `stdin`.
pub fn quadctl(args: &[&str], stdin: &str) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_quadctl"))
        .args(args)
        .current_dir(repo_root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("quadctl starts");
    let written = child
        .stdin
        .take()
        .expect("stdin piped")
        .write_all(stdin.as_bytes());
    // quadctl may exit (e.g. on a bad robot file) before reading its input.
    if let Err(e) = written {
        assert_eq!(e.kind(), std::io::ErrorKind::BrokenPipe, "stdin: {e}");
    }
    let out = child.wait_with_output().expect("quadctl finishes");
    Run {
        stdout: String::from_utf8(out.stdout).expect("utf-8 stdout"),
        stderr: String::from_utf8(out.stderr).expect("utf-8 stderr"),
        code: out.status.code().expect("exit code"),
    }
}

/// The workspace root (the working directory of every [`quadctl`] run).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_owned()
}

/// The JSON object on the last line of a run's stdout (the machine-readable summary).
pub fn last_line_json(run: &Run) -> serde_json::Value {
    let last = run.stdout.lines().last().expect("a last line");
    serde_json::from_str(last).expect("the last line is JSON")
}
