//! Black-box tests of the `quadctl` binary: batch commands, robot files, malformed input.

mod common;

use common::{quadctl, repo_root};
use kin_core::{LegId, Robot};
use std::path::{Path, PathBuf};

/// Position tolerance for round trips through the printed f32 values, metres.
const TOL_M: f32 = 2.0e-6;
/// Angle tolerance against f64 hand-derived values, radians.
const TOL_RAD: f32 = 1.0e-5;

fn temp_file(name: &str, text: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).expect("temp file written");
    path
}

/// Data lines of a CSV output (header removed), split into fields.
fn records(stdout: &str) -> Vec<Vec<String>> {
    stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

fn num(field: &str) -> f32 {
    field
        .parse()
        .unwrap_or_else(|_| panic!("`{field}` is a number"))
}

fn assert_close(got: f32, want: f32, tol: f32, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

#[test]
fn fk_of_zero_angles_hangs_each_foot_straight_down() {
    for name in Robot::PRESETS {
        let robot = Robot::preset(name).expect("preset");
        let input: String = LegId::ALL.iter().map(|l| format!("{l},0,0,0\n")).collect();
        let run = quadctl(&["fk", "--robot", name], &input);
        assert_eq!(run.code, 0, "{}", run.stderr);
        assert_eq!(run.stderr, "");
        let g = robot.leg;
        // (0, s·d_lat, −d_ax − L1 − L2), evaluated in f32.
        let z = -g.d_ax_m - g.femur_m - g.tibia_m;
        let expected: String = std::iter::once("leg,x_m,y_m,z_m\n".to_owned())
            .chain(LegId::ALL.iter().map(|l| {
                let y = l.side() * g.d_lat_m;
                let y = if y == 0.0 { 0.0 } else { y };
                format!("{l},0,{y},{z}\n")
            }))
            .collect();
        assert_eq!(run.stdout, expected, "{name}");
    }
}

#[test]
fn fk_signs_follow_the_frames() {
    // hip = −π/2, knee = 0: the straight leg points forward (+x) at the hip joint's height.
    // abduction = +π/2 on FL: the leg swings out to the left (+y), the offset d_lat points up.
    let g = Robot::shahriar2023().leg;
    let half_pi = std::f32::consts::FRAC_PI_2;
    let run = quadctl(
        &["fk", "--robot", "shahriar2023"],
        &format!("FL,0,{},0\nFL,{},0,0\n", -half_pi, half_pi),
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let rows = records(&run.stdout);
    let reach = g.femur_m + g.tibia_m;
    let forward = [reach, g.d_lat_m, 0.0];
    let outward = [0.0, reach, g.d_lat_m];
    for (row, want) in rows.iter().zip([forward, outward]) {
        for (i, w) in want.iter().enumerate() {
            assert_close(num(&row[1 + i]), *w, TOL_M, &format!("{row:?}"));
        }
    }
}

#[test]
fn ik_reproduces_the_seed_001_initial_pose() {
    // Seed 001: φ = 120°, α = 60° ⇒ hip = 30°, knee = −60°, foot straight below the hip at
    // depth l0 + (l1 + l2)·sin 60°.
    let depth = 0.15 + 0.9 * 60f64.to_radians().sin();
    let input: String = LegId::ALL
        .iter()
        .map(|l| format!("{l},0,0,{}\n", -depth as f32))
        .collect();
    let run = quadctl(&["ik", "--robot", "fernando2025"], &input);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let rows = records(&run.stdout);
    assert_eq!(rows.len(), 4);
    for (row, leg) in rows.iter().zip(LegId::ALL) {
        assert_eq!(row[0], leg.name());
        assert_eq!(row[4], "ok");
        assert_close(num(&row[1]), 0.0, TOL_RAD, "abduction");
        assert_close(num(&row[2]), 30f32.to_radians(), TOL_RAD, "hip");
        assert_close(num(&row[3]), -60f32.to_radians(), TOL_RAD, "knee");
    }
    // The forward knee mirrors the knee and the hip.
    let run = quadctl(
        &["ik", "--robot", "fernando2025", "--knee", "forward"],
        &input,
    );
    let rows = records(&run.stdout);
    assert_close(num(&rows[0][2]), -30f32.to_radians(), TOL_RAD, "hip");
    assert_close(num(&rows[0][3]), 60f32.to_radians(), TOL_RAD, "knee");
}

#[test]
fn ik_then_fk_through_the_binary_returns_the_targets() {
    for name in Robot::PRESETS {
        for knee in ["backward", "forward"] {
            let robot = Robot::preset(name).expect("preset");
            let reach = robot.leg.d_ax_m + robot.leg.femur_m + robot.leg.tibia_m;
            let mut targets = Vec::new();
            let mut input = String::from("leg,x_m,y_m,z_m\n");
            for leg in LegId::ALL {
                for i in 0..5 {
                    for j in 0..5 {
                        let x = (i as f32 - 2.0) * 0.12 * reach;
                        let y = leg.side() * robot.leg.d_lat_m + (j as f32 - 2.0) * 0.1 * reach;
                        let z = -0.7 * reach;
                        targets.push((leg, [x, y, z]));
                        input.push_str(&format!("{leg},{x},{y},{z}\n"));
                    }
                }
            }
            let ik = quadctl(&["ik", "--robot", name, "--knee", knee], &input);
            assert_eq!(ik.code, 0, "{}", ik.stderr);
            let rows = records(&ik.stdout);
            assert_eq!(rows.len(), targets.len());
            let mut fk_input = String::new();
            let mut solved = Vec::new();
            for (row, target) in rows.iter().zip(&targets) {
                if row[4] == "ok" {
                    fk_input.push_str(&format!("{},{},{},{}\n", row[0], row[1], row[2], row[3]));
                    solved.push(target);
                } else {
                    assert_eq!(row[1..4], ["", "", ""], "{row:?}");
                }
            }
            assert!(
                solved.len() >= targets.len() * 3 / 4,
                "{name} {knee}: only {} of {} targets solved",
                solved.len(),
                targets.len()
            );
            let fk = quadctl(&["fk", "--robot", name], &fk_input);
            assert_eq!(fk.code, 0, "{}", fk.stderr);
            for (row, (leg, want)) in records(&fk.stdout).iter().zip(solved) {
                assert_eq!(row[0], leg.name());
                for i in 0..3 {
                    assert_close(num(&row[1 + i]), want[i], TOL_M, &format!("{name} {row:?}"));
                }
            }
        }
    }
}

#[test]
fn unreachable_targets_get_a_status_and_empty_angle_cells() {
    let run = quadctl(
        &["ik", "--robot", "shahriar2023"],
        "FL,0,0,-2\nFR,0,-0.044,-0.001\nRL,0.1,0,-0.01\nRR,nan,0,-0.5\nFL,0,0.044,-0.5\n",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert_eq!(lines[0], "leg,abduction_rad,hip_rad,knee_rad,status");
    assert_eq!(lines[1], "FL,,,,too_far");
    assert_eq!(lines[2], "FR,,,,too_close");
    assert_eq!(lines[3], "RL,,,,inside_offset");
    assert_eq!(lines[4], "RR,,,,non_finite");
    assert!(lines[5].ends_with(",ok"), "{}", lines[5]);
    // fernando2025 limits abduction to ±0.8 rad; this foot needs about 1.01 rad.
    let run = quadctl(&["ik", "--robot", "fernando2025"], "FL,0,0.8,-0.5\n");
    assert_eq!(run.stdout.lines().nth(1), Some("FL,,,,joint_limit"));
    assert!(!run.stdout.to_lowercase().contains("nan,"));
}

#[test]
fn clamp_policy_reports_the_distance_moved() {
    let run = quadctl(
        &["ik", "--robot", "fernando2025", "--policy", "clamp"],
        "FL,0,0,-2\nFL,0,0,-0.9\nFL,inf,0,-1\n",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert_eq!(
        lines[0],
        "leg,abduction_rad,hip_rad,knee_rad,status,clamp_distance_m"
    );
    let far: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(far[4], "clamped:too_far");
    // Straight down the leg reaches l0 + l1 + l2 = 1.05 m, the target is at 2 m... but the
    // knee limit (≤ −0.05 rad) keeps it from straightening fully, so the distance is ≥ 0.95 m.
    let d = num(far[5]);
    assert!((0.95..0.96).contains(&d), "clamp distance {d}");
    assert!(lines[2].ends_with(",ok,0"), "{}", lines[2]);
    assert_eq!(lines[3], "FL,,,,non_finite,");
}

#[test]
fn pose_of_the_zero_pose_gives_the_stance_angles() {
    let depth = (0.15 + 0.9 * 60f64.to_radians().sin()) as f32;
    let h = depth.to_string();
    let run = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            &h,
            "--rotation-order",
            "zxy",
        ],
        "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0\n",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let header = run.stdout.lines().next().expect("header");
    let columns: Vec<&str> = header.split(',').collect();
    assert_eq!(columns.len(), 13);
    assert_eq!(columns[0], "FL_abduction_rad");
    assert_eq!(columns[5], "FR_knee_rad");
    assert_eq!(columns[12], "status");
    let row = &records(&run.stdout)[0];
    assert_eq!(row[12], "ok");
    for leg in 0..4 {
        assert_close(num(&row[3 * leg]), 0.0, TOL_RAD, "abduction");
        assert_close(num(&row[3 * leg + 1]), 30f32.to_radians(), TOL_RAD, "hip");
        assert_close(num(&row[3 * leg + 2]), -60f32.to_radians(), TOL_RAD, "knee");
    }
}

#[test]
fn pose_at_stance_matches_leg_ik_of_the_stance_feet() {
    // shahriar2023 has d_lat ≠ 0: each stance foot is at (0, s·d_lat, −H) in its hip frame.
    let pose = quadctl(
        &[
            "pose",
            "--robot",
            "shahriar2023",
            "--stance-height-m",
            "0.45",
        ],
        "0,0,0,0,0,0\n",
    );
    let ik_input: String = LegId::ALL
        .iter()
        .map(|l| format!("{l},0,{},-0.45\n", l.side() * 0.044))
        .collect();
    let ik = quadctl(&["ik", "--robot", "shahriar2023"], &ik_input);
    let pose_row = &records(&pose.stdout)[0];
    for (i, leg_row) in records(&ik.stdout).iter().enumerate() {
        for j in 0..3 {
            assert_close(
                num(&pose_row[3 * i + j]),
                num(&leg_row[1 + j]),
                TOL_RAD,
                &format!("leg {i} joint {j}"),
            );
        }
    }
}

#[test]
fn pose_names_the_first_leg_that_cannot_reach() {
    // Rolling left side down and lifting the body: the right legs cannot reach the ground.
    let run = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "0.9294",
            "--pivot-m",
            "-0.1,0,0",
        ],
        "-0.3,0,0,0,0,0.05\n0,0,0,0,0,0.5\nnan,0,0,0,0,0\n",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let empty = ",".repeat(12);
    let lines: Vec<&str> = run.stdout.lines().skip(1).collect();
    assert_eq!(
        lines,
        [
            format!("{empty}FR:too_far"),
            format!("{empty}FL:too_far"),
            format!("{empty}FL:non_finite"),
        ]
    );
}

#[test]
fn header_row_is_optional() {
    let body = "FL,0.1,0.2,-0.3\nRR,0,0,0\n";
    let with = quadctl(
        &["fk", "--robot", "shahriar2023"],
        &format!("# angles\nleg,abduction_rad,hip_rad,knee_rad\n\n{body}"),
    );
    let without = quadctl(&["fk", "--robot", "shahriar2023"], body);
    assert_eq!(with.code, 0, "{}", with.stderr);
    assert_eq!(with.stdout, without.stdout);
    assert_eq!(records(&with.stdout).len(), 2);
}

#[test]
fn a_foreign_header_stops_everything() {
    let run = quadctl(
        &["ik", "--robot", "shahriar2023"],
        "leg,abduction_rad,hip_rad,knee_rad\nFL,0,0,0\n",
    );
    assert_eq!(run.code, 2);
    assert!(
        run.stderr
            .contains("<stdin>:1: header `leg,abduction_rad,hip_rad,knee_rad` does not match"),
        "{}",
        run.stderr
    );
    assert_eq!(run.stdout, "leg,abduction_rad,hip_rad,knee_rad,status\n");
}

#[test]
fn malformed_rows_are_reported_by_line_and_the_rest_answered() {
    let input = "leg,abduction_rad,hip_rad,knee_rad\n\
                 FL,0,0,0\n\
                 XX,0,0,0\n\
                 # comment\n\
                 FR,0,zero,0\n\
                 RL,0,0\n\
                 RR,0,nan,0\n\
                 RR,0,0,0\n";
    let run = quadctl(&["fk", "--robot", "shahriar2023"], input);
    assert_eq!(run.code, 1);
    let rows = records(&run.stdout);
    assert_eq!(rows.len(), 2);
    assert_eq!((rows[0][0].as_str(), rows[1][0].as_str()), ("FL", "RR"));
    let errors: Vec<&str> = run.stderr.lines().collect();
    assert_eq!(
        errors,
        [
            "<stdin>:3: field 1 (leg): `XX` is not a leg (FL, FR, RL, RR)",
            "<stdin>:5: field 3 (hip_rad): `zero` is not a number",
            "<stdin>:6: expected 4 fields (leg,abduction_rad,hip_rad,knee_rad), found 3",
            "<stdin>:7: field 3 (hip_rad): `nan` is not a finite number",
            "quadctl: 4 malformed record(s) skipped, 2 answered",
        ]
    );
    // Same for pose and ik, with a file as input: the message names the file.
    let path = temp_file(
        "poses_malformed.csv",
        "0,0,0,0,0,0\n0,0,0,0,0\n0,0,0,0,0,x\n",
    );
    let path_str = path.to_str().expect("utf-8 path");
    let run = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "0.9",
            "--input",
            path_str,
        ],
        "",
    );
    assert_eq!(run.code, 1);
    assert_eq!(records(&run.stdout).len(), 1);
    assert!(
        run.stderr
            .contains(&format!("{path_str}:2: expected 6 fields")),
        "{}",
        run.stderr
    );
    assert!(run
        .stderr
        .contains(&format!("{path_str}:3: field 6 (z_m): `x` is not a number")));
}

#[test]
fn bad_robot_files_are_refused_with_a_clear_message() {
    let good = std::fs::read_to_string(repo_root().join("examples/robots/shahriar2023.toml"))
        .expect("example robot file");
    let cases = [
        (
            "negative.toml",
            good.replace("femur_m = 0.28", "femur_m = -0.28"),
            "`femur_m` must be a finite length",
        ),
        (
            "missing.toml",
            good.replace("tibia_m = 0.277", ""),
            "missing field `tibia_m`",
        ),
        (
            "unknown.toml",
            format!("tibia_length_m = 0.3\n{good}"),
            "unknown field `tibia_length_m`",
        ),
        (
            "inverted.toml",
            good.replace("knee_rad = [-2.8, -0.05]", "knee_rad = [-0.05, -2.8]"),
            "joint limits of `knee` must be finite with min ≤ max",
        ),
    ];
    for (name, text, message) in cases {
        let path = temp_file(name, &text);
        let run = quadctl(
            &["fk", "--robot", path.to_str().expect("utf-8 path")],
            "FL,0,0,0\n",
        );
        assert_eq!(run.code, 2, "{name}");
        assert!(run.stderr.contains(message), "{name}: {}", run.stderr);
        assert!(run.stderr.contains(name), "{name}: {}", run.stderr);
    }
    let run = quadctl(&["fk", "--robot", "shahriar2024"], "FL,0,0,0\n");
    assert_eq!(run.code, 2);
    assert!(
        run.stderr
            .contains("`shahriar2024` is not a preset (shahriar2023, fernando2025)"),
        "{}",
        run.stderr
    );
}

#[test]
fn example_robot_files_equal_the_presets() {
    for name in Robot::PRESETS {
        let path = repo_root().join(format!("examples/robots/{name}.toml"));
        let robot = quad_host::robot_file::load_file(&path).expect("example robot file");
        assert_eq!(Some(robot), Robot::preset(name), "{name}");
        let input = "FL,0.1,0.2,-0.3\nRR,-0.2,0.4,-1.1\n";
        let from_file = quadctl(&["fk", "--robot", path.to_str().expect("utf-8")], input);
        let from_preset = quadctl(&["fk", "--robot", name], input);
        assert_eq!(from_file.code, 0, "{}", from_file.stderr);
        assert_eq!(from_file.stdout, from_preset.stdout);
    }
}

#[test]
fn readme_pose_table_command_prints_the_table() {
    let run = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "0.9294",
            "--rotation-order",
            "zxy",
            "--table",
            "--input",
            "examples/poses.csv",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("Joint angles in DEGREES"));
    assert!(run.stdout.contains("rotation order zxy"));
    // First pose: the nominal stance, hip ≈ 30°, knee ≈ −60°.
    let first = run
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("FL"))
        .expect("a leg row");
    let cells: Vec<&str> = first.split_whitespace().collect();
    assert_eq!(cells[1..3], ["0.00", "30.00"]);
    assert!(run.stdout.contains("unreachable: FL:too_far"));
    let csv = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "0.9294",
            "--format",
            "table",
            "--input",
            "examples/poses.csv",
        ],
        "",
    );
    assert_eq!(csv.code, 0, "{}", csv.stderr);
    assert!(csv.stdout.contains("rotation order zyx"));
}

#[test]
fn help_states_frames_and_units() {
    for (cmd, words) in [
        ("ik", ["HIP FRAME", "RADIANS", "metres"]),
        ("fk", ["HIP FRAME", "RADIANS", "metres"]),
        ("pose", ["body frame", "RADIANS", "METRES"]),
    ] {
        let run = quadctl(&[cmd, "--help"], "");
        assert_eq!(run.code, 0);
        for w in words {
            assert!(run.stdout.contains(w), "`{cmd} --help` lacks `{w}`");
        }
        assert!(run.stdout.contains("get NO output row"), "{cmd}");
        assert!(run.stdout.contains("Exit status"), "{cmd}");
    }
}

#[test]
fn bad_arguments_are_usage_errors() {
    for args in [
        &["pose", "--robot", "fernando2025", "--stance-height-m", "-1"][..],
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "1",
            "--pivot-m",
            "1,2",
        ],
        &["ik", "--robot", "fernando2025", "--knee", "sideways"],
    ] {
        let run = quadctl(args, "");
        assert_eq!(run.code, 2, "{args:?}");
        assert!(run.stderr.contains("error"), "{args:?}: {}", run.stderr);
    }
}
