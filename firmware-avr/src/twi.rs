//! The TWI (I²C) master on SDA = PD1 (Mega pin 20) and SCL = PD0 (pin 21) at 400 kHz, by
//! interrupt: one transfer at a time — up to two bytes written (a register address and a
//! value), then, after a repeated START, up to [`MAX_READ`] bytes read — run by the `TWI`
//! interrupt ([`on_interrupt`]) from the START to the STOP. Nobody waits for it: the starter
//! returns at once and looks at [`outcome`] later.
//!
//! Ownership of the one transfer slot follows its state byte: while it is [`Outcome`]-less and
//! busy only the interrupt handler touches the slot; otherwise only the code that started it
//! (the main loop, or the clock's tick for the sensor's periodic bursts, see `crate::imu`),
//! which hands it back with [`release`]. The handler runs a few dozen instructions per bus
//! event with interrupts off (as every handler): far below the UART's two-byte cover.
//!
//! Bus recovery ([`recover_bus`]): a slave that holds SDA low (reset mid-byte) is freed by
//! clocking SCL as a GPIO until it lets go (at most nine clocks), then a STOP (NXP UM10204
//! §3.1.16).
//!
//! Datasheet: ATmega640/1280/2560 (2549Q), chapter 24 "2-wire Serial Interface": bit rate
//! §24.5.2, TWCR §24.9.2, TWSR §24.9.3, status codes Tables 24-3 (master transmitter) and
//! 24-4 (master receiver).

use crate::usart::SharedU8;
use crate::{pac, F_CPU_HZ};
use core::cell::UnsafeCell;
use core::sync::atomic::{compiler_fence, Ordering};

/// The bus clock, Hz (fast mode).
pub const SCL_HZ: u32 = 400_000;

/// TWBR for [`SCL_HZ`] with prescaler 1: SCL = F_CPU / (16 + 2·TWBR) (§24.5.2); 12 at 16 MHz.
pub const TWBR_VALUE: u8 = ((F_CPU_HZ / SCL_HZ - 16) / 2) as u8;

const _: () = assert!(F_CPU_HZ / (16 + 2 * TWBR_VALUE as u32) == SCL_HZ);

/// Most bytes one transfer reads.
pub const MAX_READ: usize = quad_device::imu::mpu6050::BURST_LEN;

/// How a transfer ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Every byte written and read.
    Done,
    /// No ACK to the address (nothing there, or the device does not answer).
    AddressNak,
    /// No ACK to a written byte.
    DataNak,
    /// Arbitration lost or a bus error (an illegal START or STOP seen).
    BusError,
}

// The state byte (`STATE`).
const IDLE: u8 = 0;
const BUSY: u8 = 1;
const DONE: u8 = 2;
const ADDRESS_NAK: u8 = 3;
const DATA_NAK: u8 = 4;
const BUS_ERROR: u8 = 5;

// Status codes (TWSR & 0xF8), Tables 24-3 and 24-4.
const START: u8 = 0x08;
const REPEATED_START: u8 = 0x10;
const MT_SLA_ACK: u8 = 0x18;
const MT_SLA_NACK: u8 = 0x20;
const MT_DATA_ACK: u8 = 0x28;
const MT_DATA_NACK: u8 = 0x30;
const MR_SLA_ACK: u8 = 0x40;
const MR_SLA_NACK: u8 = 0x48;
const MR_DATA_ACK: u8 = 0x50;
const MR_DATA_NACK: u8 = 0x58;

/// The transfer in progress.
struct Slot {
    /// SLA+W (the 7-bit address shifted left).
    sla_w: u8,
    write: [u8; 2],
    write_len: u8,
    read_len: u8,
    /// Bytes written, then bytes read (after the repeated START).
    index: u8,
    read: [u8; MAX_READ],
}

struct Shared(UnsafeCell<Slot>);

// SAFETY: one owner at a time, by `STATE` (module docs); single core.
unsafe impl Sync for Shared {}

static SLOT: Shared = Shared(UnsafeCell::new(Slot {
    sla_w: 0,
    write: [0; 2],
    write_len: 0,
    read_len: 0,
    index: 0,
    read: [0; MAX_READ],
}));

/// The slot's state: written by the starter (IDLE → BUSY, done → IDLE) and by the handler
/// (BUSY → done); each writes only in its own phase.
static STATE: SharedU8 = SharedU8::new(IDLE);

/// The TWI master (owns the peripheral's configuration; the handler steals it).
pub struct Twi {
    twi: pac::TWI,
}

