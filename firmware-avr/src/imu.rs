//! The MPU-6050 on the TWI ([`crate::twi`]): probe and configuration at boot, then a burst
//! read every [`READ_PERIOD_MS`] ms, each reading (or fault) pushed into the controller with
//! `Device::on_imu`. The sensor's registers, configuration, scales and mounting are
//! `quad_device::imu::mpu6050`'s, shared with the emulator's virtual sensor.
//!
//! ```text
//! boot: WHO_AM_I ─▶ 0x68? ─▶ CONFIG_SEQUENCE (5 writes) ─▶ run
//!         │ no ACK: Absent, pushed once; the bus is left alone (every motion runs open loop)
//!         │ another id: WrongId { who_am_i }, likewise
//! run:  Timer2 tick, every READ_PERIOD_MS ─▶ burst of 14 bytes from ACCEL_XOUT_H (TWI interrupt)
//!       main loop: finished burst ─▶ stuck check ─▶ decode ─▶ Device::on_imu(Sample)
//! fault mid-run: NAK ─▶ Nak │ STUCK_REPEATS identical bursts ─▶ Stuck │ SDA low or no end ─▶ BusHeld
//!       (SCL clocked, STOP); after RETRY_MS the probe and configuration again, then run
//!       (after Stuck too: a sensor that lost its power is asleep with frozen data)
//! ```
//!
//! The periodic burst is started by the clock's 1 kHz tick ([`on_tick`], in its interrupt),
//! so the read rate does not depend on how long the main loop's passes take; a burst the main
//! loop has not taken yet is not overwritten (the tick skips, and counts, that read). The main
//! loop ([`Imu::poll`]) only takes finished transfers and starts the few of the boot and
//! retry sequence: it never waits for the bus.
//!
//! The test's window: [`IMU_WINDOW`], a `#[no_mangle]` mirror of the controller's sensor state
//! and the driver's counters, which the emulator tests read from SRAM by its ELF symbol (until
//! the protocol reports the sensor's state).

use crate::twi::{self, Outcome, Twi};
use crate::usart::SharedU8;
use crate::{app::BoardDevice, pac};
use core::cell::UnsafeCell;
use core::sync::atomic::{compiler_fence, Ordering};
use quad_device::imu::mpu6050::{
    self, reg, StuckDetector, ADDRESS, BURST_LEN, CONFIG_SEQUENCE, READ_PERIOD_MS, WHO_AM_I_VALUE,
};
use quad_device::imu::{ImuFault, ImuReading};

/// After a fault mid-run, the driver probes the sensor again this long after, ms.
pub const RETRY_MS: u32 = 100;

/// A transfer still running after this many ticks (ms) has hung: the bus is held. (A 14-byte
/// burst takes 0.4 ms at 400 kHz.)
pub const TIMEOUT_TICKS: u8 = 5;

/// The controller's sensor state and the driver's counters, for the emulator tests (module
/// docs). Written by the main loop only (`bursts_skipped` by the tick only).
#[repr(C)]
pub struct Window {
    /// `device.imu().samples`: samples pushed since boot.
    pub samples: u32,
    /// `device.imu().fault` as a code: 0 none, 1 Absent, 2 WrongId, 3 Nak, 4 Stuck, 5 BusHeld.
    pub fault: u8,
    /// The last WHO_AM_I read (0 before any).
    pub who_am_i: u8,
    /// Bus recoveries (SCL clocked) since boot.
    pub recoveries: u16,
    /// The longest `Device::poll` (at a frame boundary: the motion engine, the IK, the
    /// limiter) together with the sensor's step, since boot, µs: the worst frame.
    pub longest_frame_us: u16,
    /// Reads the tick skipped because the last burst was not taken yet.
    pub bursts_skipped: u16,
}

// The emulator tests read the window by these offsets: samples 0, fault 4, who_am_i 5,
// recoveries 6, longest_frame_us 8, bursts_skipped 10 (`tests/tests/avr_imu.rs`).
const _: () = assert!(core::mem::size_of::<Window>() == 12);
const _: () = assert!(core::mem::offset_of!(Window, longest_frame_us) == 8);

/// [`Window`] in a static cell.
pub struct WindowCell(UnsafeCell<Window>);

// SAFETY: single core; each field has one writer (documented on `Window`), single-byte or
// main-loop-only fields, read by the host between instructions.
unsafe impl Sync for WindowCell {}

/// The test's window (module docs).
#[no_mangle]
pub static IMU_WINDOW: WindowCell = WindowCell(UnsafeCell::new(Window {
    samples: 0,
    fault: 0,
    who_am_i: 0,
    recoveries: 0,
    longest_frame_us: 0,
    bursts_skipped: 0,
}));

fn window() -> *mut Window {
    IMU_WINDOW.0.get()
}

