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
//!
//! **Whole poses per period, without waiting.** The four timers are started together (the
//! synchronous prescaler reset of GTCCR) and run in lockstep. [`Servos::set_all_pulse_ticks`],
//! [`Servos::enable`] and [`Servos::disable`] stage the outputs' next state and return; the
//! state is written (per timer: its three compare registers, then its compare-unit
//! connections) between the end of the longest pulse and the last [`WRITE_GUARD_TICKS`] of a
//! period — at once when the call falls there, else by the Timer2 millisecond interrupt
//! ([`on_tick`]) at the first tick that does. Each timer's check of its count and its writes
//! form one short interrupts-off stretch (a few dozen cycles), so no interrupt can carry a
//! write past the window: switching never cuts a pulse short or starts one late. An apply
//! begins only with a millisecond of the window left, so every period shows either the old or
//! the new widths on all twelve pins; the main loop never waits for the window.
//!
//! **Periods counted.** The tick interrupt counts the PWM periods (Timer1's overflow flag, set
//! at TOP) and notes the period in which a staged state was written; the controller latches its
//! servo frames to them (`quad_device::ServoOutputs::periods_begun`, `write_pending`), so that
//! each period gets at most one new state and no setpoint is replaced before a pulse showed it.

use crate::pac;
use core::cell::{Cell, UnsafeCell};
use core::sync::atomic::{compiler_fence, Ordering};
use embedded_hal::pwm::{ErrorKind, ErrorType, SetDutyCycle};

/// Number of servo channels.
pub const CHANNELS: usize = 12;

/// Timer ticks per period (ICRn + 1): 20 ms at 0.5 µs per tick.
pub const PERIOD_TICKS: u16 = 40_000;

/// Timer ticks per microsecond (16 MHz / prescaler 8).
pub const TICKS_PER_US: u16 = 2;

/// Period of the servo signal, µs.
pub const PERIOD_US: u32 = 20_000;

/// Ticks at the end of each period in which the compare registers are not written: one timer's
/// writes after its window check (interrupts are off in between), plus timers that are a few
/// ticks apart (as in simulators that ignore GTCCR).
pub const WRITE_GUARD_TICKS: u16 = 64;

/// Ticks of the window that must remain for an apply to begin (1 ms): room for the writes of all
/// four timers, interrupts included, so that they switch in the same period.
const START_GUARD_TICKS: u16 = 2_000;

/// Ticks after the longest pulse before the compare units may be switched.
const QUIET_MARGIN_TICKS: u16 = 16;

/// WGMn1:0 of mode 14 (fast PWM, TOP = ICRn: WGMn3:0 = `1110`), the bits in TCCRnA; datasheet
/// §17.11, Table 17-2.
const WGM_LOW_MODE14: u8 = 0b10;
/// WGMn3:2 of mode 14, the bits in TCCRnB.
const WGM_HIGH_MODE14: u8 = 0b11;

/// Which of a timer's three compare units (A, B, C) drive their pins: clear on compare match,
/// set at BOTTOM (COMnx = `10`, datasheet §17.11, Table 17-4). A unit that does not leaves its
/// pin to its PORT bit, held low. The pins: Timer1 PB5-7, Timer3 PE3-5, Timer4 PH3-5, Timer5
/// PL3-5 (Arduino Mega D11-13, D5/D2/D3, D6-8, D46-44).
type Connected = [bool; 3];

/// Writes TCCRnA of one timer — mode 14's low WGM bits and each compare unit connected or not
/// — then drives the pins of the units that are not connected low (when there are any).
macro_rules! connect {
    ($tc:expr, $tccra:ident, $wgm:ident, [$com_a:ident, $com_b:ident, $com_c:ident],
     $port:expr, $portx:ident, [$pin_a:ident, $pin_b:ident, $pin_c:ident], $on:expr) => {{
        let on: Connected = $on;
        $tc.$tccra().write(|w| {
            w.$wgm().set(WGM_LOW_MODE14);
            if on[0] {
                w.$com_a().match_clear();
            } else {
                w.$com_a().disconnected();
            }
            if on[1] {
                w.$com_b().match_clear();
            } else {
                w.$com_b().disconnected();
            }
            if on[2] {
                w.$com_c().match_clear()
            } else {
                w.$com_c().disconnected()
            }
        });
        if !(on[0] & on[1] & on[2]) {
            $port.$portx().modify(|r, w| {
                w.$pin_a()
                    .bit(r.$pin_a().bit() & on[0])
                    .$pin_b()
                    .bit(r.$pin_b().bit() & on[1])
                    .$pin_c()
                    .bit(r.$pin_c().bit() & on[2])
            });
        }
    }};
}

