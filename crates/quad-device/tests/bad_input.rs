//! Bad input: garbage, truncated, oversize, wrong-CRC and wrong-version frames get a nack or
//! nothing, never a panic, never a moved servo, and the next good frame works. Then a proptest
//! and a bounded fuzz loop over arbitrary byte streams, checking the invariants after every
//! byte.

mod common;

use common::*;
use kin_core::body::Pose;
use kin_core::{ReachPolicy, RotationOrder};
use proptest::prelude::*;
use quad_device::Config;
use quad_protocol::servo::Calibration;
use quad_protocol::{
    crc, DeviceToHost, LinkLossAction, LinkTimeout, NackReason, PoseConfig, Request, ServoId,
    PROTOCOL_VERSION,
};

/// A device after hello, outputs enabled, holding a pose: anything that moves it is visible.
fn ready() -> Dev {
    let mut dev = device(Config::fernando2025());
    hello(&mut dev);
    assert!(matches!(
        ask(&mut dev, 1, Request::SetOutputs { enabled: true }),
        DeviceToHost::Ack { .. }
    ));
    dev
}

/// Feeds `bad`, then a good GetState; checks nothing moved, the answers to `bad` are nacks
/// without a sequence number (as many as `expected`), and the good frame is answered.
fn check_bad(bad: &[u8], expected: &[NackReason]) {
    let mut dev = ready();
    let writes = dev.outputs().writes().to_vec();
    let before = dev.readback();
    let answers = feed(&mut dev, bad);
    let after = feed(&mut dev, &frame(42, Request::GetState));
    let mut all = answers;
    all.extend(after);
    let (last, nacks) = all.split_last().expect("the good frame is answered");
    let reasons: Vec<NackReason> = nacks
        .iter()
        .map(|a| match a {
            DeviceToHost::Nack { seq: None, reason } => *reason,
            other => panic!("bad input got {other:?}"),
        })
        .collect();
    assert_eq!(reasons, expected);
    match last {
        DeviceToHost::Ack { seq: 42, readback } => {
            assert_eq!(readback.angles_rad, before.angles_rad);
            assert_eq!(readback.pulses_half_us, before.pulses_half_us);
            assert_eq!(
                readback.frames_bad,
                before.frames_bad + expected.len() as u32
            );
        }
        other => panic!("good frame got {other:?}"),
    }
    assert_eq!(dev.outputs().writes(), writes, "nothing moved");
    assert!(dev.outputs().enabled);
}

#[test]
fn garbage_without_a_delimiter_is_dropped_by_the_next_frame() {
    // The good frame's leading delimiter ends the garbage, which is then reported once.
    check_bad(&[0x13, 0x37, 0xFF, 0x01, 0x02], &[NackReason::BadFrame]);
}

#[test]
fn garbage_between_delimiters_is_nacked() {
    check_bad(
        &[0x00, 0x05, 0x11, 0x22, 0x00, 0x00],
        &[NackReason::BadFrame],
    );
    check_bad(&[0x00, 0x01, 0x00], &[NackReason::BadFrame]);
    check_bad(&[0x00, 0x00, 0x00], &[]);
}

#[test]
fn a_truncated_frame_is_nacked_and_the_next_one_works() {
    let f = frame(7, Request::SetBodyPose(Pose::rotation(0.1, 0.0, 0.0)));
    for cut in 2..f.len() - 1 {
        // A cut frame is either broken COBS or too short (BadFrame), or has a wrong CRC.
        let mut dev = ready();
        let writes = dev.outputs().writes().to_vec();
        let mut wire = f[..cut].to_vec();
        wire.extend(frame(8, Request::GetState));
        let answers = feed(&mut dev, &wire);
        assert_eq!(answers.len(), 2, "cut {cut}: {answers:?}");
        assert!(
            matches!(
                answers[0],
                DeviceToHost::Nack {
                    seq: None,
                    reason: NackReason::BadFrame | NackReason::BadCrc
                }
            ),
            "cut {cut}: {:?}",
            answers[0]
        );
        assert!(matches!(answers[1], DeviceToHost::Ack { seq: 8, .. }));
        assert_eq!(dev.outputs().writes(), writes);
    }
}

#[test]
fn an_oversize_frame_is_nacked() {
    let mut bad = vec![0x00];
    bad.extend(std::iter::repeat_n(0x42, 1000));
    bad.push(0x00);
    check_bad(&bad, &[NackReason::Oversize]);
}

