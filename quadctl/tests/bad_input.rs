//! What a careless user types, and the answer: every message names the file, line, column or
//! parameter at fault and what was expected, and no message is a Debug dump.

mod common;

use common::{quadctl, repo_root, Run};
use std::path::{Path, PathBuf};

fn temp_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, bytes).expect("temp file written");
    path
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).expect("old directory removed");
    }
    std::fs::create_dir_all(&dir).expect("directory");
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A message of stderr that names no Rust type: no `Os {`, `Error(`, `Some(`, `kind:`.
fn assert_no_debug_dump(run: &Run) {
    for dump in ["Os {", "Error(", "Some(", "kind:", "{ code"] {
        assert!(!run.stderr.contains(dump), "Debug dump: {}", run.stderr);
    }
}

/// `run` failed with exit status `code` and `message` on stderr.
fn assert_refused(run: &Run, code: i32, message: &str) {
    assert_eq!(
        run.code, code,
        "stdout: {}\nstderr: {}",
        run.stdout, run.stderr
    );
    assert!(
        run.stderr.contains(message),
        "want `{message}` in: {}",
        run.stderr
    );
    assert_no_debug_dump(run);
}

/// A small motion CSV written by `quadctl motion` (roll sway, 0 to 12 s at 10 Hz).
fn motion_file(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "fernando2025",
            "--duration-s",
            "12",
            "--rate-hz",
            "10",
            "--output",
            s(&path),
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    path
}

