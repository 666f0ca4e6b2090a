//! The real firmware ELF running in simavr in-process, behind its USART0: the third [`Link`].
//!
//! ## Timing
//! Time is the emulated MCU's cycle counter (16 MHz); nothing sleeps, and simavr runs slower
//! than real time, so every rate measured on this link is in **simulated** time.
//! - **Host → device**: [`Link::send`] puts a frame on the line at the current cycle; its bytes
//!   reach the firmware at the line rate it configured (checked against
//!   [`EmulatorConfig::baud`] at boot), one per byte time of [`SIMAVR_BITS_PER_BYTE`] bits,
//!   through a receiver as strict as the chip's: two bytes of buffer plus the shift register,
//!   a byte the firmware does not read in time is lost and counted (data overrun, see
//!   [`crate::emu::Mega2560`]; [`EmulatorLink::rx_overruns`], `LineStats::rx_overflow`).
//! - **Device → host**: a byte the firmware writes to UDR0 arrives one byte time later (simavr
//!   paces the transmitter at the same byte time).
//!   [`Link::recv`] runs the MCU until a byte has arrived (or the timeout passed) and returns
//!   the bytes up to the end of that frame.
//! - The firmware's own timing (IK, answer encoding, interrupt-driven transmission, EEPROM
//!   writes of 3.4 ms per byte, its 1 kHz clock and link-loss failsafe) is emulated instruction
//!   by instruction.
//!
//! ## Interrupts off
//! A stretch with interrupts off (SREG.I clear, interrupt handlers included) while the receiver
//! is on and bytes arrive must end within [`receive_cover_cycles`] — two byte times, the cover of
//! the chip's two-byte receive buffer — or a real chip could lose a byte that the emulator's
//! timing happened to spare. The link fails with [`Error::InterruptsOff`] (naming the stretch's
//! length and its program counter) at the first that does not, unless
//! [`EmulatorConfig::check_interrupts_off`] is off (a test of a firmware that breaks the rule on
//! purpose).
//!
//! ## Faults
//! [`Faults`] apply to both directions, drawn from one seeded generator: per frame a stall, a
//! cut and a duplication, per byte a drop (its line time passes) and a bit flip — as in
//! [`super::sim::SimLink`]. Frames are the host's [`Link::send`] calls and the device's
//! answers (`00 … 00`).
//!
//! ## Inertial sensor
//! [`EmulatorConfig::imu`] puts a virtual MPU-6050 at 0x68 on the chip's TWI (simavr's own
//! TWI peripheral; the firmware's driver is the flashed one), fed by a
//! [`quad_device::sim::imu::ImuSource`] shared through [`SharedImuSource`]: level and still, a
//! CSV script, a closure (the twin), with seeded noise, bias and fault windows (NAK, stuck
//! data, absent, SDA held low). The sensor refreshes its data at the sample rate the firmware
//! configured; [`EmulatorLink::imu_bus`] counts the bursts the firmware read and lists the
//! registers it wrote.
//!
//! ```no_run
//! use quad_device::sim::imu::{LevelStill, Noisy};
//! use quad_host::emu::SharedImuSource;
//! use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
//!
//! let config = EmulatorConfig {
//!     imu: Some(SharedImuSource::new(Noisy::mpu6050(LevelStill, 1))),
//!     ..EmulatorConfig::new(115_200)
//! };
//! let link = EmulatorLink::boot_built(config)?;
//! # Ok::<(), quad_host::link::emulator::Error>(())
//! ```
//!
//! ## Pin check
//! Every pulse on the twelve servo pins (Timer1/3/4/5 incl. port L) is measured and compared
//! with the readbacks the firmware sent (decoded from its UART output before any line fault):
//! the device stages the widths before it answers and writes the compare registers in the next
//! quiet part of a period (after the pulses, with a millisecond of the period left), and the
//! hardware takes them over at the start of the following period. So a pulse that starts at
//! cycle `t` must be as wide as the pulses of the next readback, of the last one sent before
//! `t`, or of an earlier one superseded less than [`APPLY_LATENCY`] before `t`, within one timer
//! tick (0.5 µs) — or, as every output passes the device's joint-speed limiter, which brings the
//! pins to a new target over several frames, lie between the channel's previous pulse and one
//! of those widths (the limiter's bound per frame is checked by the emulator tests of the
//! motions). A pulse while all of them say the outputs are off, or at power-on before any
//! answer, is an error too. See [`PulseStats`].

