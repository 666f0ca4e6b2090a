//! Every command of the fenced `sh` blocks of README.md and docs/*.md runs as written.
//!
//! Each document's commands run in order in a scratch directory that sees the repository's
//! files (`examples/...`, `scripts/...`) and receives their outputs (`yaw.csv`, `cal.toml`, ...),
//! so nothing is written into the repository. `cargo run --release -p quadctl -- ARGS` runs as
//! `quadctl ARGS` with the binary under test (the build itself is CI's). Commands are matched in
//! order against [`RULES`]: a command that no rule covers fails the test, so a new command in
//! the docs is run or explicitly listed, never silently skipped. The commands that are not run
//! as written are the ones that need a board (the port replaced by one that does not exist, or
//! `--dry-run`), the CI itself, and the long ones that a test of their own already runs; each is
//! still checked as far as it can be without running it, as its rule says.

mod common;

use common::shell::{run_line, scratch_dir, Shell};
use common::{quadctl, repo_root};
use std::path::{Path, PathBuf};
use std::process::Command;

/// How a documented command is checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Check {
    /// Run as written; exit status 0.
    Run,
    /// `quadctl` on a board's port: run with the port replaced by a path that does not exist;
    /// the arguments must be accepted and the run must stop at opening that port.
    BoardPort,
    /// `scripts/flash.sh` on a board: run with `--dry-run`, which builds the firmware and prints
    /// the avrdude command instead of running it.
    FlashDryRun,
    /// The manual avrdude command: must equal what `scripts/flash.sh --dry-run` prints.
    Avrdude,
    /// A `cargo xtask` command that is the CI itself or is run elsewhere: xtask must list the
    /// subcommand in its usage (`ci` must also list its steps).
    Xtask,
    /// The install step of `cargo xtask ci` (its `deps` step): the script must parse.
    InstallScript,
    /// The demo: minutes at its default size; `emulator_cli`'s demo test runs it (fewer poses)
    /// and xtask's unit test pins that `cargo xtask demo` installs first. Parsed only.
    Demo,
    /// `cargo run -p PACKAGE --example NAME` or `cargo bench -p PACKAGE`, run by the package's
    /// own tests (the physics twin needs MuJoCo's Python environment and minutes; benchmarks
    /// take minutes): the package and its example or benchmarks must exist.
    CargoTarget,
    /// `quadctl sim`: the physics twin needs MuJoCo's Python environment and, rendering or with
    /// the firmware in simavr, minutes; `twin_cli` runs it. Run with `--help` appended: the
    /// arguments must be accepted.
    SimArgs,
    /// `cd firmware-avr && cargo build --release [--bin NAME]`: the firmware build, which is the
    /// `firmware` step of `cargo xtask ci`: a `--bin` must name a binary of
    /// firmware-avr/Cargo.toml.
    FirmwareBuild,
    /// `quadctl serve`: serves until Ctrl-C. Run with `--check` (and `--listen 127.0.0.1:0`
    /// unless the line sets an address): the device must open, the address bind and the page
    /// be complete, then it stops; on a board's port, as [`Check::BoardPort`].
    Serve,
    /// `quadctl port`: serves a virtual serial port until interrupted. Started as written: the
    /// first line of its output must be the port's path (and a `--link` must point to it);
    /// then SIGTERM must end it with status 0. `first_steps` runs a page's commands against it.
    Port,
    /// `QUAD_RECORD=1 cargo test --release -p integration-tests --test NAME`: re-records the
    /// files that test compares (its own run, without the variable, is part of the test
    /// suite): the test must exist.
    Recorder,
}

/// (how the command starts, how it is checked), first match wins.
const RULES: &[(&str, Check)] = &[
    ("cargo xtask demo", Check::Demo),
    ("cargo run --release -p quadctl -- demo", Check::Demo),
    ("cargo xtask ", Check::Xtask),
    ("bash scripts/install-deps.sh", Check::InstallScript),
    ("scripts/flash.sh --dry-run ", Check::Run),
    ("scripts/flash.sh ", Check::FlashDryRun),
    ("avrdude ", Check::Avrdude),
    (
        "cargo run --release -p quad-twin --example ",
        Check::CargoTarget,
    ),
    ("cargo bench -p ", Check::CargoTarget),
    (
        "cd firmware-avr && cargo build --release",
        Check::FirmwareBuild,
    ),
    (
        "QUAD_RECORD=1 cargo test --release -p integration-tests --test ",
        Check::Recorder,
    ),
    ("cargo run --release -p quadctl -- sim ", Check::SimArgs),
    ("cargo run --release -p quadctl -- serve ", Check::Serve),
    ("cargo run --release -p quadctl -- port ", Check::Port),
    ("cargo run --release -p quadctl -- ", Check::Run),
];

const QUADCTL: &str = "cargo run --release -p quadctl -- ";
const BOARD_PORT: &str = "/dev/ttyACM0";

