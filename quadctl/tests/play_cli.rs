//! Black-box tests of `quadctl play`: `quadctl motion` output and play files on the simulated
//! device and the emulated firmware, paced on the link's clock, and the files it refuses
//! before anything is sent.

mod common;

use common::{last_line_json, quadctl};

/// A `quadctl motion` CSV written by the binary itself.
fn motion_csv(args: &[&str]) -> String {
    let mut all = vec!["motion"];
    all.extend_from_slice(args);
    let run = quadctl(&all, "");
    assert_eq!(run.code, 0, "{}", run.stderr);
    run.stdout
}

#[test]
fn motion_output_plays_as_it_is_in_real_time_on_the_simulated_clock() {
    let csv = motion_csv(&[
        "roll-sway",
        "--robot",
        "fernando2025",
        "--duration-s",
        "2",
        "--rate-hz",
        "50",
    ]);
    for (send, speed) in [("joints", "1"), ("feet", "1"), ("pose", "2")] {
        let run = quadctl(
            &[
                "play",
                "-",
                "--robot",
                "fernando2025",
                "--sim",
                "--send",
                send,
                "--speed",
                speed,
            ],
            &csv,
        );
        assert_eq!(run.code, 0, "{send}: {}{}", run.stdout, run.stderr);
        let json = last_line_json(&run);
        assert_eq!(json["kind"], send);
        assert_eq!(json["rows"], 101);
        assert_eq!(json["sent"], 101, "{send}: nothing skipped at 50 Hz");
        assert_eq!(json["acked"], 101);
        assert_eq!(json["readback_mismatches"], 0);
        assert_eq!(
            json["late_max_ms"], 0.0,
            "{send}: the simulated line keeps up"
        );
        // The rows' span on the link's clock, scaled by --speed, plus the last answer.
        let motion_s = 2.0 / speed.parse::<f64>().unwrap();
        assert_eq!(json["motion_s"], motion_s);
        let elapsed = json["elapsed_s"].as_f64().unwrap();
        assert!(
            elapsed >= motion_s && elapsed < motion_s + 0.05,
            "{send}: {elapsed}"
        );
    }
}

#[test]
fn rows_that_cannot_be_sent_in_time_are_skipped_and_reported() {
    // 1 kHz rows at 115200 baud: an exchange takes about 12 ms.
    let mut csv = String::from(
        "t_s,FL_x_m,FL_y_m,FL_z_m,FR_x_m,FR_y_m,FR_z_m,RL_x_m,RL_y_m,RL_z_m,RR_x_m,RR_y_m,RR_z_m\n",
    );
    for i in 0..100 {
        let t = f64::from(i) * 1e-3;
        csv.push_str(&format!(
            "{t},0.5,0.4,-0.9,0.5,-0.4,-0.9,-0.5,0.4,-0.9,-0.5,-0.4,-0.9\n"
        ));
    }
    let run = quadctl(&["play", "-", "--robot", "fernando2025", "--sim"], &csv);
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    let json = last_line_json(&run);
    assert_eq!(json["kind"], "feet");
    let (sent, skipped) = (
        json["sent"].as_u64().unwrap(),
        json["skipped"].as_u64().unwrap(),
    );
    assert_eq!(sent + skipped, 100);
    assert!(skipped > 80, "{json}");
    assert!(json["answer_mean_ms"].as_f64().unwrap() > 5.0, "{json}");
}

#[test]
fn unreachable_rows_are_nacked_as_the_host_predicts() {
    let csv = "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m
0,0,0,0,0,0,0
0.5,0.1,0,0,0,0,0
1,0,0,0,0,0,1
";
    let run = quadctl(
        &[
            "play",
            "-",
            "--robot",
            "fernando2025",
            "--sim",
            "--allow-refused",
        ],
        csv,
    );
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    let json = last_line_json(&run);
    assert_eq!(
        (json["acked"].as_u64(), json["nacked"].as_u64()),
        (Some(2), Some(1))
    );
    assert!(
        run.stderr.contains("<stdin>:4: nacked: unreachable"),
        "{}",
        run.stderr
    );
}