impl Twi {
    /// Enables the TWI at [`SCL_HZ`] with its interrupt, and the pins' internal pull-ups
    /// (weak, about 35 kΩ; the GY-521's 10 kΩ do the work, docs/hardware.md).
    pub fn new(twi: pac::TWI, portd: &pac::PORTD) -> Twi {
        // Inputs with pull-ups (§13.2.3); the TWI takes the pins over when enabled (§24.4).
        portd
            .ddrd()
            .modify(|_, w| w.pd0().clear_bit().pd1().clear_bit());
        portd
            .portd()
            .modify(|_, w| w.pd0().set_bit().pd1().set_bit());
        twi.twsr().write(|w| w.twps().prescaler_1());
        twi.twbr().write(|w| w.set(TWBR_VALUE));
        twi.twcr().write(|w| w.twen().set_bit());
        Twi { twi }
    }

    /// True when no transfer is in progress or unreleased.
    pub fn is_idle(&self) -> bool {
        STATE.load() == IDLE
    }

    /// Starts writing `bytes` (one or two) to `address`, then reading `read_len` bytes; false
    /// (nothing started) while the slot is taken.
    pub fn start(&mut self, address: u8, bytes: &[u8], read_len: u8) -> bool {
        start(address, bytes, read_len)
    }

    /// Switches the TWI off (the pins become GPIOs with their pull-ups), frees a held bus by
    /// clocking SCL ([`recover_bus`]), and switches it on again; true when SDA is high after.
    /// A transfer in progress is dropped (its slot freed).
    pub fn recover(&mut self, portd: &pac::PORTD) -> bool {
        self.twi.twcr().write(|w| w.twen().clear_bit());
        compiler_fence(Ordering::SeqCst);
        STATE.store(IDLE);
        let free = recover_bus(portd);
        self.twi.twcr().write(|w| w.twen().set_bit());
        free
    }
}

/// [`Twi::start`] for the clock's tick, which does not own the [`Twi`].
#[inline(always)]
pub fn start(address: u8, bytes: &[u8], read_len: u8) -> bool {
    if STATE.load() != IDLE || bytes.is_empty() || bytes.len() > 2 {
        return false;
    }
    // SAFETY: the slot is idle: nobody else touches it until STATE says BUSY.
    let slot = unsafe { &mut *SLOT.0.get() };
    slot.sla_w = address << 1;
    slot.write[..bytes.len()].copy_from_slice(bytes);
    slot.write_len = bytes.len() as u8;
    slot.read_len = read_len.min(MAX_READ as u8);
    slot.index = 0;
    compiler_fence(Ordering::SeqCst);
    STATE.store(BUSY);
    // SAFETY: TWCR is written by the starter only while the slot is idle (here) and by the
    // handler while it is busy.
    let twi = unsafe { pac::TWI::steal() };
    send_start(&twi);
    true
}

/// How the last transfer ended; `None` while it runs or when none was started.
pub fn outcome() -> Option<Outcome> {
    match STATE.load() {
        DONE => Some(Outcome::Done),
        ADDRESS_NAK => Some(Outcome::AddressNak),
        DATA_NAK => Some(Outcome::DataNak),
        BUS_ERROR => Some(Outcome::BusError),
        _ => None,
    }
}

/// True while a transfer runs (started, not ended).
pub fn is_busy() -> bool {
    STATE.load() == BUSY
}

/// The bytes the finished transfer read (call before [`release`]).
pub fn read_bytes() -> [u8; MAX_READ] {
    compiler_fence(Ordering::SeqCst);
    // SAFETY: the transfer ended: the handler no longer touches the slot.
    unsafe { (*SLOT.0.get()).read }
}

/// Frees the slot of an ended transfer for the next one (no effect while one runs).
pub fn release() {
    if STATE.load() != BUSY {
        compiler_fence(Ordering::SeqCst);
        STATE.store(IDLE);
    }
}

/// TWCR: TWINT cleared (written one), TWEN and TWIE on, TWEA as `ack` (the next byte read is
/// acknowledged).
#[inline(always)]
fn go(twi: &pac::TWI, ack: bool) {
    twi.twcr().write(|w| {
        w.twint()
            .set_bit()
            .twea()
            .bit(ack)
            .twen()
            .set_bit()
            .twie()
            .set_bit()
    });
}

/// START, or a repeated START (§24.6, Table 24-2): TWINT cleared by writing one, TWSTA, TWEN,
/// TWIE.
#[inline(always)]
fn send_start(twi: &pac::TWI) {
    twi.twcr().write(|w| {
        w.twint()
            .set_bit()
            .twsta()
            .set_bit()
            .twen()
            .set_bit()
            .twie()
            .set_bit()
    });
}

