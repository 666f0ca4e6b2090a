//! Twelve servo outputs on the hardware output-compare units of the four 16-bit timers.
//!
//! Each timer runs in mode 14 (fast PWM, TOP = ICRn = 39,999) with prescaler 8: one tick is
//! 0.5 µs and the period 40,000 ticks = 20 ms (50 Hz). The compare units drive the pins
//! without software: no interrupt, no jitter under serial load.
//!
//! | channel | joint | timer unit | pin | Mega header |
//! |---|---|---|---|---|
//! | 0 | FL abduction | OC1A | PB5 | D11 |
//! | 1 | FL hip | OC1B | PB6 | D12 |
//! | 2 | FL knee | OC1C | PB7 | D13 (also the on-board LED) |
//! | 3 | FR abduction | OC3A | PE3 | D5 |
//! | 4 | FR hip | OC3B | PE4 | D2 |
//! | 5 | FR knee | OC3C | PE5 | D3 |
//! | 6 | RL abduction | OC4A | PH3 | D6 |
//! | 7 | RL hip | OC4B | PH4 | D7 |
//! | 8 | RL knee | OC4C | PH5 | D8 |
//! | 9 | RR abduction | OC5A | PL3 | D46 |
//! | 10 | RR hip | OC5B | PL4 | D45 |
//! | 11 | RR knee | OC5C | PL5 | D44 |
//!
//! Channel `3·leg + joint` follows kin-core's order (legs FL, FR, RL, RR; joints abduction,
//! hip, knee).
//!
//! **Outputs start disabled**: the pins are driven low and the compare units disconnected until
//! [`Servos::enable`]. A channel whose pulse width is 0 stays low even when enabled. Pulse
//! widths are double-buffered by the hardware (OCRn is taken over at the start of a period), so
//! a change never produces a runt or doubled pulse.

use crate::pac;
use embedded_hal::pwm::{ErrorKind, ErrorType, SetDutyCycle};

/// Number of servo channels.
pub const CHANNELS: usize = 12;

/// Timer ticks per period (ICRn + 1): 20 ms at 0.5 µs per tick.
pub const PERIOD_TICKS: u16 = 40_000;

/// Timer ticks per microsecond (16 MHz / prescaler 8).
pub const TICKS_PER_US: u16 = 2;

/// Period of the servo signal, µs.
pub const PERIOD_US: u32 = 20_000;

/// TCCRnA: WGMn1 (mode 14 = WGM 1110, low two bits `10`).
const TCCRA_MODE14: u8 = 0b0000_0010;
/// TCCRnB: WGMn3 | WGMn2 | CSn1 (prescaler 8).
const TCCRB_MODE14_PRESCALE8: u8 = 0b0001_1010;
/// COMnx = `10` (clear on compare match, set at BOTTOM) for unit A, B, C.
const COM_CLEAR: [u8; 3] = [0b1000_0000, 0b0010_0000, 0b0000_1000];

/// Pin bit of each compare output (A, B, C) of each timer: PB5-7, PE3-5, PH3-5, PL3-5.
const PIN_BIT: [[u8; 3]; 4] = [
    [1 << 5, 1 << 6, 1 << 7],
    [1 << 3, 1 << 4, 1 << 5],
    [1 << 3, 1 << 4, 1 << 5],
    [1 << 3, 1 << 4, 1 << 5],
];

/// All three pin bits of each timer.
const PIN_MASK: [u8; 4] = [
    PIN_BIT[0][0] | PIN_BIT[0][1] | PIN_BIT[0][2],
    PIN_BIT[1][0] | PIN_BIT[1][1] | PIN_BIT[1][2],
    PIN_BIT[2][0] | PIN_BIT[2][1] | PIN_BIT[2][2],
    PIN_BIT[3][0] | PIN_BIT[3][1] | PIN_BIT[3][2],
];

/// Why a pulse width was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The channel index is not below [`CHANNELS`].
    NoSuchChannel,
    /// The pulse is longer than one period ([`PERIOD_TICKS`]).
    PulseTooLong,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Error::NoSuchChannel => "no such servo channel",
            Error::PulseTooLong => "pulse longer than the 20 ms period",
        })
    }
}

impl core::error::Error for Error {}

