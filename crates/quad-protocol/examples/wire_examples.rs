//! Prints the example frames of `docs/protocol.md` and the frame sizes and wire-limited pose
//! rates of `BENCHMARKS.md`:
//!
//! ```sh
//! cargo run -p quad-protocol --example wire_examples
//! ```

#[path = "../tests/common/mod.rs"]
mod common;

use common::cases::{answers, requests};
use kin_core::Pose;
use quad_protocol::{
    encode_frame, DeviceToHost, Flags, HostToDevice, Readback, Request, MAX_DECODED_LEN,
    MAX_FRAME_LEN,
};
use serde::Serialize;

/// Bits per byte on an 8N1 UART line: start + 8 data + stop.
const BITS_PER_BYTE: f64 = 10.0;

/// Hex bytes, 16 per line, continuation lines indented under the first.
fn wrapped(label: &str, bytes: &[u8]) -> String {
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
            format!("{head}{}", common::to_hex(c))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn show<T: Serialize>(name: &str, msg: &T) -> String {
    let mut payload = [0u8; MAX_DECODED_LEN];
    let payload = postcard::to_slice(msg, &mut payload).unwrap();
    let mut wire = [0u8; MAX_FRAME_LEN];
    let frame = encode_frame(msg, &mut wire).unwrap();
    format!(
        "#### {name}\n\n```text\n{}\n{}\n```\n\n",
        wrapped("payload", payload),
        wrapped("frame  ", frame)
    )
}

fn wire_len<T: Serialize>(msg: &T) -> usize {
    let mut wire = [0u8; MAX_FRAME_LEN];
    encode_frame(msg, &mut wire).unwrap().len()
}

fn pose_request(seq: u16) -> HostToDevice {
    HostToDevice {
        seq,
        request: Request::SetBodyPose(Pose::from_array([0.1, -0.05, 0.2, 0.01, -0.02, 0.03])),
    }
}

fn ack(seq: u16, frames_ok: u32, frames_bad: u32) -> DeviceToHost {
    DeviceToHost::Ack {
        seq,
        readback: Readback {
            angles_rad: [0.3; 12],
            // Any real pulse (600..=5400 half-µs) takes two varint bytes.
            pulses_half_us: [3000; 12],
            flags: Flags(Flags::OUTPUTS_ENABLED),
            frames_ok,
            frames_bad,
        },
    }
}

/// The generated part of `docs/protocol.md`: the size table and the example frames.
pub fn render() -> String {
    let mut out = String::new();
    out += "| case | SetBodyPose, B | Ack, B | round trip, B | poses/s @ 115200 | poses/s @ 1000000 |\n";
    out += "|---|---|---|---|---|---|\n";
    let cases = [
        (
            "worst case (seq ≥ 16384, counters ≥ 2²⁸)",
            20000,
            u32::MAX,
            u32::MAX,
        ),
        (
            "typical (seq and frames_ok 128…16383, frames_bad < 128)",
            5000,
            5000,
            3,
        ),
        ("best case (seq < 128, counters < 128)", 5, 5, 0),
    ];
    for (label, seq, ok, bad) in cases {
        let req = wire_len(&pose_request(seq));
        let ans = wire_len(&ack(seq, ok, bad));
        let bits = (req + ans) as f64 * BITS_PER_BYTE;
        out += &format!(
            "| {label} | {req} | {ans} | {} | {:.1} | {:.1} |\n",
            req + ans,
            115_200.0 / bits,
            1_000_000.0 / bits
        );
    }
    out += "\n## Example frames\n\n";
    out += "One example of every request and answer (and of each nack layout with fields): its\n";
    out += "postcard payload and the complete frame on the wire. The golden tests\n";
    out +=
        "(`crates/quad-protocol/tests/golden.rs`) hold the same payloads written by hand, and a\n";
    out += "test checks that this section matches the output of the example.\n\n";
    for (name, msg, _) in requests() {
        out += &show(&format!("HostToDevice / {name}"), &msg);
    }
    for (name, msg, _) in answers() {
        out += &show(&format!("DeviceToHost / {name}"), &msg);
    }
    out
}

#[allow(dead_code)] // unused when included by the docs test
fn main() {
    print!("{}", render());
}
