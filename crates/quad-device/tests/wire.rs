//! The device's codec against the wire declarations: every request and answer variant, by an
//! exhaustive `match` (a variant added without a case here does not compile), has the index
//! this file expects in its postcard bytes, and the device's receive path and answer encoder
//! give exactly the frames of postcard's bytes with an independent CRC and COBS; the index
//! after the last is refused. The nested enums' indices are tested where they are declared
//! (quad-protocol's `wire` module). Then a differential property test: random byte streams
//! through `Device::receive` against the protocol's frame decoder driving a twin device at
//! message level.

mod common;

use common::*;
use kin_core::body::Pose;
use kin_core::motion::path::PathKind;
use kin_core::{Joint, LegId, ReachPolicy, RotationOrder};
use proptest::prelude::*;
use quad_device::device::RX_LEN;
use quad_device::device::{encode_answer, feed_request};
use quad_device::Config;
use quad_protocol::servo::{self, Calibration};
use quad_protocol::{
    crc, Accumulator, DeviceInfo, DeviceToHost, Feed, Field, FirmwareVersion, Flags, HostToDevice,
    LegSet, LinkLossAction, LinkTimeout, MotionCommand, MotionKind, MotionParam, MotionStage,
    MotionStatus, NackReason, ParamProblem, PoseConfig, PreflightFault, ReachFault, Readback,
    Request, RobotPreset, ServoId, Setting, MAX_DECODED_LEN, MAX_FRAME_LEN,
};
use quad_protocol::{BalanceConfig, FallKind, ImuFaultKind, ImuHealth, ImuReport, SafeState};

// ---- The expected index of every variant (written here, independently of the declarations).

fn request_index(r: &Request) -> u8 {
    match r {
        Request::Hello { .. } => 0,
        Request::GetState => 1,
        Request::SetBodyPose(_) => 2,
        Request::SetFeet { .. } => 3,
        Request::SetJoints { .. } => 4,
        Request::SetOutputs { .. } => 5,
        Request::SetLinkTimeout(_) => 6,
        Request::SetCalibration { .. } => 7,
        Request::GetCalibration { .. } => 8,
        Request::SaveCalibration => 9,
        Request::SetPoseConfig(_) => 10,
        Request::StartMotion(_) => 11,
        Request::StopMotion => 12,
        Request::GetMotion => 13,
        Request::SetVelocity { .. } => 14,
        Request::SetJointSpeedLimit { .. } => 15,
        Request::SetBalance(_) => 16,
        Request::GetImu => 17,
        Request::SetRobot(_) => 18,
        Request::GetRobot => 19,
        Request::SaveRobot => 20,
    }
}

fn answer_index(a: &DeviceToHost) -> u8 {
    match a {
        DeviceToHost::Nack { .. } => 0,
        DeviceToHost::HelloAck { .. } => 1,
        DeviceToHost::Ack { .. } => 2,
        DeviceToHost::Calibration { .. } => 3,
        DeviceToHost::Configured { .. } => 4,
        DeviceToHost::MotionAck { .. } => 5,
        DeviceToHost::Imu { .. } => 6,
        DeviceToHost::Robot { .. } => 7,
    }
}

// ---- One value of every variant.

const CAL: Calibration = Calibration {
    zero_rad: -0.5,
    reversed: true,
    us_per_rad: 640.0,
    center_us: 1500,
    min_us: 600,
    max_us: 2400,
};

const SERVO: ServoId = ServoId {
    leg: LegId::RL,
    joint: Joint::Hip,
};

