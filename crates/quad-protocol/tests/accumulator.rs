//! The frame accumulator: split and concatenated frames (looping on `remaining`), garbage,
//! truncation, oversize, bit flips, and a differential property test against an independent
//! reference decoder over arbitrary byte streams.

mod common;

use common::{ref_cobs_decode, ref_cobs_encode, ref_crc, ref_frame};
use kin_core::{Joint, LegId, Pose, ReachPolicy, RotationOrder};
use proptest::prelude::*;
use quad_protocol::frame::Error;
use quad_protocol::{
    encode_frame, encode_frame_in_pieces, servo, Accumulator, DeviceToHost, Feed, Flags,
    HostToDevice, LinkLossAction, LinkTimeout, MotionKind, MotionStage, MotionStatus, NackReason,
    PoseConfig, Readback, Request, ServoId, Setting, MAX_DECODED_LEN, MAX_FRAME_LEN,
};
use serde::Serialize;

/// A mixed set of requests of every size.
fn messages() -> Vec<HostToDevice> {
    let reqs = [
        Request::Hello { version: 0x0100 },
        Request::GetState,
        Request::SetBodyPose(Pose {
            roll_rad: 0.1,
            pitch_rad: -0.2,
            yaw_rad: 0.3,
            x_m: 0.01,
            y_m: -0.02,
            z_m: 0.03,
        }),
        Request::SetFeet {
            feet_in_body_m: [[0.3, 0.2, -0.25]; 4],
        },
        Request::SetJoints {
            angles_rad: [
                0.0, 0.7, -1.4, 0.0, 0.7, -1.4, 0.0, 0.7, -1.4, 0.0, 0.7, -1.4,
            ],
        },
        Request::SetOutputs { enabled: false },
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 65535,
            action: LinkLossAction::Hold,
        }),
        Request::SetCalibration {
            servo: ServoId {
                leg: LegId::RR,
                joint: Joint::Abduction,
            },
            calibration: servo::Calibration::STANDARD,
        },
        Request::GetCalibration {
            servo: ServoId::ALL[11],
        },
        Request::SaveCalibration,
        Request::SetPoseConfig(PoseConfig {
            stance_height_m: 0.2,
            order: RotationOrder::Xyz,
            policy: ReachPolicy::Reject,
        }),
    ];
    reqs.into_iter()
        .enumerate()
        .map(|(i, request)| HostToDevice {
            seq: [0, 1, 127, 128, 16383, 16384, 65535][i % 7],
            request,
        })
        .collect()
}

fn frame_of<T: Serialize>(msg: &T) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    encode_frame(msg, &mut buf).unwrap().to_vec()
}

fn stream_of(msgs: &[HostToDevice]) -> Vec<u8> {
    msgs.iter().flat_map(frame_of).collect()
}

/// What one frame produced, without borrowed data.
#[derive(Debug, Clone, PartialEq)]
enum Event<T> {
    Frame(T),
    BadCrc,
    BadFrame(Error),
    Oversize,
}

/// Feeds `chunk` completely, looping on `remaining`, and appends every event.
fn feed_all<const N: usize>(
    acc: &mut Accumulator<N>,
    mut chunk: &[u8],
    events: &mut Vec<Event<HostToDevice>>,
) {
    loop {
        let feed = acc.feed::<HostToDevice>(chunk);
        chunk = feed.remaining();
        events.push(match feed {
            Feed::NeedMore => return,
            Feed::Frame { msg, .. } => Event::Frame(msg),
            Feed::BadCrc { .. } => Event::BadCrc,
            Feed::BadFrame { error, .. } => Event::BadFrame(error),
            Feed::Oversize { .. } => Event::Oversize,
        });
    }
}

