//! Golden bytes: the exact postcard encoding of one example of every message, written by hand
//! from the postcard wire format (varint u16/u32, f32 little-endian, enum variant index as a
//! varint, bool and option tags as one byte, arrays without length), and the exact frames.

mod common;

use common::cases::{answers, h2d, requests};
use common::{hex, ref_frame, to_hex};
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, NackReason, Request, MAX_DECODED_LEN,
    MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use serde::{de::DeserializeOwned, Serialize};

fn postcard_bytes<T: Serialize>(msg: &T) -> Vec<u8> {
    let mut buf = [0u8; MAX_DECODED_LEN];
    postcard::to_slice(msg, &mut buf).unwrap().to_vec()
}

fn decode_frame<T: DeserializeOwned>(frame: &[u8]) -> T {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    match acc.feed::<T>(frame) {
        Feed::Frame { msg, remaining } => {
            assert!(remaining.is_empty());
            msg
        }
        _ => panic!("frame {} not accepted", to_hex(frame)),
    }
}

fn check<T: Serialize + DeserializeOwned + PartialEq + core::fmt::Debug>(
    name: &str,
    msg: &T,
    golden: &str,
) {
    let expected = hex(golden);
    assert_eq!(
        to_hex(&postcard_bytes(msg)),
        to_hex(&expected),
        "postcard bytes of {name}"
    );
    let back: T = postcard::from_bytes(&expected).unwrap();
    assert_eq!(&back, msg, "decoding the golden bytes of {name}");

    let mut buf = [0u8; MAX_FRAME_LEN];
    let frame = encode_frame(msg, &mut buf).unwrap();
    assert_eq!(
        to_hex(frame),
        to_hex(&ref_frame(&expected)),
        "frame of {name}"
    );
    assert_eq!(&decode_frame::<T>(frame), msg, "frame round trip of {name}");
}

#[test]
fn every_request_has_its_golden_bytes() {
    let cases = requests();
    // One case per request variant (the match fails to compile when a variant is added).
    for (_, m, _) in &cases {
        match m.request {
            Request::Hello { .. }
            | Request::GetState
            | Request::SetBodyPose(_)
            | Request::SetFeet { .. }
            | Request::SetJoints { .. }
            | Request::SetOutputs { .. }
            | Request::SetLinkTimeout(_)
            | Request::SetCalibration { .. }
            | Request::GetCalibration { .. }
            | Request::SaveCalibration
            | Request::SetPoseConfig(_)
            | Request::StartMotion(_)
            | Request::StopMotion
            | Request::GetMotion
            | Request::SetVelocity { .. }
            | Request::SetJointSpeedLimit { .. }
            | Request::SetBalance(_)
            | Request::GetImu => {}
        }
    }
    assert_eq!(cases.len(), 22);
    for (name, msg, golden) in cases {
        check(name, &msg, golden);
    }
}

#[test]
fn every_answer_has_its_golden_bytes() {
    let cases = answers();
    let variants = [
        "Nack UnknownVersion",
        "HelloAck",
        "Ack",
        "Calibration",
        "Configured",
        "Nack OutOfRange",
        "MotionAck",
        "Imu",
    ];
    for v in variants {
        assert!(cases.iter().any(|(n, _, _)| *n == v), "{v} has no golden");
    }
    for (name, msg, golden) in cases {
        check(name, &msg, golden);
    }
}

#[test]
fn hand_written_frames() {
    // Hello: payload 01 00 80 02, CRC 0x3651 → 01 00 80 02 36 51 → COBS 02 01 | 05 80 02 36 51,
    // between two delimiters.
    let mut buf = [0u8; MAX_FRAME_LEN];
    let hello = h2d(1, Request::Hello { version: 0x0100 });
    assert_eq!(
        to_hex(encode_frame(&hello, &mut buf).unwrap()),
        "00 02 01 05 80 02 36 51 00"
    );
    // GetState seq 300: ac 02 01 + CRC 0x8DDD, no zero → one block of 5.
    let get = h2d(300, Request::GetState);
    assert_eq!(
        to_hex(encode_frame(&get, &mut buf).unwrap()),
        "00 06 ac 02 01 8d dd 00"
    );
    // Nack BadCrc: 00 00 01 + CRC 0x2342 → two empty blocks, then 01 23 42.
    let nack = DeviceToHost::Nack {
        seq: None,
        reason: NackReason::BadCrc,
    };
    assert_eq!(
        to_hex(encode_frame(&nack, &mut buf).unwrap()),
        "00 01 01 04 01 23 42 00"
    );
}

#[test]
fn version_is_two_three() {
    // 2.1 appended the onboard motion requests, answer and nack reasons to 2.0; 2.2 appended
    // the idle motion stage and the watchdog-reset flag; 2.3 the inertial sensor's requests,
    // answer, nack reasons, parameters and the fall flag, the motion ack's frame numbers and the
    // statically stable yaw turn.
    assert_eq!(PROTOCOL_VERSION, 0x0203);
    assert_eq!(quad_protocol::version_major(PROTOCOL_VERSION), 2);
    assert_eq!(quad_protocol::version_minor(PROTOCOL_VERSION), 3);
    assert!(quad_protocol::is_compatible(0x0207));
    assert!(!quad_protocol::is_compatible(0x0100));
    assert!(!quad_protocol::is_compatible(0x0300));
    assert!(!quad_protocol::is_compatible(0x0001));
}