use super::{Faults, LineStats, Link};
use crate::emu::{
    self, build, cycles_to_duration, duration_to_cycles, duration_to_cycles_ceil, EmuError, ImuBus,
    Mega2560, Pulse, SharedImuSource, CYCLES_PER_TICK, PERIOD_CYCLES, SERVO_PINS,
};
use quad_protocol::{Accumulator, DeviceToHost, Feed, Flags, MAX_DECODED_LEN};
use seeded_rng::SplitMix64;
use serde::Serialize;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Bit times per byte in simavr's USART model: start, 8 data, stop, and a parity bit that
/// simavr counts even with parity off — 10 % slower than a real 8N1 line (10 bit times), so
/// rates measured on this link are slightly conservative.
pub const SIMAVR_BITS_PER_BYTE: u64 = 11;

/// Longest boot (reset until the firmware's receiver is on), simulated.
pub const BOOT_LIMIT: Duration = Duration::from_secs(1);

/// Largest relative difference between the firmware's line rate and the host's (UART
/// receivers tolerate about ±2 % per side; 115,200 baud is 2.1 % fast at 16 MHz).
pub const BAUD_TOLERANCE: f64 = 0.03;

/// A pulse may differ from the readback by this much: one timer tick (beyond the uncertainty
/// of seeing its edges between simavr steps, see [`Pulse::width_could_be`]).
pub const PULSE_TOLERANCE_CYCLES: u64 = CYCLES_PER_TICK;

/// How the emulated line and MCU are set up.
#[derive(Debug, Clone, PartialEq)]
pub struct EmulatorConfig {
    /// The host's line rate, bit/s; must match the firmware's within [`BAUD_TOLERANCE`].
    pub baud: u32,
    /// Line faults.
    pub faults: Faults,
    /// Seed of the fault generator.
    pub seed: u64,
    /// EEPROM contents at power-on (`None`: erased, all 0xFF).
    pub eeprom: Option<Vec<u8>>,
    /// Fail on an interrupts-off stretch beyond [`receive_cover_cycles`] while bytes arrive
    /// (see the module docs); on by default.
    pub check_interrupts_off: bool,
    /// The MPU-6050 on the TWI and its source (`None`: nothing at 0x68, as on a board without
    /// the sensor). See the module docs' "Inertial sensor".
    pub imu: Option<SharedImuSource>,
}

impl EmulatorConfig {
    /// A clean line at `baud`, erased EEPROM.
    pub fn new(baud: u32) -> EmulatorConfig {
        EmulatorConfig {
            baud,
            faults: Faults::NONE,
            seed: 1,
            eeprom: None,
            check_interrupts_off: true,
            imu: None,
        }
    }
}

/// The longest interrupts-off stretch while bytes arrive that loses none, cycles, for a line of
/// `byte_cycles` cycles per byte: two byte times (the chip's two-byte receive buffer fills while
/// the third byte is still in the shift register).
pub const fn receive_cover_cycles(byte_cycles: u64) -> u64 {
    2 * byte_cycles
}