/// [`feed_all`] through [`Accumulator::feed_in_place`], the message of each frame taken from
/// `place` (which keeps whatever the last frame left in it).
fn feed_all_in_place<const N: usize>(
    acc: &mut Accumulator<N>,
    mut chunk: &[u8],
    place: &mut HostToDevice,
    events: &mut Vec<Event<HostToDevice>>,
) {
    loop {
        let feed = acc.feed_in_place(chunk, place);
        chunk = feed.remaining();
        events.push(match feed {
            Feed::NeedMore => return,
            Feed::Frame { .. } => Event::Frame(*place),
            Feed::BadCrc { .. } => Event::BadCrc,
            Feed::BadFrame { error, .. } => Event::BadFrame(error),
            Feed::Oversize { .. } => Event::Oversize,
        });
    }
}

/// The events' frames as their wire bytes (NaN payloads are not equal to themselves).
fn comparable(events: &[Event<HostToDevice>]) -> Vec<Event<Vec<u8>>> {
    events
        .iter()
        .map(|e| match e {
            Event::Frame(m) => Event::Frame(frame_of(m)),
            Event::BadCrc => Event::BadCrc,
            Event::BadFrame(error) => Event::BadFrame(*error),
            Event::Oversize => Event::Oversize,
        })
        .collect()
}

fn frames(msgs: &[HostToDevice]) -> Vec<Event<HostToDevice>> {
    msgs.iter().copied().map(Event::Frame).collect()
}

#[test]
fn back_to_back_frames_in_one_read_are_all_seen() {
    let msgs = messages();
    let stream = stream_of(&msgs);
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut events = Vec::new();
    feed_all(&mut acc, &stream, &mut events);
    assert_eq!(events, frames(&msgs));
    assert_eq!(acc.frames_ok(), msgs.len() as u32);
    assert_eq!(acc.frames_bad(), 0);
    assert!(!acc.in_frame());
}

#[test]
fn split_at_every_byte_boundary() {
    let msgs = messages();
    let stream = stream_of(&msgs);
    for cut in 0..=stream.len() {
        let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
        let mut events = Vec::new();
        feed_all(&mut acc, &stream[..cut], &mut events);
        feed_all(&mut acc, &stream[cut..], &mut events);
        assert_eq!(events, frames(&msgs), "cut at {cut}");
    }
}

#[test]
fn every_chunk_size() {
    let msgs = messages();
    let stream = stream_of(&msgs);
    for size in 1..=stream.len() {
        let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
        let mut events = Vec::new();
        for chunk in stream.chunks(size) {
            feed_all(&mut acc, chunk, &mut events);
        }
        assert_eq!(events, frames(&msgs), "chunks of {size}");
    }
}

#[test]
fn garbage_between_frames_costs_no_good_frame() {
    let msgs = messages();
    let garbage: [&[u8]; 5] = [
        &[0x55, 0xAA, 0x13],      // line noise
        &[0x00, 0x00, 0x00],      // idle delimiters
        &[0x05, 0x01, 0x02],      // a COBS block that runs past its delimiter
        &[0xFF; 300],             // longer than any buffer
        b"t1,t2,t3\n 90,45,30\n", // the ASCII protocol of an older firmware
    ];
    let mut stream = Vec::new();
    let mut expected_bad = 0;
    for (i, m) in msgs.iter().enumerate() {
        stream.extend(frame_of(m));
        let g = garbage[i % garbage.len()];
        stream.extend_from_slice(g);
        // A non-empty garbage run is ended by the next frame's leading delimiter: one bad
        // event. The run after the last frame is never ended.
        if g.iter().any(|&b| b != 0) && i + 1 < msgs.len() {
            expected_bad += 1;
        }
    }
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut events = Vec::new();
    feed_all(&mut acc, &stream, &mut events);
    let good: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::Frame(m) => Some(*m),
            _ => None,
        })
        .collect();
    assert_eq!(good, msgs);
    assert_eq!(events.len() - good.len(), expected_bad);
    assert_eq!(acc.frames_bad() as usize, expected_bad);
}

