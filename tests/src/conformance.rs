//! The conformance kit (docs/conformance.md): exchanges with the firmware in simavr recorded
//! as JSON lines, one object per request and its answer, for clients in other languages to
//! replay against their encoder and decoder.
//!
//! [`record`] runs a fixed workload on a freshly booted firmware (simulated time, no random
//! input, so every run writes the same lines) and returns the exchanges; [`to_jsonl`] and
//! [`from_jsonl`] write and read the file; [`compare`] checks decoded fields against recorded
//! ones within the recorded tolerances; [`render_examples`] prints the exchanges as the
//! "Example frames" section of docs/protocol.md.

use crate::wire::frame;
use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{LegId, Pose, ReachPolicy, RotationOrder};
use quad_host::link::emulator::EmulatorLink;
use quad_host::link::Link;
use quad_protocol::{
    timing, Accumulator, BalanceConfig, DeviceToHost, Feed, HostToDevice, LegSet, LinkLossAction,
    LinkTimeout, MotionCommand, PoseConfig, Request, SafeState, ServoId, MAX_DECODED_LEN,
    PROTOCOL_VERSION,
};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::Duration;

/// The command that re-records the kit (and the examples of docs/protocol.md).
pub const RECORD_COMMAND: &str =
    "QUAD_RECORD=1 cargo test --release -p integration-tests --test conformance";

/// The kit's file for the firmware at `baud`, relative to the workspace root.
pub fn file_name(baud: u32) -> String {
    format!("docs/conformance/firmware-{baud}.jsonl")
}

/// The stance height of the default robot, m.
const STANCE_HEIGHT_M: f32 = 0.277;

/// The longest any answer may take before the recorder calls it lost.
pub const PATIENCE: Duration = Duration::from_secs(5);

/// Absolute tolerance of the joint angles a device computes (its IK in f32, its own sine and
/// cosine), rad.
pub const ANGLE_TOLERANCE_RAD: f64 = 1e-4;
/// Absolute tolerance of a pulse width, half-µs: an angle within [`ANGLE_TOLERANCE_RAD`] may
/// round to the neighbouring half-µs.
pub const PULSE_TOLERANCE_HALF_US: f64 = 1.0;
/// Absolute tolerance of a motion's time and phase: one 20 ms servo frame, s (and the phase
/// that frame makes of a 2 s period).
pub const MOTION_TIME_TOLERANCE_S: f64 = 0.02;
/// The phase's tolerance: one 20 ms frame of the shortest cycle recorded (1 s).
pub const PHASE_TOLERANCE: f64 = 0.02;
/// Absolute tolerance of a motion's frame numbers (`MotionFrames`, since 2.3): one frame, as
/// its time.
pub const FRAME_NUMBER_TOLERANCE: f64 = 1.0;

/// One recorded exchange: a line of the kit (docs/conformance.md explains every field).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exchange {
    /// What the exchange shows, unique in its file.
    pub name: String,
    /// The line rate, baud (8N1).
    pub baud: u32,
    /// Silence on the line before the request, ms (a motion running meanwhile).
    pub idle_before_ms: u32,
    /// The request's frame as sent, both delimiters included: hex bytes.
    pub request_hex: String,
    /// The request as fields; `None` for a frame that carries no valid request.
    pub request: Option<HostToDevice>,
    /// The answer's frame as received: hex bytes.
    pub answer_hex: String,
    /// The answer as fields.
    pub answer: DeviceToHost,
    /// Absolute tolerance per field name, wherever the field occurs in `answer`.
    pub tolerance: BTreeMap<String, f64>,
    /// Fields of `answer` whose value may be anything (counters of the line's history).
    pub ignore: Vec<String>,
    /// The documented worst answer time of the request's kind at `baud`
    /// (`quad_protocol::timing`), from the request's first byte to the answer's last, µs.
    pub worst_answer_us: u32,
    /// The documented timeout of the request's kind at `baud` (the worst answer time and the
    /// host's latency): no answer within it is a lost answer, ms.
    pub timeout_ms: u32,
}