#[test]
fn a_wrong_crc_is_nacked_for_every_bit() {
    let f = frame(9, Request::SetBodyPose(Pose::rotation(0.0, 0.1, 0.0)));
    // Flip each bit of every byte between the delimiters that keeps the delimiters intact.
    for i in 1..f.len() - 1 {
        for bit in 0..8 {
            let mut bad = f.clone();
            bad[i] ^= 1 << bit;
            if bad[i] == 0 {
                continue; // a new delimiter: two frames, covered by the fuzz tests
            }
            let mut dev = ready();
            let writes = dev.outputs().writes().to_vec();
            let answers = feed(&mut dev, &bad);
            assert_eq!(answers.len(), 1);
            assert!(
                matches!(
                    answers[0],
                    DeviceToHost::Nack {
                        seq: None,
                        reason: NackReason::BadCrc | NackReason::BadFrame
                    }
                ),
                "byte {i} bit {bit}: {:?}",
                answers[0]
            );
            assert_eq!(dev.outputs().writes(), writes);
        }
    }
}

#[test]
fn a_valid_crc_over_an_unknown_message_is_a_bad_frame() {
    // seq 5, variant 99 (no such request), CRC correct.
    let body = [0x05u8, 99];
    let sum = crc::checksum(&body).to_be_bytes();
    let decoded = [body[0], body[1], sum[0], sum[1]];
    // COBS by hand: no zero inside.
    let mut bad = vec![0x00, 5];
    bad.extend_from_slice(&decoded);
    bad.push(0x00);
    assert!(decoded.iter().all(|&b| b != 0));
    check_bad(&bad, &[NackReason::BadFrame]);
}

#[test]
fn a_wrong_version_is_refused_and_the_session_goes_on() {
    let mut dev = ready();
    let a = ask(&mut dev, 3, Request::Hello { version: 0x0900 });
    assert_eq!(
        a,
        DeviceToHost::Nack {
            seq: Some(3),
            reason: NackReason::UnknownVersion {
                supported: PROTOCOL_VERSION
            }
        }
    );
    assert!(matches!(
        ask(&mut dev, 4, Request::SetBodyPose(Pose::default())),
        DeviceToHost::Ack { .. }
    ));
}

// --- properties over arbitrary streams -------------------------------------------------------

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -1.0f32..1.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(-1e30f32),
        1 => any::<f32>(),
    ]
}

fn any_request() -> BoxedStrategy<Request> {
    let pose = prop::array::uniform6(any_f32().boxed()).prop_map(|a| {
        // Mostly small, reachable-ish poses: translations scaled down.
        Pose::from_array([
            a[0] * 0.3,
            a[1] * 0.3,
            a[2] * 0.3,
            a[3] * 0.1,
            a[4] * 0.1,
            a[5] * 0.1,
        ])
    });
    let cal = (
        any_f32(),
        any::<bool>(),
        200.0f32..1200.0,
        400u16..2600,
        300u16..1600,
        1400u16..2800,
    )
        .prop_map(|(z, r, g, c, lo, hi)| Calibration {
            zero_rad: z,
            reversed: r,
            us_per_rad: g,
            center_us: c,
            min_us: lo,
            max_us: hi,
        });
    prop_oneof![
        3 => pose.prop_map(Request::SetBodyPose),
        1 => prop::array::uniform12(any_f32()).prop_map(|a| Request::SetJoints { angles_rad: a }),
        1 => prop::array::uniform12(any_f32())
            .prop_map(|a| Request::SetFeet { feet_in_body_m: [[a[0], a[1], a[2] - 0.9], [a[3], a[4], a[5] - 0.9], [a[6], a[7], a[8] - 0.9], [a[9], a[10], a[11] - 0.9]] }),
        1 => any::<bool>().prop_map(|enabled| Request::SetOutputs { enabled }),
        1 => (0usize..12, cal).prop_map(|(i, calibration)| Request::SetCalibration { servo: ServoId::ALL[i], calibration }),
        1 => Just(Request::GetState),
        1 => (0u16..3).prop_map(|v| Request::Hello { version: v << 8 }),
        1 => (any_f32(), any::<bool>()).prop_map(|(h, clamp)| Request::SetPoseConfig(PoseConfig {
            stance_height_m: 0.9 + 0.1 * h,
            order: RotationOrder::Zxy,
            policy: if clamp { ReachPolicy::Clamp } else { ReachPolicy::Reject },
        })),
        1 => (0u16..50).prop_map(|t| Request::SetLinkTimeout(LinkTimeout { timeout_ms: t, action: LinkLossAction::Disable })),
    ]
    .boxed()
}

/// One piece of a stream: a valid frame, a damaged frame, or raw bytes.
#[derive(Debug, Clone)]
enum Piece {
    Frame(u16, Request),
    Damaged(u16, Request, usize, u8),
    Cut(u16, Request, usize),
    Raw(Vec<u8>),
}

