//! Test doubles: recording outputs, a settable clock, RAM storage with a power-cut budget, and
//! frame helpers.

#![allow(dead_code)]

use quad_device::store::STORAGE_LEN;
use quad_device::{Clock, Config, Device, ServoOutputs, Storage};
use quad_protocol::{
    encode_frame, Accumulator, DeviceToHost, Feed, HostToDevice, Request, MAX_DECODED_LEN,
    MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use std::cell::Cell;
use std::rc::Rc;

/// What the outputs saw.
#[derive(Debug, Default, Clone)]
pub struct Outputs {
    pub enabled: bool,
    /// Every `set_pulses` call, in order.
    pub writes: Vec<[u16; 12]>,
    /// Every `set_enabled` call, in order.
    pub enables: Vec<bool>,
}

impl ServoOutputs for Outputs {
    fn set_pulses(&mut self, pulses_half_us: &[u16; 12]) {
        self.writes.push(*pulses_half_us);
    }
    fn set_enabled(&mut self, enabled: bool) {
        self.enabled = enabled;
        self.enables.push(enabled);
    }
}

/// A clock the test sets.
#[derive(Debug, Clone, Default)]
pub struct TestClock(pub Rc<Cell<u32>>);

impl TestClock {
    pub fn set(&self, ms: u32) {
        self.0.set(ms);
    }
}

impl Clock for TestClock {
    fn now_ms(&self) -> u32 {
        self.0.get()
    }
}

/// RAM "EEPROM" (erased = 0xFF). With `budget = Some(n)`, the power fails after `n` more
/// bytes: later writes write nothing and fail.
#[derive(Debug, Clone)]
pub struct Mem {
    pub bytes: Vec<u8>,
    pub budget: Option<usize>,
    pub written: usize,
}

impl Mem {
    pub fn erased() -> Mem {
        Mem {
            bytes: vec![0xFF; STORAGE_LEN as usize],
            budget: None,
            written: 0,
        }
    }
}

#[derive(Debug, PartialEq, Eq)]
pub struct PowerCut;

impl Storage for Mem {
    type Error = PowerCut;
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), PowerCut> {
        let a = addr as usize;
        buf.copy_from_slice(&self.bytes[a..a + buf.len()]);
        Ok(())
    }
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), PowerCut> {
        for (i, &b) in data.iter().enumerate() {
            if let Some(budget) = &mut self.budget {
                if *budget == 0 {
                    return Err(PowerCut);
                }
                *budget -= 1;
            }
            self.bytes[addr as usize + i] = b;
            self.written += 1;
        }
        Ok(())
    }
}

pub type Dev = Device<Outputs, TestClock, Mem>;

pub fn device(config: Config) -> Dev {
    Device::new(
        config,
        Outputs::default(),
        TestClock::default(),
        Mem::erased(),
    )
    .unwrap()
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
    for w in &dev.outputs().writes {
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
