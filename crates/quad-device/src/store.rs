//! Tables in non-volatile storage — the servo calibration, and since protocol 2.4 the robot —
//! each in two banks with a generation counter and a CRC, so that a power loss during a save
//! keeps the previous one. One bank machinery ([`Banks`]) serves both; what differs is the
//! payload ([`Payload`]): its magic, its length and how its bytes are read and checked.
//!
//! ## Layout of one bank
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 2 | magic, written **last** (calibration `51 CA`, robot `52 0B`) |
//! | 2 | 1 | layout version, 1 |
//! | 3 | 4 | generation, u32 little-endian |
//! | 7 | payload | the payload (below) |
//! | 7 + payload | 2 | CRC-16 ([`quad_protocol::crc`]) of bytes 2 ‥ 7 + payload, big-endian |
//!
//! | payload | bytes | bank | bank A at | bank B at | content |
//! |---|---|---|---|---|---|
//! | calibration ([`Table`]) | 12 × 15 = 180 | [`BANK_LEN`] = 189 | base | base + [`BANK_STRIDE`] (192) | one record per servo, canonical order (below) |
//! | robot ([`RobotImage`], 2.4) | 74 | 83 | base + [`ROBOT_OFFSET`] (384) | base + 384 + [`ROBOT_BANK_STRIDE`] (84) | the robot's wire bytes ([`quad_protocol::RobotDescription`], docs/protocol.md) |
//!
//! A servo record (15 bytes, little-endian): `zero_rad` f32, `reversed` u8 (0 or 1),
//! `us_per_rad` f32, `center_us` u16, `min_us` u16, `max_us` u16 — the fields of
//! [`Calibration`] in declaration order. [`USED_LEN`] bytes from the base address are used in
//! all (551 of the ATmega2560's 4096).
//!
//! ## Save
//! The save goes to the bank that does **not** hold the table loaded or saved last (the active
//! one), with the active generation + 1:
//! 1. the magic is overwritten with `00 00` — the bank is now invalid;
//! 2. version, generation, the payload and the CRC are written;
//! 3. the magic is written, its first byte then its second.
//!
//! 191 bytes in all for the calibration, 85 for the robot. The save takes effect with its
//! last byte: a power loss before it leaves that bank invalid (no complete magic: both bytes
//! were cleared in step 1) and the active bank untouched; after it, the new bank is complete
//! and has the higher generation.
//!
//! ## Load
//! A bank is valid when its magic, version and CRC match and every piece of the payload passes
//! its check ([`Payload::decode`]: for the calibration, [`Calibration::validate`] of every
//! record; the robot's is checked as a whole by its user, `quad_protocol::check_robot`). The
//! valid bank with the higher generation (serial-number arithmetic, so the counter may wrap)
//! wins; with no valid bank the caller keeps its defaults. Loading reads each bank twice
//! (verify, then copy) so that only [`PIECE_LEN`] bytes of buffer are needed.

use crate::hal::Storage;
use core::marker::PhantomData;
use quad_protocol::crc;
use quad_protocol::servo::Calibration;
use quad_protocol::RobotDescription;

/// Twelve servo calibrations, canonical order.
pub type Table = [Calibration; 12];

/// Magic bytes at the start of a valid calibration bank.
pub const MAGIC: [u8; 2] = [0x51, 0xCA];
/// Layout version of this module.
pub const LAYOUT_VERSION: u8 = 1;
/// Bytes of one servo record.
pub const RECORD_LEN: usize = 15;
/// Bytes before the payload: magic, version, generation.
pub const HEADER_LEN: usize = 7;
/// Bytes of one calibration bank.
pub const BANK_LEN: usize = HEADER_LEN + 12 * RECORD_LEN + 2;
/// Distance between the starts of calibration bank A and bank B, bytes.
pub const BANK_STRIDE: u16 = 192;
/// Storage bytes the calibration uses from the base address.
pub const STORAGE_LEN: u16 = BANK_STRIDE + BANK_LEN as u16;

/// Magic bytes at the start of a valid robot bank (since protocol 2.4).
pub const ROBOT_MAGIC: [u8; 2] = [0x52, 0x0B];
/// Where the robot's bank A starts, bytes after the base address: after the calibration's
/// banks.
pub const ROBOT_OFFSET: u16 = 384;
/// Bytes of one robot bank.
pub const ROBOT_BANK_LEN: usize = HEADER_LEN + RobotDescription::WIRE_LEN + 2;
/// Distance between the starts of robot bank A and bank B, bytes.
pub const ROBOT_BANK_STRIDE: u16 = 84;
/// Storage bytes used from the base address: the calibration's banks, then the robot's.
pub const USED_LEN: u16 = ROBOT_OFFSET + ROBOT_BANK_STRIDE + ROBOT_BANK_LEN as u16;

