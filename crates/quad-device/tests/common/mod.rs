//! The device on the shared in-memory fakes (`quad_device::sim`: logging outputs, a settable
//! clock, RAM storage with a power-cut budget), and frame helpers.

#![allow(dead_code)]

pub use quad_device::sim::{Outputs, RamEeprom, VirtualClock};
use quad_device::{Clock, Config, Device, ServoOutputs, Storage};
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, HostToDevice, Request, MAX_DECODED_LEN,
    MAX_FRAME_LEN, PROTOCOL_VERSION,
};

pub type Dev = Device<Outputs, VirtualClock, RamEeprom>;

pub fn device(config: Config) -> Dev {
    Device::new(
        config,
        Outputs::logging(),
        VirtualClock::default(),
        RamEeprom::erased(),
    )
    .unwrap()
}

/// The fernando2025 device on logging outputs, with its virtual clock at 1 s (not yet greeted).
pub fn clocked_device() -> (Dev, VirtualClock) {
    let clock = VirtualClock::default();
    clock.set_ms(1_000);
    let dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        clock.clone(),
        RamEeprom::erased(),
    )
    .unwrap();
    (dev, clock)
}

/// `n` servo frames: the clock a frame on, the device polled, each time.
pub fn frames(dev: &mut Dev, clock: &VirtualClock, n: u32) {
    for _ in 0..n {
        clock.advance_ms(quad_device::engine::FRAME_MS);
        dev.poll();
    }
}

/// The status of a `MotionAck`.
pub fn status(a: DeviceToHost) -> quad_protocol::MotionStatus {
    match a {
        DeviceToHost::MotionAck { status, .. } => status,
        other => panic!("not a motion ack: {other:?}"),
    }
}

pub fn frame(seq: u16, request: Request) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    encode_frame(&HostToDevice { seq, request }, &mut buf)
        .unwrap()
        .to_vec()
}

/// Feeds bytes and decodes every answer (any outputs, clock and storage).
pub fn feed<O: ServoOutputs, C: Clock, S: Storage>(
    dev: &mut Device<O, C, S>,
    bytes: &[u8],
) -> Vec<DeviceToHost> {
    let mut wire = Vec::new();
    dev.receive(bytes, |f| wire.extend_from_slice(f));
    decode_all(&wire)
}

pub fn decode_all(wire: &[u8]) -> Vec<DeviceToHost> {
    let mut acc = Accumulator::<MAX_DECODED_LEN>::new();
    let mut out = Vec::new();
    let mut input = wire;
    loop {
        match acc.feed::<DeviceToHost>(input) {
            Feed::NeedMore => break,
            Feed::Frame { msg, remaining } => {
                out.push(msg);
                input = remaining;
            }
            other => panic!("device sent a bad frame: {other:?}"),
        }
    }
    out
}

/// Sends one request as a frame and returns its single answer.
pub fn ask<O: ServoOutputs, C: Clock, S: Storage>(
    dev: &mut Device<O, C, S>,
    seq: u16,
    request: Request,
) -> DeviceToHost {
    let answers = feed(dev, &frame(seq, request));
    assert_eq!(answers.len(), 1, "one answer per frame: {answers:?}");
    assert_eq!(answers[0].seq(), Some(seq));
    answers[0]
}

pub fn hello<O: ServoOutputs, C: Clock, S: Storage>(dev: &mut Device<O, C, S>) {
    match ask(
        dev,
        0,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    ) {
        DeviceToHost::HelloAck { .. } => {}
        other => panic!("hello refused: {other:?}"),
    }
}

/// Checks that every pulse ever written lies within the device's calibrated travel.
pub fn assert_writes_in_travel(dev: &Dev) {
    for w in dev.outputs().writes() {
        for (i, (&p, c)) in w.iter().zip(dev.calibration()).enumerate() {
            assert!(
                c.min_half_us() <= p && p <= c.max_half_us(),
                "servo {i}: pulse {p} outside [{}, {}]",
                c.min_half_us(),
                c.max_half_us()
            );
        }
    }
}