impl embedded_hal::pwm::Error for Error {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// The four 16-bit timers as servo outputs.
pub struct Servos {
    tc1: pac::TC1,
    tc3: pac::TC3,
    tc4: pac::TC4,
    tc5: pac::TC5,
    portb: pac::PORTB,
    porte: pac::PORTE,
    porth: pac::PORTH,
    portl: pac::PORTL,
    /// Pulse width of each channel, ticks (0 = no pulse).
    pulse_ticks: [u16; CHANNELS],
    enabled: bool,
}

impl Servos {
    /// Takes the four timers and the four ports of their pins, drives the twelve pins low as
    /// outputs and starts the timers; outputs stay disabled (compare units disconnected) until
    /// [`Servos::enable`]. The other pins of the ports keep their state (PE0/PE1 belong to
    /// USART0, which overrides them).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        tc1: pac::TC1,
        tc3: pac::TC3,
        tc4: pac::TC4,
        tc5: pac::TC5,
        portb: pac::PORTB,
        porte: pac::PORTE,
        porth: pac::PORTH,
        portl: pac::PORTL,
    ) -> Servos {
        // Pins low first, then outputs: no glitch.
        // SAFETY (all `bits` writes below): every bit pattern is valid in PORTx/DDRx and in the
        // timer control registers; the values are the documented mode-14 settings.
        portb
            .portb()
            .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[0]) });
        porte
            .porte()
            .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[1]) });
        porth
            .porth()
            .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[2]) });
        portl
            .portl()
            .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[3]) });
        portb
            .ddrb()
            .modify(|r, w| unsafe { w.bits(r.bits() | PIN_MASK[0]) });
        porte
            .ddre()
            .modify(|r, w| unsafe { w.bits(r.bits() | PIN_MASK[1]) });
        porth
            .ddrh()
            .modify(|r, w| unsafe { w.bits(r.bits() | PIN_MASK[2]) });
        portl
            .ddrl()
            .modify(|r, w| unsafe { w.bits(r.bits() | PIN_MASK[3]) });

        macro_rules! init {
            ($tc:expr, $tccra:ident, $tccrb:ident, $icr:ident, $tcnt:ident) => {{
                $tc.$tccrb().write(|w| unsafe { w.bits(0) });
                $tc.$tccra().write(|w| unsafe { w.bits(TCCRA_MODE14) });
                $tc.$icr().write(|w| w.set(PERIOD_TICKS - 1));
                $tc.$tcnt().write(|w| w.set(0));
                $tc.$tccrb()
                    .write(|w| unsafe { w.bits(TCCRB_MODE14_PRESCALE8) });
            }};
        }
        init!(tc1, tccr1a, tccr1b, icr1, tcnt1);
        init!(tc3, tccr3a, tccr3b, icr3, tcnt3);
        init!(tc4, tccr4a, tccr4b, icr4, tcnt4);
        init!(tc5, tccr5a, tccr5b, icr5, tcnt5);

        Servos {
            tc1,
            tc3,
            tc4,
            tc5,
            portb,
            porte,
            porth,
            portl,
            pulse_ticks: [0; CHANNELS],
            enabled: false,
        }
    }

    /// True after [`Servos::enable`] and before [`Servos::disable`].
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Connects the compare units of every channel with a non-zero pulse width.
    pub fn enable(&mut self) {
        self.enabled = true;
        for t in 0..4 {
            self.apply_connections(t);
        }
    }

    /// Disconnects every compare unit: all twelve pins low from now on (a pulse in progress is
    /// cut short).
    pub fn disable(&mut self) {
        self.enabled = false;
        for t in 0..4 {
            self.apply_connections(t);
        }
    }

    /// The pulse width of `channel`, ticks (0: no pulse).
    pub fn pulse_ticks(&self, channel: usize) -> Option<u16> {
        self.pulse_ticks.get(channel).copied()
    }

    /// All twelve pulse widths, ticks.
    pub fn all_pulse_ticks(&self) -> [u16; CHANNELS] {
        self.pulse_ticks
    }

    /// Sets the pulse width of `channel` to `ticks` (0.5 µs each): high for exactly `ticks`
    /// ticks at the start of every period from the next period on; 0 keeps the pin low and
    /// [`PERIOD_TICKS`] keeps it high.
    pub fn set_pulse_ticks(&mut self, channel: usize, ticks: u16) -> Result<(), Error> {
        if channel >= CHANNELS {
            return Err(Error::NoSuchChannel);
        }
        if ticks > PERIOD_TICKS {
            return Err(Error::PulseTooLong);
        }
        let was_zero = self.pulse_ticks[channel] == 0;
        self.pulse_ticks[channel] = ticks;
        if ticks > 0 {
            // Fast PWM: the pin is high for OCR + 1 ticks; OCR = TOP keeps it high.
            self.write_ocr(channel, ticks - 1);
        }
        if was_zero != (ticks == 0) {
            self.apply_connections(channel / 3);
        }
        Ok(())
    }

    /// Sets all twelve pulse widths; nothing changes when any of them is refused.
    pub fn set_all_pulse_ticks(&mut self, ticks: &[u16; CHANNELS]) -> Result<(), Error> {
        if ticks.iter().any(|&t| t > PERIOD_TICKS) {
            return Err(Error::PulseTooLong);
        }
        for (channel, &t) in ticks.iter().enumerate() {
            self.set_pulse_ticks(channel, t)?;
        }
        Ok(())
    }

    /// One channel as an `embedded_hal::pwm::SetDutyCycle` (duty = pulse width in ticks,
    /// maximum [`PERIOD_TICKS`]).
    pub fn channel(&mut self, channel: usize) -> Result<Channel<'_>, Error> {
        if channel >= CHANNELS {
            return Err(Error::NoSuchChannel);
        }
        Ok(Channel {
            servos: self,
            index: channel as u8,
        })
    }

    fn write_ocr(&mut self, channel: usize, ocr: u16) {
        match channel {
            0 => self.tc1.ocr1a().write(|w| w.set(ocr)),
            1 => self.tc1.ocr1b().write(|w| w.set(ocr)),
            2 => self.tc1.ocr1c().write(|w| w.set(ocr)),
            3 => self.tc3.ocr3a().write(|w| w.set(ocr)),
            4 => self.tc3.ocr3b().write(|w| w.set(ocr)),
            5 => self.tc3.ocr3c().write(|w| w.set(ocr)),
            6 => self.tc4.ocr4a().write(|w| w.set(ocr)),
            7 => self.tc4.ocr4b().write(|w| w.set(ocr)),
            8 => self.tc4.ocr4c().write(|w| w.set(ocr)),
            9 => self.tc5.ocr5a().write(|w| w.set(ocr)),
            10 => self.tc5.ocr5b().write(|w| w.set(ocr)),
            _ => self.tc5.ocr5c().write(|w| w.set(ocr)),
        };
    }

    /// Writes TCCRnA of timer `t` (0..4) with the compare units of the channels that should
    /// drive their pins.
    fn apply_connections(&mut self, t: usize) {
        let mut v = TCCRA_MODE14;
        // Port bits of the disconnected channels of this timer.
        let mut low = 0u8;
        for (unit, com) in COM_CLEAR.iter().enumerate() {
            if self.enabled && self.pulse_ticks[3 * t + unit] != 0 {
                v |= com;
            } else {
                low |= PIN_BIT[t][unit];
            }
        }
        // SAFETY: mode-14 bits plus COM bits: a valid TCCRnA value; any PORTx value is valid.
        // Clearing the PORT bits after disconnecting is a no-op on the chip (the compare unit
        // never writes PORTx) and keeps simulators that model the output through PORTx right.
        match t {
            0 => {
                self.tc1.tccr1a().write(|w| unsafe { w.bits(v) });
                self.portb
                    .portb()
                    .modify(|r, w| unsafe { w.bits(r.bits() & !low) });
            }
            1 => {
                self.tc3.tccr3a().write(|w| unsafe { w.bits(v) });
                self.porte
                    .porte()
                    .modify(|r, w| unsafe { w.bits(r.bits() & !low) });
            }
            2 => {
                self.tc4.tccr4a().write(|w| unsafe { w.bits(v) });
                self.porth
                    .porth()
                    .modify(|r, w| unsafe { w.bits(r.bits() & !low) });
            }
            _ => {
                self.tc5.tccr5a().write(|w| unsafe { w.bits(v) });
                self.portl
                    .portl()
                    .modify(|r, w| unsafe { w.bits(r.bits() & !low) });
            }
        }
    }
}