/// Why the emulator could not start or run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The firmware could not be built.
    #[error(transparent)]
    Build(#[from] build::Error),
    /// No firmware is built for this line rate (and no ELF was given).
    #[error(
        "no firmware is built for {0} baud (115200: firmware, 1000000: firmware-1mbaud); \
         give one with --elf"
    )]
    NoFirmwareForBaud(u32),
    /// simavr failed.
    #[error(transparent)]
    Emu(#[from] EmuError),
    /// The firmware did not switch its receiver on within [`BOOT_LIMIT`].
    #[error(
        "the firmware did not enable its USART0 receiver within {} s of simulated time",
        BOOT_LIMIT.as_secs_f64()
    )]
    NoBoot,
    /// Interrupts stayed off longer than the receive buffer covers while bytes arrived.
    #[error(
        "interrupts were off for {cycles} cycles while bytes arrived (from program counter \
         {pc:#x}, cycle {at_cycle}): more than the {limit} cycles the two-byte receive buffer \
         covers at this line rate; a real chip could lose bytes"
    )]
    InterruptsOff {
        /// The stretch's length while bytes arrived, cycles.
        cycles: u64,
        /// Where the stretch began (byte address).
        pc: u32,
        /// The cycle from which bytes arrived during it.
        at_cycle: u64,
        /// [`receive_cover_cycles`] at the firmware's line rate.
        limit: u64,
    },
    /// The firmware's line rate differs from the host's.
    #[error("the firmware listens at {firmware:.0} baud, the host sends at {host} baud")]
    Baud {
        /// The firmware's, bit/s.
        firmware: f64,
        /// The host's, bit/s.
        host: u32,
    },
}

/// The pin check so far (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct PulseStats {
    /// Pulses measured and compared.
    pub checked: u64,
    /// Pulses whose width matched no readback in force (or that came while the outputs were
    /// off).
    pub errors: u64,
    /// The first error, described.
    pub first_error: Option<String>,
}

/// The pulses of each channel, one period after another: the largest change of width between
/// two consecutive periods (the pair, so that a caller can bound it through the channel's
/// calibration, the pulses' edges known only to a simavr step) and the periods a channel
/// missed (a pulse more than a period and a half after its last).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PulseSteps {
    /// Consecutive pulses compared.
    pub compared: u64,
    /// Pulses that came more than a period and a half after the channel's last.
    pub gaps: u64,
    /// Per channel, the two consecutive pulses with the largest change of width.
    pub largest: [Option<(Pulse, Pulse)>; 12],
    /// Per channel, the narrowest and the widest pulse.
    pub extremes: [Option<(Pulse, Pulse)>; 12],
}

impl PulseSteps {
    fn on_pulse(&mut self, last: &Pulse, now: &Pulse) {
        let e = self.extremes[now.channel].get_or_insert((*now, *now));
        if now.high_cycles < e.0.high_cycles {
            e.0 = *now;
        }
        if now.high_cycles > e.1.high_cycles {
            e.1 = *now;
        }
        if now.rise_cycle - last.rise_cycle > PERIOD_CYCLES * 3 / 2 {
            self.gaps += 1;
            return;
        }
        self.compared += 1;
        let d = now.high_cycles.abs_diff(last.high_cycles);
        let slot = &mut self.largest[now.channel];
        if slot.is_none_or(|(a, b)| b.high_cycles.abs_diff(a.high_cycles) < d) {
            *slot = Some((*last, *now));
        }
    }
}

/// The longest a staged state may wait before the pins show it: a period, the window's last
/// millisecond in which no apply begins, and the millisecond tick that applies it.
pub const APPLY_LATENCY: std::time::Duration = std::time::Duration::from_millis(23);

/// What the firmware reported at one cycle: the pulses on its outputs (`None`: off).
#[derive(Debug, Clone, Copy)]
struct Expect {
    start_cycle: u64,
    pulses: Option<[u16; 12]>,
}

/// The pin check (see the module docs).
struct PulseCheck {
    acc: Accumulator<MAX_DECODED_LEN>,
    in_frame: bool,
    last_zero_cycle: u64,
    frame_start_cycle: u64,
    /// Readbacks in order; the first is the power-on state (outputs off).
    expects: VecDeque<Expect>,
    /// Pulses waiting for the next readback.
    pending: VecDeque<Pulse>,
    /// The last pulse judged on each channel (`None` after a gap: outputs off or a reset).
    last: [Option<Pulse>; 12],
    stats: PulseStats,
}

