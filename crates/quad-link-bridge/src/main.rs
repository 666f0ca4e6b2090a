//! `quad-link-bridge`: one of quad-host's device links served over stdin/stdout.
//!
//! The Python package's extension module is a shared library, and simavr's static libelf
//! (initial-exec TLS, not position-independent) cannot be linked into one; the firmware in
//! simavr therefore runs in this process, and the package talks to it through the
//! [`quad_host::link::Link`] calls below.
//!
//! ```text
//! quad-link-bridge --emulator [--elf FILE] [--baud B] [--storage FILE]
//! quad-link-bridge --sim ROBOT [--baud B] [--storage FILE]
//! quad-link-bridge --port PATH [--baud B]
//! ```
//!
//! Wire (little-endian), after the link opened: one reply, then requests, each answered by one
//! reply:
//! - request `S` `len: u32` `bytes`: [`Link::send`];
//! - request `R` `max: u32` `timeout_ns: u64`: [`Link::recv`] into at most `max` bytes;
//! - request `Q`: close the link (an emulator's EEPROM file is written) and exit.
//! - reply: `0` `baud: u32` `now_ns: u64` `len: u32` `bytes` (the bytes received by `R`), or
//!   `1` `len: u32` `message` (UTF-8; the link failed, the process exits).

use quad_host::link::{self, emulator::EmulatorConfig, sim::SimConfig, Link, Target};
use quad_protocol::RobotPreset;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// The largest receive a request may ask for, bytes.
const MAX_RECV: usize = 1 << 16;

fn target(args: &[String]) -> Result<Target, String> {
    let mut baud = 115_200u32;
    let (mut elf, mut storage, mut kind) = (None, None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{a} needs a value"))
        };
        match a.as_str() {
            "--emulator" => kind = Some(("emulator", String::new())),
            "--sim" => kind = Some(("sim", value()?)),
            "--port" => kind = Some(("port", value()?)),
            "--elf" => elf = Some(PathBuf::from(value()?)),
            "--storage" => storage = Some(PathBuf::from(value()?)),
            "--baud" => {
                let v = value()?;
                baud = v.parse().map_err(|_| format!("--baud {v}: not a rate"))?;
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    match kind {
        Some(("emulator", _)) => Ok(Target::Emulator {
            elf,
            config: EmulatorConfig::new(baud),
            storage,
        }),
        Some(("sim", robot)) => Ok(Target::Sim {
            preset: RobotPreset::from_name(&robot)
                .ok_or_else(|| format!("--sim {robot}: not a preset"))?,
            config: SimConfig {
                baud,
                ..SimConfig::default()
            },
            storage,
        }),
        Some((_, path)) => Ok(Target::Serial { path, baud }),
        None => Err("expected --emulator, --sim ROBOT or --port PATH".to_owned()),
    }
}

fn ok(out: &mut impl Write, baud: u32, now: Duration, bytes: &[u8]) -> io::Result<()> {
    out.write_all(&[0])?;
    out.write_all(&baud.to_le_bytes())?;
    out.write_all(&(now.as_nanos() as u64).to_le_bytes())?;
    out.write_all(&(bytes.len() as u32).to_le_bytes())?;
    out.write_all(bytes)?;
    out.flush()
}

fn fail(out: &mut impl Write, message: &str) -> io::Result<()> {
    out.write_all(&[1])?;
    out.write_all(&(message.len() as u32).to_le_bytes())?;
    out.write_all(message.as_bytes())?;
    out.flush()
}

fn read_u32(input: &mut impl Read) -> io::Result<u32> {
    let mut b = [0u8; 4];
    input.read_exact(&mut b)?;
    Ok(u32::from_le_bytes(b))
}

fn serve(link: &mut dyn Link, input: &mut impl Read, out: &mut impl Write) -> io::Result<()> {
    let baud = link.baud();
    ok(out, baud, link.now(), &[])?;
    let mut buf = vec![0u8; MAX_RECV];
    loop {
        let mut op = [0u8; 1];
        if input.read_exact(&mut op).is_err() {
            return Ok(());
        }
        let result = match op[0] {
            b'S' => {
                let len = read_u32(input)? as usize;
                let mut bytes = vec![0u8; len];
                input.read_exact(&mut bytes)?;
                link.send(&bytes).map(|()| 0)
            }
            b'R' => {
                let max = (read_u32(input)? as usize).min(MAX_RECV);
                let mut t = [0u8; 8];
                input.read_exact(&mut t)?;
                let timeout = Duration::from_nanos(u64::from_le_bytes(t));
                link.recv(&mut buf[..max], timeout)
            }
            b'Q' => return Ok(()),
            other => {
                return fail(out, &format!("unknown request {other:#04x}"));
            }
        };
        match result {
            Ok(n) => {
                let got = if op[0] == b'R' { &buf[..n] } else { &[][..] };
                ok(out, baud, link.now(), got)?;
            }
            Err(e) => return fail(out, &e.to_string()),
        }
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (stdin, stdout) = (io::stdin(), io::stdout());
    let mut input = BufReader::new(stdin.lock());
    let mut out = BufWriter::new(stdout.lock());
    let opened = target(&args).and_then(|t| link::open(&t).map_err(|e| e.to_string()));
    let mut link = match opened {
        Ok(l) => l,
        Err(message) => {
            let _ = fail(&mut out, &message);
            return ExitCode::from(2);
        }
    };
    match serve(&mut *link, &mut input, &mut out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("quad-link-bridge: {e}");
            ExitCode::FAILURE
        }
    }
}