#[test]
fn truncated_frame_then_good_frame() {
    let msgs = messages();
    for m in &msgs {
        let whole = frame_of(m);
        // Every truncation that keeps at least one non-delimiter byte.
        for keep in 2..whole.len() - 1 {
            let mut stream = whole[..keep].to_vec();
            stream.extend(frame_of(&msgs[2]));
            let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
            let mut events = Vec::new();
            feed_all(&mut acc, &stream, &mut events);
            assert_eq!(events.len(), 2, "keep {keep}: {events:?}");
            assert!(!matches!(events[0], Event::Frame(_)), "keep {keep}");
            assert_eq!(events[1], Event::Frame(msgs[2]), "keep {keep}");
        }
    }
}

#[test]
fn oversize_is_reported_once_and_the_next_frame_works() {
    let big = HostToDevice {
        seq: 1,
        request: Request::SetJoints {
            angles_rad: [0.5; 12],
        },
    };
    let small = HostToDevice {
        seq: 2,
        request: Request::GetState,
    };
    let mut stream = frame_of(&big);
    stream.extend(frame_of(&big));
    stream.extend(frame_of(&small));
    let mut acc = Accumulator::<16>::new();
    let mut events = Vec::new();
    feed_all(&mut acc, &stream, &mut events);
    assert_eq!(
        events,
        vec![Event::Oversize, Event::Oversize, Event::Frame(small)]
    );
    assert_eq!((acc.frames_ok(), acc.frames_bad()), (1, 2));
}

#[test]
fn frame_of_exactly_the_buffer_size_fits() {
    let msg = HostToDevice {
        seq: 1,
        request: Request::SetJoints {
            angles_rad: [0.5; 12],
        },
    };
    // seq 1 + variant 1 + 48 + CRC 2 = 52 decoded bytes.
    let stream = frame_of(&msg);
    let mut events = Vec::new();
    feed_all(&mut Accumulator::<52>::new(), &stream, &mut events);
    assert_eq!(events, vec![Event::Frame(msg)]);
    let mut events = Vec::new();
    feed_all(&mut Accumulator::<51>::new(), &stream, &mut events);
    assert_eq!(events, vec![Event::Oversize]);
}

#[test]
fn every_single_bit_flip_of_the_decoded_bytes_is_bad_crc() {
    for m in messages() {
        let mut payload = [0u8; MAX_DECODED_LEN];
        let body = postcard::to_slice(&m, &mut payload).unwrap().to_vec();
        let mut data = body.clone();
        data.extend(ref_crc(&body).to_be_bytes());
        for bit in 0..data.len() * 8 {
            let mut bad = data.clone();
            bad[bit / 8] ^= 1 << (bit % 8);
            let mut stream = vec![0];
            stream.extend(ref_cobs_encode(&bad));
            stream.push(0);
            let mut events = Vec::new();
            feed_all(
                &mut Accumulator::<MAX_DECODED_LEN>::new(),
                &stream,
                &mut events,
            );
            assert_eq!(events, vec![Event::BadCrc], "{m:?} bit {bit}");
        }
    }
}

#[test]
fn every_single_bit_flip_on_the_wire_loses_only_that_frame() {
    let msgs = messages();
    let after = msgs[1];
    for m in &msgs {
        let wire = frame_of(m);
        for bit in 0..wire.len() * 8 {
            let mut stream = wire.clone();
            stream[bit / 8] ^= 1 << (bit % 8);
            stream.extend(frame_of(&after));
            let mut events = Vec::new();
            feed_all(
                &mut Accumulator::<MAX_DECODED_LEN>::new(),
                &stream,
                &mut events,
            );
            let (last, before) = events.split_last().unwrap();
            assert_eq!(*last, Event::Frame(after), "{m:?} bit {bit}");
            assert!(
                before.iter().all(|e| !matches!(e, Event::Frame(_))),
                "{m:?} bit {bit}: {before:?}"
            );
        }
    }
}