impl PulseCheck {
    fn new() -> PulseCheck {
        PulseCheck {
            acc: Accumulator::new(),
            in_frame: false,
            last_zero_cycle: 0,
            frame_start_cycle: 0,
            expects: VecDeque::from([Expect {
                start_cycle: 0,
                pulses: None,
            }]),
            pending: VecDeque::new(),
            last: [None; 12],
            stats: PulseStats::default(),
        }
    }

    /// One byte the firmware wrote to UDR0 at `cycle`.
    fn on_device_byte(&mut self, cycle: u64, b: u8) {
        if b == 0 {
            self.in_frame = false;
            self.last_zero_cycle = cycle;
        } else if !self.in_frame {
            self.in_frame = true;
            self.frame_start_cycle = self.last_zero_cycle;
        }
        let mut rest: &[u8] = &[b];
        loop {
            match self.acc.feed::<DeviceToHost>(rest) {
                Feed::NeedMore => break,
                Feed::Frame { msg, remaining } => {
                    rest = remaining;
                    if let Some(readback) = msg.readback() {
                        let on = readback.flags.contains(Flags::OUTPUTS_ENABLED);
                        self.expects.push_back(Expect {
                            start_cycle: self.frame_start_cycle,
                            pulses: on.then_some(readback.pulses_half_us),
                        });
                        self.resolve(false);
                    }
                }
                other => rest = other.remaining(),
            }
        }
    }

    /// The MCU was reset at `cycle`: outputs off from then on.
    fn on_reset(&mut self, cycle: u64) {
        self.acc = Accumulator::new();
        self.in_frame = false;
        self.expects.push_back(Expect {
            start_cycle: cycle,
            pulses: None,
        });
        self.resolve(false);
    }

    fn on_pulse(&mut self, p: Pulse) {
        self.pending.push_back(p);
        self.resolve(false);
    }

    /// Judges the pending pulses whose candidates are known (all of them when `last`).
    fn resolve(&mut self, last: bool) {
        while let Some(&p) = self.pending.front() {
            let Some(k) = self
                .expects
                .iter()
                .rposition(|e| e.start_cycle <= p.rise_cycle)
            else {
                // Older than every readback kept: cannot happen (the first is at cycle 0).
                self.pending.pop_front();
                continue;
            };
            let next = self.expects.get(k + 1).copied();
            if next.is_none() && !last {
                break;
            }
            self.pending.pop_front();
            self.judge(p, k, next);
            // Readbacks superseded longer than the apply latency before this pulse are not
            // needed again.
            let latency = duration_to_cycles(APPLY_LATENCY);
            while self.expects.len() > 2 && self.expects[1].start_cycle + latency < p.rise_cycle {
                self.expects.pop_front();
            }
        }
    }

