//! The firmware proper: hardware bring-up and the main loop around the device controller
//! ([`quad_device::Device`]), shared by the `firmware` binaries (which differ only in their
//! line rate).
//!
//! ```text
//! USART0 RX interrupt ─▶ RX ring ─▶ Device::receive ─▶ answer frames ─▶ TX ring ─▶ USART0 UDRE
//!                                        │                                           interrupt
//!   Timer1/3/4/5 compare outputs ◀─ staged state ◀─ ServoOutputs        Clock ◀─ Timer2 (1 kHz)
//!                    ▲ written between pulses, by the main loop or the Timer2 tick
//!                                                   Storage ◀─ EEPROM (EE_READY interrupt)
//!   MPU-6050 ─ TWI interrupt ─▶ burst (started by the Timer2 tick) ─▶ imu::Imu ─▶ Device::on_imu
//! main loop: feed the watchdog, hand received bytes to the controller, Device::poll (failsafe),
//!            take the sensor's finished burst
//! ```
//!
//! The main loop never waits for the line or for a servo window: answers leave by interrupt
//! while the next request is solved, and the servo widths are applied between pulses by
//! whoever comes first (the request's own call, or the clock's tick). Neither path turns
//! interrupts off for longer than a few instructions (`usart`, `servo`).
//!
//! - Robot and defaults: [`DEVICE_CONFIG`], [`quad_device::Config::shahriar2023`] (seed 000's
//!   robot, the one with the Arduino Mega): body poses in rotation order zyx at its default
//!   stance height, unreachable targets rejected, no link-loss timeout until the host sets one.
//!   A robot stored in the EEPROM (protocol 2.4, `SaveRobot`) replaces it at boot.
//! - Math: [`avr_libc_math::AvrFast`] (`sqrt` with avr-libc's bits; kin-core's fixed-point arctangent
//!   `poly::atan2_fixed` in the assembly form of `AvrLibm::atan2_fixed`, bit for bit the same;
//!   kin-core's sine/cosine `poly::sin_cos_fixed` with its fixed-point part in the assembly
//!   of `AvrLibm::sin_cos_fixed`, likewise; the tables read from flash), the fastest
//!   backend measured (`cargo xtask avr-bench`).
//! - Outputs stay low until the host sends `SetOutputs { enabled: true }`.
//! - Watchdog: [`WATCHDOG_TIMEOUT`], fed by the main loop and during EEPROM writes. A hung main
//!   loop resets the MCU; the reset leaves every pin an input (no pulses) and the device comes
//!   back with its outputs off, waiting for a new handshake.

use crate::clock::Clock;
use crate::eeprom::Eeprom;
use crate::imu::Imu;
use crate::servo::Servos;
use crate::usart::{Baud, Usart0};
use crate::watchdog::{self, Timeout, Watchdog};
use avr_libc_math::AvrFast;
use quad_device::{Config, Device, ValidConfig};

/// What the device runs: seed 000's robot with the controller's defaults, validated when the
/// firmware is built (an invalid one fails the build; no validation code on the device).
pub const DEVICE_CONFIG: ValidConfig = ValidConfig::checked(Config::shahriar2023());

/// Watchdog timeout: far above the longest main-loop iteration (one body-pose solve plus, when
/// the transmit ring is full, waiting for room in it: a few ms each at 115,200 baud; see
/// BENCHMARKS.md).
pub const WATCHDOG_TIMEOUT: Timeout = Timeout::Ms250;

/// Received bytes handed to the controller per call.
const CHUNK: usize = 16;

/// The controller as built for this board.
pub type BoardDevice = Device<Servos, Clock, Eeprom, AvrFast>;

/// Brings the board up and runs the device forever at `baud`.
pub fn run(baud: Baud) -> ! {
    run_with_receive_hold(baud, 0)
}

/// [`run`], but each pass of the main loop takes the received bytes with interrupts off and
/// keeps them off for `hold_cycles` more cycles — **a defect on purpose**, for the
/// `firmware-1mbaud-cli-hold` binary only: the emulator tests show that a receive path which
/// blocks interrupts for longer than the chip's two-byte buffer covers loses bytes, and that
/// the emulator counts them. [`run`] passes 0 (no interrupts-off stretch at all).
pub fn run_with_receive_hold(baud: Baud, hold_cycles: u32) -> ! {
    crate::stack::paint();
    let Some(dp) = crate::pac::Peripherals::take() else {
        panic!()
    };
    // Clears the reset flags (a set WDRF would keep the watchdog from being reconfigured).
    let reset_cause = watchdog::take_reset_cause(&dp.CPU);
    let mut watchdog = Watchdog::enable(dp.WDT, WATCHDOG_TIMEOUT);
    let servos = Servos::new(
        &dp.TC0, dp.TC1, dp.TC3, dp.TC4, dp.TC5, dp.PORTB, dp.PORTE, dp.PORTH, dp.PORTL,
    );
    let clock = Clock::new(dp.TC2);
    let mut usart = Usart0::new(dp.USART0, baud);
    let eeprom = Eeprom::new(dp.EEPROM);
    let portd = dp.PORTD;
    let mut imu = Imu::new(dp.TWI, &portd);
    // SAFETY: the binaries define the handlers (`forward_interrupts!`); each touches only its
    // own module's state.
    unsafe { avr_device::interrupt::enable() };

    let mut device = new_device(servos, clock, eeprom);
    // In place: the controller exists once, in this frame.
    device.boot();
    // Reported to the host (`Flags::WATCHDOG_RESET`); the outputs are off as after any reset,
    // and nothing moves until the host enables them.
    if reset_cause.watchdog() {
        device.note_watchdog_reset();
    }
    loop {
        watchdog.feed();
        serve(&mut device, &mut usart, &mut imu, &portd, hold_cycles);
    }
}