#[test]
fn typed_decode_errors() {
    let with_crc = ref_frame;
    let cases: [(Vec<u8>, Event<HostToDevice>); 6] = [
        // Request variant 200 (varint c8 01): a newer minor's request.
        (
            with_crc(&[0x05, 0xC8, 0x01]),
            Event::BadFrame(Error::UnknownVariant),
        ),
        // GetState followed by an extra byte.
        (
            with_crc(&[0x05, 0x01, 0x07]),
            Event::BadFrame(Error::TrailingBytes),
        ),
        // SetBodyPose with only 2 of 24 bytes.
        (
            with_crc(&[0x05, 0x02, 0x00, 0x00]),
            Event::BadFrame(Error::Truncated),
        ),
        // SetOutputs with a bool of 2.
        (
            with_crc(&[0x05, 0x05, 0x02]),
            Event::BadFrame(Error::BadEncoding),
        ),
        // One byte: shorter than any CRC-protected message.
        (
            vec![0x00, 0x02, 0x01, 0x00],
            Event::BadFrame(Error::TooShort),
        ),
        // A block of 5 that ends after 2 bytes.
        (
            vec![0x00, 0x05, 0x01, 0x02, 0x00],
            Event::BadFrame(Error::Cobs),
        ),
    ];
    for (stream, expected) in cases {
        let mut events = Vec::new();
        feed_all(
            &mut Accumulator::<MAX_DECODED_LEN>::new(),
            &stream,
            &mut events,
        );
        assert_eq!(events, vec![expected], "{stream:02x?}");
    }
}

#[test]
fn encode_into_too_small_buffer_is_an_error_at_every_size() {
    let ack = DeviceToHost::Ack {
        seq: 65535,
        readback: Readback {
            angles_rad: [-1.5; 12],
            pulses_half_us: [65535; 12],
            flags: Flags(0xFF),
            frames_ok: u32::MAX,
            frames_bad: u32::MAX,
        },
    };
    let mut buf = [0u8; MAX_FRAME_LEN];
    let full = encode_frame(&ack, &mut buf).unwrap().len();
    for size in 0..full {
        let mut small = vec![0u8; size];
        assert_eq!(
            encode_frame(&ack, &mut small),
            Err(Error::BufferFull),
            "size {size}"
        );
    }
}

/// The frame of any payload up to the largest decoded length is the reference COBS encoding
/// of its bytes and CRC between two delimiters (zero-dense payloads, zero-free ones, zeros at
/// both ends); one byte more is refused as oversize, since no receiver takes it.
#[test]
fn encoded_frames_are_the_reference_cobs_of_payload_and_crc() {
    let mut rng = seeded_rng::SplitMix64::new(3);
    let largest = MAX_DECODED_LEN - 2;
    for case in 0..3000 {
        // A byte slice serializes as its varint length and its bytes.
        let len = (rng.next_u64() % (largest as u64 - 1)) as usize;
        let zero_share = [0, 1, 2, 8][case % 4];
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                let b = rng.next_u64() as u8;
                if zero_share > 0 && b.is_multiple_of(zero_share) {
                    0
                } else {
                    b
                }
            })
            .collect();
        let msg: &[u8] = &bytes;
        let mut tmp = [0u8; 2 * MAX_FRAME_LEN];
        let payload = postcard::to_slice(&msg, &mut tmp).unwrap().to_vec();
        if payload.len() + 2 > MAX_DECODED_LEN {
            continue;
        }
        let want = ref_frame(&payload);
        let mut buf = [0u8; MAX_FRAME_LEN];
        assert_eq!(
            encode_frame(&msg, &mut buf).unwrap(),
            &want[..],
            "{bytes:?}"
        );
        // In pieces: the same frame, cut after the first block (the first code byte and the
        // bytes it covers) when the message holds a zero, else whole; nothing emitted when the
        // buffer is too small.
        let mut pieces: Vec<Vec<u8>> = Vec::new();
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame_in_pieces(&msg, &mut buf, |p| pieces.push(p.to_vec())).unwrap();
        assert_eq!(n, want.len());
        assert_eq!(pieces.concat(), want, "{bytes:?}");
        if payload.contains(&0) {
            assert_eq!(pieces.len(), 2, "{bytes:?}");
            assert_eq!(pieces[0].len(), usize::from(want[1]) + 1, "{bytes:?}");
        } else {
            assert_eq!(pieces.len(), 1, "{bytes:?}");
        }
        let mut small = vec![0u8; want.len() - 1];
        let mut emitted = false;
        assert_eq!(
            encode_frame_in_pieces(&msg, &mut small, |_| emitted = true),
            Err(Error::BufferFull)
        );
        assert!(!emitted);
    }
    // A payload of MAX_DECODED_LEN − 1 bytes: with its CRC one byte beyond the bound.
    let too_long = [7u8; MAX_DECODED_LEN - 2];
    let mut buf = [0u8; 2 * MAX_FRAME_LEN];
    assert_eq!(encode_frame(&too_long[..], &mut buf), Err(Error::Oversize));
}

