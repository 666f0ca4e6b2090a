//! Black-box tests of `quadctl robot` on the simulated device: the robot shown, sent, stored
//! across runs (the simulated EEPROM in a file), refused before sending, and the device
//! commands' check of the robot they are given (or, without one, their use of the device's).

mod common;

use common::quadctl;
use std::path::{Path, PathBuf};

fn temp_path(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    // Left over from an earlier run.
    let _ = std::fs::remove_file(&path);
    path
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

#[test]
fn a_robot_sent_and_saved_is_the_device_s_in_the_next_run_and_another_is_refused_by_name() {
    let eeprom = temp_path("robot-cli.eeprom");
    let sim = ["--sim", "--sim-storage", s(&eeprom)];
    // The simulated device is built with the firmware's robot, as for every device command.
    let shown = quadctl(&[&["robot"][..], &sim, &["show"]].concat(), "");
    assert_eq!(shown.code, 0, "{}", shown.stderr);
    assert!(
        shown.stdout.contains("name = \"shahriar2023\""),
        "{}",
        shown.stdout
    );

    let sent = quadctl(
        &[
            &["robot"][..],
            &sim,
            &["send", "examples/robots/bench-pup.toml", "--save"],
        ]
        .concat(),
        "",
    );
    assert_eq!(sent.code, 0, "{}", sent.stderr);
    // A later run (a power cycle of the simulated device) boots the stored robot.
    let shown = quadctl(&[&["robot"][..], &sim, &["show"]].concat(), "");
    assert!(
        shown.stdout.contains("name = \"bench-pup\""),
        "{}",
        shown.stdout
    );
    assert!(shown.stdout.contains("femur_m = 0.2\n"), "{}", shown.stdout);

    // Without --robot a device command plans with the device's robot; with another it stops
    // before anything moves, naming both robots and the fix.
    let stand = quadctl(&[&["stand"][..], &sim].concat(), "");
    assert_eq!(stand.code, 0, "{}", stand.stderr);
    // `stream` too: every answer is checked against the host's kin-core for bench-pup, which
    // agrees with the device on the pose whose knee bench-pup cannot bend that far.
    let streamed = quadctl(
        &[
            &["stream"][..],
            &sim,
            &["--input", "examples/poses.csv", "--allow-refused"],
        ]
        .concat(),
        "",
    );
    assert_eq!(streamed.code, 0, "{}", streamed.stderr);
    assert!(
        streamed.stdout.contains("\"acked\":7,\"nacked\":1,")
            && streamed.stdout.contains("\"readback_mismatches\":0,"),
        "{}",
        streamed.stdout
    );
    assert!(
        streamed
            .stderr
            .contains("joint limit: FL.knee (the host's kin-core agrees)"),
        "{}",
        streamed.stderr
    );
    let refused = quadctl(
        &[&["sit"][..], &sim, &["--robot", "fernando2025"]].concat(),
        "",
    );
    assert_eq!(refused.code, 2, "{}", refused.stdout);
    for named in ["bench-pup", "fernando2025", "quadctl robot send"] {
        assert!(
            refused.stderr.contains(named),
            "{named}: {}",
            refused.stderr
        );
    }
}

#[test]
fn a_robot_the_device_cannot_hold_is_refused_before_sending_naming_the_field() {
    let eeprom = temp_path("robot-cli-refused.eeprom");
    let sim = ["--sim", "--sim-storage", s(&eeprom)];
    let file = temp_path("robot-cli-too-short.toml");
    // A stance the legs cannot reach: 0.3 m with 0.1 m of leg.
    std::fs::write(
        &file,
        "d_lat_m = 0.02\nd_ax_m = 0.0\nfemur_m = 0.05\ntibia_m = 0.05\nbody_length_m = 0.3\n\
         body_width_m = 0.15\n[device]\nname = \"stubby\"\nstance_height_m = 0.3\n",
    )
    .expect("robot file written");
    let sent = quadctl(
        &[&["robot"][..], &sim, &["send", s(&file), "--save"]].concat(),
        "",
    );
    assert_eq!(sent.code, 2, "{}", sent.stdout);
    // The field, and what it must be for this robot, in its own numbers.
    for said in [
        "stance_height_m",
        "[0.01, 0.240] m",
        "= 0.120 m",
        "not sent",
    ] {
        assert!(sent.stderr.contains(said), "{said}: {}", sent.stderr);
    }
    // Nothing stored: the device still holds the firmware's robot.
    let shown = quadctl(&[&["robot"][..], &sim, &["show"]].concat(), "");
    assert!(
        shown.stdout.contains("name = \"shahriar2023\""),
        "{}",
        shown.stdout
    );
}
