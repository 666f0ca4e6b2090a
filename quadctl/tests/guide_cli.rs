//! `quadctl calibrate guide` end to end, from key scripts: against the simulated device (its
//! EEPROM kept in a file between runs), and once against the emulated firmware. A save shows in
//! a later `calibrate get`, an abort leaves the calibration as it was, a refusal of the device
//! is shown with its reason.

mod common;

use common::quadctl;
use std::path::PathBuf;

/// A scratch directory of this test.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadctl-guide-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("a scratch directory");
    d
}

/// `quadctl calibrate --sim --robot shahriar2023 --sim-storage EEPROM ARGS`.
fn sim(eeprom: &str, args: &[&str]) -> common::Run {
    let mut all = vec![
        "calibrate",
        "--sim",
        "--robot",
        "shahriar2023",
        "--sim-storage",
        eeprom,
    ];
    all.extend_from_slice(args);
    quadctl(&all, "")
}

/// The `center_us` of `servo` in a calibration TOML.
fn center_us(toml: &str, servo: &str) -> u16 {
    let line = toml
        .lines()
        .find(|l| l.starts_with(&format!("{servo} ")))
        .unwrap_or_else(|| panic!("{servo} in {toml}"));
    let rest = line.split("center_us = ").nth(1).expect("center_us");
    rest.split(',')
        .next()
        .expect("a value")
        .trim()
        .parse()
        .expect("a number")
}

#[test]
fn a_guided_jog_saved_shows_in_calibrate_get_and_an_abort_changes_nothing() {
    let d = dir("save");
    let eeprom = d.join("eeprom.bin");
    let eeprom = eeprom.to_str().expect("utf-8");
    // Jog FL abduction +2 +2 µs, FL hip (reversed on no servo of the left legs) one coarse step
    // down, skip to the test poses, confirm all three, save.
    let run = sim(eeprom, &["guide", "--script", "n,+,+,n,[,t,n,n,n,s"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.starts_with("# saved\n"), "{}", run.stdout);
    for step in [
        "[posture]",
        "[test rest]",
        "[test stand]",
        "[test step_in_place]",
        "[saved]",
    ] {
        assert!(run.stderr.contains(step), "{step}: {}", run.stderr);
    }
    let get = sim(eeprom, &["get"]);
    assert_eq!(get.code, 0, "{}", get.stderr);
    assert_eq!(center_us(&get.stdout, "FL_abduction"), 1504);
    assert_eq!(center_us(&get.stdout, "FL_hip"), 1480);
    assert_eq!(center_us(&get.stdout, "FL_knee"), 1500);

    // An abort after jogs: the calibration read at the start, in RAM and in the EEPROM.
    let run = sim(eeprom, &["guide", "--script", "n,],],n,+,q"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.starts_with("# aborted"), "{}", run.stdout);
    assert_eq!(center_us(&run.stdout, "FL_abduction"), 1504);
    assert_eq!(center_us(&run.stdout, "FL_hip"), 1480);
    assert!(run.stderr.contains("nothing saved"), "{}", run.stderr);
    let after = sim(eeprom, &["get"]);
    assert_eq!(after.stdout, get.stdout);
    // A script that ends before saving aborts.
    let run = sim(eeprom, &["guide", "--script", "n,]"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.starts_with("# aborted"), "{}", run.stdout);
    assert_eq!(sim(eeprom, &["get"]).stdout, get.stdout);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_devices_refusal_of_a_jog_is_shown_with_its_reason_and_changes_nothing() {
    let d = dir("refused");
    let eeprom = d.join("eeprom.bin");
    let eeprom = eeprom.to_str().expect("utf-8");
    // FL abduction's travel ends 10 µs above its centre: a coarse jog up leaves it.
    let file = d.join("narrow.toml");
    std::fs::write(
        &file,
        "FL_abduction = { zero_rad = 0.0, reversed = false, us_per_rad = 636.62, center_us = 1500, min_us = 500, max_us = 1510 }\n",
    )
    .expect("written");
    let set = sim(eeprom, &["set", file.to_str().expect("utf-8"), "--save"]);
    assert_eq!(set.code, 0, "{}", set.stderr);
    let run = sim(eeprom, &["guide", "--script", "n,],+,s,q"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("the device refused SetCalibration: bad calibration"),
        "{}",
        run.stderr
    );
    // The fine jog within the travel went through; `s` does nothing on the jog step.
    assert!(run.stderr.contains("center_us 1502"), "{}", run.stderr);
    assert!(
        run.stderr.contains("`s` does nothing on the jog step"),
        "{}",
        run.stderr
    );
    assert_eq!(center_us(&run.stdout, "FL_abduction"), 1500);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_simulated_device_has_no_default_robot() {
    // `--robot` used to default to fernando2025; the simulated device now needs one named.
    let run = quadctl(&["calibrate", "--sim", "get"], "");
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--robot"), "{}", run.stderr);
    // A robot file is no simulated device.
    let run = quadctl(
        &[
            "calibrate",
            "--sim",
            "--robot",
            "examples/robots/shahriar2023.toml",
            "guide",
            "--script",
            "q",
        ],
        "",
    );
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("runs a preset"), "{}", run.stderr);
    // A script key that is none.
    let run = quadctl(
        &[
            "calibrate",
            "--sim",
            "--robot",
            "shahriar2023",
            "guide",
            "--script",
            "n,x",
        ],
        "",
    );
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("`x` is no key"), "{}", run.stderr);
    // Without a terminal and without a script.
    let run = quadctl(
        &["calibrate", "--sim", "--robot", "shahriar2023", "guide"],
        "",
    );
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--script"), "{}", run.stderr);
}

#[test]
fn a_guided_calibration_on_the_emulated_firmware_is_saved() {
    let d = dir("emulator");
    let eeprom = d.join("eeprom.bin");
    let eeprom = eeprom.to_str().expect("utf-8");
    let emu = |args: &[&str]| {
        let mut all = vec!["calibrate", "--emulator", "--sim-storage", eeprom];
        all.extend_from_slice(args);
        quadctl(&all, "")
    };
    // The firmware's robot (shahriar2023) as it reports it: no --robot.
    let run = emu(&["guide", "--script", "n,n,n,n,],t,n,n,n,s"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.starts_with("# saved\n"), "{}", run.stdout);
    let get = emu(&["get"]);
    assert_eq!(get.code, 0, "{}", get.stderr);
    // FR abduction (not reversed): +20 µs.
    assert_eq!(center_us(&get.stdout, "FR_abduction"), 1520);
    assert_eq!(center_us(&get.stdout, "FL_abduction"), 1500);
    let _ = std::fs::remove_dir_all(&d);
}