/// The frame encoder writes the bytes postcard's own slice serializer writes, for answers
/// whose values take every varint width (1 to 5 bytes) and any `f32` bits: each frame is the
/// reference COBS of `postcard::to_slice`'s bytes and their CRC.
#[test]
fn encoded_answers_carry_postcards_own_bytes() {
    let mut rng = seeded_rng::SplitMix64::new(11);
    // A value of a random varint width: its top bit at a random position.
    let varint = |rng: &mut seeded_rng::SplitMix64| {
        let bits = rng.next_u64() % 33;
        (rng.next_u64() & ((1u64 << bits) - 1)) as u32
    };
    for case in 0..2000 {
        let mut readback = Readback {
            angles_rad: [0.0; 12],
            pulses_half_us: [0; 12],
            flags: Flags(rng.next_u64() as u8),
            frames_ok: varint(&mut rng),
            frames_bad: varint(&mut rng),
        };
        for (a, p) in readback
            .angles_rad
            .iter_mut()
            .zip(&mut readback.pulses_half_us)
        {
            *a = f32::from_bits(rng.next_u64() as u32);
            *p = varint(&mut rng) as u16;
        }
        let seq = varint(&mut rng) as u16;
        let msg = match case % 4 {
            0 => DeviceToHost::Ack { seq, readback },
            1 => DeviceToHost::Configured {
                seq,
                setting: Setting::LinkTimeout(LinkTimeout {
                    timeout_ms: varint(&mut rng) as u16,
                    action: LinkLossAction::Disable,
                }),
                readback,
            },
            2 => DeviceToHost::MotionAck {
                seq,
                status: MotionStatus {
                    kind: Some(MotionKind::Walk),
                    stage: MotionStage::Run,
                    t_s: f32::from_bits(rng.next_u64() as u32),
                    phase: f32::from_bits(rng.next_u64() as u32),
                    fault: None,
                },
                readback,
                frames: None,
            },
            _ => DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::UnknownVersion {
                    supported: varint(&mut rng) as u16,
                },
            },
        };
        let mut tmp = [0u8; MAX_FRAME_LEN];
        let payload = postcard::to_slice(&msg, &mut tmp).unwrap().to_vec();
        let want = ref_frame(&payload);
        let mut buf = [0u8; MAX_FRAME_LEN];
        assert_eq!(encode_frame(&msg, &mut buf).unwrap(), &want[..], "{msg:?}");
    }
}