#[test]
fn frozen_hello_layout() {
    // Whatever the version, the device can read Hello's version at the same bytes:
    // seq varint, variant 0, version varint.
    for version in [0x0000u16, 0x0100, 0x0203, 0xFFFF] {
        let bytes = postcard_bytes(&h2d(0x1234, Request::Hello { version }));
        let mut expected = hex("b4 24 00");
        let mut v = u32::from(version);
        loop {
            let b = (v & 0x7F) as u8;
            v >>= 7;
            if v == 0 {
                expected.push(b);
                break;
            }
            expected.push(b | 0x80);
        }
        assert_eq!(bytes, expected);
    }
}

#[test]
fn the_appendices_of_two_two_have_their_golden_bytes() {
    use quad_protocol::{Flags, MotionStage, MotionStatus, Readback};
    // An idle MotionAck to a 2.2 host: variant 5 | seq 9 | kind None = 0 | stage Idle = 4 |
    // t 0 | phase 0 | fault None = 0 | 12 angles 0 | pulses 0 | flags WATCHDOG_RESET 0x40 |
    // frames_ok 2 | frames_bad 0.
    let idle = DeviceToHost::MotionAck {
        seq: 9,
        status: MotionStatus {
            kind: None,
            stage: MotionStage::Idle,
            t_s: 0.0,
            phase: 0.0,
            fault: None,
        },
        readback: Readback {
            angles_rad: [0.0; 12],
            pulses_half_us: [0; 12],
            flags: Flags(Flags::WATCHDOG_RESET),
            frames_ok: 2,
            frames_bad: 0,
        },
        frames: None,
    };
    check(
        "MotionAck Idle WATCHDOG_RESET",
        &idle,
        "05 09 00 04 00 00 00 00 00 00 00 00 00 \
         00 00 00 00 00 00 00 00 00 00 00 00 \
         00 00 00 00 00 00 00 00 00 00 00 00 \
         00 00 00 00 00 00 00 00 00 00 00 00 \
         00 00 00 00 00 00 00 00 00 00 00 00 \
         00 00 00 00 00 00 00 00 00 00 00 00 \
         40 02 00",
    );
    assert_eq!(Flags::WATCHDOG_RESET, 0x40);
    // What a 2.0 or 2.1 host gets for the same idle status: stage Run = 1, the rest as sent
    // to a 2.2 host (t_s and phase 0). A running status is the same for every minor.
    let DeviceToHost::MotionAck { status, .. } = idle else {
        unreachable!()
    };
    for minor in [0, 1] {
        let old = status.for_minor(minor);
        assert_eq!(old.stage, MotionStage::Run);
        assert_eq!((old.kind, old.t_s, old.phase), (None, 0.0, 0.0));
        assert_eq!(postcard_bytes(&old)[..3], [0x00, 0x01, 0x00]);
    }
    assert_eq!(status.for_minor(2), status);
    let running = MotionStatus {
        kind: Some(quad_protocol::MotionKind::Walk),
        stage: MotionStage::Run,
        t_s: 3.5,
        phase: 0.25,
        fault: None,
    };
    assert_eq!(running.for_minor(1), running);
    // kind None = 0 | stage Idle = 4.
    assert_eq!(postcard_bytes(&status)[..2], [0x00, 0x04]);
}

#[test]
fn the_appendix_of_two_three_has_its_golden_bytes() {
    use quad_protocol::{Flags, MotionFrames, MotionKind, MotionStage, MotionStatus, Readback};
    let ack = |frames| DeviceToHost::MotionAck {
        seq: 9,
        status: MotionStatus {
            kind: Some(MotionKind::Walk),
            stage: MotionStage::Stopping,
            t_s: 0.0,
            phase: 0.0,
            fault: None,
        },
        readback: Readback {
            angles_rad: [0.0; 12],
            pulses_half_us: [0; 12],
            flags: Flags(0),
            frames_ok: 2,
            frames_bad: 0,
        },
        frames,
    };
    let old = postcard_bytes(&ack(None));
    // To a 2.3 host the same bytes, then frame 300 = AC 02 | stop_frame Some = 01, 200 = C8 01.
    let new = postcard_bytes(&ack(Some(MotionFrames {
        frame: 300,
        stop_frame: Some(200),
    })));
    assert_eq!(new[..old.len()], old[..]);
    assert_eq!(new[old.len()..], [0xAC, 0x02, 0x01, 0xC8, 0x01]);
    // Both read back; the older answer as `frames: None`.
    for bytes in [&old, &new] {
        let back: DeviceToHost = postcard::from_bytes(bytes).unwrap();
        let DeviceToHost::MotionAck { frames, .. } = back else {
            unreachable!()
        };
        assert_eq!(frames.is_some(), bytes.len() > old.len());
    }
    // The numbers wrap at 2^14: at most two bytes each.
    assert_eq!(MotionFrames::wrap(16_384 + 5), 5);
    assert_eq!(MotionFrames::wrap(16_383), 16_383);
}