/// Lower-case hex bytes separated by spaces.
pub fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The bytes of [`hex`]'s form.
///
/// # Panics
/// When `text` is not that form.
pub fn unhex(text: &str) -> Vec<u8> {
    text.split(' ')
        .map(|b| u8::from_str_radix(b, 16).unwrap_or_else(|e| panic!("{b:?}: {e}")))
        .collect()
}

/// A step of the workload.
enum Step {
    /// A request with the next sequence number.
    Send(&'static str, Request),
    /// The previous frame again, byte for byte (a retry whose answer was lost).
    Repeat(&'static str),
    /// A request with the next sequence number, one bit of its CRC flipped on the line.
    BadCrc(&'static str, Request),
    /// Silence on the line, ms.
    Pause(u32),
}

fn sway(axis: Axis, period_s: f32) -> Request {
    Request::StartMotion(MotionCommand::Sway {
        axis,
        amplitude_rad: 0.15,
        period_s,
        duration_s: None,
    })
}

/// Every request kind, every motion kind and the nacks a client meets, in an order in which
/// each acts as named.
fn workload() -> Vec<Step> {
    use Step::{BadCrc, Pause, Repeat, Send};
    let servo = ServoId::ALL[11];
    let stance_feet: [[f32; 3]; 4] = core::array::from_fn(|i| {
        let x = if i < 2 { 0.3 } else { -0.3 };
        let y = if i % 2 == 0 { 0.184 } else { -0.184 };
        [x, y, -STANCE_HEIGHT_M]
    });
    vec![
        // The firmware's start after power-on.
        Pause(50),
        Send("get_state before hello", Request::GetState),
        Send(
            "set_outputs before hello: hello_required",
            Request::SetOutputs { enabled: true },
        ),
        Send(
            "hello of version 1.0: unknown_version",
            Request::Hello { version: 0x0100 },
        ),
        Send(
            "hello",
            Request::Hello {
                version: PROTOCOL_VERSION,
            },
        ),
        Send("get_state", Request::GetState),
        BadCrc("get_state with a bad crc: bad_crc", Request::GetState),
        Send(
            "set_link_timeout",
            Request::SetLinkTimeout(LinkTimeout {
                timeout_ms: 0,
                action: LinkLossAction::Hold,
            }),
        ),
        Send(
            "set_pose_config",
            Request::SetPoseConfig(PoseConfig {
                stance_height_m: STANCE_HEIGHT_M,
                order: RotationOrder::Zyx,
                policy: ReachPolicy::Reject,
            }),
        ),
        Send("set_outputs on", Request::SetOutputs { enabled: true }),
        Send(
            "set_body_pose",
            Request::SetBodyPose(Pose {
                roll_rad: 0.1,
                pitch_rad: -0.05,
                yaw_rad: 0.08,
                x_m: 0.02,
                y_m: -0.01,
                z_m: 0.03,
            }),
        ),
        Repeat("set_body_pose repeated exactly: the same answer"),
        Send(
            "set_body_pose out of reach: unreachable",
            Request::SetBodyPose(Pose {
                z_m: 0.3,
                ..Pose::default()
            }),
        ),
        Send(
            "set_body_pose roll of 4 rad: out_of_range",
            Request::SetBodyPose(Pose {
                roll_rad: 4.0,
                ..Pose::default()
            }),
        ),
        Send(
            "set_feet",
            Request::SetFeet {
                feet_in_body_m: stance_feet,
            },
        ),
        Send(
            "set_joints",
            Request::SetJoints {
                angles_rad: [
                    0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
                ],
            },
        ),
        Send(
            "set_joint_speed_limit",
            Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s: 6.0,
            },
        ),
        // The balance requests (2.3) on a board without an inertial sensor.
        Send("get_imu without a sensor", Request::GetImu),
        Send(
            "set_balance leveling on without a sensor: imu_absent",
            Request::SetBalance(BalanceConfig {
                leveling: true,
                ..BalanceConfig::DEFAULT
            }),
        ),
        Send(
            "set_balance with a kp of 2: invalid_parameter",
            Request::SetBalance(BalanceConfig {
                level_kp: 2.0,
                ..BalanceConfig::DEFAULT
            }),
        ),
        Send(
            "set_balance safe state off",
            Request::SetBalance(BalanceConfig {
                safe_state: SafeState::Off,
                ..BalanceConfig::DEFAULT
            }),
        ),
        Send(
            "set_balance the defaults",
            Request::SetBalance(BalanceConfig::DEFAULT),
        ),
        Send("get_calibration", Request::GetCalibration { servo }),
        // The calibration sent is the one read (see `record`).
        Send("set_calibration", Request::GetCalibration { servo }),
        Send("save_calibration", Request::SaveCalibration),
        Send(
            "set_velocity while no walk runs: not_walking",
            Request::SetVelocity {
                forward_m_s: 0.02,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.0,
            },
        ),
        Send(
            "start_motion stand_up",
            Request::StartMotion(MotionCommand::StandUp),
        ),
        Pause(3000),
        Send("get_motion after stand_up", Request::GetMotion),
        Send(
            "start_motion sway with a period of -1 s: invalid_parameter",
            sway(Axis::Roll, -1.0),
        ),
        Send("start_motion sway", sway(Axis::Roll, 2.0)),
        Repeat("start_motion sway repeated exactly: the same answer"),
        Pause(500),
        Send(
            "start_motion while a motion runs: motion_running",
            sway(Axis::Pitch, 2.0),
        ),
        Send("get_motion during sway", Request::GetMotion),
        Send("stop_motion sway", Request::StopMotion),
        Pause(4000),
        Send(
            "start_motion yaw_turn",
            Request::StartMotion(MotionCommand::YawTurn {
                yaw_rate_rad_s: 0.2,
                step_period_s: 1.0,
                lift_height_m: 0.03,
                duration_s: None,
            }),
        ),
        Pause(500),
        Send("stop_motion yaw_turn", Request::StopMotion),
        Pause(4000),
        Send(
            "start_motion stable_turn",
            Request::StartMotion(MotionCommand::StableTurn {
                yaw_per_cycle_rad: 0.2,
                cycle_s: 2.0,
                lift_height_m: 0.03,
                shift_fraction: 0.8,
                duration_s: None,
            }),
        ),
        Pause(500),
        Send("stop_motion stable_turn", Request::StopMotion),
        Pause(4000),
        Send(
            "start_motion foot_path",
            Request::StartMotion(MotionCommand::FootPath {
                path: PathKind::Bezier,
                legs: LegSet::One(LegId::FL),
                stride_m: 0.06,
                step_height_m: 0.03,
                duty_factor: 0.5,
                cycle_s: 1.0,
                duration_s: None,
            }),
        ),
        Pause(500),
        Send("stop_motion foot_path", Request::StopMotion),
        Pause(3000),
        Send(
            "start_motion walk",
            Request::StartMotion(MotionCommand::Walk {
                gait: Pattern::Trot,
                body_height_m: STANCE_HEIGHT_M,
                step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * STANCE_HEIGHT_M,
                cycle_s: GaitParams::DEFAULT_CYCLE_S,
                velocity_timeout_ms: 1000,
            }),
        ),
        Pause(300),
        Send(
            "set_velocity",
            Request::SetVelocity {
                forward_m_s: 0.02,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.05,
            },
        ),
        Pause(300),
        Send("stop_motion walk", Request::StopMotion),
        Pause(4000),
        Send("get_motion after walk", Request::GetMotion),
        Send("start_motion sit", Request::StartMotion(MotionCommand::Sit)),
        Pause(3000),
        Send(
            "start_motion rest",
            Request::StartMotion(MotionCommand::Rest),
        ),
        Pause(3000),
        Send(
            "start_motion sway with the outputs off: outputs_disabled",
            sway(Axis::Roll, 2.0),
        ),
        Send("set_outputs off", Request::SetOutputs { enabled: false }),
    ]
}

/// Runs the workload on `link` (a freshly booted firmware at `baud`) and returns every
/// exchange.
///
/// # Panics
/// When an answer does not come within [`PATIENCE`] or after its documented timeout, or
/// when the line carries a byte nobody asked for.
pub fn record(link: &mut EmulatorLink, baud: u32) -> Vec<Exchange> {
    let column = timing::BAUDS
        .iter()
        .position(|&b| b == baud)
        .unwrap_or_else(|| panic!("no answer times at {baud} baud"));
    let mut out = Vec::new();
    let mut seq = 1u16;
    let mut idle_ms = 0u32;
    let mut last: Option<(Vec<u8>, Option<HostToDevice>, Request)> = None;
    let mut calibration = None;
    for step in workload() {
        let (name, bytes, request, kind_of) = match step {
            Step::Pause(ms) => {
                pause(link, Duration::from_millis(u64::from(ms)));
                idle_ms += ms;
                continue;
            }
            Step::Repeat(name) => {
                let (bytes, request, kind_of) = last.clone().expect("a frame to repeat");
                (name, bytes, request, kind_of)
            }
            Step::Send(name, request) | Step::BadCrc(name, request) => {
                let bad = matches!(step, Step::BadCrc(..));
                // The second calibration read turns into a write of what the first read.
                let request = match (request, calibration.take()) {
                    (Request::GetCalibration { servo }, Some(calibration))
                        if name == "set_calibration" =>
                    {
                        Request::SetCalibration { servo, calibration }
                    }
                    (request, c) => {
                        calibration = c;
                        request
                    }
                };
                let msg = HostToDevice { seq, request };
                seq = seq.wrapping_add(1);
                let mut bytes = frame(msg.seq, msg.request);
                if bad {
                    let n = bytes.len();
                    bytes[n - 2] ^= 0x10;
                    assert_ne!(bytes[n - 2], 0, "the flipped bit makes a delimiter");
                }
                (name, bytes, (!bad).then_some(msg), request)
            }
        };
        let (answer_bytes, answer, elapsed) = exchange(link, &bytes);
        let kind = timing::Kind::of(&kind_of);
        let bound_us = kind.worst_us()[column];
        let timeout = kind.timeout(baud);
        assert!(
            elapsed <= timeout,
            "{name}: answered in {elapsed:?}, after the documented timeout {timeout:?}"
        );
        if elapsed > Duration::from_micros(u64::from(bound_us)) {
            println!(
                "{name} @ {baud}: answered in {elapsed:?}, the table's worst is {bound_us} µs"
            );
        }
        if let DeviceToHost::Calibration { calibration: c, .. } = answer {
            calibration = Some(c);
        }
        check_named(name, &answer, out.last());
        let (tolerance, ignore) = tolerances(&answer);
        out.push(Exchange {
            name: name.to_owned(),
            baud,
            idle_before_ms: idle_ms,
            request_hex: hex(&bytes),
            request,
            answer_hex: hex(&answer_bytes),
            answer,
            tolerance,
            ignore,
            worst_answer_us: bound_us,
            timeout_ms: u32::try_from(timeout.as_millis()).expect("a short timeout"),
        });
        idle_ms = 0;
        last = Some((bytes, request, kind_of));
    }
    let mut names: Vec<_> = out.iter().map(|e| &e.name).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), out.len(), "names are unique");
    out
}