#[test]
fn a_utf8_byte_order_mark_is_accepted() {
    let run = quadctl(
        &["fk", "--robot", "shahriar2023"],
        "\u{feff}leg,abduction_rad,hip_rad,knee_rad\nFL,0,0,0\n",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert_eq!(
        run.stdout.lines().nth(1),
        Some("FL,0,0.044,-0.55700004,ok,2")
    );
    // The motion reader too.
    let text = std::fs::read(motion_file("bom-source.csv")).expect("motion file");
    let bom = temp_file("bom.csv", &[b"\xEF\xBB\xBF".as_slice(), &text].concat());
    let run = quadctl(&["check", "--robot", "fernando2025", s(&bom)], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    // And a robot file.
    let robot = std::fs::read(repo_root().join("examples/robots/shahriar2023.toml")).unwrap();
    let robot = temp_file("bom.toml", &[b"\xEF\xBB\xBF".as_slice(), &robot].concat());
    let run = quadctl(&["fk", "--robot", s(&robot)], "FL,0,0,0\n");
    assert_eq!(run.code, 0, "{}", run.stderr);
}

#[test]
fn a_semicolon_separated_file_gets_a_hint() {
    let run = quadctl(
        &["ik", "--robot", "shahriar2023"],
        "leg;x_m;y_m;z_m\nFL;0;0.044;-0.5\n",
    );
    assert_refused(
        &run,
        2,
        "<stdin>:1: fields must be separated by commas (leg,x_m,y_m,z_m); this line uses `;` \
         (semicolons)",
    );
    // One such line among good ones: that record is malformed, the others answered.
    let run = quadctl(
        &["ik", "--robot", "shahriar2023"],
        "FL,0,0.044,-0.5\nFR;0;-0.044;-0.5\n",
    );
    assert_refused(&run, 1, "<stdin>:2: fields must be separated by commas");
    let motion = std::fs::read_to_string(motion_file("semicolon-source.csv")).unwrap();
    let semi = temp_file("semicolon.csv", motion.replace(',', ";").as_bytes());
    let run = quadctl(&["check", "--robot", "fernando2025", s(&semi)], "");
    assert_refused(
        &run,
        2,
        &format!("{}:2: fields must be separated by commas", s(&semi)),
    );
}

#[test]
fn invalid_utf8_is_reported_with_file_line_and_column() {
    let path = temp_file(
        "latin1.csv",
        b"leg,x_m,y_m,z_m\nFL,0,0.044,-0.5\nFR,0,-0.044,-0.5 \xB5m\nRL,0,0.044,-0.5\n",
    );
    let run = quadctl(&["ik", "--robot", "shahriar2023", "--input", s(&path)], "");
    assert_refused(
        &run,
        1,
        &format!(
            "{}:3: not UTF-8 text: byte 0xB5 at column 18 (save the file as UTF-8)",
            s(&path)
        ),
    );
    // The records around it are answered, each naming its line.
    let rows: Vec<&str> = run.stdout.lines().skip(1).collect();
    assert_eq!(rows.len(), 2);
    assert!(
        rows[0].ends_with(",ok,2") && rows[1].ends_with(",ok,4"),
        "{rows:?}"
    );
    // In a motion file, reading stops there with the same message.
    let mut motion = std::fs::read(motion_file("latin1-source.csv")).unwrap();
    motion.extend_from_slice(b"# \xE9t\xE9\n");
    let path = temp_file("latin1-motion.csv", &motion);
    let run = quadctl(&["check", "--robot", "fernando2025", s(&path)], "");
    assert_refused(&run, 2, "not UTF-8 text: byte 0xE9 at column 3");
}

#[test]
fn a_plot_into_a_missing_directory_is_refused_before_any_output() {
    let dir = temp_dir("missing-plot-dir");
    let csv = dir.join("yaw.csv");
    let plot = dir.join("no-such-dir/yaw.svg");
    let run = quadctl(
        &[
            "motion",
            "yaw-turn",
            "--robot",
            "fernando2025",
            "--duration-s",
            "12",
            "--rate-hz",
            "50",
            "--output",
            s(&csv),
            "--plot",
            s(&plot),
        ],
        "",
    );
    assert_refused(
        &run,
        2,
        &format!(
            "cannot write the plot `{}`: directory `{}` does not exist",
            s(&plot),
            s(&dir.join("no-such-dir"))
        ),
    );
    assert!(!csv.exists(), "no CSV is left behind");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
    // The same for `plot` and `accuracy`.
    let motion = motion_file("plot-dir-source.csv");
    let run = quadctl(&["plot", s(&motion), "--output", s(&plot)], "");
    assert_refused(&run, 2, "directory");
    assert!(run.stderr.contains(s(&plot)), "{}", run.stderr);
    let run = quadctl(
        &[
            "accuracy",
            "--target",
            "examples/accuracy-target.csv",
            "--measured",
            "examples/accuracy-measured.csv",
            "--plot",
            s(&plot),
        ],
        "",
    );
    assert_refused(&run, 2, "directory");
    assert!(run.stderr.contains(s(&plot)), "{}", run.stderr);
    assert_eq!(run.stdout, "", "no table before the error");
}

#[test]
fn stream_without_a_target_lists_the_three_choices() {
    let run = quadctl(
        &[
            "stream",
            "--robot",
            "shahriar2023",
            "--input",
            "examples/poses.csv",
        ],
        "",
    );
    assert_refused(&run, 2, "<--sim|--emulator|--port <PATH>>");
    let run = quadctl(&["calibrate", "get"], "");
    assert_refused(&run, 2, "<--sim|--emulator|--port <PATH>>");
}

#[test]
fn negative_numbers_are_option_values() {
    // A range error naming the option, not "unexpected argument '-0' found".
    for args in [
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "-0.4",
        ][..],
        &[
            "stream",
            "--sim",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "-0.4",
        ],
    ] {
        let run = quadctl(args, "");
        assert_refused(
            &run,
            2,
            "'--stance-height-m <H>': -0.4 must be a finite length > 0",
        );
        assert!(
            !run.stderr.contains("unexpected argument"),
            "{}",
            run.stderr
        );
    }
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "-0.4",
            "--duration-s",
            "1",
            "--rate-hz",
            "10",
        ],
        "",
    );
    assert_refused(&run, 2, "invalid --stance-height-m");
    let motion = motion_file("negative-source.csv");
    let run = quadctl(
        &[
            "plot",
            s(&motion),
            "--output",
            s(&motion.with_extension("svg")),
            "--robot",
            "fernando2025",
            "--at-s",
            "-1",
        ],
        "",
    );
    assert_refused(
        &run,
        2,
        "--at-s: -1 s is outside the file's samples, from 0 s to 12 s",
    );
}

