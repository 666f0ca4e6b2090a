//! A real serial port (the Arduino Mega's USB serial), through the `serialport` crate.
//!
//! Reads wait at most the requested timeout. An I/O error other than a timeout drops the port;
//! the next access reopens it (up to [`REOPEN_ATTEMPTS`] times, [`REOPEN_PAUSE`] apart), so a
//! replugged cable or a board reset costs a few retries of the client, not the session.
//!
//! Opening the port of an Arduino Mega pulses DTR, which resets the board: its bootloader runs
//! for about 1.5 s before the firmware listens. The client's handshake retries cover that.

use super::{Error, Link};
use serialport::SerialPort;
use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

/// Attempts to reopen a port after an error.
pub const REOPEN_ATTEMPTS: u32 = 5;

/// Pause between two reopen attempts.
pub const REOPEN_PAUSE: Duration = Duration::from_millis(200);

/// A serial port, reopened on error.
pub struct SerialLink {
    path: String,
    baud: u32,
    port: Option<Box<dyn SerialPort>>,
    epoch: Instant,
    reopens: u32,
}

impl SerialLink {
    /// Opens `path` at `baud`, 8N1, no flow control.
    ///
    /// # Errors
    /// [`Error::Open`] when the port cannot be opened.
    pub fn open(path: &str, baud: u32) -> Result<SerialLink, Error> {
        let mut link = SerialLink {
            path: path.to_owned(),
            baud,
            port: None,
            epoch: Instant::now(),
            reopens: 0,
        };
        link.port = Some(link.open_port()?);
        Ok(link)
    }

    /// How many times the port was reopened after an error.
    pub fn reopens(&self) -> u32 {
        self.reopens
    }

    fn open_port(&self) -> Result<Box<dyn SerialPort>, Error> {
        serialport::new(&self.path, self.baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(100))
            .open()
            .map_err(|e| Error::Open {
                path: self.path.clone(),
                message: e.to_string(),
            })
    }

    /// The open port, reopening it when it was dropped.
    fn port(&mut self) -> Result<&mut Box<dyn SerialPort>, Error> {
        if self.port.is_none() {
            let mut last = None;
            for attempt in 0..REOPEN_ATTEMPTS {
                if attempt > 0 {
                    std::thread::sleep(REOPEN_PAUSE);
                }
                match self.open_port() {
                    Ok(p) => {
                        self.port = Some(p);
                        self.reopens += 1;
                        break;
                    }
                    Err(e) => last = Some(e),
                }
            }
            if self.port.is_none() {
                return Err(last.unwrap_or_else(|| Error::Open {
                    path: self.path.clone(),
                    message: "no attempt made".to_owned(),
                }));
            }
        }
        self.port
            .as_mut()
            .ok_or_else(|| Error::Io(io::ErrorKind::NotConnected.into()))
    }
}

impl Link for SerialLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
        // One retry on a fresh port.
        for attempt in 0..2 {
            let port = self.port()?;
            match port.write_all(bytes).and_then(|()| port.flush()) {
                Ok(()) => return Ok(()),
                Err(e) if attempt == 1 => return Err(Error::Io(e)),
                Err(_) => self.port = None,
            }
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        let port = self.port()?;
        // serialport refuses a zero timeout on some platforms.
        let timeout = timeout.max(Duration::from_millis(1));
        if let Err(e) = port.set_timeout(timeout) {
            self.port = None;
            return Err(Error::Io(io::Error::other(e.to_string())));
        }
        match port.read(buf) {
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                ) =>
            {
                Ok(0)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(_) => {
                // Reopened on the next access; to the caller this read timed out.
                self.port = None;
                Ok(0)
            }
        }
    }

    fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    fn baud(&self) -> u32 {
        self.baud
    }
}