/// Checks that `answer` is what the exchange's name says: after `: ` a nack's reason, or the
/// same answer as the `previous` exchange's for an exact repeat; any other answer but a nack
/// without.
///
/// # Panics
/// When it is not.
fn check_named(name: &str, answer: &DeviceToHost, previous: Option<&Exchange>) {
    let json = serde_json::to_value(answer).expect("JSON");
    let reason = json.get("nack").map(|n| match &n["reason"] {
        Value::Object(m) => m.keys().next().cloned().unwrap_or_default(),
        other => other.as_str().unwrap_or_default().to_owned(),
    });
    match name.split_once(": ") {
        Some((_, "the same answer")) => {
            let previous = previous.expect("a previous exchange");
            assert_eq!(*answer, previous.answer, "{name}");
        }
        Some((_, expected)) => assert_eq!(reason.as_deref(), Some(expected), "{name}"),
        None => assert_eq!(reason, None, "{name}: {answer:?}"),
    }
}

/// The tolerances of `answer`'s fields: the joint angles and pulses of a readback, a motion's
/// time, phase and frame numbers; the frame counters and the inertial sensor's sample count are
/// ignored.
fn tolerances(answer: &DeviceToHost) -> (BTreeMap<String, f64>, Vec<String>) {
    let mut tolerance = BTreeMap::new();
    let mut ignore = Vec::new();
    let readback = matches!(
        answer,
        DeviceToHost::Ack { .. } | DeviceToHost::Configured { .. } | DeviceToHost::MotionAck { .. }
    );
    if readback {
        tolerance.insert("angles_rad".to_owned(), ANGLE_TOLERANCE_RAD);
        tolerance.insert("pulses_half_us".to_owned(), PULSE_TOLERANCE_HALF_US);
        ignore.push("frames_ok".to_owned());
        ignore.push("frames_bad".to_owned());
    }
    if matches!(answer, DeviceToHost::MotionAck { .. }) {
        tolerance.insert("t_s".to_owned(), MOTION_TIME_TOLERANCE_S);
        tolerance.insert("phase".to_owned(), PHASE_TOLERANCE);
        // Since 2.3: the frame numbers, one servo frame as the time.
        tolerance.insert("frame".to_owned(), FRAME_NUMBER_TOLERANCE);
        tolerance.insert("stop_frame".to_owned(), FRAME_NUMBER_TOLERANCE);
    }
    if matches!(answer, DeviceToHost::Imu { .. }) {
        // The sensor's sample count depends on when the request came.
        ignore.push("samples".to_owned());
    }
    (tolerance, ignore)
}

