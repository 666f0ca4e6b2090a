//! Prints the frame sizes and wire-limited pose rates of `docs/protocol.md` and `BENCHMARKS.md`
//! (the example frames of `docs/protocol.md` are recorded from the firmware: docs/conformance.md):
//!
//! ```sh
//! cargo run -p quad-protocol --example wire_examples
//! ```

use kin_core::Pose;
use quad_protocol::{
    encode_frame, DeviceToHost, Flags, HostToDevice, Readback, Request, MAX_FRAME_LEN,
};
use serde::Serialize;

/// Bits per byte on an 8N1 UART line: start + 8 data + stop.
const BITS_PER_BYTE: f64 = 10.0;

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

/// The generated end of `docs/protocol.md`: the size table.
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
    out
}

#[allow(dead_code)] // unused when included by the docs test
fn main() {
    print!("{}", render());
}
