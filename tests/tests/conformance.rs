//! The conformance kit (docs/conformance.md) and the example frames of docs/protocol.md, both
//! recorded from the firmware in simavr:
//!
//! - the kit re-recorded at both line rates must equal the committed files
//!   (`docs/conformance/firmware-*.jsonl`); `QUAD_RECORD=1` writes them instead, and the
//!   examples of docs/protocol.md with them;
//! - every recorded request encodes to its recorded bytes and every recorded answer decodes to
//!   its recorded fields (this crate's client passes its own kit);
//! - docs/protocol.md's "Example frames" are the 115,200-baud recording.

use integration_tests::conformance::{
    self, compare, file_name, from_jsonl, render_examples, to_jsonl, unhex, Exchange,
    RECORD_COMMAND,
};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::{
    encode_frame, timing::BAUDS, Accumulator, DeviceToHost, Feed, HostToDevice, MAX_DECODED_LEN,
    MAX_FRAME_LEN,
};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the workspace")
        .to_path_buf()
}

fn recording() -> bool {
    std::env::var_os("QUAD_RECORD").is_some_and(|v| v == "1")
}

const BEGIN: &str = "<!-- conformance-examples:begin -->\n";
const END: &str = "<!-- conformance-examples:end -->";

/// docs/protocol.md and the byte range of its generated examples.
fn doc_examples() -> (String, std::ops::Range<usize>) {
    let doc = std::fs::read_to_string(root().join("docs/protocol.md")).expect("protocol.md");
    let start = doc.find(BEGIN).expect("the examples' begin marker") + BEGIN.len();
    let stop = doc[start..].find(END).expect("the examples' end marker") + start;
    (doc, start..stop)
}

fn committed(baud: u32) -> Vec<Exchange> {
    let path = root().join(file_name(baud));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; run `{RECORD_COMMAND}`", path.display()));
    from_jsonl(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn rerecord(bin: &str, baud: u32) {
    let elf = build::firmware_elf(bin).unwrap_or_else(|e| panic!("{e}"));
    let mut link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
    let exchanges = conformance::record(&mut link, baud);
    let text = to_jsonl(&exchanges);
    let path = root().join(file_name(baud));
    if recording() {
        std::fs::create_dir_all(path.parent().expect("a folder")).expect("mkdir");
        std::fs::write(&path, &text).expect("write the kit");
        if baud == BAUDS[0] {
            let (mut doc, range) = doc_examples();
            doc.replace_range(range, &render_examples(&exchanges));
            std::fs::write(root().join("docs/protocol.md"), doc).expect("write protocol.md");
        }
        println!("wrote {} ({} exchanges)", path.display(), exchanges.len());
        return;
    }
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    if old != text {
        let first = old
            .lines()
            .zip(text.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || "the line count".to_owned(),
                |i| format!("line {}", i + 1),
            );
        panic!(
            "{} differs from the firmware's answers (first at {first}); re-record with `{RECORD_COMMAND}`",
            path.display()
        );
    }
}

#[test]
fn the_kit_at_115200_baud_is_what_the_firmware_answers() {
    rerecord(build::FIRMWARE, BAUDS[0]);
}

#[test]
fn the_kit_at_1000000_baud_is_what_the_firmware_answers() {
    rerecord(build::FIRMWARE_1MBAUD, BAUDS[1]);
}

/// Decodes one frame (both delimiters included) of type `T`.
fn decode<T: serde::de::DeserializeOwned + std::fmt::Debug>(bytes: &[u8]) -> T {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    match acc.feed::<T>(bytes) {
        Feed::Frame { msg, remaining } => {
            assert!(remaining.is_empty(), "one frame: {remaining:?}");
            msg
        }
        other => panic!("not a frame: {other:?}"),
    }
}

#[test]
fn every_recorded_request_encodes_and_every_answer_decodes_as_recorded() {
    if recording() {
        return;
    }
    let mut checked = 0;
    for baud in BAUDS {
        for e in committed(baud) {
            let request_bytes = unhex(&e.request_hex);
            match e.request {
                Some(request) => {
                    let mut buf = [0u8; MAX_FRAME_LEN];
                    let encoded = encode_frame(&request, &mut buf).expect("encodes");
                    assert_eq!(
                        encoded,
                        &request_bytes[..],
                        "{}: the request's frame",
                        e.name
                    );
                    assert_eq!(
                        decode::<HostToDevice>(&request_bytes),
                        request,
                        "{}: the request's fields",
                        e.name
                    );
                }
                None => {
                    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
                    assert!(
                        !matches!(acc.feed::<HostToDevice>(&request_bytes), Feed::Frame { .. }),
                        "{}: a frame without fields must not decode",
                        e.name
                    );
                }
            }
            let answer: DeviceToHost = decode(&unhex(&e.answer_hex));
            assert_eq!(answer, e.answer, "{}: the answer's fields", e.name);
            let problems = compare(
                &serde_json::to_value(e.answer).expect("JSON"),
                &serde_json::to_value(answer).expect("JSON"),
                &e.tolerance,
                &e.ignore,
            );
            assert!(problems.is_empty(), "{}: {problems:?}", e.name);
            let mut buf = [0u8; MAX_FRAME_LEN];
            let reencoded = encode_frame(&answer, &mut buf).expect("encodes");
            assert_eq!(
                hex(reencoded),
                e.answer_hex,
                "{}: the answer re-encoded",
                e.name
            );
            checked += 1;
        }
    }
    println!("{checked} exchanges replayed");
}

fn hex(bytes: &[u8]) -> String {
    conformance::hex(bytes)
}

#[test]
fn the_comparison_applies_the_tolerances() {
    let tol = [("angles_rad".to_owned(), 0.01)].into_iter().collect();
    let ignore = ["frames_ok".to_owned()];
    let e = serde_json::json!({"ack": {"seq": 3, "readback": {"angles_rad": [0.5, 1.0], "frames_ok": 7}}});
    let near = serde_json::json!({"ack": {"seq": 3, "readback": {"angles_rad": [0.505, 1.0], "frames_ok": 9}}});
    let far = serde_json::json!({"ack": {"seq": 4, "readback": {"angles_rad": [0.52, 1.0], "frames_ok": 7}}});
    assert!(compare(&e, &near, &tol, &ignore).is_empty());
    assert_eq!(compare(&e, &far, &tol, &ignore).len(), 2);
}

#[test]
fn protocol_doc_examples_are_the_recorded_exchanges() {
    if recording() {
        return;
    }
    let exchanges = committed(BAUDS[0]);
    let (doc, range) = doc_examples();
    assert!(
        doc[range] == render_examples(&exchanges),
        "docs/protocol.md's example frames differ from {}; re-record with `{RECORD_COMMAND}`",
        file_name(BAUDS[0])
    );
    let hello = exchanges
        .iter()
        .find(|e| e.name == "hello")
        .expect("the example hello");
    assert!(
        matches!(hello.answer, DeviceToHost::HelloAck { .. }),
        "the example hello connects: {:?}",
        hello.answer
    );
}
