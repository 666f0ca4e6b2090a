//! A device link served on a pseudo-terminal: the simulated device or the emulated firmware
//! behind `/dev/pts/N`, so that any program that opens a serial port (every `quadctl` command
//! with `--port`, the panel, a terminal program, a script with pyserial) talks to it as to a
//! board, and the device keeps its state from one program to the next.
//!
//! The pseudo-terminal comes from the `serialport` crate ([`TTYPort::pair`]), which the serial
//! link ([`super::serial`]) already uses: no second terminal library, and the pair is set up
//! raw (no echo, no line editing) before anyone opens it. This end keeps the terminal's own
//! side (the one programs open) open as well, so that the terminal lives while programs come
//! and go (a closed terminal would hang up); a program that opens it finds it as it would find
//! a board's port, and its line settings (rate, 8N1, DTR) are taken and ignored, as a USB
//! serial bridge ignores most of them.
//!
//! ## Time
//! The simulated and the emulated links run on their own clocks ([`Link::recv`] lets time
//! pass). [`VirtualPort::serve`] holds the link's clock to the wall clock: the device's 20 ms
//! servo frames, the link-loss timeout and a motion's duration take as long as on a board,
//! and the bytes cross the device's line at its rate ([`Link::baud`]) whatever the program set.
//! The simulated device keeps up easily; simavr runs the firmware at about two thirds of the
//! chip's speed on a desktop machine, so the emulated firmware's time falls behind the wall
//! clock and it answers more slowly than a board would (never sooner).
//!
//! [`crate::link`]'s other pipe, the `quad-link-bridge` binary, serves a link over its
//! standard input and output to the Python package, which drives the link's clock itself;
//! here nobody drives it, so the clock follows the wall clock.

use super::{Error, Link};
use serialport::{SerialPort, TTYPort};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Longest stretch of the link's time let pass without looking for the program's bytes.
pub const MAX_STEP: Duration = Duration::from_millis(2);

/// How long [`VirtualPort::serve`] waits for the program's bytes when the link's clock is up
/// to the wall clock: the granularity of the port's timing.
pub const POLL: Duration = Duration::from_micros(500);

/// How long a write of the device's bytes waits for room in the terminal before they are
/// dropped (nobody reads them: a board's bytes are lost the same way).
pub const WRITE_WAIT: Duration = Duration::from_millis(50);

/// What went through a [`VirtualPort`].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct PortStats {
    /// Bytes the programs sent to the device.
    pub h2d_bytes: u64,
    /// Bytes the device sent to the programs.
    pub d2h_bytes: u64,
    /// Device bytes dropped because nobody read the terminal.
    pub d2h_dropped: u64,
    /// How far the link's clock fell behind the wall clock at most, ms (the emulated firmware
    /// runs slower than the chip).
    pub behind_max_ms: f64,
}

/// A pseudo-terminal pair: the end this process serves, and the path programs open.
pub struct VirtualPort {
    master: TTYPort,
    /// Held open so that the terminal lives between the programs that open it.
    _slave: TTYPort,
    path: PathBuf,
}

impl VirtualPort {
    /// A new pseudo-terminal, raw.
    ///
    /// # Errors
    /// [`Error::Open`] when the system has no free pseudo-terminal.
    pub fn open() -> Result<VirtualPort, Error> {
        let (master, slave) = TTYPort::pair().map_err(|e| Error::Open {
            path: "a pseudo-terminal".to_owned(),
            message: e.to_string(),
        })?;
        let path = slave.name().map(PathBuf::from).ok_or_else(|| Error::Open {
            path: "a pseudo-terminal".to_owned(),
            message: "it has no name".to_owned(),
        })?;
        Ok(VirtualPort {
            master,
            _slave: slave,
            path,
        })
    }

