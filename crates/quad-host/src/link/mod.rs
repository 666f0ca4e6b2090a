//! Byte links to the device: the [`Link`] trait and its implementations.
//!
//! - [`serial::SerialLink`]: a real serial port (an Arduino Mega on USB), with timeouts and
//!   reconnect on error.
//! - [`sim::SimLink`]: a simulated UART running the `quad-device` controller in-process, with the
//!   timing of a real line on a virtual clock and seeded fault injection.
//!
//! - [`emulator::EmulatorLink`]: the real firmware ELF in simavr in-process, behind its USART0,
//!   on the emulated MCU's clock, with the same fault injection and a check of the pulses on
//!   the twelve servo pins against the readbacks.
//! - [`pty::VirtualPort`] (Unix): either of the two above served on a pseudo-terminal, for
//!   programs that open a serial port.
//!
//! A link moves bytes and tells the time; framing, sequence numbers and retries are the
//! [`crate::client`]'s. [`open`] is the one way to open a link from a [`Target`].

pub mod emulator;
#[cfg(unix)]
pub mod pty;
pub mod serial;
pub mod sim;

use quad_device::{Config, ConfigError};
use quad_protocol::RobotPreset;
use seeded_rng::SplitMix64;
use std::io;
use std::path::PathBuf;
use std::str::FromStr;
use std::time::Duration;

/// Bits on the wire per byte: 8N1 (start, 8 data, stop).
pub const BITS_PER_BYTE: u32 = 10;

/// Time one byte takes on a line of `baud` bit/s.
pub fn byte_time(baud: u32) -> Duration {
    Duration::from_nanos(u64::from(BITS_PER_BYTE) * 1_000_000_000 / u64::from(baud.max(1)))
}

/// A bidirectional byte link with a clock.
pub trait Link {
    /// Hands `bytes` to the line. Returns without waiting for them to be sent (like a write to
    /// a serial port's driver buffer); the line sends them at its own rate.
    ///
    /// # Errors
    /// When the link is down and cannot be reopened.
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error>;

    /// Waits at most `timeout` for received bytes and copies them into `buf`; returns 0 when
    /// the timeout passed without any. May return as soon as one byte is there.
    ///
    /// # Errors
    /// When the link is down and cannot be reopened.
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error>;

    /// The link's clock: simulated time for simulated links, monotonic wall time otherwise.
    /// Timeouts and rates are measured on it.
    fn now(&self) -> Duration;

    /// The line rate, bit/s.
    fn baud(&self) -> u32;

    /// The emulated firmware behind this link, when it is one: its pin check and MCU.
    fn emulator(&mut self) -> Option<&mut emulator::EmulatorLink> {
        None
    }
}

impl<L: Link + ?Sized> Link for &mut L {
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
        (**self).recv(buf, timeout)
    }
    fn now(&self) -> Duration {
        (**self).now()
    }
    fn baud(&self) -> u32 {
        (**self).baud()
    }
    fn emulator(&mut self) -> Option<&mut emulator::EmulatorLink> {
        (**self).emulator()
    }
}

impl<L: Link + ?Sized> Link for Box<L> {
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
        (**self).recv(buf, timeout)
    }
    fn now(&self) -> Duration {
        (**self).now()
    }
    fn baud(&self) -> u32 {
        (**self).baud()
    }
    fn emulator(&mut self) -> Option<&mut emulator::EmulatorLink> {
        (**self).emulator()
    }
}

/// Where the device is, and how its line is set up.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Target {
    /// The `quad-device` controller of a preset robot behind a simulated UART ([`sim`]).
    Sim {
        /// The robot the simulated device runs.
        preset: RobotPreset,
        /// Line and device timing, faults.
        config: sim::SimConfig,
        /// EEPROM image file, read at power-on and written on every change.
        storage: Option<PathBuf>,
    },
    /// The real firmware in simavr ([`emulator`]).
    Emulator {
        /// The firmware ELF; `None`: built from `firmware-avr/` for the line rate.
        elf: Option<PathBuf>,
        /// Line rate, faults, EEPROM at power-on (overridden by `storage` when it exists).
        config: emulator::EmulatorConfig,
        /// EEPROM image file, read at power-on and written back when the link is dropped.
        storage: Option<PathBuf>,
    },
    /// A real device on a serial port ([`serial`]).
    Serial {
        /// The port, e.g. `/dev/ttyACM0`.
        path: String,
        /// Line rate, bit/s.
        baud: u32,
    },
}

impl Target {
    /// True when the device runs the host's own maths (the simulated controller), so that its
    /// angles equal the host's bit for bit.
    pub fn runs_host_math(&self) -> bool {
        matches!(self, Target::Sim { .. })
    }
}

