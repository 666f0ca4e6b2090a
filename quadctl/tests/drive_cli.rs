//! `quadctl drive` on the simulated device with a key script: commands at 20 Hz, refusals
//! taken back and shown, the height change, and the script's errors.

mod common;

use common::{last_line_json, quadctl};

fn drive(script: &str) -> common::Run {
    let path = std::env::temp_dir().join(format!(
        "quadctl-drive-{}-{}.txt",
        std::process::id(),
        script.len()
    ));
    std::fs::write(&path, script).expect("the script");
    let path = path.display().to_string();
    let r = quadctl(
        &["drive", "--robot", "shahriar2023", "--sim", "--keys", &path],
        "",
    );
    let _ = std::fs::remove_file(&path);
    r
}

#[test]
fn a_key_script_drives_the_trot_at_20_hz() {
    let r = drive(
        "# forward, turn, higher, stop, quit\n0 w\n0 up\n500 left\n1500 +\n4000 space\n5000 q\n",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let json = last_line_json(&r);
    assert_eq!(json["keys"], 6);
    assert_eq!(json["height_changes"], 1);
    assert_eq!(json["refused"], 0, "{}", r.stderr);
    assert!(
        json["max_gap_ms"].as_f64().unwrap() <= 50.0 + 1e-6,
        "{json}"
    );
    assert!(json["commands_sent"].as_u64().unwrap() >= 40, "{json}");
    assert_eq!(json["last"]["forward_m_s"], 0.0);
}

#[test]
fn a_velocity_beyond_reach_is_refused_in_words_and_taken_back() {
    let mut script = String::new();
    for i in 0..60 {
        script.push_str(&format!("{} w\n", i * 10));
    }
    let r = drive(&script);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let json = last_line_json(&r);
    assert!(json["refused"].as_u64().unwrap() >= 1, "{json}");
    assert!(
        r.stderr
            .contains("refused: --forward-m-s is outside its admissible range"),
        "{}",
        r.stderr
    );
    let last = json["last"]["forward_m_s"].as_f64().unwrap();
    assert!(
        last > 0.0 && last < 1.2,
        "the last accepted command: {json}"
    );
}

#[test]
fn a_malformed_script_is_refused_with_its_line() {
    let r = drive("0 w\n100 jump\n");
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains(":2: `100 jump` is not `<ms> <key>`"),
        "{}",
        r.stderr
    );
}
