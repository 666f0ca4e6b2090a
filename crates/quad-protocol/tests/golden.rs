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
            // 2.4's requests: their golden bytes are in the appendix of 2.4 (below).
            Request::SetRobot(_) | Request::GetRobot | Request::SaveRobot => {}
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
fn version_is_two_four() {
    // 2.1 appended the onboard motion requests, answer and nack reasons to 2.0; 2.2 appended
    // the idle motion stage and the watchdog-reset flag; 2.3 the inertial sensor's requests,
    // answer, nack reasons, parameters and the fall flag, the motion ack's frame numbers and the
    // statically stable yaw turn; 2.4 the robot's requests, answer and nack reasons and the
    // robot's hash at the end of the hello.
    assert_eq!(PROTOCOL_VERSION, 0x0204);
    assert_eq!(quad_protocol::version_major(PROTOCOL_VERSION), 2);
    assert_eq!(quad_protocol::version_minor(PROTOCOL_VERSION), 4);
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

#[test]
fn the_appendix_of_two_four_has_its_golden_bytes() {
    use kin_core::{KneeBend, Robot, RotationOrder};
    use quad_protocol::{DeviceInfo, RobotDescription, RobotField};
    // A robot with exactly representable values.
    let robot = RobotDescription {
        name: RobotDescription::name_bytes("dog").unwrap(),
        robot: Robot {
            leg: kin_core::LegGeometry {
                d_lat_m: 0.0625,
                d_ax_m: 0.0,
                femur_m: 0.25,
                tibia_m: 0.25,
            },
            body_length_m: 0.5,
            body_width_m: 0.25,
            limits: kin_core::JointLimits {
                min_rad: [-1.0, -2.0, -2.5],
                max_rad: [1.0, 2.0, -0.125],
            },
            knee_bend: KneeBend::Backward,
        },
        stance_height_m: 0.375,
        order: RotationOrder::Zyx,
        joint_speed_limit_rad_s: 4.0,
    };
    // name "dog" + 13 zeros | d_lat 0.0625, d_ax 0, femur 0.25, tibia 0.25, length 0.5,
    // width 0.25 | min -1, -2, -2.5 | max 1, 2, -0.125 | Backward = 0 | stance 0.375 |
    // Zyx = 5 | 4 rad/s
    let description = "64 6f 67 00 00 00 00 00 00 00 00 00 00 00 00 00 \
                       00 00 80 3d 00 00 00 00 00 00 80 3e 00 00 80 3e 00 00 00 3f 00 00 80 3e \
                       00 00 80 bf 00 00 00 c0 00 00 20 c0 00 00 80 3f 00 00 00 40 00 00 00 be \
                       00 00 00 c0 3e 05 00 00 80 40";
    // seq 7 | SetRobot = 0x12 | the description
    check(
        "SetRobot",
        &h2d(7, Request::SetRobot(robot)),
        &format!("07 12 {description}"),
    );
    check("GetRobot", &h2d(7, Request::GetRobot), "07 13");
    check("SaveRobot", &h2d(7, Request::SaveRobot), "07 14");
    // Robot = 7 | seq 7 | the description
    check(
        "Robot",
        &DeviceToHost::Robot { seq: 7, robot },
        &format!("07 07 {description}"),
    );
    assert_eq!(hex(description).len(), RobotDescription::WIRE_LEN);
    // Nack | seq 7 (Some = 01 07) | BadRobot = 0x16 | Limit = 7 | Knee = 2; OutputsEnabled = 0x17
    check(
        "Nack BadRobot",
        &DeviceToHost::Nack {
            seq: Some(7),
            reason: NackReason::BadRobot(RobotField::Limit(kin_core::Joint::Knee)),
        },
        "00 01 07 16 07 02",
    );
    check(
        "Nack OutputsEnabled",
        &DeviceToHost::Nack {
            seq: Some(7),
            reason: NackReason::OutputsEnabled,
        },
        "00 01 07 17",
    );
    // The hash is the CRC-32 of the description's bytes.
    assert_eq!(robot.hash(), quad_protocol::robot::crc32(&hex(description)));
    // The hello: to a 2.4 host the 2.3 bytes, then the hash as a varint.
    let (_, hello, _) = common::cases::answers()
        .into_iter()
        .find(|(name, _, _)| *name == "HelloAck")
        .unwrap();
    let DeviceToHost::HelloAck { info, .. } = hello else {
        unreachable!()
    };
    let with_hash = DeviceInfo {
        robot_hash: Some(0x1234_5678),
        ..info
    };
    let old = postcard_bytes(&DeviceToHost::HelloAck { seq: 1, info });
    let new = postcard_bytes(&DeviceToHost::HelloAck {
        seq: 1,
        info: with_hash,
    });
    assert_eq!(new[..old.len()], old[..]);
    assert_eq!(new[old.len()..], [0xF8, 0xAC, 0xD1, 0x91, 0x01]);
    // A device answers a 2.3 host without it, a 2.4 host with it.
    let device = DeviceInfo {
        version: PROTOCOL_VERSION,
        ..with_hash
    };
    let DeviceToHost::HelloAck { info: to_23, .. } = device.answer_hello(1, 0x0203) else {
        unreachable!()
    };
    assert_eq!(to_23.robot_hash, None);
    let DeviceToHost::HelloAck { info: to_24, .. } = device.answer_hello(1, 0x0204) else {
        unreachable!()
    };
    assert_eq!(to_24.robot_hash, Some(0x1234_5678));
}
