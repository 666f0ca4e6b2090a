//! Black-box tests of `quadctl export` and `quadctl sim`: exit codes, errors naming the field
//! and its line, no partial output file on bad input. `sim` needs the twin's Python
//! environment (`scripts/install-deps.sh`); one short run (stand, no rendering) keeps it
//! bounded.

mod common;

use common::quadctl;
use std::path::{Path, PathBuf};

const MINIMAL: &str = "d_lat_m = 0.044\nd_ax_m = 0.0\nfemur_m = 0.28\ntibia_m = 0.277\n\
                       body_length_m = 0.6\nbody_width_m = 0.28\n";

fn temp_path(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    // Left over from an earlier run.
    let _ = std::fs::remove_file(&path);
    path
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let path = temp_path(name);
    std::fs::write(&path, text).expect("temp file written");
    path
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

#[test]
fn export_writes_mjcf_and_urdf_and_a_urdf_reads_back_as_the_robot() {
    let mjcf = temp_path("export-shahriar2023.xml");
    let run = quadctl(&["export", "--format", "mjcf", "--output", s(&mjcf)], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    let text = std::fs::read_to_string(&mjcf).expect("MJCF written");
    assert!(
        text.contains("<mujoco") && text.contains("FL_knee"),
        "{text}"
    );

    let run = quadctl(
        &["export", "--format", "urdf", "--robot", "fernando2025"],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("<robot name=\"fernando2025\""));
    let urdf = temp_file("export-fernando2025.urdf", &run.stdout);
    // The URDF is a robot description: exported again, the same model as the preset's.
    let again = quadctl(&["export", "--format", "mjcf", "--robot", s(&urdf)], "");
    assert_eq!(again.code, 0, "{}", again.stderr);
    let preset = quadctl(
        &["export", "--format", "mjcf", "--robot", "fernando2025"],
        "",
    );
    assert_eq!(again.stdout, preset.stdout);
}

#[test]
fn export_writes_a_toml_robot_file_that_reads_back_as_the_same_robot_and_body() {
    // A robot of neither preset's lengths, with a [physical] table of its own.
    let custom = temp_file(
        "export-custom.toml",
        "d_lat_m = 0.05\nd_ax_m = 0.01\nfemur_m = 0.21\ntibia_m = 0.23\nbody_length_m = 0.45\n\
         body_width_m = 0.2\n[limits]\nknee_rad = [-2.6, -0.1]\n[physical]\nbody_mass_kg = 1.9\n",
    );
    for source in [s(&custom), "shahriar2023", "fernando2025"] {
        let run = quadctl(&["export", "--format", "toml", "--robot", source], "");
        assert_eq!(run.code, 0, "{}", run.stderr);
        let toml = temp_file("export-roundtrip.toml", &run.stdout);
        // The TOML, the URDF written from it and the source give the same model.
        let urdf = quadctl(&["export", "--format", "urdf", "--robot", s(&toml)], "");
        assert_eq!(urdf.code, 0, "{}", urdf.stderr);
        let from_source = quadctl(&["export", "--format", "mjcf", "--robot", source], "");
        let from_toml = quadctl(&["export", "--format", "mjcf", "--robot", s(&toml)], "");
        assert_eq!(from_toml.code, 0, "{}", from_toml.stderr);
        assert_eq!(from_toml.stdout, from_source.stdout, "{}", run.stdout);
        // And the TOML written again from the TOML is the same text.
        let again = quadctl(&["export", "--format", "toml", "--robot", s(&toml)], "");
        assert_eq!(again.stdout, run.stdout);
    }
}

#[test]
fn export_takes_the_physical_table_of_a_robot_file() {
    let file = temp_file(
        "heavy.toml",
        &format!("{MINIMAL}[physical]\nbody_mass_kg = 3.25\nservo = \"mg996r\"\n"),
    );
    let run = quadctl(&["export", "--format", "urdf", "--robot", s(&file)], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("value=\"3.25\""), "{}", run.stdout);
}

#[test]
fn bad_physical_values_exit_2_naming_field_and_line_and_leave_no_file() {
    let cases = [
        ("body_mass_kg = 0.0\n", "`body_mass_kg`"),
        ("femur_mass_kg = -0.1\n", "`femur_mass_kg`"),
        ("foot_friction = nan\n", "`foot_friction`"),
        ("servo = \"sg90\"\n", "`sg90`"),
    ];
    for (i, (line, named)) in cases.into_iter().enumerate() {
        let file = temp_file(
            &format!("bad-physical-{i}.toml"),
            &format!("{MINIMAL}[physical]\n{line}"),
        );
        let out = temp_path(&format!("bad-physical-{i}.xml"));
        let run = quadctl(
            &[
                "export",
                "--format",
                "mjcf",
                "--robot",
                s(&file),
                "--output",
                s(&out),
            ],
            "",
        );
        assert_eq!(run.code, 2, "{line}: {}", run.stderr);
        assert!(run.stderr.contains(named), "{line}: {}", run.stderr);
        assert!(run.stderr.contains(":8: "), "{line}: {}", run.stderr);
        assert!(!out.exists(), "{line}: partial output");
        assert!(run.stdout.is_empty());
    }
    // The unknown servo lists the known ones.
    let file = temp_file(
        "bad-servo.toml",
        &format!("{MINIMAL}[physical]\nservo = \"sg90\"\n"),
    );
    let run = quadctl(&["sim", "stand", "--robot", s(&file)], "");
    assert_eq!(run.code, 2);
    for known in ["mg996r", "ds3235", "qdd17", "qdd33"] {
        assert!(run.stderr.contains(known), "{}", run.stderr);
    }
}

#[test]
fn sim_refuses_bad_input_before_running_and_leaves_no_picture() {
    let gif = temp_path("refused.gif");
    let bad_robot = temp_file(
        "bad-length.toml",
        &MINIMAL.replace("tibia_m = 0.277", "tibia_m = -0.277"),
    );
    for args in [
        vec![
            "sim",
            "stand",
            "--robot",
            s(&bad_robot),
            "--render",
            s(&gif),
        ],
        vec!["sim", "stand", "--servo", "sg90", "--render", s(&gif)],
        vec![
            "sim",
            "stand",
            "--robot",
            "fernando2025",
            "--emulator",
            "--render",
            s(&gif),
        ],
        vec!["sim", "moonwalk", "--render", s(&gif)],
        vec!["sim", "stand", "--sim", "--emulator"],
    ] {
        let run = quadctl(&args, "");
        assert_eq!(run.code, 2, "{args:?}: {}", run.stderr);
        assert!(!run.stderr.is_empty(), "{args:?}");
        assert!(!gif.exists(), "{args:?}: picture left behind");
    }
    let run = quadctl(&["sim", "stand", "--robot", s(&bad_robot)], "");
    assert!(run.stderr.contains("tibia_m"), "{}", run.stderr);
}

#[test]
fn sim_stand_runs_in_the_twin_and_keeps_its_summary() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sim-stand");
    let _ = std::fs::remove_dir_all(&dir);
    let run = quadctl(&["sim", "stand", "--out-dir", s(&dir)], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("fell=false"), "{}", run.stdout);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
            .expect("summary.json");
    assert_eq!(summary["fell"], false);
    assert_eq!(summary["robot"], "shahriar2023");
    assert!(dir.join("plots.png").exists() && dir.join("model.xml").exists());
}

#[test]
fn sim_refuses_a_slope_out_of_range_or_an_impulse_that_is_not_a_number() {
    let gif = temp_path("refused-scenario.gif");
    for (args, field) in [
        (
            vec!["sim", "stand", "--slope-deg", "45", "--render", s(&gif)],
            "slope_deg",
        ),
        (
            vec![
                "sim",
                "stand",
                "--slope-deg",
                "25",
                "--tilt-floor",
                "--render",
                s(&gif),
            ],
            "slope_deg",
        ),
        (
            vec!["sim", "stand", "--push-n-s", "inf", "--render", s(&gif)],
            "push-n-s",
        ),
        (
            vec!["sim", "stand", "--slope-axis", "yaw", "--render", s(&gif)],
            "slope-axis",
        ),
    ] {
        let run = quadctl(&args, "");
        assert_eq!(run.code, 2, "{args:?}: {}", run.stderr);
        assert!(run.stderr.contains(field), "{args:?}: {}", run.stderr);
        assert!(!gif.exists(), "{args:?}: picture left behind");
    }
}

#[test]
fn sim_stand_on_a_slope_reports_the_body_going_with_the_floor() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sim-slope");
    let _ = std::fs::remove_dir_all(&dir);
    let run = quadctl(
        &[
            "sim",
            "stand",
            "--slope-deg",
            "-10",
            "--slope-axis",
            "pitch",
            "--out-dir",
            s(&dir),
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stdout.contains("scenario: slope -10.0° pitch"),
        "{}",
        run.stdout
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
            .expect("summary.json");
    let pitch = summary["scenario"]["settled_pitch_rad"].as_f64().unwrap();
    assert!((pitch.to_degrees() + 10.0).abs() < 1.5, "{summary}");
    assert_eq!(
        summary["attitude"]["imu_rate_hz"].as_f64().unwrap().round(),
        200.0
    );
}