/// Timer `t`'s connections (0..4: Timer1, 3, 4, 5), see [`connect!`].
#[inline(always)]
fn apply_connections(dp: &pac::Peripherals, t: usize, on: Connected) {
    // Clearing the PORT bits after disconnecting is a no-op on the chip (the compare unit never
    // writes PORTx) and keeps simulators that model the output through PORTx right. The port is
    // written only when a channel is disconnected: such a simulator also drives every
    // connected pin of the port from PORTx on any write.
    match t {
        0 => connect!(
            dp.TC1,
            tccr1a,
            wgm1,
            [com1a, com1b, com1c],
            dp.PORTB,
            portb,
            [pb5, pb6, pb7],
            on
        ),
        1 => connect!(
            dp.TC3,
            tccr3a,
            wgm3,
            [com3a, com3b, com3c],
            dp.PORTE,
            porte,
            [pe3, pe4, pe5],
            on
        ),
        2 => connect!(
            dp.TC4,
            tccr4a,
            wgm4,
            [com4a, com4b, com4c],
            dp.PORTH,
            porth,
            [ph3, ph4, ph5],
            on
        ),
        _ => connect!(
            dp.TC5,
            tccr5a,
            wgm5,
            [com5a, com5b, com5c],
            dp.PORTL,
            portl,
            [pl3, pl4, pl5],
            on
        ),
    }
}

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

/// A value shared between the main loop and the Timer2 tick interrupt, written whole.
///
/// Bytes and the staged widths are plain volatile memory: a byte access is one instruction, and
/// the staging protocol ([`stage`]) keeps the widths from being read while they are written.
/// Not atomics: LLVM's AVR backend turns every atomic access into a `cli` stretch.
struct Shared<T>(UnsafeCell<T>);

// SAFETY: single core; the access rules are those of [`stage`] and [`apply_staged`]: the main
// loop writes the staged values only while `PENDING` is clear, the interrupt reads them only
// while it is set, and `BUSY` keeps the two appliers apart.
unsafe impl<T> Sync for Shared<T> {}

impl<T: Copy> Shared<T> {
    const fn new(v: T) -> Shared<T> {
        Shared(UnsafeCell::new(v))
    }

    #[inline(always)]
    fn get(&self) -> T {
        // SAFETY: see the `Sync` impl.
        unsafe { self.0.get().read_volatile() }
    }

    #[inline(always)]
    fn set(&self, v: T) {
        // SAFETY: see the `Sync` impl.
        unsafe { self.0.get().write_volatile(v) }
    }
}

/// The staged outputs: widths (ticks, 0 = off) and whether the outputs are on.
static STAGED_TICKS: Shared<[u16; CHANNELS]> = Shared::new([0; CHANNELS]);
static STAGED_ENABLED: Shared<bool> = Shared::new(false);
/// 1 while a staged state waits to be applied.
static PENDING: Shared<u8> = Shared::new(0);
/// 1 while the main loop applies (the tick interrupt then leaves it alone).
static BUSY: Shared<u8> = Shared::new(0);
/// PWM periods begun, wrapping (counted by the tick interrupt from Timer1's overflow flag,
/// which the chip sets at TOP, the end of each period).
static PERIODS: Shared<u8> = Shared::new(0);

/// The PWM periods begun, modulo 256 (counted by the clock's tick): the device runs a servo
/// frame in the first `Device::poll` after it changes.
pub fn periods_mod_256() -> u8 {
    PERIODS.get()
}
/// [`PERIODS`] when the last staged state was written to the registers: the chip takes it over
/// when the next period begins.
static APPLIED_IN: Shared<u8> = Shared::new(0);
/// The longest width the hardware may still be producing in this or the next period, ticks
/// (written by whoever applies, under `BUSY` or inside the interrupt).
static ACTIVE_LONGEST: Shared<u16> = Shared::new(0);

