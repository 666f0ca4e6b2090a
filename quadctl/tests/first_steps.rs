//! docs/first-steps.md is true: every `quadctl` command in its shell blocks (`cargo run --release
//! -p quadctl -- ARGS`) runs against the
//! emulated firmware (`--port /dev/ttyACM0` replaced by `--emulator`, `> FILE` written by the
//! test), in order, in a scratch directory, and exits 0.

mod common;

use common::repo_root;
use std::process::Command;

#[test]
fn every_command_of_first_steps_runs_on_the_emulator() {
    let root = repo_root();
    let doc = std::fs::read_to_string(root.join("docs/first-steps.md")).expect("the page");
    let dir = std::env::temp_dir().join(format!("quadctl-first-steps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    std::fs::create_dir_all(dir.join("examples")).expect("examples");
    for file in ["examples/stance.csv", "examples/drive.keys"] {
        std::fs::copy(root.join(file), dir.join(file)).expect(file);
    }
    let mut in_block = false;
    let mut ran = 0;
    for line in doc.lines() {
        if line.starts_with("```") {
            in_block = line == "```sh";
            continue;
        }
        let Some(args) = line
            .strip_prefix("cargo run --release -p quadctl -- ")
            .filter(|_| in_block)
        else {
            continue;
        };
        let (args, output) = match args.split_once(" > ") {
            Some((a, file)) => (a, Some(file.trim())),
            None => (args, None),
        };
        let args = args.replace("--port /dev/ttyACM0", "--emulator");
        assert!(!args.contains("/dev/"), "{line}: a board-only path left");
        let out = Command::new(env!("CARGO_BIN_EXE_quadctl"))
            .args(args.split_whitespace())
            .current_dir(&dir)
            .output()
            .expect("quadctl runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{line}: {stderr}");
        if let Some(file) = output {
            std::fs::write(dir.join(file), &out.stdout).expect("the output file");
        }
        ran += 1;
    }
    assert!(ran >= 15, "{ran} commands found");
    let _ = std::fs::remove_dir_all(&dir);
}