/// Disconnects every compare unit (pins fall back to their PORT value, low). For the panic
/// handler, which cannot own the timers.
pub fn force_all_low(dp: &pac::Peripherals) {
    // SAFETY: mode-14 bits without COM bits: a valid TCCRnA value; any PORTx value is valid.
    dp.TC1.tccr1a().write(|w| unsafe { w.bits(TCCRA_MODE14) });
    dp.TC3.tccr3a().write(|w| unsafe { w.bits(TCCRA_MODE14) });
    dp.TC4.tccr4a().write(|w| unsafe { w.bits(TCCRA_MODE14) });
    dp.TC5.tccr5a().write(|w| unsafe { w.bits(TCCRA_MODE14) });
    dp.PORTB
        .portb()
        .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[0]) });
    dp.PORTE
        .porte()
        .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[1]) });
    dp.PORTH
        .porth()
        .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[2]) });
    dp.PORTL
        .portl()
        .modify(|r, w| unsafe { w.bits(r.bits() & !PIN_MASK[3]) });
}

/// One servo channel, borrowed from [`Servos`].
pub struct Channel<'a> {
    servos: &'a mut Servos,
    index: u8,
}

impl ErrorType for Channel<'_> {
    type Error = Error;
}

impl SetDutyCycle for Channel<'_> {
    fn max_duty_cycle(&self) -> u16 {
        PERIOD_TICKS
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Error> {
        self.servos.set_pulse_ticks(self.index as usize, duty)
    }
}
