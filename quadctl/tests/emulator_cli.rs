//! Black-box tests of `quadctl stream --emulator` and `quadctl demo`: the real firmware in
//! simavr (built from `firmware-avr/` by the command itself; a test fails when it cannot be).

mod common;

use common::quadctl;

const POSES: &str = "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m
0,0,0,0,0,0
0.2,0,0,0,0,0
0,-0.15,0.1,0.01,0,-0.01
0,0,0,0,0,1
";

#[test]
fn stream_on_the_emulator_checks_readbacks_and_pins() {
    let run = quadctl(
        &[
            "stream",
            "--emulator",
            "--robot",
            "shahriar2023",
            "--allow-refused",
            "--input",
            "-",
        ],
        POSES,
    );
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    let last = run.stdout.lines().last().expect("a last line");
    let json: serde_json::Value = serde_json::from_str(last).expect("JSON");
    assert_eq!(json["sent"], 4);
    assert_eq!(json["acked"], 3);
    assert_eq!(json["nacked"], 1, "the lifted body is unreachable");
    assert_eq!(json["readback_mismatches"], 0);
    assert_eq!(json["pulse_width_errors"], 0);
    assert!(json["pulses_checked"].as_u64().expect("a count") >= 12);
    assert!(json["max_angle_err_rad"].as_f64().expect("a number") > 0.0);
    // The stream's own fields come first, in their documented order.
    assert!(last.starts_with("{\"sent\":"), "{last}");
    assert!(last.ends_with("\"pulse_width_errors\":0}"), "{last}");
    assert!(
        run.stderr.contains(":5: nacked: unreachable"),
        "{}",
        run.stderr
    );
}

#[test]
fn stream_refuses_a_line_rate_the_firmware_does_not_run() {
    let run = quadctl(
        &[
            "stream",
            "--emulator",
            "--baud",
            "57600",
            "--robot",
            "shahriar2023",
        ],
        POSES,
    );
    assert_eq!(run.code, 2);
    assert!(
        run.stderr.contains("no firmware is built for 57600"),
        "{}",
        run.stderr
    );
}

#[test]
fn demo_passes_on_the_emulator() {
    let run = quadctl(&["demo", "--poses-per-sweep", "8", "--baud", "1000000"], "");
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    assert!(
        run.stdout
            .contains("24 sent, 24 acked, 0 nacked, 0 lost, 0 readback mismatches"),
        "{}",
        run.stdout
    );
    assert!(
        run.stdout.contains(" 0 off their readback"),
        "{}",
        run.stdout
    );
    assert!(run.stdout.contains("result: PASS"), "{}", run.stdout);
}