#[test]
fn too_many_samples_blames_the_rate_when_the_rate_is_absurd() {
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "fernando2025",
            "--duration-s",
            "12",
            "--rate-hz",
            "1e9",
        ],
        "",
    );
    assert_refused(
        &run,
        2,
        "invalid --rate-hz: 12 s at 1000000000 Hz is 1.200e10 samples, at most 2^24 = 16777216",
    );
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "fernando2025",
            "--duration-s",
            "1e9",
            "--rate-hz",
            "10",
        ],
        "",
    );
    assert_refused(&run, 2, "invalid --duration-s: 1000000000 s at 10 Hz");
}

#[test]
fn plot_at_a_time_beyond_the_file_is_an_error() {
    let motion = motion_file("at-s-source.csv");
    let run = quadctl(
        &[
            "plot",
            s(&motion),
            "--output",
            s(&motion.with_extension("svg")),
            "--robot",
            "fernando2025",
            "--at-s",
            "0,100",
        ],
        "",
    );
    assert_refused(
        &run,
        2,
        "--at-s: 100 s is outside the file's samples, from 0 s to 12 s",
    );
}

#[test]
fn a_header_only_motion_file_is_an_error_not_a_pass() {
    let text = std::fs::read_to_string(motion_file("header-only-source.csv")).unwrap();
    let header_only: String = text.lines().take(2).map(|l| format!("{l}\n")).collect();
    let path = temp_file("header-only.csv", header_only.as_bytes());
    let message = format!(
        "{}: no records (expected samples after the header)",
        s(&path)
    );
    let run = quadctl(&["check", "--robot", "fernando2025", s(&path)], "");
    assert_refused(&run, 2, &message);
    assert!(!run.stdout.contains("PASS"), "{}", run.stdout);
    let run = quadctl(
        &["plot", s(&path), "--output", s(&path.with_extension("svg"))],
        "",
    );
    assert_refused(&run, 2, &message);
    let run = quadctl(
        &["accuracy", "--target", s(&path), "--measured", s(&path)],
        "",
    );
    assert_refused(&run, 2, &message);
}

#[test]
fn an_input_without_records_is_an_error() {
    let empty = temp_file(
        "empty-poses.csv",
        b"# no poses yet\nroll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n",
    );
    let message = format!(
        "{}: no records (expected lines of `roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m`)",
        s(&empty)
    );
    let run = quadctl(
        &[
            "pose",
            "--robot",
            "fernando2025",
            "--stance-height-m",
            "0.9",
            "--input",
            s(&empty),
        ],
        "",
    );
    assert_refused(&run, 2, &message);
    let run = quadctl(
        &[
            "stream",
            "--sim",
            "--robot",
            "fernando2025",
            "--input",
            s(&empty),
        ],
        "",
    );
    assert_refused(&run, 2, &message);
    let run = quadctl(&["fk", "--robot", "fernando2025"], "");
    assert_refused(
        &run,
        2,
        "<stdin>: no records (expected lines of `leg,abduction_rad",
    );
}