/// The most payload bytes read or written at a time (one servo record).
pub const PIECE_LEN: usize = RECORD_LEN;

const _: () = assert!(BANK_LEN <= BANK_STRIDE as usize);
const _: () = assert!(STORAGE_LEN <= ROBOT_OFFSET);
const _: () = assert!(ROBOT_BANK_LEN <= ROBOT_BANK_STRIDE as usize);

/// What a pair of banks holds: its magic and length, and how its bytes are written and read,
/// [`PIECE_LEN`] bytes at a time at most.
pub trait Payload {
    /// The magic of a valid bank.
    const MAGIC: [u8; 2];
    /// Payload bytes.
    const LEN: usize;
    /// Bytes per piece ([`Payload::encode`], [`Payload::decode`]), at most [`PIECE_LEN`]; the
    /// last piece may be shorter.
    const PIECE: usize;
    /// Writes the payload's bytes `[offset, offset + out.len())` into `out`.
    fn encode(&self, offset: usize, out: &mut [u8]);
    /// Checks the payload's bytes `[offset, offset + piece.len())`, and stores them in `out`
    /// when given; false when they are not valid.
    fn decode(out: Option<&mut Self>, offset: usize, piece: &[u8]) -> bool;
}

impl Payload for Table {
    const MAGIC: [u8; 2] = MAGIC;
    const LEN: usize = 12 * RECORD_LEN;
    const PIECE: usize = RECORD_LEN;

    fn encode(&self, offset: usize, out: &mut [u8]) {
        out.copy_from_slice(&encode_record(&self[offset / RECORD_LEN]));
    }

    fn decode(out: Option<&mut Self>, offset: usize, piece: &[u8]) -> bool {
        let Ok(record) = <&[u8; RECORD_LEN]>::try_from(piece) else {
            return false;
        };
        match decode_record(record) {
            Some(c) => {
                if let Some(table) = out {
                    table[offset / RECORD_LEN] = c;
                }
                true
            }
            None => false,
        }
    }
}

/// A robot's wire bytes as stored (since protocol 2.4): [`quad_protocol::RobotDescription`]'s
/// postcard form, [`RobotDescription::WIRE_LEN`] bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RobotImage(pub [u8; RobotDescription::WIRE_LEN]);

impl RobotImage {
    /// The wire bytes of `robot`.
    pub fn of(robot: &RobotDescription) -> RobotImage {
        RobotImage(robot.to_wire())
    }

    /// The robot these bytes hold; `None` when they are not one.
    pub fn robot(&self) -> Option<RobotDescription> {
        RobotDescription::from_wire(&self.0)
    }
}

impl Payload for RobotImage {
    const MAGIC: [u8; 2] = ROBOT_MAGIC;
    const LEN: usize = RobotDescription::WIRE_LEN;
    const PIECE: usize = PIECE_LEN;

    fn encode(&self, offset: usize, out: &mut [u8]) {
        out.copy_from_slice(&self.0[offset..offset + out.len()]);
    }

    fn decode(out: Option<&mut Self>, offset: usize, piece: &[u8]) -> bool {
        if let Some(image) = out {
            image.0[offset..offset + piece.len()].copy_from_slice(piece);
        }
        true
    }
}

/// One of the two banks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bank {
    /// At the base address.
    A,
    /// One stride after the base address.
    B,
}

impl Bank {
    /// The other bank.
    pub const fn other(self) -> Bank {
        match self {
            Bank::A => Bank::B,
            Bank::B => Bank::A,
        }
    }
}

/// Where a payload `P` lives and which bank holds the current one.
#[derive(Debug)]
pub struct Banks<P> {
    base: u16,
    stride: u16,
    /// The bank holding the last payload loaded or saved, and its generation.
    active: Option<(Bank, u32)>,
    payload: PhantomData<fn() -> P>,
}

// By hand: derives would ask `P` for the same traits.
impl<P> Clone for Banks<P> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<P> Copy for Banks<P> {}
impl<P> PartialEq for Banks<P> {
    fn eq(&self, other: &Self) -> bool {
        (self.base, self.stride, self.active) == (other.base, other.stride, other.active)
    }
}
impl<P> Eq for Banks<P> {}

/// The calibration's banks.
pub type Store = Banks<Table>;

/// The robot's banks (since protocol 2.4).
pub type RobotStore = Banks<RobotImage>;

