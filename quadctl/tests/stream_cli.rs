//! Black-box tests of `quadctl stream` and `quadctl calibrate` on the simulated device.

mod common;

use common::{last_line_json, quadctl, repo_root};

const KEYS: [&str; 9] = [
    "sent",
    "acked",
    "nacked",
    "retries",
    "lost",
    "readback_mismatches",
    "max_angle_err_rad",
    "pulses_out_of_range",
    "poses_per_s",
];

#[test]
fn stream_sim_on_the_example_poses() {
    let run = quadctl(
        &[
            "stream",
            "--robot",
            "fernando2025",
            "--sim",
            "--stance-height-m",
            "0.9294",
            "--rotation-order",
            "zxy",
            "--allow-refused",
            "--input",
            "examples/poses.csv",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let s = last_line_json(&run);
    for k in KEYS {
        assert!(s.get(k).is_some(), "key {k} in {s}");
    }
    assert_eq!(s["sent"], 8);
    assert_eq!(s["acked"], 7);
    assert_eq!(s["nacked"], 1);
    assert_eq!(s["lost"], 0);
    assert_eq!(s["retries"], 0);
    assert_eq!(s["readback_mismatches"], 0);
    assert_eq!(s["pulses_out_of_range"], 0);
    assert_eq!(s["max_angle_err_rad"], 0.0);
    assert!(s["poses_per_s"].as_f64().unwrap() > 90.0);
    // The unreachable pose (line 21, the body 15 cm higher) is reported, with the host's
    // agreement.
    assert!(
        run.stderr
            .contains("examples/poses.csv:21: nacked: unreachable: FL too_far"),
        "{}",
        run.stderr
    );
}

#[test]
fn stream_with_faults_is_reproducible_and_reads_stdin() {
    let poses = std::fs::read_to_string(repo_root().join("examples/poses.csv")).unwrap();
    let args = [
        "stream",
        "--robot",
        "fernando2025",
        "--sim",
        "--baud",
        "1000000",
        "--faults",
        "drop=0.01,flip=0.001,dup=0.05,trunc=0.05",
        "--seed",
        "42",
        "--allow-refused",
        "--input",
        "-",
    ];
    let a = quadctl(&args, &poses);
    let b = quadctl(&args, &poses);
    assert_eq!(a.code, 0, "{}", a.stderr);
    assert_eq!(a.stdout, b.stdout);
    let s = last_line_json(&a);
    assert_eq!(s["sent"], 8);
    assert_eq!(
        s["acked"].as_u64().unwrap() + s["nacked"].as_u64().unwrap() + s["lost"].as_u64().unwrap(),
        8
    );
    assert_eq!(s["readback_mismatches"], 0);
    assert!(s["retries"].as_u64().unwrap() > 0);
}

#[test]
fn stream_refuses_what_it_cannot_check() {
    let r = quadctl(&["stream", "--robot", "fernando2025", "--input", "-"], "");
    assert_eq!(r.code, 2, "neither --sim nor --port");
    let r = quadctl(
        &[
            "stream",
            "--robot",
            "fernando2025",
            "--sim",
            "--port",
            "/dev/null",
        ],
        "",
    );
    assert_eq!(r.code, 2, "both --sim and --port");
    let r = quadctl(
        &[
            "stream",
            "--robot",
            "examples/robots/does-not-matter.toml",
            "--sim",
        ],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("preset"), "{}", r.stderr);
    let r = quadctl(
        &[
            "stream",
            "--robot",
            "fernando2025",
            "--sim",
            "--faults",
            "drop=3",
        ],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("probability"), "{}", r.stderr);
}

#[test]
fn stream_reports_malformed_records_and_goes_on() {
    let r = quadctl(
        &["stream", "--robot", "shahriar2023", "--sim", "--input", "-"],
        "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0\n0,0,zero,0,0,0\n0.1,0,0,0,0,0\n",
    );
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("<stdin>:3:"), "{}", r.stderr);
    let s = last_line_json(&r);
    assert_eq!(
        (s["sent"].as_u64(), s["acked"].as_u64()),
        (Some(2), Some(2))
    );
}

#[test]
fn calibrate_get_set_save_through_a_simulated_eeprom() {
    let dir = std::env::temp_dir().join(format!("quadctl-cal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let eeprom = dir.join("eeprom.bin");
    let eeprom_s = eeprom.to_str().unwrap();
    let get = || {
        quadctl(
            &[
                "calibrate",
                "--sim",
                "--robot",
                "fernando2025",
                "--sim-storage",
                eeprom_s,
                "get",
            ],
            "",
        )
    };

    let first = get();
    assert_eq!(first.code, 0, "{}", first.stderr);
    assert_eq!(
        first
            .stdout
            .lines()
            .filter(|l| l.contains("center_us = 1500"))
            .count(),
        12
    );
    // Trim FR's knee by 20 µs: take its line from `get`, edit it, set and save.
    let line = first
        .stdout
        .lines()
        .find(|l| l.starts_with("FR_knee"))
        .unwrap()
        .replace("center_us = 1500", "center_us = 1520");
    let file = dir.join("trim.toml");
    let file_s = file.to_str().unwrap();
    // `calibrate set` of the trim file, saved to the EEPROM or not.
    let set = |save: bool| {
        let mut args = vec![
            "calibrate",
            "--sim",
            "--robot",
            "fernando2025",
            "--sim-storage",
            eeprom_s,
            "set",
            file_s,
        ];
        if save {
            args.push("--save");
        }
        quadctl(&args, "")
    };
    std::fs::write(&file, format!("{line}\n")).unwrap();
    let run = set(true);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains(&line), "{}", run.stdout);
    // A new run powers the simulated device on from the EEPROM image.
    let again = get();
    assert!(again.stdout.contains(&line), "{}", again.stdout);
    // Without --save a set is gone at the next power-on.
    let other = line.replace("center_us = 1520", "center_us = 1530");
    std::fs::write(&file, format!("{other}\n")).unwrap();
    let run = set(false);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains(&other));
    assert!(get().stdout.contains(&line));
    // A travel that excludes the held stance angle is refused by the device.
    let bad = "FR_knee = { zero_rad = 1.0, reversed = true, us_per_rad = 636.0, center_us = 2000, min_us = 2000, max_us = 2500 }";
    std::fs::write(&file, format!("{bad}\n")).unwrap();
    let run = set(false);
    assert_eq!(run.code, 2);
    assert!(
        run.stderr.contains("FR_knee") && run.stderr.contains("servo range"),
        "{}",
        run.stderr
    );
    // An invalid file is refused before anything is sent.
    std::fs::write(&file, "FR_knee = { zero_rad = 0.0 }\n").unwrap();
    let run = quadctl(
        &[
            "calibrate",
            "--sim",
            "--robot",
            "fernando2025",
            "set",
            file_s,
        ],
        "",
    );
    assert_eq!(run.code, 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The example poses of the README's `pose` command: one of them (line 21) is out of reach of
/// fernando2025 at this stance height, and the device refuses it.
const REFUSED_ONE: [&str; 10] = [
    "stream",
    "--robot",
    "fernando2025",
    "--sim",
    "--stance-height-m",
    "0.9294",
    "--rotation-order",
    "zxy",
    "--input",
    "examples/poses.csv",
];

#[test]
fn a_refused_pose_makes_the_exit_status_4_unless_allowed() {
    let args = &REFUSED_ONE[..];
    let run = quadctl(args, "");
    assert_eq!(run.code, 4, "{}", run.stderr);
    let s = last_line_json(&run);
    assert_eq!(
        (s["acked"].as_u64(), s["nacked"].as_u64()),
        (Some(7), Some(1))
    );
    assert!(run.stderr.contains(":21: nacked:"), "{}", run.stderr);
    let mut allowed = args.to_vec();
    allowed.push("--allow-refused");
    let run = quadctl(&allowed, "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    // Every pose acked: 0 without the flag.
    let run = quadctl(
        &[
            "stream",
            "--robot",
            "shahriar2023",
            "--sim",
            "--input",
            "examples/poses.csv",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert_eq!(last_line_json(&run)["acked"], 8);
    // Refused and malformed: the refusal's status comes first.
    let run = quadctl(
        &["stream", "--robot", "shahriar2023", "--sim", "--input", "-"],
        "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,1\n0,0,zero,0,0,0\n",
    );
    assert_eq!(run.code, 4, "{}", run.stderr);
    let run = quadctl(
        &[
            "stream",
            "--robot",
            "shahriar2023",
            "--sim",
            "--allow-refused",
            "--input",
            "-",
        ],
        "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,1\n0,0,zero,0,0,0\n",
    );
    assert_eq!(run.code, 1, "{}", run.stderr);
}

#[test]
fn the_exit_statuses_are_in_the_help() {
    for cmd in ["stream", "play"] {
        let run = quadctl(&[cmd, "--help"], "");
        assert_eq!(run.code, 0);
        assert!(
            run.stdout
                .contains("4 every check\npassed but at least one")
                || run.stdout.contains("; 4 every check"),
            "{cmd}: {}",
            run.stdout
        );
        assert!(run.stdout.contains("--allow-refused"), "{}", run.stdout);
    }
}