fn any_piece() -> BoxedStrategy<Piece> {
    prop_oneof![
        4 => (any::<u16>(), any_request()).prop_map(|(s, r)| Piece::Frame(s, r)),
        1 => (any::<u16>(), any_request(), any::<usize>(), 1u8..=255).prop_map(|(s, r, i, x)| Piece::Damaged(s, r, i, x)),
        1 => (any::<u16>(), any_request(), any::<usize>()).prop_map(|(s, r, i)| Piece::Cut(s, r, i)),
        2 => prop::collection::vec(any::<u8>(), 0..200).prop_map(Piece::Raw),
    ]
    .boxed()
}

fn bytes_of(p: &Piece) -> Vec<u8> {
    match p {
        Piece::Frame(s, r) => frame(*s, *r),
        Piece::Damaged(s, r, i, x) => {
            let mut f = frame(*s, *r);
            let n = f.len();
            f[i % n] ^= x;
            f
        }
        Piece::Cut(s, r, i) => {
            let f = frame(*s, *r);
            f[..i % f.len()].to_vec()
        }
        Piece::Raw(b) => b.clone(),
    }
}

/// Feeds `stream` one byte at a time, checking after each byte: every new output write lies in
/// the calibrated travel, answers are well-formed frames, readback angles are finite, and the
/// clock moves so that the failsafe may act. Then a good frame must be answered. Returns the
/// number of output writes (to show that the stream reached the outputs).
fn run_stream(stream: &[u8]) -> usize {
    let mut dev = device(Config::fernando2025());
    let mut checked = 0;
    let mut t = 0u32;
    for &b in stream {
        let mut wire = Vec::new();
        dev.receive(&[b], |f| wire.extend_from_slice(f));
        for answer in decode_all(&wire) {
            if let DeviceToHost::Ack { readback, .. } = answer {
                assert!(readback.angles_rad.iter().all(|a| a.is_finite()));
                for (i, &p) in readback.pulses_half_us.iter().enumerate() {
                    let c = dev.calibration()[i];
                    assert!(p == 0 || (c.min_half_us() <= p && p <= c.max_half_us()));
                }
            }
        }
        let writes = &dev.outputs().writes();
        for w in &writes[checked..] {
            for (i, &p) in w.iter().enumerate() {
                let c = dev.calibration()[i];
                assert!(
                    c.min_half_us() <= p && p <= c.max_half_us(),
                    "servo {i}: {p} outside its travel"
                );
            }
        }
        checked = writes.len();
        t += 1;
        dev.clock().set_ms(t);
        dev.poll();
    }
    let answers = feed(&mut dev, &frame(0xBEEF, Request::GetState));
    assert!(matches!(
        answers.last(),
        Some(DeviceToHost::Ack { seq: 0xBEEF, .. })
    ));
    checked
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_streams_keep_the_invariants(pieces in prop::collection::vec(any_piece(), 0..24)) {
        let mut stream = Vec::new();
        // Open with a hello often, so that motion requests get through.
        stream.extend(frame(1, Request::Hello { version: PROTOCOL_VERSION }));
        for p in &pieces {
            stream.extend(bytes_of(p));
        }
        run_stream(&stream);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        run_stream(&bytes);
    }
}

/// A deterministic, bounded fuzz loop (no cargo-fuzz needed): valid frames mutated by bit
/// flips, byte drops, duplications and cuts, concatenated, fed in random chunk sizes.
#[test]
fn bounded_fuzz_loop() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let requests = [
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
        Request::SetOutputs { enabled: true },
        Request::SetBodyPose(Pose::rotation(0.1, -0.1, 0.05)),
        Request::SetBodyPose(Pose {
            z_m: 0.3,
            ..Pose::default()
        }),
        Request::SetJoints {
            angles_rad: [
                0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
            ],
        },
        Request::GetState,
        Request::SetCalibration {
            servo: ServoId::ALL[3],
            calibration: Calibration {
                center_us: 1510,
                ..Calibration::STANDARD
            },
        },
    ];
    let mut writes = 0;
    for _ in 0..300 {
        let mut stream = Vec::new();
        for _ in 0..12 {
            let r = requests[(next() % requests.len() as u64) as usize];
            let mut f = frame((next() & 0xFFFF) as u16, r);
            match next() % 6 {
                0 => {
                    let i = (next() as usize) % f.len();
                    f[i] ^= 1 << (next() % 8);
                }
                1 => {
                    let i = (next() as usize) % f.len();
                    f.remove(i);
                }
                2 => {
                    let copy = f.clone();
                    f.extend(copy);
                }
                3 => {
                    let i = (next() as usize) % f.len();
                    f.truncate(i);
                }
                _ => {}
            }
            stream.extend(f);
        }
        writes += run_stream(&stream);
    }
    assert!(
        writes > 100,
        "the fuzz reaches the outputs: {writes} writes"
    );
}