#[test]
fn bad_files_are_refused_with_line_and_column_before_anything_is_sent() {
    let cases = [
        (
            "roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0\n",
            "<stdin>:1: header has no `t_s` column",
        ),
        (
            "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n",
            "<stdin>:4: column t_s (field 1): 0.1 s does not follow 0.1 s",
        ),
        (
            "# comment\nt_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m,gain\n0,0,0,0,0,0,0,1\n",
            "<stdin>:2: column 8 `gain` is of no known kind",
        ),
        (
            "t_s,roll_rad,pitch_rad\n0,0,0\n",
            "<stdin>:1: header has pose columns but no `yaw_rad`",
        ),
        (
            "t_s\n0\n",
            "<stdin>:1: header has no joint, foot or pose columns",
        ),
        (
            "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0,0\nnan,0,0,0,0,0,0\n",
            "<stdin>:3: column t_s (field 1): time is not finite",
        ),
        (
            "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,x,0,0,0\n",
            "<stdin>:2: field 4: `x` is not a number",
        ),
    ];
    for (csv, message) in cases {
        let run = quadctl(&["play", "-", "--robot", "fernando2025", "--sim"], csv);
        assert_eq!(run.code, 2, "{csv}: {}", run.stderr);
        assert!(run.stdout.is_empty(), "{csv}: nothing played");
        assert!(run.stderr.contains(message), "{csv}: {}", run.stderr);
    }
}

#[test]
fn motion_output_with_unreachable_samples_is_refused_naming_the_row() {
    let csv = motion_csv(&[
        "roll-sway",
        "--robot",
        "fernando2025",
        "--duration-s",
        "1",
        "--rate-hz",
        "10",
    ]);
    // The third sample as `quadctl motion` writes an unreachable one: empty angles, the status.
    let mut lines: Vec<String> = csv.lines().map(str::to_owned).collect();
    let row = lines
        .iter()
        .position(|l| l.starts_with("0.2,"))
        .expect("t = 0.2 s");
    let mut fields: Vec<&str> = lines[row].split(',').collect();
    for f in &mut fields[1..13] {
        *f = "";
    }
    *fields.last_mut().expect("status") = "FL:too_far";
    lines[row] = fields.join(",");
    let play = quadctl(
        &["play", "-", "--robot", "fernando2025", "--sim"],
        &lines.join("\n"),
    );
    assert_eq!(play.code, 2, "{}", play.stderr);
    assert!(
        play.stderr.contains(&format!(
            "<stdin>:{}: column status (field 32): `FL:too_far`",
            row + 1
        )),
        "{}",
        play.stderr
    );
}

#[test]
fn play_on_the_emulator_checks_the_pins() {
    let csv = motion_csv(&[
        "pitch-sway",
        "--robot",
        "shahriar2023",
        "--stance-height-m",
        "0.2",
        "--amplitude-rad",
        "0.1",
        "--period-s",
        "1",
        "--duration-s",
        "1",
        "--rate-hz",
        "50",
    ]);
    let run = quadctl(
        &[
            "play",
            "-",
            "--robot",
            "shahriar2023",
            "--emulator",
            "--baud",
            "1000000",
        ],
        &csv,
    );
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    let json = last_line_json(&run);
    assert_eq!(json["acked"], 51);
    assert_eq!(json["readback_mismatches"], 0);
    assert_eq!(json["pulse_width_errors"], 0);
    assert!(json["pulses_checked"].as_u64().unwrap() > 12 * 40);
}

#[test]
fn motion_uses_the_devices_rotation_order_for_a_preset() {
    for (law, robot, order) in [
        ("roll-sway", "shahriar2023", "zyx"),
        ("roll-sway", "fernando2025", "zxy"),
        ("trot", "fernando2025", "zxy"),
        ("trot", "shahriar2023", "zyx"),
    ] {
        let csv = motion_csv(&[
            law,
            "--robot",
            robot,
            "--stance-height-m",
            if robot == "fernando2025" {
                "0.9294"
            } else {
                "0.4"
            },
            "--duration-s",
            "0.1",
            "--rate-hz",
            "10",
        ]);
        let first = csv.lines().next().expect("a comment line");
        assert!(
            first.contains(&format!("rotation_order={order}")),
            "{law} {robot}: {first}"
        );
    }
}

#[test]
fn a_refused_row_makes_the_exit_status_4_unless_allowed() {
    let csv = "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m
0,0,0,0,0,0,0
1,0,0,0,0,0,1
";
    let run = quadctl(&["play", "-", "--robot", "fernando2025", "--sim"], csv);
    assert_eq!(run.code, 4, "{}{}", run.stdout, run.stderr);
    assert_eq!(last_line_json(&run)["nacked"], 1);
    assert!(run.stderr.contains("<stdin>:3: nacked"), "{}", run.stderr);
    let run = quadctl(
        &[
            "play",
            "-",
            "--robot",
            "fernando2025",
            "--sim",
            "--allow-refused",
        ],
        csv,
    );
    assert_eq!(run.code, 0, "{}{}", run.stdout, run.stderr);
    let run = quadctl(
        &["play", "-", "--robot", "fernando2025", "--sim"],
        "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n0,0,0,0,0,0,0\n1,0.1,0,0,0,0,0\n",
    );
    assert_eq!(run.code, 0, "every row acked: {}", run.stderr);
}
