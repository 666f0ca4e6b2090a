//! Black-box tests of the onboard motions on the simulated device: `quadctl stand`, `sit`,
//! `rest` and `run`, their refusals in words (the option named) and their exit status.

mod common;

use common::{last_line_json, quadctl};

fn run(args: &[&str]) -> common::Run {
    let mut all = args.to_vec();
    all.extend_from_slice(&["--robot", "shahriar2023", "--sim"]);
    quadctl(&all, "")
}

#[test]
fn stand_runs_to_the_stance_and_sit_rest_have_nothing_to_do_with_the_outputs_off() {
    let r = run(&["stand"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let json = last_line_json(&r);
    assert_eq!(json["motion"], "stand_up");
    assert_eq!(json["outputs_enabled"], true);
    for posture in ["sit", "rest"] {
        let r = run(&[posture]);
        assert_eq!(r.code, 0, "{posture}: {}", r.stderr);
        let json = last_line_json(&r);
        assert_eq!(json["motion"], "none");
        assert_eq!(json["outputs_enabled"], false);
    }
}

#[test]
fn every_motion_runs_to_its_end_after_standing_up() {
    for args in [
        vec![
            "run",
            "sway-roll",
            "--amplitude-rad",
            "0.1",
            "--period-s",
            "2",
        ],
        vec![
            "run",
            "sway-pitch",
            "--amplitude-rad",
            "0.1",
            "--period-s",
            "2",
        ],
        vec![
            "run",
            "yaw-turn",
            "--yaw-rate-rad-s",
            "0.1",
            "--step-period-s",
            "2",
            "--lift-height-m",
            "0.05",
        ],
        vec!["run", "foot-path", "--leg", "FL", "--cycle-s", "1"],
        vec!["run", "trot", "--forward-m-s", "0.05", "--duration-s", "2"],
        vec!["run", "walk", "--lateral-m-s", "0.02", "--duration-s", "2"],
    ] {
        let r = run(&args);
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
        let json = last_line_json(&r);
        assert_eq!(json["stood_up_first"], true, "{args:?}");
        assert_eq!(json["outputs_enabled"], true, "{args:?}");
        assert!(
            json["motion_s"].as_f64().unwrap() >= 1.0,
            "{args:?}: {json}"
        );
        if args[1] == "trot" || args[1] == "walk" {
            assert!(json["velocity_commands"].as_u64().unwrap() >= 19, "{json}");
        }
    }
}

#[test]
fn bad_values_are_refused_naming_the_option() {
    for (args, words) in [
        (
            vec!["run", "sway-roll", "--amplitude-rad", "nan"],
            "--amplitude-rad is not a finite number",
        ),
        (
            vec!["run", "sway-pitch", "--period-s", "-1"],
            "--period-s must be > 0",
        ),
        (
            vec!["run", "sway-roll", "--duration-s", "0"],
            "--duration-s must be > 0",
        ),
        (
            vec!["run", "foot-path", "--step-height-m", "2"],
            "--step-height-m",
        ),
        (
            vec!["run", "trot", "--forward-m-s", "5"],
            "--forward-m-s is outside its admissible range",
        ),
        (
            vec!["run", "yaw-turn", "--amplitude-rad", "1"],
            "--amplitude-rad does not apply to yaw-turn",
        ),
    ] {
        let r = run(&args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stdout);
        assert!(r.stdout.is_empty(), "{args:?}: no summary");
        assert!(r.stderr.contains(words), "{args:?}: {}", r.stderr);
    }
}

#[test]
fn values_outside_their_range_are_refused_before_sending_naming_the_option_and_its_range() {
    for (args, words) in [
        (
            vec!["run", "sway-roll", "--amplitude-rad", "1e30"],
            "--amplitude-rad is outside its admissible range [-1.5707964, 1.5707964] rad",
        ),
        (
            vec!["run", "sway-pitch", "--period-s", "1e-45"],
            "--period-s is outside its admissible range [0.1, 60] s",
        ),
        (
            vec!["run", "trot", "--forward-m-s", "inf"],
            "--forward-m-s is not a finite number (admissible: [-10, 10] m/s)",
        ),
        (
            vec!["run", "foot-path", "--duty-factor", "0.99"],
            "--duty-factor is outside its admissible range [0.05, 0.95]",
        ),
    ] {
        let r = run(&args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stdout);
        assert!(r.stdout.is_empty(), "{args:?}: no summary");
        assert!(r.stderr.contains("not sent"), "{args:?}: {}", r.stderr);
        assert!(r.stderr.contains(words), "{args:?}: {}", r.stderr);
    }
}