    /// The path programs open, e.g. `/dev/pts/3`.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Passes bytes between the terminal and `link` until `stop` is set, holding the link's
    /// clock to the wall clock (see the module docs).
    ///
    /// # Errors
    /// When the link fails, or the terminal cannot be read.
    pub fn serve(&mut self, link: &mut dyn Link, stop: &AtomicBool) -> Result<PortStats, Error> {
        let mut stats = PortStats::default();
        let start_wall = Instant::now();
        let start_link = link.now();
        let mut buf = [0u8; 512];
        while !stop.load(Ordering::Relaxed) {
            // The device's side: its clock up to the wall clock, a step at a time.
            let wall = start_link + start_wall.elapsed();
            let step_end = wall.min(link.now() + MAX_STEP);
            while link.now() < step_end {
                let n = link.recv(&mut buf, step_end - link.now())?;
                if n > 0 {
                    stats.d2h_bytes += n as u64;
                    if !self.write(&buf[..n]) {
                        stats.d2h_dropped += n as u64;
                    }
                }
            }
            let behind = (start_link + start_wall.elapsed()).saturating_sub(link.now());
            stats.behind_max_ms = stats.behind_max_ms.max(behind.as_secs_f64() * 1e3);
            // The programs' side: what they wrote, waiting a little when the device is up to
            // date and not at all when it is behind.
            let wait = if behind > MAX_STEP {
                Duration::from_micros(1)
            } else {
                POLL
            };
            self.master
                .set_timeout(wait)
                .map_err(|e| Error::Io(io::Error::other(e.to_string())))?;
            match self.master.read(&mut buf) {
                Ok(n) if n > 0 => {
                    stats.h2d_bytes += n as u64;
                    link.send(&buf[..n])?;
                }
                Ok(_) => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::TimedOut
                            | io::ErrorKind::WouldBlock
                            | io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(Error::Io(e)),
            }
        }
        Ok(stats)
    }

    /// Hands the device's bytes to the terminal; false when nobody made room for them in
    /// [`WRITE_WAIT`].
    fn write(&mut self, bytes: &[u8]) -> bool {
        if self.master.set_timeout(WRITE_WAIT).is_err() {
            return false;
        }
        self.master.write_all(bytes).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::serial::SerialLink;
    use std::sync::Arc;

    /// A link that echoes what it is sent, on a clock that `recv` advances.
    struct Echo {
        now: Duration,
        pending: Vec<u8>,
    }

    impl Link for Echo {
        fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
            self.pending.extend_from_slice(bytes);
            Ok(())
        }
        fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
            let n = self.pending.len().min(buf.len());
            buf[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            if n == 0 {
                self.now += timeout;
            }
            Ok(n)
        }
        fn now(&self) -> Duration {
            self.now
        }
        fn baud(&self) -> u32 {
            115_200
        }
    }

    #[test]
    fn the_serial_link_opens_the_virtual_port_twice_and_its_bytes_go_through() {
        let mut port = VirtualPort::open().expect("a pseudo-terminal");
        let path = port.path().to_str().expect("a UTF-8 path").to_owned();
        let stop = Arc::new(AtomicBool::new(false));
        let stop_server = stop.clone();
        let server = std::thread::spawn(move || {
            let mut link = Echo {
                now: Duration::ZERO,
                pending: Vec::new(),
            };
            port.serve(&mut link, &stop_server)
        });
        for round in 0..2u8 {
            // The serial link's settings (rate, 8N1, no flow control, HUPCL) on a pty.
            let mut link = SerialLink::open(&path, 115_200).expect("the serial link opens it");
            let sent = [0, 1, 2, 3, round, 0];
            link.send(&sent).expect("send");
            let mut got = Vec::new();
            let deadline = Instant::now() + Duration::from_secs(5);
            while got.len() < sent.len() && Instant::now() < deadline {
                let mut buf = [0u8; 16];
                let n = link
                    .recv(&mut buf, Duration::from_millis(100))
                    .expect("recv");
                got.extend_from_slice(&buf[..n]);
            }
            assert_eq!(got, sent, "round {round}");
        }
        stop.store(true, Ordering::Relaxed);
        let stats = server.join().expect("the server").expect("served");
        assert_eq!((stats.h2d_bytes, stats.d2h_bytes), (12, 12));
    }
}
