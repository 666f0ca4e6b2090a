//! `quadctl status`, `watch` and `balance` on the simulated device (protocol 2.3): the sensor's
//! health live, the balance switch, a refused gain named by its option.

mod common;

use common::quadctl;

#[test]
fn watch_shows_the_sensor_start_and_then_ok() {
    let run = quadctl(
        &[
            "watch",
            "--robot",
            "shahriar2023",
            "--sim",
            "--count",
            "6",
            "--period-ms",
            "250",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert_eq!(lines.len(), 7, "{}", run.stdout);
    assert!(lines[0].contains("imu starting"), "{}", lines[0]);
    assert!(lines[5].contains("imu ok"), "{}", lines[5]);
    assert!(lines[5].contains("roll +0.00°"), "{}", lines[5]);
    let json: serde_json::Value = serde_json::from_str(lines[6]).unwrap();
    assert_eq!(json["polls"], 6);
    assert_eq!(json["last"]["imu"]["health"], "ok");
}

#[test]
fn status_reports_the_sensor_and_the_outputs() {
    let run = quadctl(&["status", "--robot", "fernando2025", "--sim"], "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    let last = run.stdout.lines().last().unwrap();
    let json: serde_json::Value = serde_json::from_str(last).unwrap();
    assert_eq!(json["outputs_enabled"], false);
    assert_eq!(json["fall_detected"], false);
    assert_eq!(json["imu"]["config"]["leveling"], false);
}

#[test]
fn balance_switches_leveling_and_keeps_the_other_settings() {
    let run = quadctl(
        &[
            "balance",
            "--robot",
            "shahriar2023",
            "--sim",
            "--leveling",
            "on",
            "--safe-state",
            "off",
        ],
        "",
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let json: serde_json::Value = serde_json::from_str(run.stdout.lines().last().unwrap()).unwrap();
    assert_eq!(json["config"]["leveling"], true);
    assert_eq!(json["config"]["safe_state"], "off");
    assert_eq!(json["config"]["on_fault"], "open_loop");
}

#[test]
fn a_gain_out_of_range_is_refused_naming_its_option() {
    let run = quadctl(
        &["balance", "--robot", "shahriar2023", "--sim", "--kp", "2"],
        "",
    );
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--kp"), "{}", run.stderr);
    assert!(run.stderr.contains("[0, 0.9]"), "{}", run.stderr);
}