fn requests() -> Vec<Request> {
    vec![
        Request::Hello { version: 0x0100 },
        Request::GetState,
        Request::SetBodyPose(Pose {
            roll_rad: 0.1,
            pitch_rad: -0.05,
            yaw_rad: 0.02,
            x_m: 0.01,
            y_m: -0.01,
            z_m: 0.005,
        }),
        Request::SetFeet {
            feet_in_body_m: [
                [0.2, 0.1, -0.3],
                [0.2, -0.1, -0.3],
                [-0.2, 0.1, -0.3],
                [-0.2, -0.1, -0.3],
            ],
        },
        Request::SetJoints {
            angles_rad: core::array::from_fn(|i| i as f32 * 0.05 - 0.3),
        },
        Request::SetOutputs { enabled: true },
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 300,
            action: LinkLossAction::Disable,
        }),
        Request::SetCalibration {
            servo: SERVO,
            calibration: CAL,
        },
        Request::GetCalibration { servo: SERVO },
        Request::SaveCalibration,
        Request::SetPoseConfig(PoseConfig {
            stance_height_m: 0.25,
            order: RotationOrder::Yzx,
            policy: ReachPolicy::Clamp,
        }),
        Request::StartMotion(MotionCommand::FootPath {
            path: PathKind::Rectangle,
            legs: LegSet::One(LegId::RL),
            stride_m: 0.1,
            step_height_m: 0.05,
            duty_factor: 0.75,
            cycle_s: 3.0,
            duration_s: Some(6.0),
        }),
        Request::StopMotion,
        Request::GetMotion,
        Request::SetVelocity {
            forward_m_s: 0.05,
            lateral_m_s: -0.01,
            yaw_rate_rad_s: 0.1,
        },
        Request::SetJointSpeedLimit {
            joint_speed_limit_rad_s: 2.5,
        },
        Request::SetBalance(BalanceConfig {
            leveling: true,
            safe_state: SafeState::Off,
            ..BalanceConfig::DEFAULT
        }),
        Request::GetImu,
        Request::SetRobot(Config::shahriar2023().description()),
        Request::GetRobot,
        Request::SaveRobot,
    ]
}

fn nack_reasons() -> Vec<NackReason> {
    vec![
        NackReason::UnknownVersion { supported: 0x0102 },
        NackReason::BadCrc,
        NackReason::BadFrame,
        NackReason::Oversize,
        NackReason::HelloRequired,
        NackReason::Unreachable {
            leg: LegId::FR,
            fault: ReachFault::TooClose,
        },
        NackReason::JointLimit {
            leg: LegId::RR,
            joint: Joint::Knee,
        },
        NackReason::ServoRange {
            leg: LegId::RL,
            joint: Joint::Hip,
            fault: servo::Error::AboveMax,
        },
        NackReason::NonFinite,
        NackReason::BadCalibration(servo::Error::BadGain),
        NackReason::Busy,
        NackReason::OutputsDisabled,
        NackReason::Storage,
        NackReason::InvalidArgument,
        NackReason::OutOfRange {
            field: Field::JointAngle {
                leg: LegId::FR,
                joint: Joint::Abduction,
            },
        },
        NackReason::InvalidParameter {
            param: MotionParam::CycleS,
            problem: ParamProblem::NotPositive,
        },
        NackReason::Preflight {
            leg: LegId::FR,
            fault: PreflightFault::JointLimit(Joint::Knee),
        },
        NackReason::MotionRunning,
        NackReason::NotWalking,
        NackReason::ImuAbsent,
        NackReason::ImuFault(ImuFaultKind::Stuck),
        NackReason::NotUpright,
        NackReason::BadRobot(quad_protocol::RobotField::Stance(LegId::RL)),
        NackReason::OutputsEnabled,
    ]
}

fn info(robot: RobotPreset) -> DeviceInfo {
    DeviceInfo {
        version: 0x0100,
        firmware: FirmwareVersion {
            major: 0,
            minor: 1,
            patch: 2,
        },
        robot,
        max_frame_len: 128,
        pose_config: PoseConfig {
            stance_height_m: 0.277,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        },
        link_timeout: LinkTimeout::default(),
        robot_hash: Some(0xDEAD_BEEF),
    }
}