/// Publishes the outputs' next state: the widths and the enable of every channel. Applied at
/// once when no pulse is in progress and the period does not end soon, else by the next tick
/// of the millisecond clock that falls in such a moment (at most the longest pulse later):
/// the main loop never waits for the window.
fn stage(ticks: &[u16; CHANNELS], enabled: bool) {
    PENDING.set(0);
    compiler_fence(Ordering::SeqCst);
    STAGED_TICKS.set(*ticks);
    STAGED_ENABLED.set(enabled);
    compiler_fence(Ordering::SeqCst);
    PENDING.set(1);
    BUSY.set(1);
    compiler_fence(Ordering::SeqCst);
    apply_staged();
    compiler_fence(Ordering::SeqCst);
    BUSY.set(0);
}

/// Applies the staged state if one is pending and the moment is quiet (see `stage`); call
/// from the `TIMER2_COMPA` interrupt (with interrupts re-enabled: this takes longer than one
/// byte time at 1 Mbaud and needs no protection from the receive interrupt).
#[inline(never)]
pub fn on_tick() {
    count_period();
    // Nothing pending: return before `apply_staged` sets up its frame (this interrupt may come
    // on top of the main loop's deepest stack).
    if BUSY.get() != 0 || PENDING.get() == 0 {
        return;
    }
    BUSY.set(1);
    compiler_fence(Ordering::SeqCst);
    apply_staged();
    compiler_fence(Ordering::SeqCst);
    BUSY.set(0);
}

/// Counts a period when Timer1's overflow flag says one began, and clears the flag (a one
/// written clears it). Only the tick interrupt calls it: the millisecond tick sees every
/// period start within 1 ms, long before the longest pulse ends and a state can be applied.
#[inline(always)]
fn count_period() {
    // SAFETY: TIFR1 is touched only here; writing TOV1 alone leaves the other flags.
    let dp = unsafe { pac::Peripherals::steal() };
    if dp.TC1.tifr1().read().tov1().bit_is_set() {
        dp.TC1.tifr1().write(|w| w.tov1().set_bit());
        PERIODS.set(PERIODS.get().wrapping_add(1));
    }
}

/// Writes the staged widths and connections when a state is pending and every timer is in the
/// quiet part of its period: after the longest pulse (old or new) and before the last
/// [`WRITE_GUARD_TICKS`]. With pulses so long that no such moment exists, applies at once.
///
/// Each timer's registers are written in one short stretch with interrupts off that begins by
/// checking that timer's count: an interrupt can delay the writes, but never carry them past
/// the window, where a compare unit switched on or off would cut or start a pulse (and where a
/// simulator that applies compare registers at once would change the pulse in progress). The
/// apply starts only with [`START_GUARD_TICKS`] of the window left, so all four timers take the
/// new state in the same period; should interrupts ever delay the writes that long, the
/// remaining timers keep their state (each pin its old width) and follow at the next tick.
fn apply_staged() {
    if PENDING.get() == 0 {
        return;
    }
    compiler_fence(Ordering::SeqCst);
    let ticks = STAGED_TICKS.get();
    let enabled = STAGED_ENABLED.get();
    let longest_new = ticks.iter().copied().max().unwrap_or(0);
    let after = ACTIVE_LONGEST
        .get()
        .max(longest_new)
        .saturating_add(QUIET_MARGIN_TICKS);
    let before = PERIOD_TICKS - WRITE_GUARD_TICKS;
    let connections: [Connected; 4] = core::array::from_fn(|t| connection(t, enabled, &ticks));
    // SAFETY: after `Servos::new` the timers' compare and control registers and the servo
    // bits of the ports are written only here, under `BUSY` (or by the panic handler, which
    // never returns).
    let dp = unsafe { pac::Peripherals::steal() };
    // No quiet moment: every timer is written at once.
    let at_once = after >= before;
    if !at_once {
        let start_before = before.saturating_sub(START_GUARD_TICKS).max(after);
        if !(0..4).all(|t| in_window(tcnt(&dp, t), after, start_before)) {
            return;
        }
    }
    // One stretch per timer, each with its timer's registers as constants (a timer index
    // looked up inside the stretch made it longer than a byte time at 1 Mbaud); the same
    // writes at once, so that the firmware holds one copy of them.
    let written = write_in_window::<0>(&dp, &ticks, connections[0], after, before, at_once)
        && write_in_window::<1>(&dp, &ticks, connections[1], after, before, at_once)
        && write_in_window::<2>(&dp, &ticks, connections[2], after, before, at_once)
        && write_in_window::<3>(&dp, &ticks, connections[3], after, before, at_once);
    if !written {
        return;
    }
    ACTIVE_LONGEST.set(longest_new);
    APPLIED_IN.set(PERIODS.get());
    compiler_fence(Ordering::SeqCst);
    PENDING.set(0);
}

