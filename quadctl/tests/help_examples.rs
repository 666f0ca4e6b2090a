//! Every subcommand's `--help` (and `-h`) ends with example command lines, and those lines run
//! as written from the repository root.

mod common;

use common::quadctl;
use common::shell::{run_line, scratch_dir};

/// Examples that are not run here, each with the reason; they are still parsed (the line with
/// `--help` appended must be accepted).
const NOT_RUN: &[(&str, &str)] = &[
    (
        "quadctl demo",
        "the full demo (300 poses on the emulated firmware) takes minutes; \
         emulator_cli's demo_passes_on_the_emulator runs it with fewer poses",
    ),
    (
        "quadctl demo --poses-per-sweep 20 --baud 1000000",
        "emulator_cli's demo_passes_on_the_emulator runs the demo at 1000000 baud",
    ),
    (
        "quadctl serve --emulator",
        "serves until Ctrl-C; crates/quad-web's browser tests run the server on the emulator",
    ),
    (
        "quadctl serve --sim --listen 127.0.0.1:0",
        "serves until Ctrl-C; crates/quad-web's browser tests run the server on the simulated device",
    ),
    (
        "quadctl port --sim --robot shahriar2023",
        "serves until Ctrl-C; docs_commands runs the port of first-steps.md and stops it",
    ),
    (
        "quadctl port --emulator --link /tmp/quad-port",
        "serves until Ctrl-C; first_steps runs every command of first-steps.md against it",
    ),
];

/// The subcommands listed by `quadctl --help`.
fn subcommands() -> Vec<String> {
    let run = quadctl(&["--help"], "");
    assert_eq!(run.code, 0);
    run.stdout
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_owned)
        .collect()
}

/// The `quadctl ...` lines of the examples section of a help text.
fn examples(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Example"))
        .filter_map(|l| {
            let l = l.trim_start_matches("Example: ").trim();
            l.starts_with("quadctl ").then(|| l.to_owned())
        })
        .collect()
}

#[test]
fn every_subcommand_help_ends_with_examples() {
    let commands = subcommands();
    assert!(commands.len() >= 10, "{commands:?}");
    for cmd in &commands {
        for flag in ["-h", "--help"] {
            let run = quadctl(&[cmd, flag], "");
            assert_eq!(run.code, 0, "{cmd} {flag}");
            let lines = examples(&run.stdout);
            assert!(
                lines
                    .iter()
                    .any(|l| l.starts_with(&format!("quadctl {cmd} "))
                        || l == &format!("quadctl {cmd}")),
                "`quadctl {cmd} {flag}` has no example of itself: {lines:?}"
            );
        }
    }
    for action in ["get", "set", "save"] {
        let run = quadctl(&["calibrate", action, "--help"], "");
        assert_eq!(run.code, 0);
        assert!(
            examples(&run.stdout)
                .iter()
                .any(|l| l.starts_with("quadctl calibrate") && l.contains(action)),
            "calibrate {action}: {}",
            run.stdout
        );
    }
}

#[test]
fn help_examples_run_as_written() {
    let mut not_run_seen = Vec::new();
    for cmd in subcommands() {
        let help = quadctl(&[&cmd, "--help"], "").stdout;
        // One directory per subcommand: its examples may use each other's files, in order.
        let dir = scratch_dir(&format!("help-examples-{cmd}"));
        for line in examples(&help) {
            if let Some((_, reason)) = NOT_RUN.iter().find(|(l, _)| *l == line) {
                not_run_seen.push(line.clone());
                let parsed = run_line(&format!("{line} --help"), &dir);
                assert_eq!(parsed.code, 0, "{line} ({reason}): {}", parsed.stderr);
                continue;
            }
            if line.contains("/dev/ttyACM0") {
                // Needs a board: run against a port that does not exist; the line must get as
                // far as opening it (arguments accepted, the error names the port).
                let port = dir.join("no-board");
                let port = port.to_str().expect("utf-8 path");
                let run = run_line(&line.replace("/dev/ttyACM0", port), &dir);
                assert_eq!(run.code, 2, "{}: {}", run.line, run.stderr);
                assert!(run.stderr.contains(port), "{}: {}", run.line, run.stderr);
                assert!(!run.stderr.contains("Usage:"), "{}", run.stderr);
                continue;
            }
            let run = run_line(&line, &dir);
            assert_eq!(run.code, 0, "{line}:\n{}\n{}", run.stdout, run.stderr);
        }
    }
    for (line, _) in NOT_RUN {
        assert!(
            not_run_seen.iter().any(|l| l == line),
            "`{line}` is listed as not run but is no longer an example"
        );
    }
}