/// STOP, and the transfer ends with `state`. TWINT is cleared; no interrupt follows a STOP.
#[inline(always)]
fn stop(twi: &pac::TWI, state: u8) {
    twi.twcr()
        .write(|w| w.twint().set_bit().twsto().set_bit().twen().set_bit());
    compiler_fence(Ordering::SeqCst);
    STATE.store(state);
}

/// One bus event of the transfer in progress; call from the `TWI` interrupt.
#[inline(always)]
pub fn on_interrupt() {
    // SAFETY: while the slot is busy the handler owns TWCR/TWDR and the slot (module docs).
    let twi = unsafe { pac::TWI::steal() };
    if STATE.load() != BUSY {
        // Nothing of ours: let the bus go.
        stop(&twi, STATE.load());
        return;
    }
    // SAFETY: as above.
    let slot = unsafe { &mut *SLOT.0.get() };
    match twi.twsr().read().tws().bits() << 3 {
        START => {
            twi.twdr().write(|w| w.set(slot.sla_w));
            go(&twi, false);
        }
        REPEATED_START => {
            twi.twdr().write(|w| w.set(slot.sla_w | 1));
            go(&twi, false);
        }
        MT_SLA_ACK | MT_DATA_ACK => {
            if slot.index < slot.write_len {
                twi.twdr()
                    .write(|w| w.set(slot.write[usize::from(slot.index & 1)]));
                slot.index += 1;
                go(&twi, false);
            } else if slot.read_len > 0 {
                slot.index = 0;
                // Repeated START (§24.7.2).
                send_start(&twi);
            } else {
                stop(&twi, DONE);
            }
        }
        MR_SLA_ACK => go(&twi, slot.read_len > 1),
        MR_DATA_ACK | MR_DATA_NACK => {
            let i = usize::from(slot.index);
            if i < MAX_READ {
                slot.read[i] = twi.twdr().read().bits();
            }
            slot.index += 1;
            if slot.index >= slot.read_len {
                stop(&twi, DONE);
            } else {
                // The last byte is not acknowledged: the slave lets SDA go for the STOP.
                go(&twi, slot.index + 1 < slot.read_len);
            }
        }
        MT_SLA_NACK | MR_SLA_NACK => stop(&twi, ADDRESS_NAK),
        MT_DATA_NACK => stop(&twi, DATA_NAK),
        _ => stop(&twi, BUS_ERROR),
    }
}

/// Half an SCL period of the recovery clock, cycles (5 µs: 100 kHz, standard mode).
const RECOVERY_HALF_PERIOD_CYCLES: u32 = F_CPU_HZ / 200_000;

/// Frees a bus whose SDA a slave holds low (the TWI must be off): up to nine SCL clocks by
/// GPIO (SCL pulled low by driving the pin, released to its pull-up), each followed by a look
/// at SDA, then a STOP (SDA low → high while SCL is high). True when SDA is high at the end.
///
/// This waits: at most about 100 µs, on this fault path only, interrupts on.
pub fn recover_bus(portd: &pac::PORTD) -> bool {
    let delay = || avr_device::asm::delay_cycles(RECOVERY_HALF_PERIOD_CYCLES);
    let sda_high = || portd.pind().read().pd1().bit_is_set();
    // Open drain by hand: a low is the pin driven (DDR set, PORT clear), a high the pin let go
    // to the pull-ups (DDR clear, PORT set as pull-up) (§13.2.3).
    let scl = |high: bool| {
        if high {
            portd.ddrd().modify(|_, w| w.pd0().clear_bit());
            portd.portd().modify(|_, w| w.pd0().set_bit());
        } else {
            portd.portd().modify(|_, w| w.pd0().clear_bit());
            portd.ddrd().modify(|_, w| w.pd0().set_bit());
        }
    };
    let sda = |high: bool| {
        if high {
            portd.ddrd().modify(|_, w| w.pd1().clear_bit());
            portd.portd().modify(|_, w| w.pd1().set_bit());
        } else {
            portd.portd().modify(|_, w| w.pd1().clear_bit());
            portd.ddrd().modify(|_, w| w.pd1().set_bit());
        }
    };
    for _ in 0..9 {
        if sda_high() {
            break;
        }
        scl(false);
        delay();
        scl(true);
        delay();
    }
    // STOP: SDA low while SCL low, SCL high, then SDA high.
    scl(false);
    delay();
    sda(false);
    delay();
    scl(true);
    delay();
    sda(true);
    delay();
    sda_high()
}