/// True when a timer count `t` is strictly between `after` and `before`.
#[inline(always)]
fn in_window(t: u16, after: u16, before: u16) -> bool {
    t > after && t < before
}

/// The count of timer `t` (0..4: Timer1, 3, 4, 5).
#[inline(always)]
fn tcnt(dp: &pac::Peripherals, t: usize) -> u16 {
    match t {
        0 => dp.TC1.tcnt1().read().bits(),
        1 => dp.TC3.tcnt3().read().bits(),
        2 => dp.TC4.tcnt4().read().bits(),
        _ => dp.TC5.tcnt5().read().bits(),
    }
}

/// Timer `T`'s writes — its three compare registers (channels with a non-zero width: fast
/// PWM keeps the pin high for OCR + 1 ticks, OCR = TOP high throughout) and its connections
/// ([`apply_connections`]) — in one interrupts-off stretch that begins by checking
/// that its count lies in `(after, before)` (or `at_once`, without that check); false (nothing
/// written) when it does not.
#[inline(always)]
fn write_in_window<const T: usize>(
    dp: &pac::Peripherals,
    ticks: &[u16; CHANNELS],
    connection: Connected,
    after: u16,
    before: u16,
    at_once: bool,
) -> bool {
    // The compare values before the stretch.
    let ocr: [u16; 3] = core::array::from_fn(|unit| ticks[3 * T + unit].wrapping_sub(1));
    let on: [bool; 3] = core::array::from_fn(|unit| ticks[3 * T + unit] > 0);
    // Not `interrupt::free`: its closure may be left out of line, and the call would lengthen
    // the stretch.
    let irq = avr_device::interrupt::disable_save();
    let inside = at_once || in_window(tcnt(dp, T), after, before);
    if inside {
        // Unit by unit, not a loop: each write with its register as a constant.
        if on[0] {
            write_ocr(dp, 3 * T, ocr[0]);
        }
        if on[1] {
            write_ocr(dp, 3 * T + 1, ocr[1]);
        }
        if on[2] {
            write_ocr(dp, 3 * T + 2, ocr[2]);
        }
        apply_connections(dp, T, connection);
    }
    // SAFETY: restores the interrupt flag saved above, at the end of the stretch it began.
    unsafe { avr_device::interrupt::restore(irq) };
    inside
}

#[inline(always)]
fn write_ocr(dp: &pac::Peripherals, channel: usize, ocr: u16) {
    match channel {
        0 => dp.TC1.ocr1a().write(|w| w.set(ocr)),
        1 => dp.TC1.ocr1b().write(|w| w.set(ocr)),
        2 => dp.TC1.ocr1c().write(|w| w.set(ocr)),
        3 => dp.TC3.ocr3a().write(|w| w.set(ocr)),
        4 => dp.TC3.ocr3b().write(|w| w.set(ocr)),
        5 => dp.TC3.ocr3c().write(|w| w.set(ocr)),
        6 => dp.TC4.ocr4a().write(|w| w.set(ocr)),
        7 => dp.TC4.ocr4b().write(|w| w.set(ocr)),
        8 => dp.TC4.ocr4c().write(|w| w.set(ocr)),
        9 => dp.TC5.ocr5a().write(|w| w.set(ocr)),
        10 => dp.TC5.ocr5b().write(|w| w.set(ocr)),
        _ => dp.TC5.ocr5c().write(|w| w.set(ocr)),
    };
}

/// The compare units of timer `t` (0..4) that should drive their pins: outputs `enabled` and a
/// non-zero width.
fn connection(t: usize, enabled: bool, ticks: &[u16; CHANNELS]) -> Connected {
    core::array::from_fn(|unit| enabled && ticks[3 * t + unit] != 0)
}