/// The commands of the `sh`/`bash` fenced blocks of `text`: comments and blank lines dropped,
/// `\` continuations joined.
fn commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut pending = String::new();
    for line in text.lines() {
        let t = line.trim();
        if let Some(info) = t.strip_prefix("```") {
            in_block = !in_block && matches!(info.trim(), "sh" | "bash" | "shell" | "console");
            continue;
        }
        if !in_block || t.is_empty() || t.starts_with('#') {
            continue;
        }
        // A trailing comment: ` # ...` (no command here has a `#` of its own).
        let t = t.split(" #").next().unwrap_or(t).trim();
        if let Some(head) = t.strip_suffix('\\') {
            pending.push_str(head);
            continue;
        }
        pending.push_str(t);
        out.push(std::mem::take(&mut pending));
    }
    out
}

/// The documents whose commands must run: README.md and docs/*.md.
fn documents() -> Vec<PathBuf> {
    let root = repo_root();
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    docs.insert(0, root.join("README.md"));
    docs
}

fn rule(command: &str) -> Option<Check> {
    RULES
        .iter()
        .find(|(start, _)| command.starts_with(start) || command == start.trim_end())
        .map(|&(_, check)| check)
}

fn as_quadctl(command: &str) -> String {
    match command.strip_prefix(QUADCTL) {
        Some(args) => format!("quadctl {args}"),
        None => command.to_owned(),
    }
}

fn assert_ok(run: &Shell, what: &str) {
    assert_eq!(
        run.code, 0,
        "{what}: `{}` failed\nstdout:\n{}\nstderr:\n{}",
        run.line, run.stdout, run.stderr
    );
}

/// The xtask program built on its own (it has no dependencies: seconds) in a target directory
/// of this test, so that no lock of the build running this test is needed.
fn xtask(args: &[&str]) -> std::process::Output {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let target = Path::new(env!("CARGO_TARGET_TMPDIR")).join("docs-xtask-target");
    Command::new(cargo)
        .args([
            "run",
            "--quiet",
            "--offline",
            "--package",
            "xtask",
            "--target-dir",
        ])
        .arg(target)
        .arg("--")
        .args(args)
        .current_dir(repo_root())
        .env_remove("RUSTUP_TOOLCHAIN")
        .output()
        .expect("cargo runs")
}

/// What `scripts/flash.sh --dry-run` prints for `args`, with the repository's path made
/// relative.
fn flash_dry_run(args: &str, dir: &Path) -> String {
    let run = run_line(&format!("scripts/flash.sh --dry-run {args}"), dir);
    assert_ok(&run, "flash.sh --dry-run");
    let last = run
        .stdout
        .lines()
        .last()
        .expect("the avrdude line")
        .to_owned();
    let root = format!("{}/", repo_root().canonicalize().expect("root").display());
    let dir = format!("{}/", dir.display());
    last.replace(&dir, "").replace(&root, "")
}