/// Opens the link to `target`: the one factory of links.
///
/// # Errors
/// [`Error::Open`] for a port, [`Error::Emulator`] when the firmware cannot be built or booted,
/// [`Error::Storage`] for an unreadable EEPROM image, [`Error::NoSimulatedRobot`] and
/// [`Error::Device`] for a simulated device that cannot be built.
pub fn open(target: &Target) -> Result<Box<dyn Link>, Error> {
    match target {
        Target::Serial { path, baud } => Ok(Box::new(serial::SerialLink::open(path, *baud)?)),
        Target::Emulator {
            elf,
            config,
            storage,
        } => {
            let mut config = config.clone();
            if let Some(path) = storage {
                match std::fs::read(path) {
                    Ok(bytes) => config.eeprom = Some(bytes),
                    Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                    Err(source) => {
                        return Err(Error::Storage {
                            path: path.clone(),
                            source,
                        })
                    }
                }
            }
            let link = match elf {
                Some(elf) => emulator::EmulatorLink::boot(elf, config),
                None => emulator::EmulatorLink::boot_built(config),
            }?;
            Ok(Box::new(emulator::WithStorage {
                link,
                eeprom_file: storage.clone(),
            }))
        }
        Target::Sim {
            preset,
            config,
            storage,
        } => {
            let device = Config::for_preset(*preset).ok_or(Error::NoSimulatedRobot)?;
            let storage = match storage {
                Some(path) => {
                    sim::EepromImage::with_file(path.clone()).map_err(|source| Error::Storage {
                        path: path.clone(),
                        source,
                    })?
                }
                None => sim::EepromImage::erased(),
            };
            Ok(Box::new(sim::SimLink::new(*config, device, storage)?))
        }
    }
}

/// Why a link could not be opened or failed, or a `--faults` value could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The port could not be opened or reopened.
    #[error("cannot open {path}: {message}")]
    Open {
        /// The port.
        path: String,
        /// The driver's message.
        message: String,
    },
    /// Reading or writing failed and reopening did not help.
    #[error("link I/O error: {0}")]
    Io(#[from] io::Error),
    /// The emulator could not be started or stopped.
    #[error(transparent)]
    Emulator(#[from] emulator::Error),
    /// The EEPROM image file of a simulated or emulated device could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Storage {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// The simulated device was asked for a robot that is not a preset.
    #[error("the simulated device needs a preset robot (shahriar2023 or fernando2025)")]
    NoSimulatedRobot,
    /// The simulated device refused its configuration.
    #[error("the simulated device: {0}")]
    Device(#[from] ConfigError),
    /// A `--faults` entry is not `KEY=VALUE`.
    #[error("`{0}` is not KEY=VALUE{FAULTS_SYNTAX}")]
    FaultsSyntax(String),
    /// A `--faults` value is not a number.
    #[error("`{0}` is not a number{FAULTS_SYNTAX}")]
    FaultsNumber(String),
    /// A `--faults` probability is outside [0, 1].
    #[error("{key}={value} is not a probability{FAULTS_SYNTAX}")]
    FaultsProbability {
        /// The key.
        key: String,
        /// The value given.
        value: f64,
    },
    /// A negative or non-finite `stall_ms`.
    #[error("stall_ms={0} must be >= 0{FAULTS_SYNTAX}")]
    FaultsStall(f64),
    /// An unknown `--faults` key.
    #[error("unknown fault `{0}`{FAULTS_SYNTAX}")]
    FaultsKey(String),
}

/// The syntax of a `--faults` value, appended to its errors.
const FAULTS_SYNTAX: &str = " (expected KEY=VALUE,... with keys drop, flip, dup, trunc, stall \
(probabilities in [0, 1]) and stall_ms (>= 0))";

/// Fault injection of the simulated line, the same in both directions. Probabilities are per
/// byte (`drop`, `flip`) or per frame, i.e. per [`Link::send`] call and per device answer
/// (`dup`, `trunc`, `stall`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// A byte is lost (the line time passes, nothing arrives).
    pub drop: f64,
    /// One random bit of a byte is flipped.
    pub flip: f64,
    /// A frame is sent twice back to back.
    pub dup: f64,
    /// A frame is cut after a random number of bytes.
    pub trunc: f64,
    /// The line stalls for `stall_ms` before a frame.
    pub stall: f64,
    /// Length of a stall, ms.
    pub stall_ms: f64,
}

/// Default stall length, ms.
pub const DEFAULT_STALL_MS: f64 = 50.0;

impl Faults {
    /// No faults.
    pub const NONE: Faults = Faults {
        drop: 0.0,
        flip: 0.0,
        dup: 0.0,
        trunc: 0.0,
        stall: 0.0,
        stall_ms: DEFAULT_STALL_MS,
    };

    /// True when no fault can happen.
    pub fn is_none(&self) -> bool {
        self.drop == 0.0
            && self.flip == 0.0
            && self.dup == 0.0
            && self.trunc == 0.0
            && self.stall == 0.0
    }

    /// Draws the per-frame faults of `frame`, always in the order stall, cut, duplicate, so that
    /// a seed injects the same faults on every link.
    pub(crate) fn plan_frame<'a, T>(
        &self,
        rng: &mut SplitMix64,
        frame: &'a [T],
        stats: &mut impl FaultStats,
    ) -> FramePlan<'a, T> {
        let stall = rng.chance(self.stall);
        if stall {
            stats.count(Fault::Stall);
        }
        let mut bytes = frame;
        if bytes.len() > 1 && rng.chance(self.trunc) {
            stats.count(Fault::Truncate);
            bytes = &bytes[..1 + rng.below(bytes.len() as u64 - 1) as usize];
        }
        let copies = if rng.chance(self.dup) {
            stats.count(Fault::Duplicate);
            2
        } else {
            1
        };
        FramePlan {
            stall,
            bytes,
            copies,
        }
    }

    /// Passes one byte through the per-byte faults: `None` when it is dropped, else the byte,
    /// with one random bit flipped with probability `flip`.
    pub(crate) fn pass_byte(
        &self,
        rng: &mut SplitMix64,
        b: u8,
        stats: &mut impl FaultStats,
    ) -> Option<u8> {
        if rng.chance(self.drop) {
            stats.count(Fault::Drop);
            return None;
        }
        Some(if rng.chance(self.flip) {
            stats.count(Fault::Flip);
            b ^ (1 << rng.below(8))
        } else {
            b
        })
    }
}