/// The four 16-bit timers as servo outputs. After [`Servos::new`] it holds the outputs' target
/// state; the registers are written when the state is applied (`stage`).
pub struct Servos {
    _tc1: pac::TC1,
    _tc3: pac::TC3,
    _tc4: pac::TC4,
    _tc5: pac::TC5,
    _ports: (pac::PORTB, pac::PORTE, pac::PORTH, pac::PORTL),
    /// Pulse width of each channel, ticks (0 = no pulse).
    pulse_ticks: [u16; CHANNELS],
    enabled: bool,
    /// [`PERIODS`] widened to 32 bits for the controller: the count and the byte it was
    /// last widened from.
    periods: Cell<(u32, u8)>,
}

impl Servos {
    /// Takes the four timers and the four ports of their pins, drives the twelve pins low as
    /// outputs and starts the timers together (`tc0` lends its GTCCR register, which controls
    /// the shared prescaler); outputs stay disabled (compare units disconnected) until
    /// [`Servos::enable`]. The other pins of the ports keep their state (PE0/PE1 belong to
    /// USART0, which overrides them).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        tc0: &pac::TC0,
        tc1: pac::TC1,
        tc3: pac::TC3,
        tc4: pac::TC4,
        tc5: pac::TC5,
        portb: pac::PORTB,
        porte: pac::PORTE,
        porth: pac::PORTH,
        portl: pac::PORTL,
    ) -> Servos {
        // Pins low first, then outputs: no glitch (datasheet §13.2.3, switching between input
        // and output).
        macro_rules! pins_low_out {
            ($port:expr, $portx:ident, $ddrx:ident, [$a:ident, $b:ident, $c:ident]) => {{
                $port
                    .$portx()
                    .modify(|_, w| w.$a().clear_bit().$b().clear_bit().$c().clear_bit());
                $port
                    .$ddrx()
                    .modify(|_, w| w.$a().set_bit().$b().set_bit().$c().set_bit());
            }};
        }
        pins_low_out!(portb, portb, ddrb, [pb5, pb6, pb7]);
        pins_low_out!(porte, porte, ddre, [pe3, pe4, pe5]);
        pins_low_out!(porth, porth, ddrh, [ph3, ph4, ph5]);
        pins_low_out!(portl, portl, ddrl, [pl3, pl4, pl5]);

        // Each timer stopped, set to mode 14 with its compare units disconnected, TOP = one
        // period, count 0, then clocked at f_cpu / 8 (datasheet §17.11: TCCRnA, TCCRnB, ICRn,
        // TCNTn; Table 17-6, the clock select).
        macro_rules! init {
            ($tc:expr, $tccra:ident, $tccrb:ident, $icr:ident, $tcnt:ident, $wgm:ident, $cs:ident,
             [$a:ident, $b:ident, $c:ident]) => {{
                $tc.$tccrb().write(|w| w.$cs().no_clock());
                $tc.$tccra().write(|w| {
                    w.$wgm()
                        .set(WGM_LOW_MODE14)
                        .$a()
                        .disconnected()
                        .$b()
                        .disconnected()
                        .$c()
                        .disconnected()
                });
                $tc.$icr().write(|w| w.set(PERIOD_TICKS - 1));
                $tc.$tcnt().write(|w| w.set(0));
                $tc.$tccrb()
                    .write(|w| w.$wgm().set(WGM_HIGH_MODE14).$cs().prescale_8());
            }};
        }
        // The shared prescaler halted while the timers are set up, then released: all four
        // count from 0 on the same prescaler edge (datasheet §18.4.1, GTCCR: TSM, PSRSYNC).
        tc0.gtccr().write(|w| w.tsm().set_bit().psrsync().set_bit());
        init!(
            tc1,
            tccr1a,
            tccr1b,
            icr1,
            tcnt1,
            wgm1,
            cs1,
            [com1a, com1b, com1c]
        );
        init!(
            tc3,
            tccr3a,
            tccr3b,
            icr3,
            tcnt3,
            wgm3,
            cs3,
            [com3a, com3b, com3c]
        );
        init!(
            tc4,
            tccr4a,
            tccr4b,
            icr4,
            tcnt4,
            wgm4,
            cs4,
            [com4a, com4b, com4c]
        );
        init!(
            tc5,
            tccr5a,
            tccr5b,
            icr5,
            tcnt5,
            wgm5,
            cs5,
            [com5a, com5b, com5c]
        );
        tc0.gtccr().write(|w| w.tsm().clear_bit());

        Servos {
            _tc1: tc1,
            _tc3: tc3,
            _tc4: tc4,
            _tc5: tc5,
            _ports: (portb, porte, porth, portl),
            pulse_ticks: [0; CHANNELS],
            enabled: false,
            periods: Cell::new((0, 0)),
        }
    }

    /// True after [`Servos::enable`] and before [`Servos::disable`].
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Connects the compare units of every channel with a non-zero pulse width, after the
    /// longest pulse of the current period (the first pulse is complete): at once, or by the
    /// clock's tick within at most one period. Does not wait.
    pub fn enable(&mut self) {
        self.enabled = true;
        stage(&self.pulse_ticks, true);
    }

    /// Disconnects every compare unit: all twelve pins low from the end of the longest pulse of
    /// the current period on (no pulse is cut short; at most one period later). Does not wait.
    /// The panic handler uses [`force_all_low`], which acts at once.
    pub fn disable(&mut self) {
        self.enabled = false;
        stage(&self.pulse_ticks, false);
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
    /// ticks at the start of every period from the next quiet moment on (see
    /// [`Servos::set_all_pulse_ticks`]); 0 keeps the pin low and [`PERIOD_TICKS`] keeps it
    /// high.
    pub fn set_pulse_ticks(&mut self, channel: usize, ticks: u16) -> Result<(), Error> {
        if channel >= CHANNELS {
            return Err(Error::NoSuchChannel);
        }
        if ticks > PERIOD_TICKS {
            return Err(Error::PulseTooLong);
        }
        self.pulse_ticks[channel] = ticks;
        stage(&self.pulse_ticks, self.enabled);
        Ok(())
    }

    /// Sets all twelve pulse widths so that they take effect in the same period (see the
    /// module docs); nothing changes when any of them is refused. Does not wait: the widths
    /// are staged and written between pulses — at once when the call falls between pulses,
    /// else by the millisecond clock's interrupt after the longest pulse, before the period
    /// ends. The chip takes them over at the next period either way; writing between pulses
    /// also keeps simulators right that apply a compare register at once (simavr does).
    pub fn set_all_pulse_ticks(&mut self, ticks: &[u16; CHANNELS]) -> Result<(), Error> {
        if ticks.iter().any(|&t| t > PERIOD_TICKS) {
            return Err(Error::PulseTooLong);
        }
        self.pulse_ticks = *ticks;
        stage(&self.pulse_ticks, self.enabled);
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
}

/// Disconnects every compare unit (pins fall back to their PORT value, low). For the panic
/// handler, which cannot own the timers.
pub fn force_all_low(dp: &pac::Peripherals) {
    for t in 0..4 {
        apply_connections(dp, t, [false; 3]);
    }
}

impl quad_device::ServoOutputs for Servos {
    /// All twelve at once ([`Servos::set_all_pulse_ticks`]). The controller only passes widths
    /// within the servos' calibrated travel (≤ 2,700 µs); a width beyond one period, which it
    /// never passes, stops the outputs rather than being ignored.
    fn set_pulses(&mut self, pulses_half_us: &[u16; CHANNELS]) {
        if self.set_all_pulse_ticks(pulses_half_us).is_err() {
            self.disable();
        }
    }

    fn set_enabled(&mut self, enabled: bool) {
        if enabled {
            self.enable();
        } else {
            self.disable();
        }
    }

    /// The periods counted by the tick interrupt, widened (the controller polls far more often
    /// than every 255 periods, 5.1 s).
    fn periods_begun(&self) -> Option<u32> {
        let (count, last) = self.periods.get();
        let now = PERIODS.get();
        let count = count.wrapping_add(u32::from(now.wrapping_sub(last)));
        self.periods.set((count, now));
        Some(count)
    }

    /// A staged state not written yet, or written in the period running now: the chip has not
    /// taken it over.
    fn write_pending(&self) -> bool {
        PENDING.get() != 0 || APPLIED_IN.get() == PERIODS.get()
    }
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