fn answers() -> Vec<DeviceToHost> {
    vec![
        DeviceToHost::Nack {
            seq: Some(7),
            reason: NackReason::BadCrc,
        },
        DeviceToHost::HelloAck {
            seq: 8,
            info: info(RobotPreset::Fernando2025),
        },
        DeviceToHost::Ack {
            seq: 9,
            readback: Readback {
                angles_rad: core::array::from_fn(|i| i as f32 * -0.1),
                pulses_half_us: core::array::from_fn(|i| 2000 + 100 * i as u16),
                flags: Flags(Flags::OUTPUTS_ENABLED | Flags::CLAMPED),
                frames_ok: 300,
                frames_bad: 2,
            },
        },
        DeviceToHost::Calibration {
            seq: 10,
            servo: SERVO,
            calibration: CAL,
        },
        DeviceToHost::Configured {
            seq: 11,
            setting: Setting::Calibration {
                servo: SERVO,
                calibration: CAL,
            },
            readback: Readback {
                angles_rad: [0.25; 12],
                pulses_half_us: [3000; 12],
                flags: Flags(Flags::CALIBRATION_UNSAVED),
                frames_ok: 20,
                frames_bad: 0,
            },
        },
        DeviceToHost::MotionAck {
            seq: 11,
            status: MotionStatus {
                kind: Some(MotionKind::Walk),
                stage: MotionStage::Stopping,
                t_s: 12.5,
                phase: 0.25,
                fault: Some(NackReason::Unreachable {
                    leg: LegId::FL,
                    fault: ReachFault::TooFar,
                }),
            },
            readback: Readback {
                angles_rad: core::array::from_fn(|i| i as f32 * 0.1),
                pulses_half_us: core::array::from_fn(|i| 2500 + 50 * i as u16),
                flags: Flags(Flags::OUTPUTS_ENABLED),
                frames_ok: 70_000,
                frames_bad: 1,
            },
            frames: None,
        },
        DeviceToHost::Imu {
            seq: 12,
            report: ImuReport {
                health: ImuHealth::Fault(ImuFaultKind::BusHeld),
                roll_rad: 0.1,
                pitch_rad: -0.2,
                correction_roll_rad: -0.1,
                correction_pitch_rad: 0.2,
                leveling_active: true,
                correction_limited: true,
                fall: Some(FallKind::FreeFall),
                samples: 123_456,
                config: BalanceConfig::DEFAULT,
            },
        },
        DeviceToHost::Robot {
            seq: 13,
            robot: Config::fernando2025().description(),
        },
    ]
}

// ---- The device's codec.

/// postcard's bytes of `msg`.
fn postcard_bytes<T: serde::Serialize>(msg: &T) -> Vec<u8> {
    let mut buf = [0u8; MAX_DECODED_LEN];
    postcard::to_slice(msg, &mut buf).unwrap().to_vec()
}

/// The frame of postcard bytes `body` with its CRC (COBS written here, independently of the
/// crate's encoder).
fn frame_of(body: &[u8]) -> Vec<u8> {
    let mut data = body.to_vec();
    data.extend_from_slice(&crc::checksum(body).to_be_bytes());
    let mut out = vec![0];
    let mut run: Vec<u8> = Vec::new();
    for &b in &data {
        if b == 0 {
            out.push(run.len() as u8 + 1);
            out.append(&mut run);
        } else {
            run.push(b);
            if run.len() == 254 {
                out.push(0xFF);
                out.append(&mut run);
            }
        }
    }
    out.push(run.len() as u8 + 1);
    out.append(&mut run);
    out.push(0);
    out
}

/// The device's decoding of one frame.
fn device_decode(frame: &[u8]) -> Feed<'static, HostToDevice> {
    let mut acc = Accumulator::<RX_LEN>::new();
    match feed_request(&mut acc, frame) {
        Feed::NeedMore => Feed::NeedMore,
        Feed::Frame { msg, .. } => Feed::Frame {
            msg,
            remaining: &[],
        },
        Feed::BadCrc { .. } => Feed::BadCrc { remaining: &[] },
        Feed::BadFrame { error, .. } => Feed::BadFrame {
            error,
            remaining: &[],
        },
        Feed::Oversize { .. } => Feed::Oversize { remaining: &[] },
    }
}