/// Serializes one calibration record.
pub fn encode_record(c: &Calibration) -> [u8; RECORD_LEN] {
    let mut r = [0u8; RECORD_LEN];
    r[0..4].copy_from_slice(&c.zero_rad.to_le_bytes());
    r[4] = u8::from(c.reversed);
    r[5..9].copy_from_slice(&c.us_per_rad.to_le_bytes());
    r[9..11].copy_from_slice(&c.center_us.to_le_bytes());
    r[11..13].copy_from_slice(&c.min_us.to_le_bytes());
    r[13..15].copy_from_slice(&c.max_us.to_le_bytes());
    r
}

/// Reads one calibration record; `None` when the `reversed` byte is not 0 or 1 or the
/// calibration does not validate.
pub fn decode_record(r: &[u8; RECORD_LEN]) -> Option<Calibration> {
    let f32_at = |i: usize| f32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]]);
    let u16_at = |i: usize| u16::from_le_bytes([r[i], r[i + 1]]);
    let reversed = match r[4] {
        0 => false,
        1 => true,
        _ => return None,
    };
    let c = Calibration {
        zero_rad: f32_at(0),
        reversed,
        us_per_rad: f32_at(5),
        center_us: u16_at(9),
        min_us: u16_at(11),
        max_us: u16_at(13),
    };
    c.validate().ok().map(|()| c)
}

/// True when generation `a` is newer than `b` (serial-number arithmetic).
const fn newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

impl Banks<Table> {
    /// The calibration's banks at `base` (not read yet).
    pub const fn new(base: u16) -> Store {
        Banks::at(base, BANK_STRIDE)
    }
}

impl Banks<RobotImage> {
    /// The robot's banks of a device whose storage starts at `base` (at `base` +
    /// [`ROBOT_OFFSET`]; not read yet).
    pub const fn robot(base: u16) -> RobotStore {
        Banks::at(base.wrapping_add(ROBOT_OFFSET), ROBOT_BANK_STRIDE)
    }
}

impl<P: Payload> Banks<P> {
    /// Bytes of one bank.
    pub const BANK_LEN: usize = HEADER_LEN + P::LEN + 2;

    /// Banks at `base` and `base + stride`, not read yet.
    pub const fn at(base: u16, stride: u16) -> Banks<P> {
        Banks {
            base,
            stride,
            active: None,
            payload: PhantomData,
        }
    }

    /// The active bank and its generation, if a valid payload was loaded or saved.
    pub const fn active(&self) -> Option<(Bank, u32)> {
        self.active
    }

    /// Address of a bank.
    pub const fn bank_addr(&self, bank: Bank) -> u16 {
        match bank {
            Bank::A => self.base,
            Bank::B => self.base.wrapping_add(self.stride),
        }
    }

    /// The generation of `bank` when it holds a valid payload; each piece read is also
    /// decoded into `out` when given (whatever the verdict: the pieces before a bad one stay
    /// there).
    fn verify<S: Storage>(
        &self,
        storage: &mut S,
        bank: Bank,
        mut out: Option<&mut P>,
    ) -> Option<u32> {
        let addr = self.bank_addr(bank);
        let mut header = [0u8; HEADER_LEN];
        storage.read(addr, &mut header).ok()?;
        if header[0..2] != P::MAGIC || header[2] != LAYOUT_VERSION {
            return None;
        }
        let generation = u32::from_le_bytes([header[3], header[4], header[5], header[6]]);
        let mut sum = crc::update_slice(crc::INIT, &header[2..]);
        let mut buf = [0u8; PIECE_LEN];
        let mut offset = 0;
        while offset < P::LEN {
            let piece = &mut buf[..P::PIECE.min(P::LEN - offset)];
            storage
                .read(addr + (HEADER_LEN + offset) as u16, piece)
                .ok()?;
            if !P::decode(out.as_deref_mut(), offset, piece) {
                return None;
            }
            sum = crc::update_slice(sum, piece);
            offset += piece.len();
        }
        let mut stored = [0u8; 2];
        storage
            .read(addr + (Self::BANK_LEN - 2) as u16, &mut stored)
            .ok()?;
        (u16::from_be_bytes(stored) == sum).then_some(generation)
    }