#[test]
fn largest_messages_fit_the_declared_bounds() {
    // Worst-case varints everywhere.
    let readback = Readback {
        angles_rad: [f32::MAX; 12],
        pulses_half_us: [u16::MAX; 12],
        flags: Flags(0xFF),
        frames_ok: u32::MAX,
        frames_bad: u32::MAX,
    };
    let ack = DeviceToHost::Ack {
        seq: u16::MAX,
        readback,
    };
    // The largest answer: a calibration echo with a full readback.
    let configured = DeviceToHost::Configured {
        seq: u16::MAX,
        setting: Setting::Calibration {
            servo: ServoId::ALL[11],
            calibration: servo::Calibration {
                zero_rad: f32::MAX,
                reversed: true,
                us_per_rad: f32::MAX,
                center_us: u16::MAX,
                min_us: u16::MAX,
                max_us: u16::MAX,
            },
        },
        readback,
    };
    let joints = HostToDevice {
        seq: u16::MAX,
        request: Request::SetJoints {
            angles_rad: [f32::MAX; 12],
        },
    };
    let nack = DeviceToHost::Nack {
        seq: Some(u16::MAX),
        reason: NackReason::UnknownVersion {
            supported: u16::MAX,
        },
    };
    // A motion ack (since 2.1): the readback and the engine's status with the longest fault,
    // still below a `Configured` echoing a calibration.
    let motion_ack = DeviceToHost::MotionAck {
        seq: u16::MAX,
        status: MotionStatus {
            kind: Some(MotionKind::Walk),
            stage: MotionStage::Leave,
            t_s: f32::MAX,
            phase: f32::MAX,
            fault: Some(NackReason::UnknownVersion {
                supported: u16::MAX,
            }),
        },
        readback: match ack {
            DeviceToHost::Ack { readback, .. } => readback,
            _ => unreachable!(),
        },
        frames: None,
    };
    let mut buf = [0u8; MAX_DECODED_LEN];
    let ack_len = postcard::to_slice(&ack, &mut buf).unwrap().len() + 2;
    let configured_len = postcard::to_slice(&configured, &mut buf).unwrap().len() + 2;
    assert_eq!(configured_len, quad_protocol::DEVICE_TO_HOST_MAX_LEN);
    assert!(ack_len < configured_len);
    let motion_len = postcard::to_slice(&motion_ack, &mut buf).unwrap().len() + 2;
    assert!(ack_len < motion_len && motion_len < configured_len);
    let joints_len = postcard::to_slice(&joints, &mut buf).unwrap().len() + 2;
    assert_eq!(joints_len, quad_protocol::HOST_TO_DEVICE_MAX_LEN);
    let nack_len = postcard::to_slice(&nack, &mut buf).unwrap().len() + 2;
    assert!(nack_len < ack_len);
    let mut wire = [0u8; MAX_FRAME_LEN];
    assert_eq!(
        encode_frame(&motion_ack, &mut wire).unwrap().len(),
        quad_protocol::frame::encoded_len_max(motion_len)
    );
    assert_eq!(
        encode_frame(&configured, &mut wire).unwrap().len(),
        quad_protocol::frame::encoded_len_max(configured_len)
    );
}

// ---------------------------------------------------------------------------------------------
// Property tests: arbitrary streams, checked against the reference decoder of `common`.

/// The frame bodies of a stream: the bytes between consecutive delimiters, non-empty, in order;
/// the unterminated tail is left out.
fn reference_chunks(stream: &[u8]) -> Vec<&[u8]> {
    let mut parts: Vec<&[u8]> = stream.split(|&b| b == 0).collect();
    parts.pop(); // after the last delimiter (or everything, when there is none)
    parts.into_iter().filter(|c| !c.is_empty()).collect()
}

/// The postcard bytes of a chunk if it is a frame the accumulator must accept: valid COBS,
/// decoded length within `n`, good CRC.
fn reference_payload(chunk: &[u8], n: usize) -> Option<Vec<u8>> {
    let data = ref_cobs_decode(chunk)?;
    if data.len() > n || data.len() < 3 {
        return None;
    }
    let (body, crc) = data.split_at(data.len() - 2);
    (ref_crc(body).to_be_bytes() == crc).then(|| body.to_vec())
}