/// The device's answer frame of `answer`: its pieces, joined, are the frame left in the
/// buffer.
fn device_encode(answer: &DeviceToHost) -> Vec<u8> {
    let mut buf = [0u8; RX_LEN];
    let mut pieces: Vec<Vec<u8>> = Vec::new();
    let n = encode_answer(answer, &mut buf, &mut |p: &[u8]| pieces.push(p.to_vec()));
    assert!(n > 0, "{answer:?} fits the device's buffer");
    assert_eq!(pieces.concat(), buf[..n], "{answer:?}");
    // Two pieces when the message holds a zero: the first ends before it, where the first
    // code byte points. One when it holds none.
    let first = &pieces[0];
    match pieces.len() {
        2 => {
            assert_eq!(
                usize::from(first[1]),
                first.len() - 1,
                "{answer:?}: {first:02x?}"
            );
            assert!(!first[2..].contains(&0), "{answer:?}: {first:02x?}");
        }
        n => assert_eq!(n, 1, "{answer:?}: {pieces:02x?}"),
    }
    buf[..n].to_vec()
}

/// The request `r` (seq 5) goes through the device: its index is `index` at byte `at` of the
/// postcard bytes, and it decodes to itself; with `index` replaced by `past` it is refused.
fn check_request(r: Request, at: usize, index: u8, past: u8) {
    let msg = HostToDevice { seq: 5, request: r };
    let mut bytes = postcard_bytes(&msg);
    let frame = frame_of(&bytes);
    assert_eq!(bytes[at], index, "index of {r:?} in {bytes:02x?}");
    assert_eq!(
        device_decode(&frame),
        Feed::Frame {
            msg,
            remaining: &[]
        },
        "{r:?}"
    );
    bytes[at] = past;
    assert!(
        matches!(
            device_decode(&frame_of(&bytes)),
            Feed::BadFrame {
                error: quad_protocol::frame::Error::UnknownVariant,
                ..
            }
        ),
        "index {past} after the last one of {r:?} is refused"
    );
}

/// The answer `a` from the device: its index is `index` at byte `at`, it decodes to itself;
/// with `past` there it does not decode.
fn check_answer(a: DeviceToHost, at: usize, index: u8, past: u8) {
    let frame = device_encode(&a);
    let mut bytes = postcard_bytes(&a);
    assert_eq!(frame, frame_of(&bytes), "the device's frame of {a:?}");
    assert_eq!(bytes[at], index, "index of {a:?} in {bytes:02x?}");
    assert_eq!(decode_all(&frame), vec![a]);
    bytes[at] = past;
    assert_eq!(
        postcard::from_bytes::<DeviceToHost>(&bytes).err(),
        Some(postcard::Error::SerdeDeCustom),
        "index {past} after the last one of {a:?} is refused"
    );
}

#[test]
fn every_request_variant_has_its_index_and_round_trips() {
    let all = requests();
    for r in &all {
        check_request(*r, 1, request_index(r), all.len() as u8);
    }
    let indices: Vec<u8> = all.iter().map(request_index).collect();
    assert_eq!(indices, (0..all.len() as u8).collect::<Vec<_>>());
}

#[test]
fn every_answer_and_nack_variant_has_its_index_and_round_trips() {
    let all = answers();
    for a in &all {
        check_answer(*a, 0, answer_index(a), all.len() as u8);
    }
    // Every nack reason through the device's encoder (their indices: quad-protocol's
    // `wire` tests, where the non-exhaustive enum can be matched exhaustively).
    let reasons = nack_reasons();
    let past = reasons.len() as u8;
    for (i, reason) in reasons.into_iter().enumerate() {
        let nack = DeviceToHost::Nack { seq: None, reason };
        check_answer(nack, 2, i as u8, past);
    }
}

// ---- Differential: the device's receive path against the protocol's frame decoder.

/// What a device answers to one decoded frame, computed at message level on `twin`: `None`
/// when no frame ended, `Some(None)` for an unreadable frame whose nack the rate limit drops
/// (the test clock stands still: only the first one is answered, `framing_nacked` tells).
fn expected_answer(
    twin: &mut Dev,
    framing_nacked: &mut bool,
    feed: Feed<'_, HostToDevice>,
) -> Option<Option<DeviceToHost>> {
    let reason = match feed {
        Feed::NeedMore => return None,
        Feed::Frame { msg, .. } => return Some(Some(twin.handle(msg))),
        Feed::BadCrc { .. } => NackReason::BadCrc,
        Feed::BadFrame { .. } => NackReason::BadFrame,
        Feed::Oversize { .. } => NackReason::Oversize,
    };
    if std::mem::replace(framing_nacked, true) {
        return Some(None);
    }
    Some(Some(DeviceToHost::Nack { seq: None, reason }))
}

