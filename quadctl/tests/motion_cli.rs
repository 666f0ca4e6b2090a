//! Black-box tests of `quadctl motion`, `check`, `plot` and `accuracy`.

mod common;

use common::{last_line_json, quadctl};
use std::path::{Path, PathBuf};

/// Largest allowed change of a joint angle over one period, rad (issue 5).
const PERIODIC_TOL_RAD: f32 = 1e-4;
/// Largest allowed drift of a stance foot in the printed world coordinates, m.
const FOOT_TOL_M: f32 = 1e-6;

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("quadctl-motion-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Data rows of a motion CSV as (header, rows of fields).
fn parse(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect();
    (header, rows)
}

fn col(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

fn num(row: &[String], i: usize) -> f32 {
    row[i]
        .parse()
        .unwrap_or_else(|_| panic!("`{}` not a number", row[i]))
}

#[test]
fn motion_csv_has_the_documented_columns_and_the_seed001_roll_is_periodic() {
    let r = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "fernando2025",
            "--duration-s",
            "40",
            "--rate-hz",
            "10",
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.is_empty(),
        "no progress bar when piped: {}",
        r.stderr
    );
    assert!(r
        .stdout
        .starts_with("# quadctl motion roll-sway robot=fernando2025 rotation_order=zxy"));
    let (h, rows) = parse(&r.stdout);
    let mut want = vec!["t_s".to_owned()];
    for l in ["FL", "FR", "RL", "RR"] {
        for j in ["abduction", "hip", "knee"] {
            want.push(format!("{l}_{j}_rad"));
        }
    }
    for l in ["FL", "FR", "RL", "RR"] {
        for a in ["x", "y", "z"] {
            want.push(format!("{l}_{a}_m"));
        }
    }
    for c in [
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "x_m",
        "y_m",
        "z_m",
        "status",
    ] {
        want.push(c.to_owned());
    }
    assert_eq!(h, want);
    assert_eq!(rows.len(), 401);
    // Stance height from seed 001's initial pose; roll = 0.2·sin(2πt/20).
    assert!((num(&rows[0], col(&h, "FL_z_m")) + 0.929_422_9).abs() < 1e-5);
    let t5 = &rows[50];
    assert!((num(t5, col(&h, "t_s")) - 5.0).abs() < 1e-9);
    assert!((num(t5, col(&h, "roll_rad")) - 0.2).abs() < 1e-6);
    let mut worst = 0.0f32;
    for k in 0..200 {
        for i in 1..13 {
            worst = worst.max((num(&rows[k], i) - num(&rows[k + 200], i)).abs());
        }
        for i in 13..25 {
            assert!((num(&rows[k], i) - num(&rows[0], i)).abs() <= FOOT_TOL_M);
        }
        assert_eq!(rows[k].last().unwrap(), "ok");
    }
    assert!(worst < PERIODIC_TOL_RAD, "{worst}");
}

#[test]
fn output_file_appears_complete_and_bad_input_leaves_nothing() {
    let dir = scratch("output");
    let out = dir.join("yaw.csv");
    let o = out.to_str().unwrap();
    let r = quadctl(
        &[
            "motion",
            "yaw-turn",
            "--robot",
            "fernando2025",
            "--duration-s",
            "12",
            "--rate-hz",
            "20",
            "--output",
            o,
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.is_empty());
    assert_eq!(entries(&dir), vec!["yaw.csv"]);
    let (_, rows) = parse(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(rows.len(), 241);

    let bad: [(&[&str], &str); 9] = [
        (
            &["roll-sway", "--duration-s", "-1", "--rate-hz", "10"],
            "--duration-s",
        ),
        (
            &["roll-sway", "--duration-s", "1", "--rate-hz", "0"],
            "--rate-hz",
        ),
        (
            &[
                "roll-sway",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                "--amplitude-rad",
                "nan",
            ],
            "--amplitude-rad",
        ),
        (
            &[
                "roll-sway",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                "--period-s",
                "-20",
            ],
            "--period-s",
        ),
        (
            &[
                "yaw-turn",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                "--lift-height-m",
                "0.8",
            ],
            "--lift-height-m",
        ),
        (
            &[
                "trot",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                "--step-height-m",
                "0.85",
            ],
            "--step-height-m",
        ),
        (
            &[
                "trot",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                // yaw-turn's own option (--yaw-rate-rad-s is the gaits' yaw rate too).
                "--step-period-s",
                "1",
            ],
            "--step-period-s",
        ),
        (
            &["moonwalk", "--duration-s", "1", "--rate-hz", "10"],
            "moonwalk",
        ),
        (
            &[
                "trot",
                "--duration-s",
                "1",
                "--rate-hz",
                "10",
                "--plot",
                "x.pdf",
            ],
            "x.pdf",
        ),
    ];
    let before = std::fs::read(&out).unwrap();
    for (args, named) in bad {
        let mut a = vec!["motion"];
        a.extend_from_slice(args);
        a.extend_from_slice(&["--robot", "fernando2025", "--output", o]);
        let r = quadctl(&a, "");
        assert_ne!(r.code, 0, "{args:?} accepted");
        assert!(r.stderr.contains(named), "{args:?}: {}", r.stderr);
        assert_eq!(entries(&dir), vec!["yaw.csv"], "{args:?} left a file");
        assert_eq!(
            std::fs::read(&out).unwrap(),
            before,
            "{args:?} touched the output"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn check_passes_seed001_yaw_turn_from_a_file_and_as_a_law() {
    let dir = scratch("check");
    let out = dir.join("yaw.csv");
    let o = out.to_str().unwrap();
    let r = quadctl(
        &[
            "motion",
            "yaw-turn",
            "--robot",
            "fernando2025",
            "--duration-s",
            "6",
            "--rate-hz",
            "100",
            "--output",
            o,
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    for args in [
        vec!["check", o, "--robot", "fernando2025", "--json"],
        vec![
            "check",
            "--motion",
            "yaw-turn",
            "--robot",
            "fernando2025",
            "--json",
        ],
    ] {
        let r = quadctl(&args, "");
        assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
        assert!(r.stdout.contains("result: PASS"), "{}", r.stdout);
        let json = last_line_json(&r);
        assert_eq!(json["ok"], true);
        assert_eq!(json["report"]["samples"], 601);
        for l in json["report"]["legs"].as_array().unwrap() {
            let ic = l["inverse_condition"]["value"].as_f64().unwrap();
            assert!(ic > 0.05 && ic < 0.3, "{ic}");
            assert!(l["workspace_margin_m"]["value"].as_f64().unwrap() > 0.1);
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn check_fails_a_too_fast_motion_and_names_the_first_failure() {
    let r = quadctl(
        &[
            "check",
            "--motion",
            "trot",
            "--robot",
            "shahriar2023",
            "--stance-height-m",
            "0.4",
            "--forward-m-s",
            "0.2",
            "--max-joint-speed-rad-s",
            "0.5",
            "--json",
        ],
        "",
    );
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("result: FAIL"));
    let json = last_line_json(&r);
    assert_eq!(json["ok"], false);
    let f = &json["report"]["first_failure"];
    assert!(f["kind"]["JointSpeed"].is_object(), "{f}");
    // Bad check arguments.
    let r = quadctl(
        &[
            "check",
            "--motion",
            "trot",
            "--robot",
            "shahriar2023",
            "--max-joint-speed-rad-s",
            "0",
        ],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("--max-joint-speed-rad-s"), "{}", r.stderr);
}

#[test]
fn plots_are_written_as_svg_and_png() {
    let dir = scratch("plot");
    let csv = dir.join("pitch.csv");
    let svg = dir.join("pitch.svg");
    let r = quadctl(
        &[
            "motion",
            "pitch-sway",
            "--robot",
            "fernando2025",
            "--duration-s",
            "20",
            "--rate-hz",
            "20",
            "--output",
            csv.to_str().unwrap(),
            "--plot",
            svg.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg") && text.contains("knee angle") && text.contains("FL"));
    let png = dir.join("views.png");
    let r = quadctl(
        &[
            "plot",
            csv.to_str().unwrap(),
            "--output",
            png.to_str().unwrap(),
            "--robot",
            "fernando2025",
            "--at-s",
            "0,5,15",
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let joints = dir.join("joints.png");
    let r = quadctl(
        &[
            "plot",
            csv.to_str().unwrap(),
            "--output",
            joints.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(std::fs::metadata(&joints).unwrap().len() > 10_000);
    let r = quadctl(
        &[
            "plot",
            csv.to_str().unwrap(),
            "--output",
            dir.join("v.svg").to_str().unwrap(),
            "--at-s",
            "1",
        ],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("--robot"), "{}", r.stderr);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn accuracy_reproduces_seed000_per_joint_figures() {
    let dir = scratch("accuracy");
    let (t, m) = (dir.join("target.csv"), dir.join("measured.csv"));
    let d = [2.59f64, 3.64, 20.83];
    let mut ts = String::from("abduction_rad,hip_rad,knee_rad\n");
    let mut ms = ts.clone();
    for i in 0..50 {
        let tv = [
            0.3 + 0.01 * i as f64,
            0.6 - 0.005 * i as f64,
            -1.2 - 0.01 * i as f64,
        ];
        let s = if i % 2 == 0 { 1.0 } else { -1.0 };
        let mv: Vec<f64> = (0..3).map(|j| tv[j] * (1.0 + s * d[j] / 100.0)).collect();
        ts += &format!("{},{},{}\n", tv[0] as f32, tv[1] as f32, tv[2] as f32);
        ms += &format!("{},{},{}\n", mv[0] as f32, mv[1] as f32, mv[2] as f32);
    }
    std::fs::write(&t, ts).unwrap();
    std::fs::write(&m, ms).unwrap();
    let plot = dir.join("acc.svg");
    let r = quadctl(
        &[
            "accuracy",
            "--target",
            t.to_str().unwrap(),
            "--measured",
            m.to_str().unwrap(),
            "--robot",
            "shahriar2023",
            "--plot",
            plot.to_str().unwrap(),
            "--json",
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.contains("21.30 %") && r.stdout.contains("78.70 %"),
        "{}",
        r.stdout
    );
    let json = last_line_json(&r);
    let dev = &json["deviation_pct"];
    for (k, want) in ["abduction", "hip", "knee"].iter().zip(d) {
        assert!(
            (dev[k].as_f64().unwrap() - want).abs() < 1e-3,
            "{k}: {}",
            dev[k]
        );
    }
    assert!((json["rsse_pct"].as_f64().unwrap() - 21.30).abs() < 0.005);
    assert!((json["accuracy_pct"].as_f64().unwrap() - 78.70).abs() < 0.005);
    let foot = json["foot_error"]["max_m"].as_f64().unwrap();
    assert!(foot > 0.01 && foot < 0.3, "{foot}");
    assert!(std::fs::read_to_string(&plot).unwrap().contains("<svg"));
    // Row counts must match.
    std::fs::write(&m, "abduction_rad,hip_rad,knee_rad\n0.3,0.6,-1.2\n").unwrap();
    let r = quadctl(
        &[
            "accuracy",
            "--target",
            t.to_str().unwrap(),
            "--measured",
            m.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("rows"), "{}", r.stderr);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn gaits_and_the_seed000_rectangle_run_clean() {
    for args in [
        vec![
            "trot",
            "--robot",
            "shahriar2023",
            "--stance-height-m",
            "0.4",
            "--forward-m-s",
            "0.2",
            "--yaw-rad-s",
            "0.3",
        ],
        vec![
            "walk",
            "--robot",
            "fernando2025",
            "--forward-m-s",
            "0.1",
            "--path",
            "cycloid",
        ],
        vec!["rect-path", "--robot", "shahriar2023"],
        vec![
            "yaw-sway",
            "--robot",
            "shahriar2023",
            "--stance-height-m",
            "0.4",
            "--amplitude-rad",
            "0.3665",
            "--rotation-order",
            "zyx",
        ],
    ] {
        let mut a = vec!["motion"];
        a.extend_from_slice(&args);
        a.extend_from_slice(&["--duration-s", "3", "--rate-hz", "50"]);
        let r = quadctl(&a, "");
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
        let (h, rows) = parse(&r.stdout);
        assert_eq!(rows.len(), 151);
        assert!(rows.iter().all(|row| row[col(&h, "status")] == "ok"));
    }
}

#[test]
fn check_reads_angle_only_files_and_their_status() {
    let dir = scratch("angles");
    let file = dir.join("angles.csv");
    let mut text = String::from("t_s");
    for l in ["FL", "FR", "RL", "RR"] {
        for j in ["abduction", "hip", "knee"] {
            text += &format!(",{l}_{j}_rad");
        }
    }
    text += ",status\n";
    let q = "0,0.5235988,-1.0471976";
    for k in 0..5 {
        let t = k as f32 * 0.1;
        if k == 3 {
            text += &format!("{t}{},RL:too_far\n", ",".repeat(12));
        } else {
            text += &format!("{t},{q},{q},{q},{q},ok\n");
        }
    }
    std::fs::write(&file, &text).unwrap();
    let r = quadctl(
        &[
            "check",
            file.to_str().unwrap(),
            "--robot",
            "fernando2025",
            "--json",
        ],
        "",
    );
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    let json = last_line_json(&r);
    let f = &json["report"]["first_failure"];
    assert_eq!(f["leg"], "RL");
    assert_eq!(f["sample"], 3);
    assert_eq!(f["kind"]["Unreachable"], "TooFar");
    // A reason that cannot be told is refused, naming the line.
    std::fs::write(&file, text.replace("RL:too_far", "RL:joint_limit")).unwrap();
    let r = quadctl(
        &["check", file.to_str().unwrap(), "--robot", "fernando2025"],
        "",
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("angles.csv:5"), "{}", r.stderr);
    let _ = std::fs::remove_dir_all(dir);
}