/// Feeds `stream` in `cuts`-sized pieces into an accumulator of `N` bytes and checks every
/// event against the reference.
fn check_stream<const N: usize>(stream: &[u8], cuts: &[usize]) -> Result<(), TestCaseError> {
    let mut acc = Accumulator::<N>::new();
    let mut events = Vec::new();
    let mut rest = stream;
    let mut k = 0;
    while !rest.is_empty() {
        let take = cuts
            .get(k)
            .copied()
            .unwrap_or(rest.len())
            .clamp(1, rest.len());
        k += 1;
        feed_all(&mut acc, &rest[..take], &mut events);
        rest = &rest[take..];
    }
    let chunks = reference_chunks(stream);
    prop_assert_eq!(events.len(), chunks.len());
    for (event, chunk) in events.iter().zip(&chunks) {
        let payload = reference_payload(chunk, N);
        match event {
            Event::Frame(msg) => {
                // Never a frame whose CRC was wrong, and exactly its bytes.
                let payload = payload.ok_or_else(|| {
                    TestCaseError::fail(format!("frame from a bad chunk {chunk:02x?}"))
                })?;
                let mut buf = [0u8; MAX_DECODED_LEN];
                let again = postcard::to_slice(msg, &mut buf).unwrap();
                prop_assert_eq!(&again[..], &payload[..]);
            }
            other => {
                // A good chunk is only refused when its message is not a valid request.
                if let Some(p) = payload {
                    prop_assert!(
                        matches!(other, Event::BadFrame(_)),
                        "good chunk refused: {:?}",
                        other
                    );
                    prop_assert!(postcard::take_from_bytes::<HostToDevice>(&p)
                        .map(|(_, rest)| !rest.is_empty())
                        .unwrap_or(true));
                }
            }
        }
    }
    prop_assert_eq!(acc.frames_ok() + acc.frames_bad(), events.len() as u32);
    Ok(())
}

fn arb_request() -> impl Strategy<Value = HostToDevice> {
    let f = any::<u32>().prop_map(f32::from_bits); // any bits: NaN and inf included
    (
        any::<u16>(),
        0u8..6,
        prop::array::uniform12(f),
        any::<bool>(),
        any::<u16>(),
    )
        .prop_map(|(seq, kind, a, b, v)| HostToDevice {
            seq,
            request: match kind {
                0 => Request::Hello { version: v },
                1 => Request::GetState,
                2 => Request::SetBodyPose(Pose::from_array([a[0], a[1], a[2], a[3], a[4], a[5]])),
                3 => Request::SetJoints { angles_rad: a },
                4 => Request::SetOutputs { enabled: b },
                _ => Request::SetLinkTimeout(LinkTimeout {
                    timeout_ms: v,
                    action: if b {
                        LinkLossAction::Disable
                    } else {
                        LinkLossAction::Hold
                    },
                }),
            },
        })
}