#[test]
fn check_refuses_nan_in_the_angle_columns() {
    let text = std::fs::read_to_string(motion_file("nan-source.csv")).unwrap();
    let broken: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 4 {
                let mut f: Vec<&str> = l.split(',').collect();
                f[2] = "NaN";
                f.join(",") + "\n"
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let path = temp_file("nan.csv", broken.as_bytes());
    let run = quadctl(&["check", "--robot", "fernando2025", s(&path)], "");
    assert_refused(
        &run,
        2,
        &format!("{}:5: field 3: `NaN` is not a finite number", s(&path)),
    );
}

#[test]
fn an_implausible_robot_dimension_is_refused_on_its_line() {
    let good = std::fs::read_to_string(repo_root().join("examples/robots/shahriar2023.toml"))
        .expect("example robot file");
    let line = good
        .lines()
        .position(|l| l.starts_with("femur_m"))
        .expect("femur line")
        + 1;
    assert!(line > 1);
    let path = temp_file(
        "millimetres.toml",
        good.replace("femur_m = 0.28", "femur_m = 280").as_bytes(),
    );
    let run = quadctl(&["fk", "--robot", s(&path)], "FL,0,0,0\n");
    assert_refused(
        &run,
        2,
        &format!(
            "robot file `{}`:{line}: `femur_m` = 280 m is implausible (more than 10 m): values \
             are in metres, e.g. 0.28 for 280 mm",
            s(&path)
        ),
    );
    // kin-core's refusals name the line too; a missing key has no line (not line 1, a comment).
    let path = temp_file(
        "negative-femur.toml",
        good.replace("femur_m = 0.28", "femur_m = -0.28").as_bytes(),
    );
    let run = quadctl(&["fk", "--robot", s(&path)], "FL,0,0,0\n");
    assert_refused(
        &run,
        2,
        &format!("robot file `{}`:{line}: `femur_m`", s(&path)),
    );
    let path = temp_file(
        "no-tibia.toml",
        good.replace("tibia_m = 0.277", "").as_bytes(),
    );
    let run = quadctl(&["fk", "--robot", s(&path)], "FL,0,0,0\n");
    assert_refused(
        &run,
        2,
        &format!("robot file `{}`: missing field `tibia_m`", s(&path)),
    );
}

#[test]
fn ik_fk_and_pose_answer_nan_and_1e300_the_same_way() {
    for value in ["nan", "1e300", "-inf"] {
        let ik = quadctl(
            &["ik", "--robot", "shahriar2023"],
            &format!("FL,{value},0.044,-0.5\n"),
        );
        let fk = quadctl(
            &["fk", "--robot", "shahriar2023"],
            &format!("FL,0,{value},0\n"),
        );
        let pose = quadctl(
            &[
                "pose",
                "--robot",
                "shahriar2023",
                "--stance-height-m",
                "0.4",
            ],
            &format!("0,0,{value},0,0,0\n"),
        );
        for run in [&ik, &fk, &pose] {
            assert_eq!(run.code, 0, "{value}: {}", run.stderr);
            assert!(
                run.stdout
                    .lines()
                    .nth(1)
                    .is_some_and(|l| l.ends_with("non_finite,1")),
                "{value}: {}",
                run.stdout
            );
        }
        assert_eq!(ik.stdout.lines().nth(1), Some("FL,,,,non_finite,1"));
        assert_eq!(fk.stdout.lines().nth(1), Some("FL,,,,non_finite,1"));
    }
}

#[test]
fn ik_pipes_into_fk_and_back_with_the_input_lines() {
    let feet = std::fs::read_to_string(repo_root().join("examples/feet.csv")).unwrap();
    let ik = quadctl(&["ik", "--robot", "shahriar2023"], &feet);
    assert_eq!(ik.code, 0, "{}", ik.stderr);
    let fk = quadctl(&["fk", "--robot", "shahriar2023"], &ik.stdout);
    assert_eq!(fk.code, 0, "{}", fk.stderr);
    let back = quadctl(&["ik", "--robot", "shahriar2023"], &fk.stdout);
    assert_eq!(back.code, 0, "{}", back.stderr);
    // Every record of feet.csv, unreachable ones included, lines up through the pipe, by its
    // line in feet.csv.
    let lines_of = |out: &str| -> Vec<String> {
        out.lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap().to_owned())
            .collect()
    };
    let records: Vec<String> = feet
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with('#') && !t.starts_with("leg")
        })
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    assert_eq!(lines_of(&ik.stdout), records);
    assert_eq!(lines_of(&fk.stdout), records);
    assert_eq!(lines_of(&back.stdout), records);
    // The feet come back; an unreachable target keeps its status.
    for (a, b) in ik.stdout.lines().zip(back.stdout.lines()).skip(1) {
        let (a, b): (Vec<&str>, Vec<&str>) = (a.split(',').collect(), b.split(',').collect());
        assert_eq!(a[4], b[4], "{a:?} {b:?}");
        if a[4] == "ok" {
            for j in 1..4 {
                let (x, y): (f32, f32) = (a[j].parse().unwrap(), b[j].parse().unwrap());
                assert!((x - y).abs() < 1e-4, "{a:?} {b:?}");
            }
        }
    }
    // fk | ik from angles.
    let angles = std::fs::read_to_string(repo_root().join("examples/angles.csv")).unwrap();
    let fk = quadctl(&["fk", "--robot", "shahriar2023"], &angles);
    let ik = quadctl(&["ik", "--robot", "shahriar2023"], &fk.stdout);
    assert_eq!((fk.code, ik.code), (0, 0), "{}{}", fk.stderr, ik.stderr);
    assert_eq!(lines_of(&fk.stdout), lines_of(&ik.stdout));
}