/// Builds the controller, stopped and not yet booted ([`BoardDevice::stopped`]): [`run`]
/// boots it where it lies, so that no second copy of it is ever on the stack. Out of line so
/// that the temporaries of its construction do not stay in [`run`]'s stack frame for good.
///
/// The configuration was validated at compile time ([`DEVICE_CONFIG`]): construction cannot
/// fail.
#[inline(never)]
fn new_device(servos: Servos, clock: Clock, eeprom: Eeprom) -> BoardDevice {
    BoardDevice::stopped_valid(DEVICE_CONFIG, servos, clock, eeprom)
}

/// The millisecond clock and Timer1's count (0.5 µs ticks, wrapping every 20 ms), read
/// together with interrupts off (a 16-bit count is read through the timer's shared TEMP
/// register, which a tick's compare writes would clobber between the two bytes).
fn pass_stamp() -> (u32, u16) {
    avr_device::interrupt::free(|_| {
        // SAFETY: TCNT1 is only read here; the servo code owns Timer1's configuration.
        let tc1 = unsafe { crate::pac::TC1::steal() };
        (crate::clock::now_ms(), tc1.tcnt1().read().bits())
    })
}

/// Microseconds between two [`pass_stamp`]s (saturating at 65,535 µs). No division: this runs
/// on every pass of the main loop.
fn elapsed_us(a: (u32, u16), b: (u32, u16)) -> u16 {
    let ms = b.0.wrapping_sub(a.0);
    if ms >= 20 {
        return if ms >= 65 { u16::MAX } else { ms as u16 * 1000 };
    }
    let period = crate::servo::PERIOD_TICKS;
    // Both counts are below `period`: no overflow.
    let ticks = if b.1 >= a.1 {
        b.1 - a.1
    } else {
        b.1 + (period - a.1)
    };
    ticks / 2
}

/// One pass of the main loop: received bytes to the controller, answers out, failsafe check,
/// the sensor's finished transfer.
///
/// Kept out of line: inlined into [`run`], whose stack frame holds the whole controller, every
/// access to a local would need a frame pointer beyond the AVR's 63-byte displacement (about
/// 8 instructions per access) — it doubled the firmware's flash.
#[inline(never)]
fn serve(
    device: &mut BoardDevice,
    usart: &mut Usart0,
    imu: &mut Imu,
    portd: &crate::pac::PORTD,
    hold_cycles: u32,
) {
    if hold_cycles == 0 {
        // The bytes are read where they lie in the receive ring: no copy.
        Usart0::with_received(CHUNK, |bytes| {
            if !bytes.is_empty() {
                device.receive(bytes, |frame| usart.send(frame));
            }
        });
    } else {
        let mut chunk = [0u8; CHUNK];
        let n = avr_device::interrupt::free(|_| {
            let n = usart.read_into(&mut chunk);
            avr_device::asm::delay_cycles(hold_cycles);
            n
        });
        if n > 0 {
            device.receive(&chunk[..n], |frame| usart.send(frame));
        }
    }
    // Timed when a servo frame is due (a PWM period began since the last timed pass): the
    // frame's work (the motion engine, the IK, the limiter) and the sensor's step, without
    // the request handled above (its time is the request's answer time). The other passes
    // pay one comparison. (A period that begins in the few instructions between this look
    // and the device's own lets that one frame go untimed.)
    let period = crate::servo::periods_mod_256();
    if period == FRAME_TIMED.load() {
        device.poll();
        imu.poll(device, portd, crate::clock::now_ms());
        return;
    }
    FRAME_TIMED.store(period);
    let start = pass_stamp();
    device.poll();
    imu.poll(device, portd, crate::clock::now_ms());
    crate::imu::note_frame_us(elapsed_us(start, pass_stamp()));
}

/// [`crate::servo::periods_mod_256`] at the last timed pass (main loop only).
static FRAME_TIMED: crate::usart::SharedU8 = crate::usart::SharedU8::new(0);

/// Defines the interrupt handlers of a binary that calls [`run`] (handlers must live in the
/// binary crate to be linked): `USART0_RX`, `USART0_UDRE`, `TIMER2_COMPA`, `TWI` and
/// `EE_READY`.
/// The binary needs `#![feature(abi_avr_interrupt)]`.
#[macro_export]
macro_rules! forward_interrupts {
    () => {
        #[avr_device::interrupt(atmega2560)]
        fn USART0_RX() {
            $crate::usart::on_rx_interrupt();
        }

        #[avr_device::interrupt(atmega2560)]
        fn USART0_UDRE() {
            $crate::usart::on_udre_interrupt();
        }

        #[avr_device::interrupt(atmega2560)]
        fn TIMER2_COMPA() {
            $crate::clock::on_tick_interrupt();
        }

        #[avr_device::interrupt(atmega2560)]
        fn TWI() {
            $crate::twi::on_interrupt();
        }

        #[avr_device::interrupt(atmega2560)]
        fn EE_READY() {
            $crate::eeprom::on_ready_interrupt();
        }
    };
}
