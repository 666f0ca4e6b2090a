//! The ATmega2560's 4 KiB EEPROM as the device controller's calibration storage
//! ([`quad_device::Storage`]).
//!
//! - **Read**: immediate (4 cycles per byte).
//! - **Write**: one byte takes 3.3–3.4 ms (the EEPROM's own timing). [`Eeprom`] skips bytes that
//!   already hold the value (as avr-libc's `eeprom_update_block`), so rewriting an unchanged
//!   calibration costs nothing. A whole calibration save (191 bytes) takes about 650 ms, longer
//!   than the watchdog timeout: the wait after each byte **feeds the watchdog**.
//! - **Waiting**: the EEPROM-ready interrupt (`EE_READY`) is enabled together with the write and
//!   ends the wait; the handler disables it again (the interrupt is level-triggered: it would
//!   fire continuously while the EEPROM is idle). A wait that lasts [`WRITE_TIMEOUT_MS`] ends
//!   the write with [`Error::Timeout`] unless the EEPROM reports idle by then.
//!
//! The binary forwards the `EE_READY` interrupt to [`on_ready_interrupt`]; the millisecond clock
//! ([`crate::clock`]) must be running.

use crate::pac;
use avr_device::interrupt::{self, Mutex};
use core::cell::Cell;

/// Size of the EEPROM, bytes.
pub const SIZE: u16 = 4096;

/// Longest wait for one byte to be written, ms (the datasheet's 3.3 ms with a wide margin).
pub const WRITE_TIMEOUT_MS: u32 = 10;

/// Set by the `EE_READY` handler when the byte being written is done.
static WRITE_DONE: Mutex<Cell<bool>> = Mutex::new(Cell::new(true));

/// Why an EEPROM access failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The access reaches beyond the last byte ([`SIZE`]).
    OutOfRange,
    /// A byte was still being written after [`WRITE_TIMEOUT_MS`].
    Timeout,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Error::OutOfRange => "EEPROM address out of range",
            Error::Timeout => "EEPROM write did not complete",
        })
    }
}

impl core::error::Error for Error {}

/// The EEPROM.
pub struct Eeprom {
    ee: pac::EEPROM,
    /// Bytes written (not skipped) since boot.
    written: u32,
}

impl Eeprom {
    /// Takes the EEPROM peripheral.
    pub fn new(ee: pac::EEPROM) -> Eeprom {
        Eeprom { ee, written: 0 }
    }

    /// Bytes physically written since boot (unchanged bytes are skipped and not counted).
    pub fn bytes_written(&self) -> u32 {
        self.written
    }

    fn check_range(addr: u16, len: usize) -> Result<(), Error> {
        if u32::from(addr) + len as u32 > u32::from(SIZE) {
            Err(Error::OutOfRange)
        } else {
            Ok(())
        }
    }

    fn busy(&self) -> bool {
        self.ee.eecr().read().eepe().bit_is_set()
    }

    fn read_byte(&mut self, addr: u16) -> u8 {
        while self.busy() {}
        self.ee.eear().write(|w| w.set(addr));
        self.ee.eecr().write(|w| w.eere().set_bit());
        self.ee.eedr().read().bits()
    }

    /// Writes one byte and waits (feeding the watchdog) until it is done.
    fn write_byte(&mut self, addr: u16, value: u8) -> Result<(), Error> {
        while self.busy() {
            avr_device::asm::wdr();
        }
        interrupt::free(|cs| {
            WRITE_DONE.borrow(cs).set(false);
            self.ee.eear().write(|w| w.set(addr));
            self.ee.eedr().write(|w| w.set(value));
            // EERIE first (with interrupts off, the ready interrupt cannot fire yet; once EEPE
            // is set it is no longer ready), then the timed sequence: EEMPE, and EEPE within
            // four cycles. `sbi` on EECR (I/O address 0x1F) keeps the two stores adjacent.
            // SAFETY: only EECR changes; the address and data registers are set above and the
            // previous write has completed (EEPE clear).
            unsafe {
                core::arch::asm!(
                    "sbi 0x1f, 3",
                    "sbi 0x1f, 2",
                    "sbi 0x1f, 1",
                    options(nostack, preserves_flags),
                );
            }
        });
        self.written = self.written.wrapping_add(1);
        let start_ms = crate::clock::now_ms();
        loop {
            avr_device::asm::wdr();
            if interrupt::free(|cs| WRITE_DONE.borrow(cs).get()) {
                return Ok(());
            }
            if crate::clock::now_ms().wrapping_sub(start_ms) > WRITE_TIMEOUT_MS {
                // The interrupt did not come: trust the EEPROM's own busy bit.
                self.ee.eecr().modify(|_, w| w.eerie().clear_bit());
                return if self.busy() {
                    Err(Error::Timeout)
                } else {
                    Ok(())
                };
            }
        }
    }
}

impl quad_device::Storage for Eeprom {
    type Error = Error;

    // Out of line: the calibration store reads at several places (headers, records, CRCs),
    // each of which would otherwise hold its own copy of the range check and the byte loop.
    #[inline(never)]
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Error> {
        Self::check_range(addr, buf.len())?;
        for (i, b) in buf.iter_mut().enumerate() {
            *b = self.read_byte(addr + i as u16);
        }
        Ok(())
    }

    /// Writes in address order, skipping bytes that already hold their value.
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), Error> {
        Self::check_range(addr, data.len())?;
        for (i, &v) in data.iter().enumerate() {
            let a = addr + i as u16;
            if self.read_byte(a) != v {
                self.write_byte(a, v)?;
            }
        }
        Ok(())
    }
}

/// Ends the wait for a byte; call from the `EE_READY` interrupt.
#[inline(always)]
pub fn on_ready_interrupt() {
    // SAFETY: only EERIE in EECR is cleared (the EEPROM is idle when this interrupt runs, so
    // the read-modify-write cannot start a write).
    let ee = unsafe { pac::EEPROM::steal() };
    ee.eecr().modify(|_, w| w.eerie().clear_bit());
    interrupt::free(|cs| WRITE_DONE.borrow(cs).set(true));
}
