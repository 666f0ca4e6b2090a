//! In-memory implementations of the three [`hal`](crate::hal) traits (feature `sim`): the one
//! set of device fakes that the host's simulated link, the twin and the tests all use, in the
//! manner of `embedded-hal-mock`.
//!
//! - [`Outputs`]: twelve outputs that keep the last pulses written and count the writes;
//!   [`Outputs::logging`] also keeps every write and every enable, and [`Outputs::latched`] makes
//!   a write wait for the next PWM period of a [`PwmPeriods`] counter, as the firmware's timers
//!   do.
//! - [`VirtualClock`]: a clock its owner sets or advances (nanosecond resolution, read by the
//!   device in wrapping milliseconds); clones share one time.
//! - [`RamEeprom`]: bytes in RAM, erased to `0xFF`, with a power-cut budget on writes and a fault
//!   budget on reads.
//!
//! - [`imu`]: sources of inertial readings ([`imu::ImuSource`]) for the simulated device, the
//!   emulator's virtual MPU-6050 and the twin.
//!
//! What one user needs on top stays with it as a thin wrapper (the host's EEPROM image file,
//! the twin's frame-by-frame clock). Needs `alloc`; the firmware builds without the feature.

pub mod imu;

use crate::hal::{Clock, ServoOutputs, Storage};
use alloc::rc::Rc;
use alloc::vec;
use alloc::vec::Vec;
use core::cell::Cell;
use core::fmt;

/// Size of the ATmega2560's EEPROM, bytes: the size of [`RamEeprom::erased`].
pub const EEPROM_LEN: usize = 4096;

/// Nanoseconds per millisecond.
const NS_PER_MS: u64 = 1_000_000;

/// The PWM periods begun so far (wrapping), shared between the test or simulator that lets
/// them pass and the [`Outputs::latched`] outputs that latch their writes to them. Clones share
/// one counter.
#[derive(Debug, Clone, Default)]
pub struct PwmPeriods(Rc<Cell<u32>>);

impl PwmPeriods {
    /// A counter at `periods` periods begun.
    pub fn starting_at(periods: u32) -> PwmPeriods {
        PwmPeriods(Rc::new(Cell::new(periods)))
    }

    /// The periods begun so far.
    pub fn count(&self) -> u32 {
        self.0.get()
    }

    /// One more period begins: a pending write is taken over.
    pub fn begin(&self) {
        self.0.set(self.0.get().wrapping_add(1));
    }
}

/// Every write and every enable, in order (for [`Outputs::logging`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
struct Log {
    writes: Vec<[u16; 12]>,
    enables: Vec<bool>,
}

/// The latch of [`Outputs::latched`]: the periods, and the period of the last write.
#[derive(Debug, Clone, Default)]
struct Latch {
    periods: PwmPeriods,
    written_in: Option<u32>,
}

/// Twelve simulated servo outputs: what is on the pins.
///
/// [`Outputs::default`] keeps the state and a count only, in constant memory (a simulator that
/// runs for hours); [`Outputs::logging`] also logs every call, for tests that check the sequence.
/// Without a latch, the outputs count no PWM periods and the device times its frames by its
/// clock ([`ServoOutputs::periods_begun`] is `None`).
#[derive(Debug, Clone, Default)]
pub struct Outputs {
    /// True while the outputs are driven.
    pub enabled: bool,
    /// The last pulses written, half-µs (zeros before the first write).
    pub pulses_half_us: [u16; 12],
    /// Number of `set_pulses` calls.
    pub write_count: u64,
    log: Option<Log>,
    latch: Option<Latch>,
}

impl Outputs {
    /// Outputs that also log every `set_pulses` and `set_enabled` call ([`Outputs::writes`],
    /// [`Outputs::enables`]).
    pub fn logging() -> Outputs {
        Outputs {
            log: Some(Log::default()),
            ..Outputs::default()
        }
    }

    /// These outputs with their writes latched to `periods`, as the firmware's: a write stays
    /// pending for the rest of the period it was made in.
    #[must_use]
    pub fn latched(self, periods: PwmPeriods) -> Outputs {
        Outputs {
            latch: Some(Latch {
                periods,
                written_in: None,
            }),
            ..self
        }
    }

    /// Every `set_pulses` call, in order.
    ///
    /// # Panics
    /// When the outputs were not made with [`Outputs::logging`] (they keep no log).
    pub fn writes(&self) -> &[[u16; 12]] {
        &self.log().writes
    }

    /// Every `set_enabled` call, in order.
    ///
    /// # Panics
    /// When the outputs were not made with [`Outputs::logging`] (they keep no log).
    pub fn enables(&self) -> &[bool] {
        &self.log().enables
    }

    fn log(&self) -> &Log {
        self.log
            .as_ref()
            .expect("these outputs keep no log: make them with Outputs::logging()")
    }
}

impl ServoOutputs for Outputs {
    fn set_pulses(&mut self, pulses_half_us: &[u16; 12]) {
        self.pulses_half_us = *pulses_half_us;
        self.write_count += 1;
        if let Some(log) = &mut self.log {
            log.writes.push(*pulses_half_us);
        }
        if let Some(latch) = &mut self.latch {
            latch.written_in = Some(latch.periods.count());
        }
    }

    fn set_enabled(&mut self, enabled: bool) {
        self.enabled = enabled;
        if let Some(log) = &mut self.log {
            log.enables.push(enabled);
        }
    }

    fn periods_begun(&self) -> Option<u32> {
        self.latch.as_ref().map(|latch| latch.periods.count())
    }

    fn write_pending(&self) -> bool {
        self.latch
            .as_ref()
            .is_some_and(|latch| latch.written_in == Some(latch.periods.count()))
    }
}

