//! The watchdog: enabled at boot in reset mode, fed by the main loop.

use crate::pac;

/// WDTCSR bits.
const WDCE: u8 = 1 << 4;
const WDE: u8 = 1 << 3;

/// Watchdog timeout (the watchdog's own 128 kHz oscillator; ±10 % on real parts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timeout {
    /// 16 ms.
    Ms16 = 0b000,
    /// 125 ms.
    Ms125 = 0b011,
    /// 250 ms.
    Ms250 = 0b100,
    /// 500 ms.
    Ms500 = 0b101,
    /// 1 s.
    S1 = 0b110,
}

/// What caused the last reset (MCUSR, read and cleared at boot).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResetCause {
    /// The raw MCUSR bits: JTRF 4, WDRF 3, BORF 2, EXTRF 1, PORF 0.
    pub mcusr: u8,
}

impl ResetCause {
    /// True when the watchdog caused the reset.
    pub fn watchdog(self) -> bool {
        self.mcusr & (1 << 3) != 0
    }
}

/// Reads and clears MCUSR (WDRF must be cleared, or the watchdog cannot be reconfigured).
pub fn take_reset_cause(cpu: &pac::CPU) -> ResetCause {
    let mcusr = cpu.mcusr().read().bits();
    // Datasheet §12.5.1: each flag is cleared by writing zero to it.
    cpu.mcusr().write(|w| {
        w.porf()
            .clear_bit()
            .extrf()
            .clear_bit()
            .borf()
            .clear_bit()
            .wdrf()
            .clear_bit()
            .jtrf()
            .clear_bit()
    });
    ResetCause { mcusr }
}

/// The enabled watchdog.
pub struct Watchdog {
    _wdt: pac::WDT,
}

impl Watchdog {
    /// Enables the watchdog in system-reset mode with `timeout`.
    pub fn enable(wdt: pac::WDT, timeout: Timeout) -> Watchdog {
        let value = WDE | (timeout as u8 & 0b111);
        avr_device::interrupt::free(|_| {
            // The timed sequence: WDCE|WDE, then the new value within four cycles. Written in
            // assembly so that no instruction can come between the two stores.
            // SAFETY: WDTCSR is at data address 0x60; only the watchdog is affected.
            unsafe {
                core::arch::asm!(
                    "wdr",
                    "sts 0x60, {ce}",
                    "sts 0x60, {val}",
                    ce = in(reg) WDCE | WDE,
                    val = in(reg) value,
                    options(nostack),
                );
            }
        });
        Watchdog { _wdt: wdt }
    }

    /// Restarts the watchdog timer.
    #[inline(always)]
    pub fn feed(&mut self) {
        avr_device::asm::wdr();
    }
}
