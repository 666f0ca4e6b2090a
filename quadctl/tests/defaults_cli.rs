//! One set of defaults: `check`, `motion` and `play` judge a motion by the device's own numbers
//! (`quad_host::ops::defaults`, read from `quad_device::Config`), and the commands spell a
//! flag alike.

mod common;

use common::{last_line_json, quadctl, repo_root};

#[test]
fn check_uses_the_devices_joint_speed_limiter() {
    // A 0.1 m/s trot asks 3.67 rad/s of a knee: the device slows it.
    let trot = [
        "check",
        "--motion",
        "trot",
        "--robot",
        "shahriar2023",
        "--stance-height-m",
        "0.4",
        "--forward-m-s",
        "0.1",
        "--json",
    ];
    let run = quadctl(&trot, "");
    assert_eq!(run.code, 1, "{}", run.stderr);
    let report = last_line_json(&run);
    assert_eq!(report["ok"], false);
    let knee = report["report"]["legs"][0]["joint_speed_rad_s"][2]["value"]
        .as_f64()
        .expect("the knee's speed");
    assert!(knee > 3.0 && knee < 6.0, "{knee}");
    // The limit given explicitly still rules.
    let run = quadctl(&[&trot[..], &["--max-joint-speed-rad-s", "6"]].concat(), "");
    assert_eq!(run.code, 0, "{}", run.stderr);
}

#[test]
fn motion_stands_at_the_devices_stance_by_default() {
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "shahriar2023",
            "--duration-s",
            "0.1",
            "--rate-hz",
            "10",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let mut lines = run.stdout.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let first: Vec<&str> = lines.next().expect("a row").split(',').collect();
    let z = header.iter().position(|&c| c == "FL_z_m").expect("FL_z_m");
    // The device's 0.40 m (quad_device::Config::shahriar2023), not seed 001's pose (~0.48 m).
    assert_eq!(first[z], "-0.4");
}

#[test]
fn the_gaits_take_the_yaw_rate_by_the_name_the_other_commands_use() {
    let gait = |flag: &str| {
        let run = quadctl(
            &[
                "motion",
                "trot",
                "--robot",
                "shahriar2023",
                "--forward-m-s",
                "0.05",
                flag,
                "0.2",
                "--duration-s",
                "1",
                "--rate-hz",
                "20",
            ],
            "",
        );
        assert_eq!(run.code, 0, "{flag}: {}", run.stderr);
        run.stdout
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(str::to_owned)
            .collect::<Vec<_>>()
    };
    // `run trot --yaw-rate-rad-s` and `motion yaw-turn --yaw-rate-rad-s`: the same name for
    // `motion trot`; the former `--yaw-rad-s` still works, and means the same.
    assert_eq!(gait("--yaw-rate-rad-s"), gait("--yaw-rad-s"));
    let help = quadctl(&["motion", "--help"], "");
    assert!(help.stdout.contains("--yaw-rate-rad-s"));
    assert!(
        !help.stdout.contains("--yaw-rad-s <"),
        "the old name is hidden"
    );
}

#[test]
fn play_reports_the_rows_the_devices_limiter_slows() {
    let dir = std::env::temp_dir().join(format!("quadctl-defaults-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let csv = dir.join("trot.csv");
    let csv = csv.to_str().expect("a UTF-8 path");
    let made = quadctl(
        &[
            "motion",
            "trot",
            "--robot",
            "shahriar2023",
            "--stance-height-m",
            "0.4",
            "--forward-m-s",
            "0.1",
            "--duration-s",
            "2",
            "--rate-hz",
            "50",
            "--output",
            csv,
        ],
        "",
    );
    assert_eq!(made.code, 0, "{}", made.stderr);
    let run = quadctl(&["play", csv, "--robot", "shahriar2023", "--sim"], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    let slowed = last_line_json(&run)["slowed_rows"]
        .as_u64()
        .expect("slowed_rows");
    assert!(slowed > 0, "{}", run.stdout);
    assert!(
        run.stderr.contains("joint-speed limiter slows"),
        "{}",
        run.stderr
    );
    let stance = repo_root().join("examples/stance.csv");
    let run = quadctl(
        &[
            "play",
            stance.to_str().expect("a UTF-8 path"),
            "--robot",
            "shahriar2023",
            "--sim",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert_eq!(last_line_json(&run)["slowed_rows"], 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_and_drive_take_the_stance_height_by_the_name_motion_uses() {
    for command in ["run", "drive"] {
        let help = quadctl(&[command, "--help"], "");
        assert!(help.stdout.contains("--stance-height-m <M>"), "{command}");
        assert!(
            !help.stdout.contains("--body-height-m <"),
            "{command}: the old name is hidden"
        );
    }
    for flag in ["--stance-height-m", "--body-height-m"] {
        let run = quadctl(
            &[
                "run",
                "trot",
                "--robot",
                "shahriar2023",
                "--sim",
                flag,
                "0.38",
                "--duration-s",
                "0.5",
            ],
            "",
        );
        assert_eq!(run.code, 0, "{flag}: {}", run.stderr);
    }
}