/// A stream segment: a good frame, a good frame with bit flips, or random bytes.
fn arb_segment() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        arb_request().prop_map(|m| frame_of(&m)),
        (arb_request(), prop::collection::vec(any::<u16>(), 1..4)).prop_map(|(m, flips)| {
            let mut f = frame_of(&m);
            let bits = f.len() * 8;
            for x in flips {
                let bit = usize::from(x) % bits;
                f[bit / 8] ^= 1 << (bit % 8);
            }
            f
        }),
        prop::collection::vec(any::<u8>(), 0..80),
        prop::collection::vec(prop_oneof![Just(0u8), 1u8..=255], 0..20),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic_nor_yield_a_bad_frame(
        stream in prop::collection::vec(any::<u8>(), 0..600),
        cuts in prop::collection::vec(1usize..64, 0..20),
    ) {
        check_stream::<MAX_DECODED_LEN>(&stream, &cuts)?;
        check_stream::<24>(&stream, &cuts)?;
    }

    #[test]
    fn mixed_streams_match_the_reference_decoder(
        segments in prop::collection::vec(arb_segment(), 0..12),
        cuts in prop::collection::vec(1usize..64, 0..30),
    ) {
        let stream: Vec<u8> = segments.concat();
        check_stream::<MAX_DECODED_LEN>(&stream, &cuts)?;
        check_stream::<32>(&stream, &cuts)?;
    }

    /// Decoding in place (the device's way) reports the same frames, errors and messages as
    /// decoding by value, in any chunking, the place reused from frame to frame.
    #[test]
    fn in_place_decoding_reads_what_decoding_by_value_reads(
        segments in prop::collection::vec(arb_segment(), 0..12),
        cuts in prop::collection::vec(1usize..64, 0..30),
    ) {
        let stream: Vec<u8> = segments.concat();
        let (mut by_value, mut in_place) = (Vec::new(), Vec::new());
        let mut a = Accumulator::<MAX_DECODED_LEN>::new();
        let mut b = Accumulator::<MAX_DECODED_LEN>::new();
        let mut place = messages()[3];
        let mut rest = &stream[..];
        let mut k = 0;
        while !rest.is_empty() {
            let take = cuts.get(k).copied().unwrap_or(rest.len()).clamp(1, rest.len());
            k += 1;
            feed_all(&mut a, &rest[..take], &mut by_value);
            feed_all_in_place(&mut b, &rest[..take], &mut place, &mut in_place);
            rest = &rest[take..];
        }
        prop_assert_eq!(comparable(&by_value), comparable(&in_place));
        prop_assert_eq!((a.frames_ok(), a.frames_bad()), (b.frames_ok(), b.frames_bad()));
        prop_assert_eq!(a.frame_crc(), b.frame_crc());
    }

    #[test]
    fn every_good_frame_survives_any_chunking(
        msgs in prop::collection::vec(arb_request(), 1..8),
        cuts in prop::collection::vec(1usize..40, 0..30),
    ) {
        let stream: Vec<u8> = msgs.iter().flat_map(frame_of).collect();
        let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
        let mut events = Vec::new();
        let mut rest = &stream[..];
        let mut k = 0;
        while !rest.is_empty() {
            let take = cuts.get(k).copied().unwrap_or(rest.len()).clamp(1, rest.len());
            k += 1;
            feed_all(&mut acc, &rest[..take], &mut events);
            rest = &rest[take..];
        }
        prop_assert_eq!(events.len(), msgs.len());
        for (e, m) in events.iter().zip(&msgs) {
            // Compare bytes: NaN payloads are not equal to themselves.
            let Event::Frame(got) = e else {
                return Err(TestCaseError::fail(format!("{e:?}")));
            };
            let (mut a, mut b) = ([0u8; MAX_DECODED_LEN], [0u8; MAX_DECODED_LEN]);
            prop_assert_eq!(
                postcard::to_slice(got, &mut a).unwrap(),
                postcard::to_slice(m, &mut b).unwrap()
            );
        }
    }
}

/// `frame_crc` is the trailer of the last good frame (the CRC of its message), kept across
/// bad frames and partial input, `None` before the first.
#[test]
fn frame_crc_is_the_last_good_frames_trailer() {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    assert_eq!(acc.frame_crc(), None);
    for msg in messages() {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let frame = encode_frame(&msg, &mut buf).expect("encodes").to_vec();
        let mut payload = [0u8; MAX_DECODED_LEN];
        let body = postcard::to_slice(&msg, &mut payload)
            .expect("serializes")
            .to_vec();
        let (head, tail) = frame.split_at(frame.len() / 2);
        assert!(matches!(acc.feed::<HostToDevice>(head), Feed::NeedMore));
        assert!(matches!(acc.feed::<HostToDevice>(tail), Feed::Frame { .. }));
        assert_eq!(acc.frame_crc(), Some(ref_crc(&body)), "{msg:?}");
        // A frame with a bad CRC leaves it.
        let mut bad = frame.clone();
        bad[2] ^= 0x40;
        assert!(!matches!(
            acc.feed::<HostToDevice>(&bad),
            Feed::Frame { .. }
        ));
        assert_eq!(acc.frame_crc(), Some(ref_crc(&body)));
    }
}