/// Notes the length of one frame's work (see [`Window::longest_frame_us`]), µs.
pub fn note_frame_us(us: u16) {
    // SAFETY: the main loop is this field's only writer.
    unsafe {
        let w = window();
        if us > (*w).longest_frame_us {
            (*w).longest_frame_us = us;
        }
    }
}

/// 1 while the tick starts the periodic bursts (written by the main loop).
static RUN: SharedU8 = SharedU8::new(0);

/// Ticks until the next burst (written by the tick only).
static COUNTDOWN: SharedU8 = SharedU8::new(READ_PERIOD_MS);

/// Ticks the transfer in progress has taken (written by the tick; reset by the main loop only
/// while no transfer runs).
static BUSY_TICKS: SharedU8 = SharedU8::new(0);

/// The burst's register address, written before the read.
const BURST_START: [u8; 1] = [reg::ACCEL_XOUT_H];

/// Starts the periodic burst when it is due; call from the 1 kHz tick (interrupts may be on:
/// the TWI handler only ends a transfer, and a slot it has not released yet makes this skip).
#[inline(always)]
pub fn on_tick() {
    if twi::is_busy() {
        BUSY_TICKS.store(BUSY_TICKS.load().saturating_add(1));
        return;
    }
    if RUN.load() == 0 {
        return;
    }
    let left = COUNTDOWN.load().saturating_sub(1);
    if left > 0 {
        COUNTDOWN.store(left);
        return;
    }
    COUNTDOWN.store(READ_PERIOD_MS);
    BUSY_TICKS.store(0);
    if !twi::start(ADDRESS, &BURST_START, BURST_LEN as u8) {
        // SAFETY: the tick is this field's only writer.
        unsafe {
            let w = window();
            (*w).bursts_skipped = (*w).bursts_skipped.wrapping_add(1);
        }
    }
}

/// Where the driver is.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Reading WHO_AM_I (`booting`: the first time since power-on).
    Probe { booting: bool },
    /// Writing `CONFIG_SEQUENCE[i]`.
    Configure(u8),
    /// The tick reads bursts.
    Run,
    /// Waiting until the millisecond clock reaches `at_ms` to probe again.
    Retry { at_ms: u32 },
    /// No sensor (or not ours): the bus is left alone.
    Off,
}

/// The sensor's driver (module docs).
pub struct Imu {
    twi: Twi,
    phase: Phase,
    /// A transfer of the boot or retry sequence was started.
    started: bool,
    stuck: StuckDetector,
    /// Stuck was pushed and no fresh sample came since.
    stuck_pushed: bool,
}

impl Imu {
    /// Takes the TWI; nothing is sent before the first [`Imu::poll`].
    pub fn new(twi: pac::TWI, portd: &pac::PORTD) -> Imu {
        Imu {
            twi: Twi::new(twi, portd),
            phase: Phase::Probe { booting: true },
            started: false,
            stuck: StuckDetector::new(),
            stuck_pushed: false,
        }
    }

    /// One step: takes a finished transfer, pushes what it gave into `device`, starts the next
    /// transfer of the boot or retry sequence. Never waits (but for the bounded bus recovery
    /// on that fault path, [`twi::recover_bus`]).
    pub fn poll(&mut self, device: &mut BoardDevice, portd: &pac::PORTD, now_ms: u32) {
        match self.phase {
            Phase::Off => {}
            Phase::Retry { at_ms } => {
                if now_ms.wrapping_sub(at_ms) < u32::MAX / 2 {
                    self.phase = Phase::Probe { booting: false };
                }
            }
            Phase::Run => self.take_burst(device, portd, now_ms),
            Phase::Probe { booting } => {
                if !self.started {
                    self.begin(&[reg::WHO_AM_I], 1);
                    return;
                }
                match self.ended(device, portd, now_ms) {
                    None => {}
                    Some(Outcome::Done) => {
                        let id = twi::read_bytes()[0];
                        twi::release();
                        // SAFETY: the main loop is this field's only writer.
                        unsafe { (*window()).who_am_i = id };
                        if id == WHO_AM_I_VALUE {
                            self.phase = Phase::Configure(0);
                        } else {
                            self.push(
                                device,
                                ImuReading::Fault(ImuFault::WrongId { who_am_i: id }),
                            );
                            self.phase = if booting { Phase::Off } else { retry(now_ms) };
                        }
                    }
                    Some(other) => {
                        twi::release();
                        if booting && other == Outcome::AddressNak {
                            self.push(device, ImuReading::Fault(ImuFault::Absent));
                            self.phase = Phase::Off;
                        } else {
                            self.fault(device, portd, other, now_ms);
                        }
                    }
                }
            }
            Phase::Configure(i) => {
                if !self.started {
                    let (r, v) = CONFIG_SEQUENCE[usize::from(i)];
                    self.begin(&[r, v], 0);
                    return;
                }
                match self.ended(device, portd, now_ms) {
                    None => {}
                    Some(Outcome::Done) => {
                        twi::release();
                        let next = i + 1;
                        if usize::from(next) < CONFIG_SEQUENCE.len() {
                            self.phase = Phase::Configure(next);
                        } else {
                            // The stuck detector keeps its count: data still frozen after
                            // the configuration is stuck from the first burst on.
                            self.phase = Phase::Run;
                            compiler_fence(Ordering::SeqCst);
                            RUN.store(1);
                        }
                    }
                    Some(other) => {
                        twi::release();
                        self.fault(device, portd, other, now_ms);
                    }
                }
            }
        }
    }