/// Lets `gap` of line time pass with nothing sent.
fn pause(link: &mut EmulatorLink, gap: Duration) {
    let mut none = [0u8; 1];
    let n = link.recv(&mut none, gap).expect("recv");
    assert_eq!(n, 0, "a byte nobody asked for");
}

/// Sends `bytes` on an idle line and returns the answer's frame as it came, the answer, and
/// the time from the request's first byte to the answer's last.
fn exchange(link: &mut EmulatorLink, bytes: &[u8]) -> (Vec<u8>, DeviceToHost, Duration) {
    let start = link.now();
    link.send(bytes).expect("send");
    let end = start + PATIENCE;
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut raw = Vec::new();
    let mut buf = [0u8; 256];
    while link.now() < end {
        let n = link.recv(&mut buf, end - link.now()).expect("recv");
        match acc.feed::<DeviceToHost>(&buf[..n]) {
            Feed::NeedMore => raw.extend_from_slice(&buf[..n]),
            Feed::Frame { msg, remaining } => {
                assert!(
                    remaining.is_empty(),
                    "bytes after the answer: {remaining:?}"
                );
                raw.extend_from_slice(&buf[..n]);
                return (raw, msg, link.now() - start);
            }
            other => panic!("the device sent an unreadable frame: {other:?}"),
        }
    }
    panic!("no answer to {} within {PATIENCE:?}", hex(bytes));
}