    /// Judges pulse `p` against the readback `k` (the last sent before it), the next one
    /// (`after`) and the earlier ones still within the apply latency.
    fn judge(&mut self, p: Pulse, k: usize, after: Option<Expect>) {
        self.stats.checked += 1;
        // The channel's previous pulse, when it came in the period before this one.
        let previous = self.last[p.channel].filter(|q| {
            p.rise_cycle.saturating_sub(q.rise_cycle) <= PERIOD_CYCLES + PERIOD_CYCLES / 2
        });
        self.last[p.channel] = Some(p);
        let width = |e: &Expect| {
            e.pulses
                .map(|ps| u64::from(ps[p.channel]) * CYCLES_PER_TICK)
                .filter(|&w| w > 0)
        };
        let exact =
            |e: &Expect| width(e).is_some_and(|w| p.width_could_be(w, PULSE_TOLERANCE_CYCLES));
        let latency = duration_to_cycles(APPLY_LATENCY);
        let mut in_force = (0..=k)
            .rev()
            .take_while(|&j| j == k || self.expects[j + 1].start_cycle + latency > p.rise_cycle);
        let before = self.expects[k];
        if after.as_ref().is_some_and(exact) || in_force.any(|j| exact(&self.expects[j])) {
            return;
        }
        // On its way from the previous pulse to a target held since: the limiter steps the
        // outputs toward the target held at each frame, which is written during the period
        // before its pulse; that target is the one of the last readback sent before the
        // previous pulse or of a later one (readbacks may come faster than frames).
        if let Some(q) = previous {
            let slack = PULSE_TOLERANCE_CYCLES + p.rise_step_cycles + p.fall_step_cycles;
            let first = self
                .expects
                .iter()
                .rposition(|e| e.start_cycle <= q.rise_cycle)
                .unwrap_or(0);
            let between = self
                .expects
                .iter()
                .skip(first)
                .filter(|e| e.start_cycle <= p.rise_cycle)
                .chain([&before])
                .chain(after.as_ref())
                .filter_map(width)
                .any(|w| {
                    let (lo, hi) = (q.high_cycles.min(w), q.high_cycles.max(w));
                    p.high_cycles + slack >= lo && p.high_cycles <= hi + slack
                });
            if between {
                return;
            }
        }
        self.stats.errors += 1;
        if self.stats.first_error.is_none() {
            let show = |e: Option<&Expect>| match e {
                None => "-".to_string(),
                Some(Expect { pulses: None, .. }) => "outputs off".to_string(),
                Some(Expect {
                    pulses: Some(ps), ..
                }) => format!("{} µs", f64::from(ps[p.channel]) / 2.0),
            };
            let (port, bit) = SERVO_PINS[p.channel];
            self.stats.first_error =
                Some(format!(
                "channel {} (P{port}{bit}): pulse of {:.2} µs at {:.3} ms; readback before: {}, \
                 after: {}; the channel's previous pulse: {}",
                p.channel,
                p.high_us(),
                p.rise_cycle as f64 / 16_000.0,
                show(Some(&before)),
                show(after.as_ref()),
                previous.map_or_else(
                    || "-".to_string(),
                    |q| format!("{:.2} µs at {:.3} ms", q.high_us(), q.rise_cycle as f64 / 16_000.0)
                ),
            ));
        }
    }
}

/// The firmware in simavr behind its UART (see the module docs).
pub struct EmulatorLink {
    mcu: Mega2560,
    elf: PathBuf,
    config: EmulatorConfig,
    /// Cycles per byte on the line (the firmware's configured rate).
    byte_cycles: u64,
    /// The firmware's line rate, bit/s.
    firmware_baud: f64,
    rng: SplitMix64,
    /// Host → device bytes, with the cycle from which each may enter the line.
    h2d: VecDeque<(u64, u8)>,
    /// When the host → device line is next free.
    h2d_free: u64,
    /// The device's frame being sent: bytes with their arrival cycle, before faults.
    d2h_frame: Vec<(u64, u8)>,
    /// Device → host bytes on their way, with their arrival cycle, after faults.
    d2h: VecDeque<(u64, u8)>,
    /// Arrival of the last byte put on the device → host line.
    d2h_last: u64,
    resets_seen: u32,
    pulses: PulseCheck,
    /// The last complete pulse of each channel.
    last_pulses: [Option<Pulse>; 12],
    steps: PulseSteps,
    stats: LineStats,
}

impl EmulatorLink {
    /// Builds the firmware if needed and boots the ELF for `config.baud` (`firmware` at
    /// 115,200, `firmware-1mbaud` at 1,000,000 baud).
    ///
    /// # Errors
    /// See [`Error`].
    pub fn boot_built(config: EmulatorConfig) -> Result<EmulatorLink, Error> {
        let bin =
            build::firmware_for_baud(config.baud).ok_or(Error::NoFirmwareForBaud(config.baud))?;
        let elf = build::firmware_elf(bin).map_err(Error::Build)?;
        EmulatorLink::boot(&elf, config)
    }

