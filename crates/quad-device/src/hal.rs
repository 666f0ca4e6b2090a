//! The three small traits a target implements: servo outputs, a millisecond clock and
//! calibration storage. The ATmega2560 firmware implements them on Timer1/3/4/5, a Timer2
//! tick and the EEPROM; the host simulator on plain memory.

/// Twelve servo outputs in kin-core's canonical order
/// `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`.
///
/// Pulse widths are in **half microseconds**, one 0.5 µs tick of a 16-bit timer with prescaler 8
/// at 16 MHz: the firmware writes them to the compare registers as they are (`OCRnx = pulse`).
/// The controller only ever passes pulses that lie within the servo's calibrated
/// `[2·min_us, 2·max_us]` (see [`quad_protocol::servo::Calibration`]); never 0, never garbage.
pub trait ServoOutputs {
    /// Sets the twelve pulse widths, half-µs. Takes effect from the next PWM period; an
    /// implementation should update all twelve in one go (interrupts off) so that a period
    /// never mixes two poses. Called while the outputs are enabled or right before enabling.
    fn set_pulses(&mut self, pulses_half_us: &[u16; 12]);

    /// Drives (`true`) or stops (`false`) all twelve outputs. Stopped outputs stay low: hobby
    /// servos then hold no torque. The controller starts with the outputs stopped and calls
    /// `set_enabled(false)` once at construction.
    fn set_enabled(&mut self, enabled: bool);

    /// The PWM periods begun so far (wrapping), for a controller that latches its servo frames
    /// to them: it then writes at most one new set of pulses per period, so that no pulse
    /// train skips a setpoint (two writes between two pulses would move a servo two limiter
    /// steps at once). `None` (the default): the outputs count no periods and the controller
    /// times its frames by its clock.
    fn periods_begun(&self) -> Option<u32> {
        None
    }

    /// True while the pulses written last have not been taken over by the start of a period
    /// (a new write now would replace them before any pulse showed them). Only asked when
    /// [`ServoOutputs::periods_begun`] counts.
    fn write_pending(&self) -> bool {
        false
    }
}

/// A monotonic millisecond clock. It may wrap at `u32::MAX` (49.7 days); the controller only
/// uses wrapping differences.
pub trait Clock {
    /// Milliseconds since an arbitrary origin.
    fn now_ms(&self) -> u32;
}

/// Byte-addressed non-volatile storage, EEPROM-like: any byte may be written at any time, a
/// power loss during [`Storage::write`] may leave any prefix of the data written.
///
/// The controller uses [`crate::store::STORAGE_LEN`] bytes from the base address of its
/// [`crate::Config`]. On the ATmega2560, `write` should skip bytes that already hold the value
/// (avr-libc's `eeprom_update_block`): an EEPROM byte takes 3.4 ms to write.
pub trait Storage {
    /// Why an access failed (address out of range, bus error, …).
    type Error;

    /// Reads `buf.len()` bytes from `addr`.
    ///
    /// # Errors
    /// When the bytes cannot be read.
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Self::Error>;

    /// Writes `data` at `addr`, in address order.
    ///
    /// # Errors
    /// When the bytes cannot be written; some may have been.
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), Self::Error>;
}

impl<T: ServoOutputs + ?Sized> ServoOutputs for &mut T {
    fn set_pulses(&mut self, pulses_half_us: &[u16; 12]) {
        (**self).set_pulses(pulses_half_us);
    }
    fn periods_begun(&self) -> Option<u32> {
        (**self).periods_begun()
    }
    fn write_pending(&self) -> bool {
        (**self).write_pending()
    }
    fn set_enabled(&mut self, enabled: bool) {
        (**self).set_enabled(enabled);
    }
}

impl<T: Clock + ?Sized> Clock for &T {
    fn now_ms(&self) -> u32 {
        (**self).now_ms()
    }
}

impl<T: Storage + ?Sized> Storage for &mut T {
    type Error = T::Error;
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), Self::Error> {
        (**self).read(addr, buf)
    }
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), Self::Error> {
        (**self).write(addr, data)
    }
}
