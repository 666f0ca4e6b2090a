//! A device link served by the `quad-link-bridge` process (crates/quad-link-bridge) over its
//! stdin/stdout: how `Device.emulator` ([`crate::device::Device`]) reaches the firmware in
//! simavr, which cannot be linked into this shared library (simavr's static libelf uses
//! initial-exec TLS).

use quad_host::link::{Error, Link};
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::Duration;

/// The link to a `quad-link-bridge` child process.
pub struct BridgeLink {
    child: Child,
    input: BufWriter<ChildStdin>,
    output: BufReader<ChildStdout>,
    baud: u32,
    now: Duration,
}

fn other(message: String) -> Error {
    Error::Io(io::Error::other(message))
}

impl BridgeLink {
    /// Starts `program` with `args` and waits for its link to open.
    ///
    /// # Errors
    /// The program cannot be started, or its link did not open (its message).
    pub fn spawn(program: &Path, args: &[String]) -> Result<BridgeLink, Error> {
        let mut child = Command::new(program)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| other(format!("cannot start {}: {e}", program.display())))?;
        let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
            return Err(other("no pipes to the bridge".to_owned()));
        };
        let mut link = BridgeLink {
            child,
            input: BufWriter::new(stdin),
            output: BufReader::new(stdout),
            baud: 0,
            now: Duration::ZERO,
        };
        link.reply(&mut [])?;
        Ok(link)
    }

    /// Reads one reply: updates the clock and copies the received bytes into `buf`.
    fn reply(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        let mut status = [0u8; 1];
        self.output
            .read_exact(&mut status)
            .map_err(|e| other(format!("the bridge stopped: {e}")))?;
        if status[0] != 0 {
            let len = self.u32()? as usize;
            let mut msg = vec![0u8; len];
            self.output.read_exact(&mut msg)?;
            return Err(other(String::from_utf8_lossy(&msg).into_owned()));
        }
        self.baud = self.u32()?;
        let mut t = [0u8; 8];
        self.output.read_exact(&mut t)?;
        self.now = Duration::from_nanos(u64::from_le_bytes(t));
        let n = self.u32()? as usize;
        if n > buf.len() {
            return Err(other(format!(
                "the bridge sent {n} bytes for {}",
                buf.len()
            )));
        }
        self.output.read_exact(&mut buf[..n])?;
        Ok(n)
    }

    fn u32(&mut self) -> Result<u32, Error> {
        let mut b = [0u8; 4];
        self.output.read_exact(&mut b)?;
        Ok(u32::from_le_bytes(b))
    }
}

impl Link for BridgeLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.input.write_all(b"S")?;
        self.input.write_all(&(bytes.len() as u32).to_le_bytes())?;
        self.input.write_all(bytes)?;
        self.input.flush()?;
        self.reply(&mut []).map(|_| ())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, Error> {
        self.input.write_all(b"R")?;
        self.input
            .write_all(&(buf.len().min(u32::MAX as usize) as u32).to_le_bytes())?;
        self.input
            .write_all(&(timeout.as_nanos().min(u128::from(u64::MAX)) as u64).to_le_bytes())?;
        self.input.flush()?;
        self.reply(buf)
    }

    fn now(&self) -> Duration {
        self.now
    }

    fn baud(&self) -> u32 {
        self.baud
    }
}

impl Drop for BridgeLink {
    fn drop(&mut self) {
        // `Q`: the bridge closes its link (an emulator writes its EEPROM file) and exits.
        let _ = self.input.write_all(b"Q");
        let _ = self.input.flush();
        let _ = self.child.wait();
    }
}