/// A clock that stands still until its owner sets or advances it. The time is kept in
/// nanoseconds (a simulator's virtual time); the device reads whole milliseconds, wrapping at
/// `u32::MAX` as on the target. Clones share one time: keep one, hand the other to the device.
#[derive(Debug, Clone, Default)]
pub struct VirtualClock(Rc<Cell<u64>>);

impl VirtualClock {
    /// The time, ns since the origin.
    pub fn now_ns(&self) -> u64 {
        self.0.get()
    }

    /// Sets the time, ns since the origin.
    pub fn set_ns(&self, t_ns: u64) {
        self.0.set(t_ns);
    }

    /// Sets the time to `t_ms` whole milliseconds.
    pub fn set_ms(&self, t_ms: u32) {
        self.set_ns(u64::from(t_ms) * NS_PER_MS);
    }

    /// Advances the time by `ms` milliseconds.
    pub fn advance_ms(&self, ms: u32) {
        self.set_ns(self.now_ns() + u64::from(ms) * NS_PER_MS);
    }
}

impl Clock for VirtualClock {
    fn now_ms(&self) -> u32 {
        // Wrapping, as on the device.
        (self.now_ns() / NS_PER_MS) as u32
    }
}

/// Why a simulated EEPROM access failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EepromError {
    /// The access reaches beyond the EEPROM's bytes.
    OutOfRange,
    /// The write budget was used up: the power failed; this byte and the later ones were not
    /// written.
    PowerCut,
    /// The read budget was used up: the read failed.
    ReadFault,
}

impl fmt::Display for EepromError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EepromError::OutOfRange => "EEPROM address out of range",
            EepromError::PowerCut => "power cut during an EEPROM write",
            EepromError::ReadFault => "EEPROM read failed",
        })
    }
}

impl core::error::Error for EepromError {}

/// A RAM "EEPROM": any byte may be written at any time; erased bytes read `0xFF`.
///
/// Faults, both off by default: with `write_budget = Some(n)` the power fails after `n` more
/// bytes (a write stops at the byte that finds the budget used up and fails, its earlier bytes
/// written); with `read_budget = Some(n)` the next `n` reads succeed and every later one fails.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RamEeprom {
    /// The bytes.
    pub bytes: Vec<u8>,
    /// Bytes that may still be written before the power fails (`None`: no power cut).
    pub write_budget: Option<usize>,
    /// Reads that may still succeed (`None`: every read succeeds).
    pub read_budget: Option<usize>,
    /// Bytes written so far.
    pub written: usize,
}

impl RamEeprom {
    /// An erased EEPROM of [`EEPROM_LEN`] bytes.
    pub fn erased() -> RamEeprom {
        RamEeprom::with_bytes(vec![0xFF; EEPROM_LEN])
    }

    /// An EEPROM holding `bytes` (its size is theirs), with no faults.
    pub fn with_bytes(bytes: Vec<u8>) -> RamEeprom {
        RamEeprom {
            bytes,
            write_budget: None,
            read_budget: None,
            written: 0,
        }
    }
}

impl Default for RamEeprom {
    fn default() -> Self {
        RamEeprom::erased()
    }
}

impl Storage for RamEeprom {
    type Error = EepromError;

    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), EepromError> {
        if let Some(budget) = &mut self.read_budget {
            *budget = budget.checked_sub(1).ok_or(EepromError::ReadFault)?;
        }
        let a = usize::from(addr);
        let src = self
            .bytes
            .get(a..a + buf.len())
            .ok_or(EepromError::OutOfRange)?;
        buf.copy_from_slice(src);
        Ok(())
    }

    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), EepromError> {
        let a = usize::from(addr);
        if a + data.len() > self.bytes.len() {
            return Err(EepromError::OutOfRange);
        }
        for (i, &b) in data.iter().enumerate() {
            if let Some(budget) = &mut self.write_budget {
                *budget = budget.checked_sub(1).ok_or(EepromError::PowerCut)?;
            }
            self.bytes[a + i] = b;
            self.written += 1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_power_cut_writes_the_bytes_before_it() {
        let mut e = RamEeprom::erased();
        e.write_budget = Some(2);
        assert_eq!(e.write(10, &[1, 2, 3]), Err(EepromError::PowerCut));
        assert_eq!(&e.bytes[10..13], &[1, 2, 0xFF]);
        assert_eq!(e.written, 2);
        assert_eq!(e.write(4096, &[0]), Err(EepromError::OutOfRange));
    }

    #[test]
    fn reads_fail_once_their_budget_is_used() {
        let mut e = RamEeprom::erased();
        e.read_budget = Some(1);
        let mut b = [0u8; 2];
        assert_eq!(e.read(0, &mut b), Ok(()));
        assert_eq!(b, [0xFF; 2]);
        assert_eq!(e.read(0, &mut b), Err(EepromError::ReadFault));
    }

    #[test]
    fn the_clock_wraps_its_milliseconds_and_clones_share_it() {
        let c = VirtualClock::default();
        let device_side = c.clone();
        c.set_ms(u32::MAX);
        c.advance_ms(3);
        assert_eq!(device_side.now_ms(), 2);
        c.set_ns(2_500_000);
        assert_eq!(device_side.now_ms(), 2);
    }

    #[test]
    fn a_latched_write_is_pending_until_the_next_period() {
        let periods = PwmPeriods::starting_at(7);
        let mut s = Outputs::logging().latched(periods.clone());
        assert_eq!(s.periods_begun(), Some(7));
        assert!(!s.write_pending());
        s.set_pulses(&[3000; 12]);
        assert!(s.write_pending());
        periods.begin();
        assert!(!s.write_pending());
        assert_eq!(s.writes(), &[[3000; 12]]);
        assert_eq!(Outputs::default().periods_begun(), None);
    }
}