    /// Powers the MCU on with `elf` and runs it until its receiver is on (bytes sent earlier
    /// would be lost, as on the board).
    ///
    /// # Errors
    /// See [`Error`].
    pub fn boot(elf: &Path, config: EmulatorConfig) -> Result<EmulatorLink, Error> {
        let mut mcu = Mega2560::new(elf)?;
        if let Some(image) = &config.eeprom {
            mcu.set_eeprom(image);
        }
        if let Some(source) = &config.imu {
            mcu.attach_imu(source.clone());
        }
        mcu.capture_pulses(true);
        let limit = duration_to_cycles(BOOT_LIMIT);
        let firmware_baud = loop {
            if let Some(b) = mcu.uart_baud() {
                break b;
            }
            if mcu.cycle() > limit {
                return Err(Error::NoBoot);
            }
            mcu.step()?;
        };
        if (firmware_baud - f64::from(config.baud)).abs() > BAUD_TOLERANCE * firmware_baud {
            return Err(Error::Baud {
                firmware: firmware_baud,
                host: config.baud,
            });
        }
        let byte_cycles =
            (SIMAVR_BITS_PER_BYTE as f64 * f64::from(emu::F_CPU_HZ) / firmware_baud).round() as u64;
        let mut link = EmulatorLink {
            mcu,
            elf: elf.to_path_buf(),
            rng: SplitMix64::new(config.seed),
            config,
            byte_cycles,
            firmware_baud,
            h2d: VecDeque::new(),
            h2d_free: 0,
            d2h_frame: Vec::new(),
            d2h: VecDeque::new(),
            d2h_last: 0,
            resets_seen: 0,
            pulses: PulseCheck::new(),
            last_pulses: [None; 12],
            steps: PulseSteps::default(),
            stats: LineStats::default(),
        };
        link.collect();
        Ok(link)
    }

    /// The emulated MCU.
    pub fn mcu(&self) -> &Mega2560 {
        &self.mcu
    }

    /// The emulated MCU, e.g. to inject a fault.
    pub fn mcu_mut(&mut self) -> &mut Mega2560 {
        &mut self.mcu
    }

    /// The ELF running.
    pub fn elf(&self) -> &Path {
        &self.elf
    }

    /// The firmware's line rate, bit/s.
    pub fn firmware_baud(&self) -> f64 {
        self.firmware_baud
    }

    /// The configuration.
    pub fn config(&self) -> &EmulatorConfig {
        &self.config
    }

    /// What the line did so far; `rx_overflow` counts the bytes the chip's receive buffer
    /// lost (data overruns, see [`crate::emu::Mega2560::rx_overruns`]).
    pub fn line_stats(&self) -> LineStats {
        LineStats {
            rx_overflow: self.mcu.rx_overruns(),
            ..self.stats
        }
    }

    /// What the virtual MPU-6050 saw on the bus (`None`: no sensor configured).
    pub fn imu_bus(&self) -> Option<&ImuBus> {
        self.mcu.imu_bus()
    }

    /// Bytes the chip's receive buffer lost because the firmware did not read them in time.
    pub fn rx_overruns(&self) -> u64 {
        self.mcu.rx_overruns()
    }

    /// The pin check so far, with every pulse judged that can be (pulses that started after
    /// the last readback are judged against it).
    pub fn pulse_stats(&mut self) -> PulseStats {
        self.pulses.resolve(true);
        self.pulses.stats.clone()
    }

    /// The steps between consecutive pulses of each channel since boot (or the last
    /// [`EmulatorLink::reset_pulse_steps`]).
    pub fn pulse_steps(&self) -> PulseSteps {
        self.steps
    }

    /// Forgets the steps seen so far.
    pub fn reset_pulse_steps(&mut self) {
        self.steps = PulseSteps::default();
    }