    fn begin(&mut self, bytes: &[u8], read_len: u8) {
        // A burst the tick started before the bursts were stopped may have ended since.
        if twi::outcome().is_some() {
            twi::release();
        }
        BUSY_TICKS.store(0);
        self.started = self.twi.start(ADDRESS, bytes, read_len);
    }

    /// The outcome of the boot or retry sequence's transfer, once it ended (a hung transfer
    /// is handled as a held bus here and gives `None`).
    fn ended(
        &mut self,
        device: &mut BoardDevice,
        portd: &pac::PORTD,
        now_ms: u32,
    ) -> Option<Outcome> {
        match twi::outcome() {
            Some(o) => {
                self.started = false;
                Some(o)
            }
            None => {
                if BUSY_TICKS.load() > TIMEOUT_TICKS {
                    self.started = false;
                    self.bus_held(device, portd, now_ms);
                }
                None
            }
        }
    }

    /// Takes the periodic burst when it has ended.
    fn take_burst(&mut self, device: &mut BoardDevice, portd: &pac::PORTD, now_ms: u32) {
        match twi::outcome() {
            None => {
                if twi::is_busy() && BUSY_TICKS.load() > TIMEOUT_TICKS {
                    self.stop_bursts();
                    self.bus_held(device, portd, now_ms);
                }
            }
            Some(Outcome::Done) => {
                let burst = twi::read_bytes();
                twi::release();
                if self.stuck.is_stuck(&burst) {
                    if !self.stuck_pushed {
                        self.stuck_pushed = true;
                        self.push(device, ImuReading::Fault(ImuFault::Stuck));
                    }
                    // A sensor that lost its power and came back is asleep with frozen data:
                    // probe and configure it again (the fault stays until a fresh sample).
                    self.stop_bursts();
                    self.phase = retry(now_ms);
                } else {
                    self.stuck_pushed = false;
                    self.push(device, ImuReading::Sample(mpu6050::decode(&burst)));
                }
            }
            Some(other) => {
                self.stop_bursts();
                twi::release();
                self.fault(device, portd, other, now_ms);
            }
        }
    }

    /// Stops the tick's bursts (a burst it started before this runs to its end; the slot is
    /// then released by [`Imu::fault`] or the next probe's wait).
    fn stop_bursts(&mut self) {
        RUN.store(0);
        compiler_fence(Ordering::SeqCst);
    }

    /// A transfer failed mid-run: SDA low means a held bus (recovered), else a NAK.
    fn fault(&mut self, device: &mut BoardDevice, portd: &pac::PORTD, o: Outcome, now_ms: u32) {
        if portd.pind().read().pd1().bit_is_clear() || o == Outcome::BusError {
            self.bus_held(device, portd, now_ms);
        } else {
            self.push(device, ImuReading::Fault(ImuFault::Nak));
            self.phase = retry(now_ms);
        }
    }

    /// The bus is held: push the fault, clock SCL and STOP, probe again later.
    fn bus_held(&mut self, device: &mut BoardDevice, portd: &pac::PORTD, now_ms: u32) {
        self.push(device, ImuReading::Fault(ImuFault::BusHeld));
        self.stop_bursts();
        self.twi.recover(portd);
        // SAFETY: the main loop is this field's only writer.
        unsafe {
            let w = window();
            (*w).recoveries = (*w).recoveries.wrapping_add(1);
        }
        self.started = false;
        self.phase = retry(now_ms);
    }

    fn push(&mut self, device: &mut BoardDevice, reading: ImuReading) {
        device.on_imu(reading);
        let state = device.imu();
        let code = match state.fault {
            None => 0,
            Some(ImuFault::Absent) => 1,
            Some(ImuFault::WrongId { .. }) => 2,
            Some(ImuFault::Nak) => 3,
            Some(ImuFault::Stuck) => 4,
            Some(ImuFault::BusHeld) => 5,
        };
        // SAFETY: the main loop is these fields' only writer.
        unsafe {
            let w = window();
            (*w).samples = state.samples;
            (*w).fault = code;
        }
    }
}

fn retry(now_ms: u32) -> Phase {
    Phase::Retry {
        at_ms: now_ms.wrapping_add(RETRY_MS),
    }
}
