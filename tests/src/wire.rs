//! Raw frames to the emulated firmware and the answers that come back, for the tests that
//! speak the wire protocol below the client (unreadable frames, retries).

use quad_host::link::emulator::EmulatorLink;
use quad_host::link::Link;
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, HostToDevice, Request, MAX_DECODED_LEN,
    MAX_FRAME_LEN,
};
use std::time::Duration;

/// The frame of request `request` with sequence number `seq`.
pub fn frame(seq: u16, request: Request) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    encode_frame(&HostToDevice { seq, request }, &mut buf)
        .expect("encodes")
        .to_vec()
}

/// Sends `bytes` and returns the answers that arrive within `wait`, or, with `settle`, until
/// `settle` after the first answer (at most `wait`).
///
/// # Panics
/// When the link fails or the device sends an unreadable frame.
pub fn answers(
    link: &mut EmulatorLink,
    bytes: &[u8],
    wait: Duration,
    settle: Option<Duration>,
) -> Vec<DeviceToHost> {
    link.send(bytes).expect("send");
    let mut end = link.now() + wait;
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut answers = Vec::new();
    let mut buf = [0u8; 256];
    while link.now() < end {
        let n = link.recv(&mut buf, end - link.now()).expect("recv");
        let mut rest = &buf[..n];
        loop {
            match acc.feed::<DeviceToHost>(rest) {
                Feed::NeedMore => break,
                Feed::Frame { msg, remaining } => {
                    if answers.is_empty() {
                        if let Some(settle) = settle {
                            end = end.min(link.now() + settle);
                        }
                    }
                    answers.push(msg);
                    rest = remaining;
                }
                other => panic!("the device sent an unreadable frame: {other:?}"),
            }
        }
    }
    answers
}

/// Sends `bytes` on an idle line and returns the first answer with the time from the request's
/// first byte on the line to the answer's last byte; `None` when none comes within `patience`.
///
/// # Panics
/// When the link fails or the device sends an unreadable frame.
pub fn timed_answer(
    link: &mut EmulatorLink,
    bytes: &[u8],
    patience: Duration,
) -> Option<(DeviceToHost, Duration)> {
    let start = link.now();
    link.send(bytes).expect("send");
    let end = start + patience;
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut buf = [0u8; 256];
    while link.now() < end {
        // The emulated link returns at the end of a frame, when the clock is at its last byte.
        let n = link.recv(&mut buf, end - link.now()).expect("recv");
        match acc.feed::<DeviceToHost>(&buf[..n]) {
            Feed::NeedMore => {}
            Feed::Frame { msg, .. } => return Some((msg, link.now() - start)),
            other => panic!("the device sent an unreadable frame: {other:?}"),
        }
    }
    None
}

/// Sends `request` with sequence number `seq` and returns its one answer (within `patience`,
/// the line then watched for a second one no longer).
///
/// # Panics
/// When no answer or more than one came, or as [`answers`].
pub fn ask(
    link: &mut EmulatorLink,
    seq: u16,
    request: Request,
    patience: Duration,
) -> DeviceToHost {
    let answers = answers(link, &frame(seq, request), patience, Some(Duration::ZERO));
    assert_eq!(answers.len(), 1, "{request:?}: {answers:?}");
    answers[0]
}