    /// The last complete pulse seen on each channel.
    pub fn last_pulses(&self) -> [Option<Pulse>; 12] {
        self.last_pulses
    }

    /// Lets `d` of simulated time pass without host activity.
    ///
    /// # Errors
    /// When the CPU stopped.
    pub fn idle(&mut self, d: Duration) -> Result<(), super::Error> {
        let end = self.mcu.cycle() + duration_to_cycles_ceil(d);
        while self.mcu.cycle() < end {
            self.advance()?;
        }
        Ok(())
    }

    /// Runs until every servo channel has shown one complete pulse that started after now,
    /// at most three periods; returns them by channel (`None`: no complete pulse).
    ///
    /// # Errors
    /// When the CPU stopped.
    pub fn next_pulses(&mut self) -> Result<[Option<Pulse>; 12], super::Error> {
        let start = self.mcu.cycle();
        let end = start + 3 * PERIOD_CYCLES;
        let mut seen: [Option<Pulse>; 12] = [None; 12];
        let mut tap = Vec::new();
        while self.mcu.cycle() < end && seen.iter().any(Option::is_none) {
            self.advance_with(&mut tap)?;
            for p in tap.drain(..) {
                if p.rise_cycle > start && seen[p.channel].is_none() {
                    seen[p.channel] = Some(p);
                }
            }
        }
        Ok(seen)
    }

    fn emu_error(e: EmuError) -> super::Error {
        super::Error::Emulator(Error::Emu(e))
    }

    /// One instruction, with the line on both sides and the pin check.
    fn advance(&mut self) -> Result<(), super::Error> {
        self.step_once(None)
    }

    fn advance_with(&mut self, tap: &mut Vec<Pulse>) -> Result<(), super::Error> {
        self.step_once(Some(tap))
    }

    /// One instruction; completed pulses are also copied to `tap`.
    fn step_once(&mut self, mut tap: Option<&mut Vec<Pulse>>) -> Result<(), super::Error> {
        let now = self.mcu.cycle();
        while let Some(&(t, b)) = self.h2d.front() {
            if t > now {
                break;
            }
            self.h2d.pop_front();
            self.mcu.uart_write(&[b]);
        }
        self.mcu.step().map_err(Self::emu_error)?;
        if self.config.check_interrupts_off {
            let off = self.mcu.interrupts_off();
            let limit = receive_cover_cycles(self.byte_cycles);
            if off.longest_receiving_cycles > limit {
                return Err(super::Error::Emulator(Error::InterruptsOff {
                    cycles: off.longest_receiving_cycles,
                    pc: off.longest_receiving_pc,
                    at_cycle: off.longest_receiving_at_cycle,
                    limit,
                }));
            }
        }
        let resets = self.mcu.resets();
        if resets.count != self.resets_seen {
            self.resets_seen = resets.count;
            let at = resets.last_cycle.unwrap_or(now);
            self.pulses.on_reset(at);
            // A frame cut by the reset is sent as far as it got.
            self.finish_frame();
        }
        self.collect();
        while let Some(p) = self.mcu.pop_pulse() {
            if let Some(t) = tap.as_deref_mut() {
                t.push(p);
            }
            if let Some(last) = self.last_pulses[p.channel] {
                self.steps.on_pulse(&last, &p);
            }
            self.last_pulses[p.channel] = Some(p);
            self.pulses.on_pulse(p);
        }
        Ok(())
    }

    /// Takes the bytes the firmware sent.
    fn collect(&mut self) {
        while let Some((cycle, b)) = self.mcu.uart_pop() {
            self.stats.d2h_bytes += 1;
            self.pulses.on_device_byte(cycle, b);
            self.d2h_frame.push((cycle + self.byte_cycles, b));
            if b == 0 && self.d2h_frame.iter().any(|&(_, x)| x != 0) {
                self.finish_frame();
            }
        }
    }