/// One kind of injected fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Fault {
    /// The line stalled before a frame.
    Stall,
    /// A frame was cut.
    Truncate,
    /// A frame was sent twice.
    Duplicate,
    /// A byte was lost.
    Drop,
    /// A bit of a byte was flipped.
    Flip,
}

/// Link statistics that count the injected faults.
pub(crate) trait FaultStats {
    /// Counts one `fault`.
    fn count(&mut self, fault: Fault);
}

/// What fault injection does to one frame ([`Faults::plan_frame`]).
pub(crate) struct FramePlan<'a, T> {
    /// The line stalls for `stall_ms` before the frame.
    pub stall: bool,
    /// What is sent: the frame, or its first bytes when cut.
    pub bytes: &'a [T],
    /// 2 when the frame is sent twice back to back, else 1.
    pub copies: u64,
}

/// What the simulated and the emulated lines did (fault injection counts, bytes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LineStats {
    /// Bytes the host handed to the line (before faults).
    pub h2d_bytes: u64,
    /// Bytes the device handed to the line (before faults).
    pub d2h_bytes: u64,
    /// Bytes dropped by fault injection.
    pub dropped: u64,
    /// Bytes with a flipped bit.
    pub flipped: u64,
    /// Frames sent twice.
    pub duplicated: u64,
    /// Frames cut.
    pub truncated: u64,
    /// Stalls.
    pub stalls: u64,
    /// Bytes lost because the device's receive buffer was full: the simulated device's FIFO,
    /// or on the emulator the chip's two-byte buffer (data overruns).
    pub rx_overflow: u64,
}

impl FaultStats for LineStats {
    fn count(&mut self, fault: Fault) {
        match fault {
            Fault::Stall => self.stalls += 1,
            Fault::Truncate => self.truncated += 1,
            Fault::Duplicate => self.duplicated += 1,
            Fault::Drop => self.dropped += 1,
            Fault::Flip => self.flipped += 1,
        }
    }
}

impl FromStr for Faults {
    type Err = Error;

    /// Parses `drop=0.01,flip=0.001,dup=P,trunc=P,stall=P,stall_ms=MS`; keys may be left out.
    fn from_str(s: &str) -> Result<Faults, Error> {
        let mut f = Faults::NONE;
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| Error::FaultsSyntax(part.to_owned()))?;
            let v: f64 = value
                .trim()
                .parse()
                .map_err(|_| Error::FaultsNumber(value.trim().to_owned()))?;
            let probability = |v: f64| {
                if (0.0..=1.0).contains(&v) {
                    Ok(v)
                } else {
                    Err(Error::FaultsProbability {
                        key: key.trim().to_owned(),
                        value: v,
                    })
                }
            };
            match key.trim() {
                "drop" => f.drop = probability(v)?,
                "flip" => f.flip = probability(v)?,
                "dup" => f.dup = probability(v)?,
                "trunc" => f.trunc = probability(v)?,
                "stall" => f.stall = probability(v)?,
                "stall_ms" if v >= 0.0 && v.is_finite() => f.stall_ms = v,
                "stall_ms" => return Err(Error::FaultsStall(v)),
                other => return Err(Error::FaultsKey(other.to_owned())),
            }
        }
        Ok(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse() {
        let f: Faults = "drop=0.01, flip=0.001,stall=0.1,stall_ms=20"
            .parse()
            .unwrap();
        assert_eq!(
            f,
            Faults {
                drop: 0.01,
                flip: 0.001,
                stall: 0.1,
                stall_ms: 20.0,
                ..Faults::NONE
            }
        );
        assert!("".parse::<Faults>().unwrap().is_none());
        assert!("drop=2".parse::<Faults>().is_err());
        assert!("drip=0.1".parse::<Faults>().is_err());
        assert!("drop".parse::<Faults>().is_err());
        assert!("drop=x".parse::<Faults>().is_err());
    }

    #[test]
    fn byte_times() {
        assert_eq!(byte_time(1_000_000), Duration::from_micros(10));
        assert_eq!(byte_time(115_200), Duration::from_nanos(86_805));
    }
}
