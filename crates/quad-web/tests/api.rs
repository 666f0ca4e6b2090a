//! The panel's interface for programs is as docs/panel.md documents it: every page → server
//! example there parses as the server parses a page's message, every command is documented,
//! every field the server sends is named there, and `GET /api/state` answers the state as JSON.

use kin_core::Robot;
use quad_host::link::sim::SimConfig;
use quad_host::link::Target;
use quad_protocol::RobotPreset;
use quad_web::device::DeviceSetup;
use quad_web::msg::{ClientMsg, ServerMsg};
use quad_web::server::STATE_PATH;
use quad_web::ServeConfig;
use serde_json::Value;
use std::collections::BTreeSet;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// docs/panel.md's section on the WebSocket messages and the state endpoint.
fn section() -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = std::fs::read_to_string(root.join("docs/panel.md")).expect("docs/panel.md");
    let start = doc.find("## WebSocket messages").expect("the section");
    let end = doc[start..]
        .find("\n## Tests")
        .map_or(doc.len(), |e| start + e);
    doc[start..end].to_owned()
}

/// The lines of the section's ```json block.
fn json_examples(section: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut inside = false;
    for line in section.lines() {
        if line.starts_with("```") {
            inside = line == "```json";
            continue;
        }
        if inside && !line.trim().is_empty() {
            lines.push(line.to_owned());
        }
    }
    lines
}

#[test]
fn every_documented_page_message_parses_and_every_command_is_documented() {
    let examples = json_examples(&section());
    assert!(!examples.is_empty());
    let mut names = BTreeSet::new();
    for line in &examples {
        let msg = ClientMsg::parse(line).unwrap_or_else(|e| panic!("{line}: {e}"));
        names.insert(msg.name());
    }
    let every = [
        "take_control",
        "release_control",
        "set_outputs",
        "set_pose",
        "set_stance_height",
        "jog",
        "set_center",
        "set_direction",
        "save_calibration",
        "read_calibration",
        "start_motion",
        "stop_motion",
        "set_velocity",
        "set_balance",
        "guide_start",
        "guide_key",
    ];
    assert_eq!(names, every.into_iter().collect());
    // And what the server refuses is refused: the same parser.
    assert!(ClientMsg::parse(r#"{"type": "jog", "servo": 12, "delta_us": 1}"#).is_err());
}

/// Every key of `v`'s objects, at every depth (arrays: their first element).
fn keys(v: &Value, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(map) => {
            for (k, v) in map {
                out.insert(k.clone());
                keys(v, out);
            }
        }
        Value::Array(items) => {
            if let Some(first) = items.first() {
                keys(first, out);
            }
        }
        _ => {}
    }
}

fn get(addr: std::net::SocketAddr, path: &str) -> (String, String) {
    let mut stream = TcpStream::connect(addr).expect("connects");
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .expect("a timeout");
    write!(
        stream,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .expect("the request");
    let mut response = String::new();
    stream.read_to_string(&mut response).expect("the response");
    let (head, body) = response.split_once("\r\n\r\n").expect("head and body");
    (head.to_owned(), body.to_owned())
}

#[test]
fn the_state_endpoint_answers_json_and_every_field_the_server_sends_is_documented() {
    let preset = RobotPreset::Shahriar2023;
    let config = ServeConfig {
        device: DeviceSetup {
            target: Target::Sim {
                preset,
                config: SimConfig::default(),
                storage: None,
            },
            robot: Some(Robot::shahriar2023()),
            retries: 10,
            poll: Duration::from_millis(50),
        },
        listen: "127.0.0.1:0".parse().expect("an address"),
    };
    let running = quad_web::start(config, false).expect("the server starts");
    let (head, body) = get(running.addr, STATE_PATH);
    running.stop().expect("the server stops");
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    assert!(
        head.to_ascii_lowercase()
            .contains("content-type: application/json"),
        "{head}"
    );
    let state: Value = serde_json::from_str(&body).expect("JSON");
    assert_eq!(state["angles_rad"].as_array().map(Vec::len), Some(12));
    assert_eq!(state["link_up"], true);
    assert_eq!(state["stance_height_m"].as_f64(), Some(0.4));
    assert_eq!(state["motion"]["stage"], "idle");
    // The simulated device's sensor, level and still: measuring its gyro bias for its first
    // second, then ok.
    let health = state["imu"]["health"]
        .as_str()
        .expect("the sensor's report");
    assert!(["starting", "ok"].contains(&health), "{health}");
    assert_eq!(state["imu"]["leveling"], false);
    assert_eq!(state["flags"]["fall_detected"], false);
    // Every field of the state, the welcome, done and error is named in the docs.
    let welcome = ServerMsg::Welcome {
        page_id: 1,
        robot: Robot::shahriar2023(),
        robot_name: "shahriar2023".to_owned(),
        rotation_order: 5,
        servos: vec!["FL_abduction".to_owned()],
        link_loss_action: "hold",
        target: "sim",
    };
    let error = ServerMsg::Error {
        message: "m".to_owned(),
        field: Some("amplitude_rad"),
    };
    let done = ServerMsg::Done { command: "jog" };
    let mut fields = BTreeSet::new();
    keys(&state, &mut fields);
    for msg in [welcome, error, done] {
        let v = serde_json::to_value(&msg).expect("serializes");
        // The robot's geometry is kin-core's `Robot`, not spelt out in the panel's docs.
        if let Value::Object(map) = &v {
            fields.extend(map.keys().cloned());
        }
    }
    let doc = section();
    for field in &fields {
        assert!(
            doc.contains(&format!("\"{field}\"")),
            "`{field}` is not in docs/panel.md's WebSocket section"
        );
    }
}

#[test]
fn every_field_of_the_guided_calibration_in_the_state_is_documented() {
    use quad_host::ops::calibrate::guide::{settle, Action, Device, Guide, Key, Refusal};
    /// Acks everything.
    struct Acks;
    impl Device for Acks {
        type Error = std::convert::Infallible;
        fn act(&mut self, _: &Action) -> Result<Result<(), Refusal>, Self::Error> {
            Ok(Ok(()))
        }
    }
    let table = [quad_protocol::servo::Calibration::STANDARD; 12];
    let mut g = Guide::new(&Robot::shahriar2023(), table).expect("a posture");
    settle(&mut g, &mut Acks).expect("acked");
    g.key(Key::Next);
    settle(&mut g, &mut Acks).expect("acked");
    let v = serde_json::to_value(g.view()).expect("serializes");
    let mut fields = BTreeSet::new();
    keys(&v, &mut fields);
    assert!(fields.contains("servo_index") && fields.contains("does"));
    let doc = section();
    for field in &fields {
        assert!(
            doc.contains(&format!("\"{field}\"")),
            "`{field}` of the guide is not in docs/panel.md's WebSocket section"
        );
    }
}