/// Feeds `chunks` to a device and, through the protocol's own `Accumulator`, to a twin at
/// message level: the same answers, frame by frame (the readback's frame counters are the
/// reference accumulator's).
fn same_as_reference(chunks: &[Vec<u8>]) {
    let mut dev = device(Config::fernando2025());
    let mut twin = device(Config::fernando2025());
    let mut reference = Accumulator::<MAX_DECODED_LEN>::new();
    let mut framing_nacked = false;
    // The link rules' retry memory: an exact repeat (same seq, same frame CRC) of the last
    // request answered gets that answer again, as it was, without acting (a `Busy` nack is
    // not remembered).
    let mut last: Option<(u16, Option<u16>, DeviceToHost)> = None;
    for chunk in chunks {
        let mut wire = Vec::new();
        dev.receive(chunk, |f| wire.extend_from_slice(f));
        let got = decode_all(&wire);
        let mut expected = Vec::new();
        let mut input = &chunk[..];
        loop {
            let feed = reference.feed::<HostToDevice>(input);
            input = feed.remaining();
            let key = match &feed {
                Feed::Frame { msg, .. } => Some((msg.seq, reference.frame_crc())),
                _ => None,
            };
            if let (Some((seq, crc)), Some((last_seq, last_crc, answer))) = (key, &last) {
                if seq == *last_seq && crc == *last_crc {
                    expected.push(*answer);
                    continue;
                }
            }
            match expected_answer(&mut twin, &mut framing_nacked, feed) {
                Some(Some(mut a)) => {
                    if let DeviceToHost::Ack { readback, .. }
                    | DeviceToHost::Configured { readback, .. }
                    | DeviceToHost::MotionAck { readback, .. } = &mut a
                    {
                        readback.frames_ok = reference.frames_ok();
                        readback.frames_bad = reference.frames_bad();
                    }
                    if let Some((seq, crc)) = key {
                        let busy = matches!(
                            a,
                            DeviceToHost::Nack {
                                reason: NackReason::Busy,
                                ..
                            }
                        );
                        last = crc.filter(|_| !busy).map(|c| (seq, Some(c), a));
                    }
                    expected.push(a);
                }
                Some(None) => {}
                None => break,
            }
        }
        assert_eq!(got, expected, "chunk {chunk:02x?}");
    }
}

/// A frame around random postcard-ish bytes: a valid CRC, so that the decoder is reached.
fn framed(body: &[u8]) -> Vec<u8> {
    frame_of(body)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_bytes_get_the_reference_answers(
        chunks in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..80), 1..6)
    ) {
        same_as_reference(&chunks);
    }

    #[test]
    fn random_payloads_with_a_good_crc_get_the_reference_answers(
        bodies in prop::collection::vec(
            (0u8..17, prop::collection::vec(any::<u8>(), 0..60)), 1..6)
    ) {
        // A plausible start (seq 0, a variant index near the known ones) and random fields.
        let mut wire = Vec::new();
        wire.extend(frame(0, Request::Hello { version: quad_protocol::PROTOCOL_VERSION }));
        for (variant, rest) in &bodies {
            let mut body = vec![0, *variant];
            body.extend_from_slice(rest);
            wire.extend(framed(&body));
        }
        same_as_reference(&[wire]);
    }
}

#[test]
fn answers_fit_the_frame_limit() {
    for a in answers() {
        assert!(device_encode(&a).len() <= MAX_FRAME_LEN);
    }
}

/// The retry memory in the differential: an exact repeat of the last request, alone or in
/// the same chunk, gets the same answer with the frame counters as they were (a case the
/// random payloads found).
#[test]
fn an_exact_repeat_gets_the_remembered_answer_in_the_reference_too() {
    let hello = frame(
        0,
        Request::Hello {
            version: quad_protocol::PROTOCOL_VERSION,
        },
    );
    let state = frame(0, Request::GetState);
    let twice: Vec<u8> = state.iter().chain(&state).copied().collect();
    same_as_reference(&[hello, state.clone(), state, twice]);
}