    /// Reads the newest valid payload into `out` and makes its bank the active one. Returns
    /// `false` when neither bank holds a valid one (`out` is then as it was) or when the
    /// chosen bank does not read back the same on the second pass that loads it (unreliable
    /// storage: `out` may then be partly overwritten, and the caller fills it otherwise).
    /// The second pass verifies again while it loads: one reading loop for both.
    pub fn load<S: Storage>(&mut self, storage: &mut S, out: &mut P) -> bool {
        let a = self.verify(storage, Bank::A, None);
        let b = self.verify(storage, Bank::B, None);
        let bank = match (a, b) {
            (Some(ga), Some(gb)) if newer(gb, ga) => Bank::B,
            (Some(_), _) => Bank::A,
            (None, Some(_)) => Bank::B,
            (None, None) => return false,
        };
        match self.verify(storage, bank, Some(out)) {
            Some(generation) => {
                self.active = Some((bank, generation));
                true
            }
            None => false,
        }
    }

    /// Saves `payload` to the inactive bank (see the module docs for the order of the writes)
    /// and makes it the active one.
    ///
    /// # Errors
    /// The storage's error; the active bank is untouched and stays active.
    pub fn save<S: Storage>(&mut self, storage: &mut S, payload: &P) -> Result<(), S::Error> {
        let (bank, generation) = match self.active {
            Some((bank, generation)) => (bank.other(), generation.wrapping_add(1)),
            None => (Bank::A, 1),
        };
        let addr = self.bank_addr(bank);
        storage.write(addr, &[0x00, 0x00])?;
        let mut head = [0u8; HEADER_LEN - 2];
        head[0] = LAYOUT_VERSION;
        head[1..].copy_from_slice(&generation.to_le_bytes());
        storage.write(addr + 2, &head)?;
        let mut sum = crc::update_slice(crc::INIT, &head);
        let mut buf = [0u8; PIECE_LEN];
        let mut offset = 0;
        while offset < P::LEN {
            let piece = &mut buf[..P::PIECE.min(P::LEN - offset)];
            payload.encode(offset, piece);
            storage.write(addr + (HEADER_LEN + offset) as u16, piece)?;
            sum = crc::update_slice(sum, piece);
            offset += piece.len();
        }
        storage.write(addr + (Self::BANK_LEN - 2) as u16, &sum.to_be_bytes())?;
        storage.write(addr, &P::MAGIC)?;
        self.active = Some((bank, generation));
        Ok(())
    }
}

const _: () = assert!(Banks::<Table>::BANK_LEN == BANK_LEN);
const _: () = assert!(Banks::<RobotImage>::BANK_LEN == ROBOT_BANK_LEN);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::RamEeprom;

    #[test]
    fn record_round_trip_and_rejects() {
        let c = Calibration {
            zero_rad: -0.25,
            reversed: true,
            us_per_rad: 600.0,
            center_us: 1490,
            min_us: 800,
            max_us: 2200,
        };
        assert_eq!(decode_record(&encode_record(&c)), Some(c));
        let mut bad = encode_record(&c);
        bad[4] = 2;
        assert_eq!(decode_record(&bad), None);
        let erased = [0xFF; RECORD_LEN];
        assert_eq!(decode_record(&erased), None);
    }

    #[test]
    fn saves_alternate_banks_and_generations_grow() {
        let mut mem = RamEeprom::erased();
        let mut store = Store::new(0);
        let mut table = [Calibration::STANDARD; 12];
        assert!(!store.load(&mut mem, &mut table));
        for n in 1..=4u32 {
            table[0].center_us = 1400 + n as u16;
            store.save(&mut mem, &table).unwrap();
            let expected = if n % 2 == 1 { Bank::A } else { Bank::B };
            assert_eq!(store.active(), Some((expected, n)));
            let mut fresh = Store::new(0);
            let mut back = [Calibration::STANDARD; 12];
            assert!(fresh.load(&mut mem, &mut back));
            assert_eq!(back, table);
            assert_eq!(fresh.active(), Some((expected, n)));
        }
    }

    #[test]
    fn a_bank_that_fails_on_the_loading_pass_is_not_loaded() {
        let mut mem = RamEeprom::erased();
        let mut table = [Calibration::STANDARD; 12];
        table[0].center_us = 1400;
        Store::new(0).save(&mut mem, &table).unwrap();
        // A pass over a valid bank reads the header, twelve records and the CRC; over the
        // erased bank B only the header. Then the loading pass fails after three records.
        let mut flaky = mem;
        flaky.read_budget = Some(14 + 1 + 4);
        let mut store = Store::new(0);
        let mut back = [Calibration::STANDARD; 12];
        assert!(!store.load(&mut flaky, &mut back));
        assert_eq!(store.active(), None);
        flaky.read_budget = None;
        assert!(store.load(&mut flaky, &mut back));
        assert_eq!(back, table);
    }

    #[test]
    fn generation_wraps() {
        assert!(newer(0, u32::MAX));
        assert!(!newer(u32::MAX, 0));
        assert!(newer(5, 4));
    }
}