#[test]
fn an_angle_in_degrees_is_called_so() {
    // An option in radians given degrees: refused before anything is sent, with the conversion.
    let run = quadctl(
        &[
            "run",
            "sway-roll",
            "--robot",
            "shahriar2023",
            "--sim",
            "--amplitude-rad",
            "30",
        ],
        "",
    );
    assert_refused(&run, 2, "30 rad = 1719°; angles are in radians");
    assert!(run.stderr.contains("--amplitude-rad"), "{}", run.stderr);
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "shahriar2023",
            "--amplitude-rad",
            "-45",
        ],
        "",
    );
    assert_refused(&run, 2, "-45 rad = -2578°; angles are in radians");
    // A pose angle in degrees: the device's refusal comes with the hint.
    let run = quadctl(
        &["stream", "--robot", "shahriar2023", "--sim", "--input", "-"],
        "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n30,0,0,0,0,0\n",
    );
    assert_refused(
        &run,
        4,
        "<stdin>:2: nacked: out of range: roll_rad (the host's kin-core agrees); `roll_rad` = 30 \
         rad = 1719°; angles are in radians (30° = 0.5236 rad)",
    );
    // Within a turn, a value is left to the range checks (0.2 rad is a plausible amplitude).
    let run = quadctl(
        &[
            "motion",
            "roll-sway",
            "--robot",
            "shahriar2023",
            "--amplitude-rad",
            "0.2",
            "--duration-s",
            "1",
            "--rate-hz",
            "10",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
}

#[test]
fn a_misspelt_preset_gets_did_you_mean() {
    for (given, preset) in [
        ("shahriar2O23", "shahriar2023"),
        ("shahriar", "shahriar2023"),
        ("fernando2052", "fernando2025"),
        ("Fernando2025", "fernando2025"),
    ] {
        for args in [
            &["fk", "--robot", given][..],
            &["stream", "--sim", "--robot", given],
            &["calibrate", "--sim", "--robot", given, "get"],
            &["serve", "--sim", "--robot", given, "--check"],
        ] {
            let run = quadctl(args, "");
            assert_refused(&run, 2, &format!("did you mean `{preset}`?"));
            assert!(run.stderr.contains(given), "{}", run.stderr);
        }
    }
    // A name like no preset keeps the file error.
    let run = quadctl(&["fk", "--robot", "my-robot.toml"], "");
    assert_refused(&run, 2, "cannot be read as a robot file");
    assert!(!run.stderr.contains("did you mean"), "{}", run.stderr);
}

#[test]
fn a_misspelt_option_gets_the_similar_one() {
    let run = quadctl(&["stream", "--robt", "shahriar2023", "--sim"], "");
    assert_refused(&run, 2, "a similar argument exists: '--robot'");
    let run = quadctl(
        &[
            "run",
            "sway-roll",
            "--robot",
            "shahriar2023",
            "--sim",
            "--amplitude",
            "0.1",
        ],
        "",
    );
    assert_refused(&run, 2, "a similar argument exists: '--amplitude-rad'");
}

#[test]
fn an_empty_calibration_file_is_refused_by_name() {
    let dir = temp_dir("empty-calibration");
    for (name, text) in [("empty.toml", ""), ("comments.toml", "# nothing here\n\n")] {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("file written");
        let run = quadctl(
            &[
                "calibrate",
                "--sim",
                "--robot",
                "fernando2025",
                "set",
                s(&path),
            ],
            "",
        );
        assert_refused(&run, 2, &format!("{}: no servo calibration", s(&path)));
        assert_eq!(run.stdout, "", "nothing printed as if it were set");
    }
}