    /// Puts the device's frame on the line, with the faults.
    fn finish_frame(&mut self) {
        if self.d2h_frame.is_empty() {
            return;
        }
        let frame = std::mem::take(&mut self.d2h_frame);
        let f = self.config.faults;
        let bc = self.byte_cycles;
        let plan = f.plan_frame(&mut self.rng, &frame, &mut self.stats);
        let shift = if plan.stall {
            duration_to_cycles(Duration::from_secs_f64(f.stall_ms * 1e-3))
        } else {
            0
        };
        let span = plan.bytes.len() as u64 * bc;
        for copy in 0..plan.copies {
            for &(t, b) in plan.bytes {
                let mut arrival = t + shift + copy * span;
                arrival = arrival.max(self.d2h_last + if self.d2h_last > 0 { bc } else { 0 });
                self.d2h_last = arrival;
                if let Some(b) = f.pass_byte(&mut self.rng, b, &mut self.stats) {
                    self.d2h.push_back((arrival, b));
                }
            }
        }
    }
}

impl Link for EmulatorLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), super::Error> {
        self.stats.h2d_bytes += bytes.len() as u64;
        let f = self.config.faults;
        let bc = self.byte_cycles;
        let mut start = self.mcu.cycle().max(self.h2d_free);
        let plan = f.plan_frame(&mut self.rng, bytes, &mut self.stats);
        if plan.stall {
            start += duration_to_cycles(Duration::from_secs_f64(f.stall_ms * 1e-3));
        }
        let mut t = start;
        for _ in 0..plan.copies {
            for &b in plan.bytes {
                let slot = t;
                t += bc;
                if let Some(b) = f.pass_byte(&mut self.rng, b, &mut self.stats) {
                    self.h2d.push_back((slot, b));
                }
            }
        }
        self.h2d_free = t;
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, super::Error> {
        // Rounded up: the caller's clock must reach its deadline (a deadline a fraction of a
        // cycle away would otherwise never pass).
        let deadline = self.mcu.cycle() + duration_to_cycles_ceil(timeout);
        let mut n = 0;
        loop {
            let now = self.mcu.cycle();
            while n < buf.len() {
                match self.d2h.front() {
                    Some(&(t, b)) if t <= now => {
                        self.d2h.pop_front();
                        buf[n] = b;
                        n += 1;
                        if b == 0 && n > 1 {
                            return Ok(n);
                        }
                    }
                    _ => break,
                }
            }
            if n == buf.len() || now >= deadline {
                return Ok(n);
            }
            self.advance()?;
        }
    }

    fn now(&self) -> Duration {
        cycles_to_duration(self.mcu.cycle())
    }

    fn baud(&self) -> u32 {
        self.config.baud
    }

    fn emulator(&mut self) -> Option<&mut EmulatorLink> {
        Some(self)
    }
}

/// An [`EmulatorLink`] whose EEPROM image is written back to a file when it is dropped (as
/// [`super::open`] returns it for a `storage` file), so that a calibration saved in one run is
/// there in the next.
pub struct WithStorage {
    /// The link.
    pub link: EmulatorLink,
    /// The EEPROM image file.
    pub eeprom_file: Option<PathBuf>,
}

impl Drop for WithStorage {
    fn drop(&mut self) {
        if let Some(path) = &self.eeprom_file {
            let image = self.link.mcu_mut().eeprom();
            if let Err(e) = std::fs::write(path, image) {
                // A destructor cannot return the error; losing it silently would lose the save.
                eprintln!("quadctl: cannot write {}: {e}", path.display());
            }
        }
    }
}

impl Link for WithStorage {
    fn send(&mut self, bytes: &[u8]) -> Result<(), super::Error> {
        self.link.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, super::Error> {
        self.link.recv(buf, timeout)
    }
    fn now(&self) -> Duration {
        self.link.now()
    }
    fn baud(&self) -> u32 {
        self.link.baud()
    }
    fn emulator(&mut self) -> Option<&mut EmulatorLink> {
        Some(&mut self.link)
    }
}
