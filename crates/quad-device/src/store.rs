//! The servo calibration table in non-volatile storage: two banks, a generation counter and a
//! CRC, so that a power loss during a save keeps the previous calibration.
//!
//! ## Layout of one bank ([`BANK_LEN`] = 189 bytes)
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 2 | magic `51 CA`, written **last** |
//! | 2 | 1 | layout version, 1 |
//! | 3 | 4 | generation, u32 little-endian |
//! | 7 | 12 × 15 | one record per servo, canonical order (below) |
//! | 187 | 2 | CRC-16 ([`quad_protocol::crc`]) of bytes 2‥187, big-endian |
//!
//! A servo record (15 bytes, little-endian): `zero_rad` f32, `reversed` u8 (0 or 1),
//! `us_per_rad` f32, `center_us` u16, `min_us` u16, `max_us` u16 — the fields of
//! [`Calibration`] in declaration order.
//!
//! Bank A starts at the base address, bank B [`BANK_STRIDE`] bytes later.
//!
//! ## Save
//! The save goes to the bank that does **not** hold the calibration loaded or saved last (the
//! active one), with the active generation + 1:
//! 1. the magic is overwritten with `00 00` — the bank is now invalid;
//! 2. version, generation, the twelve records and the CRC are written;
//! 3. the magic is written, `51` then `CA`.
//!
//! 191 bytes in all. The save takes effect with its last byte: a power loss before it leaves
//! that bank invalid (no complete magic: both bytes were cleared in step 1) and the active bank
//! untouched; after it, the new bank is complete and has the higher generation.
//!
//! ## Load
//! A bank is valid when its magic, version and CRC match and every record passes
//! [`Calibration::validate`]. The valid bank with the higher generation (serial-number
//! arithmetic, so the counter may wrap) wins; with no valid bank the caller keeps its defaults.
//! Loading reads each bank twice (verify, then copy) so that only 15 bytes of buffer are needed.

use crate::hal::Storage;
use quad_protocol::crc;
use quad_protocol::servo::Calibration;

/// Twelve servo calibrations, canonical order.
pub type Table = [Calibration; 12];

/// Magic bytes at the start of a valid bank.
pub const MAGIC: [u8; 2] = [0x51, 0xCA];
/// Layout version of this module.
pub const LAYOUT_VERSION: u8 = 1;
/// Bytes of one servo record.
pub const RECORD_LEN: usize = 15;
/// Bytes before the first record: magic, version, generation.
pub const HEADER_LEN: usize = 7;
/// Bytes of one bank.
pub const BANK_LEN: usize = HEADER_LEN + 12 * RECORD_LEN + 2;
/// Distance between the starts of bank A and bank B, bytes.
pub const BANK_STRIDE: u16 = 192;
/// Storage bytes used from the base address.
pub const STORAGE_LEN: u16 = BANK_STRIDE + BANK_LEN as u16;

const _: () = assert!(BANK_LEN <= BANK_STRIDE as usize);

/// One of the two banks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bank {
    /// At the base address.
    A,
    /// [`BANK_STRIDE`] bytes after the base address.
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

/// Where the table lives and which bank holds the current one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Store {
    base: u16,
    /// The bank holding the last calibration loaded or saved, and its generation.
    active: Option<(Bank, u32)>,
}

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

impl Store {
    /// A store at `base` whose banks have not been read yet.
    pub const fn new(base: u16) -> Store {
        Store { base, active: None }
    }

    /// The active bank and its generation, if a valid table was loaded or saved.
    pub const fn active(&self) -> Option<(Bank, u32)> {
        self.active
    }

    /// Address of a bank.
    pub const fn bank_addr(&self, bank: Bank) -> u16 {
        match bank {
            Bank::A => self.base,
            Bank::B => self.base.wrapping_add(BANK_STRIDE),
        }
    }

    /// The generation of `bank` when it holds a valid table; each record read is also decoded
    /// into `out` when given (whatever the verdict: the records before a bad one stay there).
    fn verify<S: Storage>(
        &self,
        storage: &mut S,
        bank: Bank,
        mut out: Option<&mut Table>,
    ) -> Option<u32> {
        let addr = self.bank_addr(bank);
        let mut header = [0u8; HEADER_LEN];
        storage.read(addr, &mut header).ok()?;
        if header[0..2] != MAGIC || header[2] != LAYOUT_VERSION {
            return None;
        }
        let generation = u32::from_le_bytes([header[3], header[4], header[5], header[6]]);
        let mut sum = crc::update_slice(crc::INIT, &header[2..]);
        let mut record = [0u8; RECORD_LEN];
        for i in 0..12u16 {
            let at = addr + HEADER_LEN as u16 + i * RECORD_LEN as u16;
            storage.read(at, &mut record).ok()?;
            let c = decode_record(&record)?;
            if let Some(table) = out.as_deref_mut() {
                table[usize::from(i)] = c;
            }
            sum = crc::update_slice(sum, &record);
        }
        let mut stored = [0u8; 2];
        storage
            .read(addr + (BANK_LEN - 2) as u16, &mut stored)
            .ok()?;
        (u16::from_be_bytes(stored) == sum).then_some(generation)
    }

    /// Reads the newest valid table into `table` and makes its bank the active one. Returns
    /// `false` when neither bank holds a valid table (`table` is then as it was) or when the
    /// chosen bank does not read back the same on the second pass that loads it (unreliable
    /// storage: `table` may then be partly overwritten, and the caller fills it otherwise).
    /// The second pass verifies again while it loads: one reading loop for both.
    pub fn load<S: Storage>(&mut self, storage: &mut S, table: &mut Table) -> bool {
        let a = self.verify(storage, Bank::A, None);
        let b = self.verify(storage, Bank::B, None);
        let bank = match (a, b) {
            (Some(ga), Some(gb)) if newer(gb, ga) => Bank::B,
            (Some(_), _) => Bank::A,
            (None, Some(_)) => Bank::B,
            (None, None) => return false,
        };
        match self.verify(storage, bank, Some(table)) {
            Some(generation) => {
                self.active = Some((bank, generation));
                true
            }
            None => false,
        }
    }

    /// Saves `table` to the inactive bank (see the module docs for the order of the writes) and
    /// makes it the active one.
    ///
    /// # Errors
    /// The storage's error; the active bank is untouched and stays active.
    pub fn save<S: Storage>(&mut self, storage: &mut S, table: &Table) -> Result<(), S::Error> {
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
        for (i, c) in table.iter().enumerate() {
            let record = encode_record(c);
            storage.write(addr + (HEADER_LEN + i * RECORD_LEN) as u16, &record)?;
            sum = crc::update_slice(sum, &record);
        }
        storage.write(addr + (BANK_LEN - 2) as u16, &sum.to_be_bytes())?;
        storage.write(addr, &MAGIC)?;
        self.active = Some((bank, generation));
        Ok(())
    }
}

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