/// The kit's file: one JSON object per line.
///
/// # Panics
/// When an exchange has no JSON form (never for the protocol's messages).
pub fn to_jsonl(exchanges: &[Exchange]) -> String {
    exchanges
        .iter()
        .map(|e| serde_json::to_string(e).expect("JSON") + "\n")
        .collect()
}

/// Reads a file written by [`to_jsonl`].
///
/// # Errors
/// The line number and the JSON error of the first line that is not an [`Exchange`].
pub fn from_jsonl(text: &str) -> Result<Vec<Exchange>, String> {
    text.lines()
        .enumerate()
        .map(|(i, line)| serde_json::from_str(line).map_err(|e| format!("line {}: {e}", i + 1)))
        .collect()
}

/// The differences between `expected` (an exchange's `answer` as JSON) and `actual` (a
/// decoded answer as JSON): numbers of a field named in `tolerance` may differ by its value,
/// fields named in `ignore` may hold anything, everything else is equal. Empty when they
/// agree.
pub fn compare(
    expected: &Value,
    actual: &Value,
    tolerance: &BTreeMap<String, f64>,
    ignore: &[String],
) -> Vec<String> {
    let mut problems = Vec::new();
    walk(expected, actual, None, "", tolerance, ignore, &mut problems);
    problems
}

