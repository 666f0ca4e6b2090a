//! docs/first-steps.md is true: every `quadctl` command in its shell blocks (`cargo run --release
//! -p quadctl -- ARGS`) runs against the emulated firmware, in order, in a scratch directory,
//! and exits 0 (`> FILE` written by the test):
//! - with `--port /dev/ttyACM0` replaced by `--emulator` (a fresh chip for each command);
//! - against the page's own virtual serial port (`quadctl port --emulator --link FILE`), with
//!   `/dev/ttyACM0` replaced by that port: one device for all the commands, whose state carries
//!   from one to the next (`run` after `stand` does not stand up again; `sit` and `rest` find
//!   the robot standing and move it).

mod common;

use common::repo_root;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The command line of the page's `quadctl` commands, in order: the arguments, the file a
/// `> FILE` writes, the line as written.
struct DocCommand {
    args: String,
    output: Option<String>,
    line: String,
}

/// The page's commands; `port` (the virtual port's server) is returned apart.
fn doc_commands() -> (Vec<DocCommand>, Option<String>) {
    let doc = std::fs::read_to_string(repo_root().join("docs/first-steps.md")).expect("the page");
    let mut in_block = false;
    let (mut commands, mut port) = (Vec::new(), None);
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
        if args.starts_with("port ") {
            port = Some(args.to_owned());
            continue;
        }
        let (args, output) = match args.split_once(" > ") {
            Some((a, file)) => (a, Some(file.trim().to_owned())),
            None => (args, None),
        };
        commands.push(DocCommand {
            args: args.to_owned(),
            output,
            line: line.to_owned(),
        });
    }
    (commands, port)
}

/// A scratch directory holding the example files the page uses.
fn scratch(name: &str) -> PathBuf {
    let root = repo_root();
    let dir = std::env::temp_dir().join(format!("quadctl-{name}-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("examples")).expect("a scratch directory");
    for file in ["examples/stance.csv", "examples/drive.keys"] {
        std::fs::copy(root.join(file), dir.join(file)).expect(file);
    }
    dir
}

/// Runs one of the page's commands with `args` in `dir`; returns its stdout.
fn run(command: &DocCommand, args: &str, dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_quadctl"))
        .args(args.split_whitespace())
        .current_dir(dir)
        .output()
        .expect("quadctl runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{}: {stderr}", command.line);
    if let Some(file) = &command.output {
        std::fs::write(dir.join(file), &out.stdout).expect("the output file");
    }
    String::from_utf8(out.stdout).expect("utf-8 stdout")
}

#[test]
fn every_command_of_first_steps_runs_on_the_emulator() {
    let dir = scratch("first-steps");
    let (commands, _) = doc_commands();
    for command in &commands {
        let args = command.args.replace("--port /dev/ttyACM0", "--emulator");
        assert!(
            !args.contains("/dev/"),
            "{}: a board-only path left",
            command.line
        );
        run(command, &args, &dir);
    }
    assert!(commands.len() >= 15, "{} commands found", commands.len());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The JSON summary on the last line of `stdout`.
fn summary(stdout: &str) -> serde_json::Value {
    serde_json::from_str(stdout.lines().last().expect("a last line")).expect("JSON")
}

#[test]
fn every_command_of_first_steps_runs_on_the_virtual_port_one_device_throughout() {
    let dir = scratch("first-steps-port");
    let (commands, port) = doc_commands();
    let port = port.expect("the page serves a virtual port");
    let link = port
        .split_whitespace()
        .skip_while(|&a| a != "--link")
        .nth(1)
        .expect("the port command makes a --link")
        .to_owned();
    // The test's own link file, in the scratch directory.
    let link_here = dir.join("quad-port");
    let port = port.replace(&link, link_here.to_str().expect("a UTF-8 path"));
    let mut server = Command::new(env!("CARGO_BIN_EXE_quadctl"))
        .args(port.split_whitespace())
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("quadctl port starts");
    let mut out = BufReader::new(server.stdout.take().expect("piped"));
    let mut path = String::new();
    out.read_line(&mut path).expect("the port's path");
    assert!(path.starts_with("/dev/"), "{path}");
    assert_eq!(
        std::fs::read_link(&link_here).expect("the link").to_str(),
        Some(path.trim())
    );
    let (mut runs, mut postures) = (0, 0);
    for command in &commands {
        let args = command
            .args
            .replace("--port /dev/ttyACM0", &format!("--port {}", path.trim()));
        let stdout = run(command, &args, &dir);
        let verb = args.split_whitespace().next().expect("a subcommand");
        match verb {
            "run" => {
                // The robot stood up by `stand` is still standing.
                assert_eq!(
                    summary(&stdout)["stood_up_first"],
                    false,
                    "{}",
                    command.line
                );
                runs += 1;
            }
            "play" => {
                // The page's files ask no joint more than the device's limiter allows.
                assert_eq!(summary(&stdout)["slowed_rows"], 0, "{}", command.line);
            }
            "sit" | "rest" => {
                // The robot is found standing: the posture has something to do.
                assert_eq!(summary(&stdout)["motion"], verb, "{}", command.line);
                postures += 1;
            }
            _ => {}
        }
    }
    assert!(
        (runs, postures) >= (4, 2),
        "{runs} runs, {postures} postures"
    );
    // SIGTERM ends the server cleanly, with its summary and the link removed.
    let killed = Command::new("kill")
        .arg(server.id().to_string())
        .status()
        .expect("kill runs");
    assert!(killed.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut out, &mut rest).expect("the summary");
    assert_eq!(server.wait().expect("the server ends").code(), Some(0));
    let stats = summary(&rest);
    assert!(stats["h2d_bytes"].as_u64() > Some(0), "{rest}");
    assert_eq!(stats["d2h_dropped"], 0, "{rest}");
    assert!(!link_here.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