fn check_command(command: &str, check: Check, dir: &Path) {
    match check {
        Check::Run => assert_ok(&run_line(&as_quadctl(command), dir), "run as written"),
        Check::Serve => {
            let listen = if command.contains("--listen") {
                ""
            } else {
                " --listen 127.0.0.1:0"
            };
            let line = format!("{}{listen} --check", as_quadctl(command));
            if line.contains(BOARD_PORT) {
                let port = dir.join("no-board");
                let port = port.to_str().expect("utf-8 path");
                let run = run_line(&line.replace(BOARD_PORT, port), dir);
                assert_eq!(run.code, 2, "{}: {}", run.line, run.stderr);
                assert!(run.stderr.contains(port), "{}: {}", run.line, run.stderr);
            } else {
                let run = run_line(&line, dir);
                assert_ok(&run, "checked with --check");
                assert!(run.stdout.contains("page complete"), "{}", run.stdout);
            }
        }
        Check::Port => {
            let line = as_quadctl(command);
            let args: Vec<&str> = line.split_whitespace().skip(1).collect();
            let mut server = Command::new(env!("CARGO_BIN_EXE_quadctl"))
                .args(&args)
                .current_dir(dir)
                .stdout(std::process::Stdio::piped())
                .spawn()
                .expect("quadctl port starts");
            let mut out = std::io::BufReader::new(server.stdout.take().expect("piped"));
            let mut path = String::new();
            std::io::BufRead::read_line(&mut out, &mut path).expect("the port's path");
            let link = args.iter().skip_while(|&&a| a != "--link").nth(1);
            let linked = link.map(|l| std::fs::read_link(dir.join(l)));
            let stopped = Command::new("kill")
                .arg(server.id().to_string())
                .status()
                .expect("kill runs");
            let status = server.wait().expect("the server ends");
            assert!(path.starts_with("/dev/"), "{command}: {path}");
            if let Some(linked) = linked {
                assert_eq!(
                    linked.expect("the link").to_str(),
                    Some(path.trim()),
                    "{command}"
                );
            }
            assert!(stopped.success() && status.code() == Some(0), "{command}");
        }
        Check::SimArgs => assert_ok(
            &run_line(&format!("{} --help", as_quadctl(command)), dir),
            "arguments accepted",
        ),
        Check::BoardPort => {
            let port = dir.join("no-board");
            let port = port.to_str().expect("utf-8 path");
            let run = run_line(&as_quadctl(command).replace(BOARD_PORT, port), dir);
            assert_eq!(run.code, 2, "{}: {}", run.line, run.stderr);
            assert!(run.stderr.contains(port), "{}: {}", run.line, run.stderr);
            assert!(
                !run.stderr.contains("Usage:"),
                "{}: {}",
                run.line,
                run.stderr
            );
        }
        Check::FlashDryRun => {
            let args = command.strip_prefix("scripts/flash.sh ").expect("flash.sh");
            let avrdude = flash_dry_run(args, dir);
            assert!(avrdude.starts_with("avrdude "), "{avrdude}");
        }
        Check::Avrdude => {
            let printed = flash_dry_run(BOARD_PORT, dir);
            assert_eq!(
                command, printed,
                "the documented avrdude command is flash.sh's"
            );
        }
        Check::Xtask => {
            let sub = command
                .strip_prefix("cargo xtask ")
                .and_then(|a| a.split_whitespace().next())
                .expect("an xtask subcommand");
            let usage = xtask(&["--help"]);
            let usage = String::from_utf8_lossy(&usage.stdout);
            assert!(
                usage.contains(&format!("cargo xtask {sub}")),
                "xtask has no `{sub}`: {usage}"
            );
            if sub == "ci" {
                let list = xtask(&["ci", "--list"]);
                let list = String::from_utf8_lossy(&list.stdout);
                for step in ["deps", "test"] {
                    assert!(list.contains(step), "ci steps: {list}");
                }
            }
        }
        Check::InstallScript => {
            let run = run_line("bash -n scripts/install-deps.sh", dir);
            assert_ok(&run, "the install script parses");
            let list = xtask(&["ci", "--list"]);
            assert!(
                String::from_utf8_lossy(&list.stdout)
                    .contains("deps           bash scripts/install-deps.sh"),
                "the install script is ci's deps step"
            );
        }
        Check::Demo => {
            let args = command
                .strip_prefix("cargo xtask demo")
                .or_else(|| command.strip_prefix("cargo run --release -p quadctl -- demo"))
                .expect("a demo command");
            let args: Vec<&str> = args.split_whitespace().collect();
            let run = quadctl(&[&["demo"], args.as_slice(), &["--help"]].concat(), "");
            assert_eq!(run.code, 0, "{command}: {}", run.stderr);
        }
        Check::CargoTarget => {
            let words: Vec<&str> = command.split_whitespace().collect();
            let after = |flag: &str| {
                words
                    .iter()
                    .position(|w| *w == flag)
                    .and_then(|i| words.get(i + 1))
                    .copied()
            };
            let package = after("-p").expect("-p PACKAGE");
            let dir = repo_root().join("crates").join(package);
            let manifest = std::fs::read_to_string(dir.join("Cargo.toml"))
                .unwrap_or_else(|e| panic!("{command}: no crates/{package}: {e}"));
            assert!(
                manifest.contains(&format!("name = \"{package}\"")),
                "{command}"
            );
            match after("--example") {
                Some(example) => assert!(
                    dir.join(format!("examples/{example}.rs")).is_file(),
                    "{command}: no example {example}"
                ),
                None => assert!(dir.join("benches").is_dir(), "{command}: no benches"),
            }
        }
        Check::Recorder => {
            let name = command.split_whitespace().last().expect("a test name");
            assert!(
                repo_root()
                    .join("tests/tests")
                    .join(format!("{name}.rs"))
                    .is_file(),
                "{command}: no test {name}"
            );
        }
        Check::FirmwareBuild => {
            let manifest = std::fs::read_to_string(repo_root().join("firmware-avr/Cargo.toml"))
                .expect("firmware-avr/Cargo.toml");
            let words: Vec<&str> = command.split_whitespace().collect();
            if let Some(i) = words.iter().position(|w| *w == "--bin") {
                let bin = words.get(i + 1).expect("--bin NAME");
                assert!(
                    manifest.contains(&format!("name = \"{bin}\"")),
                    "{command}: firmware-avr/Cargo.toml has no binary {bin}"
                );
            }
        }
    }
}

#[test]
fn the_fenced_commands_are_found() {
    let text = "```sh\n# comment\ncargo run --release -p quadctl -- ik \\\n  --robot x  # why\n\n\
                ```\n```text\nnot a command\n```\n";
    assert_eq!(
        commands(text),
        ["cargo run --release -p quadctl -- ik --robot x"]
    );
}

#[test]
fn every_command_of_the_readme_and_docs_runs_as_written() {
    let mut total = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).expect("document");
        let name = doc
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let dir = scratch_dir(&format!("docs-{name}"));
        for command in commands(&text) {
            let check = rule(&command)
                .unwrap_or_else(|| panic!("{name}: no rule for `{command}`: add one to RULES"));
            let check = if check == Check::Run
                && command.starts_with(QUADCTL)
                && command.contains(BOARD_PORT)
            {
                Check::BoardPort
            } else {
                check
            };
            check_command(&command, check, &dir);
            total += 1;
        }
    }
    assert!(total >= 20, "only {total} commands found");
}
