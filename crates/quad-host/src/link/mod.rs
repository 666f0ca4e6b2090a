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
//!
//! A link moves bytes and tells the time; framing, sequence numbers and retries are the
//! [`crate::client`]'s.

pub mod emulator;
pub mod serial;
pub mod sim;

use sim::Rng;
use std::fmt;
use std::io;
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
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError>;

    /// Waits at most `timeout` for received bytes and copies them into `buf`; returns 0 when
    /// the timeout passed without any. May return as soon as one byte is there.
    ///
    /// # Errors
    /// When the link is down and cannot be reopened.
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError>;

    /// The link's clock: simulated time for simulated links, monotonic wall time otherwise.
    /// Timeouts and rates are measured on it.
    fn now(&self) -> Duration;

    /// The line rate, bit/s.
    fn baud(&self) -> u32;
}

impl<L: Link + ?Sized> Link for &mut L {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError> {
        (**self).recv(buf, timeout)
    }
    fn now(&self) -> Duration {
        (**self).now()
    }
    fn baud(&self) -> u32 {
        (**self).baud()
    }
}

/// Why a link failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum LinkError {
    /// The port could not be opened or reopened.
    Open {
        /// The port.
        path: String,
        /// The driver's message.
        message: String,
    },
    /// Reading or writing failed and reopening did not help.
    Io(io::Error),
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Open { path, message } => write!(f, "cannot open {path}: {message}"),
            LinkError::Io(e) => write!(f, "link I/O error: {e}"),
        }
    }
}

impl std::error::Error for LinkError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LinkError::Io(e) => Some(e),
            LinkError::Open { .. } => None,
        }
    }
}

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
        rng: &mut Rng,
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
        rng: &mut Rng,
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

/// A `--faults` value that could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultsError(pub String);

impl fmt::Display for FaultsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (expected KEY=VALUE,... with keys drop, flip, dup, trunc, stall (probabilities in [0, 1]) and stall_ms (>= 0))",
            self.0
        )
    }
}

impl std::error::Error for FaultsError {}

impl FromStr for Faults {
    type Err = FaultsError;

    /// Parses `drop=0.01,flip=0.001,dup=P,trunc=P,stall=P,stall_ms=MS`; keys may be left out.
    fn from_str(s: &str) -> Result<Faults, FaultsError> {
        let mut f = Faults::NONE;
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| FaultsError(format!("`{part}` is not KEY=VALUE")))?;
            let v: f64 = value
                .trim()
                .parse()
                .map_err(|_| FaultsError(format!("`{}` is not a number", value.trim())))?;
            let probability = |v: f64| {
                if (0.0..=1.0).contains(&v) {
                    Ok(v)
                } else {
                    Err(FaultsError(format!("{key}={v} is not a probability")))
                }
            };
            match key.trim() {
                "drop" => f.drop = probability(v)?,
                "flip" => f.flip = probability(v)?,
                "dup" => f.dup = probability(v)?,
                "trunc" => f.trunc = probability(v)?,
                "stall" => f.stall = probability(v)?,
                "stall_ms" if v >= 0.0 && v.is_finite() => f.stall_ms = v,
                "stall_ms" => return Err(FaultsError(format!("stall_ms={v} must be >= 0"))),
                other => return Err(FaultsError(format!("unknown fault `{other}`"))),
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
