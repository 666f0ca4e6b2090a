//! Millisecond clock on Timer2 (8-bit, CTC mode, prescaler 64, OCR2A = 249: 1 kHz).
//!
//! The binary forwards the `TIMER2_COMPA` interrupt to [`on_tick_interrupt`], which also gives
//! the servo outputs their chance to apply a staged state ([`crate::servo::on_tick`]) and the
//! sensor its periodic burst ([`crate::imu::on_tick`]).

use crate::pac;
use avr_device::interrupt::{self, Mutex};
use core::cell::Cell;

static MILLIS: Mutex<Cell<u32>> = Mutex::new(Cell::new(0));

/// Compare value for 1 ms at 16 MHz / 64: 250 counts.
const OCR_1MS: u8 = 249;

/// The running millisecond clock. Wraps after 2³² ms (49.7 days).
pub struct Clock {
    _tc2: pac::TC2,
}

impl Clock {
    /// Starts Timer2 at 1 kHz with its compare-A interrupt (interrupts must be enabled by the
    /// caller).
    pub fn new(tc2: pac::TC2) -> Clock {
        tc2.tccr2a().write(|w| w.wgm2().ctc());
        tc2.ocr2a().write(|w| w.set(OCR_1MS));
        tc2.tcnt2().write(|w| w.set(0));
        tc2.timsk2().write(|w| w.ocie2a().set_bit());
        tc2.tccr2b().write(|w| w.cs2().prescale_64());
        Clock { _tc2: tc2 }
    }

    /// Milliseconds since [`Clock::new`].
    pub fn now_ms(&self) -> u32 {
        now_ms()
    }
}

impl quad_device::Clock for Clock {
    fn now_ms(&self) -> u32 {
        now_ms()
    }
}

/// Milliseconds since the clock was started by [`Clock::new`] (0 before).
pub fn now_ms() -> u32 {
    interrupt::free(|cs| MILLIS.borrow(cs).get())
}

/// Advances the clock by one millisecond, then (with interrupts enabled again) starts the
/// sensor's burst when due and lets the servo outputs apply a staged state; call from the
/// `TIMER2_COMPA` interrupt.
///
/// Interrupts are re-enabled for the servo part because writing the twelve compare registers
/// takes longer than one byte time at 1 Mbaud: the receive interrupt must be able to come in
/// between. Nothing else of this handler runs then, and this handler itself cannot come again
/// before the next millisecond.
#[inline(always)]
pub fn on_tick_interrupt() {
    interrupt::free(|cs| {
        let c = MILLIS.borrow(cs);
        c.set(c.get().wrapping_add(1));
    });
    // SAFETY: the clock's state is updated; the servo code guards itself (`BUSY`) and touches
    // nothing the other handlers use; the sensor's tick starts a transfer only into an idle
    // slot, which the TWI handler does not touch (`crate::twi`).
    unsafe { interrupt::enable() };
    crate::imu::on_tick();
    crate::servo::on_tick();
}