fn walk(
    expected: &Value,
    actual: &Value,
    field: Option<&str>,
    path: &str,
    tolerance: &BTreeMap<String, f64>,
    ignore: &[String],
    problems: &mut Vec<String>,
) {
    if field.is_some_and(|f| ignore.iter().any(|i| i == f)) {
        return;
    }
    match (expected, actual) {
        (Value::Object(e), Value::Object(a)) => {
            for key in e.keys().chain(a.keys().filter(|k| !e.contains_key(*k))) {
                match (e.get(key), a.get(key)) {
                    (Some(ev), Some(av)) => walk(
                        ev,
                        av,
                        Some(key),
                        &format!("{path}/{key}"),
                        tolerance,
                        ignore,
                        problems,
                    ),
                    _ => problems.push(format!("{path}/{key}: present on one side only")),
                }
            }
        }
        (Value::Array(e), Value::Array(a)) if e.len() == a.len() => {
            for (i, (ev, av)) in e.iter().zip(a).enumerate() {
                walk(
                    ev,
                    av,
                    field,
                    &format!("{path}/{i}"),
                    tolerance,
                    ignore,
                    problems,
                );
            }
        }
        (Value::Number(e), Value::Number(a)) => {
            let tol = field.and_then(|f| tolerance.get(f)).copied().unwrap_or(0.0);
            let (e, a) = (e.as_f64().expect("a number"), a.as_f64().expect("a number"));
            if (e - a).abs() > tol {
                problems.push(format!("{path}: {a} is not {e} ± {tol}"));
            }
        }
        (e, a) if e == a => {}
        (e, a) => problems.push(format!("{path}: {a} is not {e}")),
    }
}

/// Hex bytes, 16 per line, continuation lines indented under the first.
fn wrapped(label: &str, text_hex: &str) -> String {
    let bytes: Vec<&str> = text_hex.split(' ').collect();
    let pad = " ".repeat(label.len() + 1);
    bytes
        .chunks(16)
        .enumerate()
        .map(|(i, c)| {
            let head = if i == 0 {
                format!("{label} ")
            } else {
                pad.clone()
            };
            format!("{head}{}", c.join(" "))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The variant name of a message's JSON form (`{"ack": {...}}` → `ack`, `"stand_up"` →
/// `stand_up`).
fn variant(value: &Value) -> String {
    match value {
        Value::Object(m) => m.keys().next().cloned().unwrap_or_default(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The "Example frames" section of docs/protocol.md (between its markers): every exchange of
/// `exchanges`, the request's fields and frame and the answer's frame as the firmware sent
/// it.
///
/// # Panics
/// When an exchange has no JSON form (never for the protocol's messages).
pub fn render_examples(exchanges: &[Exchange]) -> String {
    let mut out = String::new();
    for (i, e) in exchanges.iter().enumerate() {
        let answer = serde_json::to_value(e.answer).expect("JSON");
        let reason = match &answer {
            Value::Object(m) => m
                .get("nack")
                .and_then(|n| n.get("reason"))
                .map(|r| format!(" {}", variant(r))),
            _ => None,
        }
        .unwrap_or_default();
        out += &format!(
            "#### {}. {} → {}{reason}\n\n```text\n",
            i + 1,
            e.name,
            variant(&answer)
        );
        match &e.request {
            Some(r) => {
                out += &format!("fields  {}\n", serde_json::to_string(r).expect("JSON"));
            }
            None => out += "fields  (none: the frame is not a valid request)\n",
        }
        if e.idle_before_ms > 0 {
            out += &format!("after   {} ms of silence\n", e.idle_before_ms);
        }
        out += &wrapped("request", &e.request_hex);
        out += "\n";
        out += &wrapped("answer ", &e.answer_hex);
        out += "\n```\n\n";
    }
    out
}
