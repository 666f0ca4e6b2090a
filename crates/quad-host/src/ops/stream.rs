//! `quadctl stream`: body poses to the device, simulated (`--sim`) or real (`--port`), every
//! answer checked against the host's own kin-core; a JSON summary as the last line of stdout.

use super::pose::{self, Order};
use super::{InputArgs, RobotArgs, EXIT_FATAL, EXIT_MALFORMED, EXIT_OK};
use crate::client::{
    AngleCheck, Client, ClientConfig, ClientError, PoseResult, PoseStream, StreamSetup,
    AVR_ANGLE_TOLERANCE_RAD, DEFAULT_RETRIES,
};
use crate::csv_io::{self, AnswerError, Input};
use crate::link::emulator::{EmulatorConfig, EmulatorLink};
use crate::link::serial::SerialLink;
use crate::link::sim::{SimConfig, SimLink, SimStorage, DEFAULT_RX_FIFO_LEN};
use crate::link::{Faults, Link};
use kin_core::body::Pose;
use quad_device::Config;
use quad_protocol::RobotPreset;
use std::cell::RefCell;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Exit status when a readback disagreed with the host or a pulse left its travel.
pub const EXIT_CHECK_FAILED: u8 = 3;

const LONG_ABOUT: &str = "\
Streams body poses to the device and checks every answer.

Input: the CSV of `quadctl pose` (roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m: rotation in RADIANS,
translation in METRES of the body relative to the world frame; feet held at the nominal stance).

Target: --sim runs the device controller in-process behind a simulated UART with the timing of
a real line at --baud (virtual time: nothing sleeps) and optional --faults; --emulator runs the
real ATmega2560 firmware (built from firmware-avr/ if needed, or --elf PATH) in simavr
in-process at 16 MHz, in simulated time, with the same --faults, and checks the pulses on its
twelve servo pins; --port PATH talks to an Arduino Mega running the firmware.

Each pose is sent as one SetBodyPose request and retried (same sequence number) on a timeout, on
a nack of an unreadable frame, or when its answer fails the check: the device's 12 angles must
equal the host's kin-core result (the same bits with --sim; within --angle-tolerance-rad with
--emulator and --port) and its 12 pulses the device calibration's mapping of those angles; an unreachable pose
must be nacked with the host's own leg and reason. Nacked, lost and mismatching poses are reported
on stderr as <input>:<line>: ...

Output: the last line of stdout is one JSON object:
{\"sent\",\"acked\",\"nacked\",\"retries\",\"lost\",\"readback_mismatches\",\"max_angle_err_rad\",
\"pulses_out_of_range\",\"poses_per_s\", then transient_mismatches (answers a retry corrected),
timeouts, elapsed_s (link time) and reenabled}; with --emulator also pulses_checked and
pulse_width_errors: every pulse measured on the 12 servo pins compared with the readback in
force when it started (the last one sent before it, or the next), an error when it differs by
more than one 0.5 us timer tick. poses_per_s counts acked + nacked poses per second of link time
(simulated time with --sim and --emulator).

Exit status: 0 all poses answered or lost, every check passed; 1 malformed input records (the
others were streamed); 2 nothing or not everything could be streamed (arguments, robot, input,
link, firmware build, handshake); 3 a readback mismatch, a pulse out of its travel or a pulse
width error on the pins.";

/// Where the device is: `--sim`, `--emulator` or `--port`, and the line.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct TargetArgs {
    /// Run against the device controller behind a simulated UART.
    #[arg(long, conflicts_with_all = ["port", "emulator"], required_unless_present_any = ["port", "emulator"])]
    pub sim: bool,
    /// Run the real firmware in simavr (an emulated ATmega2560; simulated time).
    #[arg(long, conflicts_with = "port")]
    pub emulator: bool,
    /// Firmware ELF for --emulator; default: built from firmware-avr/ for --baud (115200:
    /// firmware.elf, 1000000: firmware-1mbaud.elf).
    #[arg(long, value_name = "PATH", requires = "emulator")]
    pub elf: Option<PathBuf>,
    /// Serial port of a real device, e.g. /dev/ttyACM0.
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Line rate, bit/s (8N1).
    #[arg(long, value_name = "B", default_value_t = 115_200, value_parser = clap::value_parser!(u32).range(300..))]
    pub baud: u32,
    /// Line faults of --sim or --emulator: drop=P,flip=P (per byte), dup=P,trunc=P,stall=P (per
    /// frame), stall_ms=MS.
    #[arg(
        long,
        value_name = "drop=P,flip=P,dup=P,trunc=P",
        conflicts_with = "port"
    )]
    pub faults: Option<Faults>,
    /// Seed of the simulated faults.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Modelled device time per answered frame in the simulation, µs (0: wire-limited).
    #[arg(long, value_name = "US", default_value_t = 0.0, value_parser = parse_us, requires = "sim")]
    pub sim_compute_us: f64,
    /// EEPROM image file of the simulated or emulated device (read at power-on; written on
    /// every change with --sim, at the end of the run with --emulator).
    #[arg(long, value_name = "FILE", conflicts_with = "port")]
    pub sim_storage: Option<PathBuf>,
    /// Resends per request after the first attempt.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_RETRIES)]
    pub retries: u32,
}

fn parse_us(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=1e7).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a time in µs within [0, 1e7]")),
    }
}

/// The emulated device and where its EEPROM image is kept between runs.
pub struct EmulatorTarget {
    /// The link.
    pub link: EmulatorLink,
    /// EEPROM image file, written back when the target is dropped.
    pub eeprom_file: Option<PathBuf>,
}

impl Drop for EmulatorTarget {
    fn drop(&mut self) {
        if let Some(path) = &self.eeprom_file {
            let image = self.link.mcu_mut().eeprom();
            if let Err(e) = std::fs::write(path, image) {
                eprintln!("quadctl: cannot write {}: {e}", path.display());
            }
        }
    }
}

/// Any link, opened.
pub enum AnyLink {
    /// The simulated UART.
    Sim(Box<SimLink>),
    /// The firmware in simavr.
    Emulator(Box<EmulatorTarget>),
    /// A serial port.
    Serial(SerialLink),
}

impl AnyLink {
    /// The emulator link, if this is one.
    pub fn emulator(&mut self) -> Option<&mut EmulatorLink> {
        match self {
            AnyLink::Emulator(t) => Some(&mut t.link),
            _ => None,
        }
    }

    /// The angle check that suits the device: the same bits for the simulated controller
    /// (the host's math), [`AVR_ANGLE_TOLERANCE_RAD`] for the ATmega2560's avr-libc math.
    pub fn default_check(&self) -> AngleCheck {
        match self {
            AnyLink::Sim(_) => AngleCheck::Exact,
            AnyLink::Emulator(_) | AnyLink::Serial(_) => {
                AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD)
            }
        }
    }
}

impl Link for AnyLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), crate::link::LinkError> {
        match self {
            AnyLink::Sim(l) => l.send(bytes),
            AnyLink::Emulator(t) => t.link.send(bytes),
            AnyLink::Serial(l) => l.send(bytes),
        }
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, crate::link::LinkError> {
        match self {
            AnyLink::Sim(l) => l.recv(buf, timeout),
            AnyLink::Emulator(t) => t.link.recv(buf, timeout),
            AnyLink::Serial(l) => l.recv(buf, timeout),
        }
    }
    fn now(&self) -> Duration {
        match self {
            AnyLink::Sim(l) => l.now(),
            AnyLink::Emulator(t) => t.link.now(),
            AnyLink::Serial(l) => l.now(),
        }
    }
    fn baud(&self) -> u32 {
        match self {
            AnyLink::Sim(l) => l.baud(),
            AnyLink::Emulator(t) => t.link.baud(),
            AnyLink::Serial(l) => l.baud(),
        }
    }
}

impl TargetArgs {
    /// Opens the link and the client configuration that suits it. `preset` is the robot of the
    /// simulated device.
    ///
    /// # Errors
    /// A message for the user.
    pub fn open(&self, preset: RobotPreset) -> Result<(AnyLink, ClientConfig), String> {
        let compute = Duration::from_secs_f64(self.sim_compute_us * 1e-6);
        if let Some(path) = &self.port {
            let link = SerialLink::open(path, self.baud).map_err(|e| e.to_string())?;
            let config = ClientConfig {
                retries: self.retries,
                ..ClientConfig::serial()
            };
            return Ok((AnyLink::Serial(link), config));
        }
        if self.emulator {
            let eeprom = match &self.sim_storage {
                Some(path) => match std::fs::read(path) {
                    Ok(b) => Some(b),
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
                    Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
                },
                None => None,
            };
            let config = EmulatorConfig {
                baud: self.baud,
                faults: self.faults.unwrap_or(Faults::NONE),
                seed: self.seed,
                eeprom,
            };
            let link = match &self.elf {
                Some(elf) => EmulatorLink::boot(elf, config),
                None => EmulatorLink::boot_built(config),
            }
            .map_err(|e| e.to_string())?;
            let client = ClientConfig {
                retries: self.retries,
                ..ClientConfig::emulator()
            };
            let target = EmulatorTarget {
                link,
                eeprom_file: self.sim_storage.clone(),
            };
            return Ok((AnyLink::Emulator(Box::new(target)), client));
        }
        let device = Config::for_preset(preset)
            .ok_or("the simulated device needs a preset robot (shahriar2023 or fernando2025)")?;
        let storage = match &self.sim_storage {
            Some(path) => SimStorage::with_file(path.clone())
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?,
            None => SimStorage::erased(),
        };
        let sim = SimConfig {
            baud: self.baud,
            faults: self.faults.unwrap_or(Faults::NONE),
            seed: self.seed,
            compute,
            rx_fifo_len: DEFAULT_RX_FIFO_LEN,
        };
        let link = SimLink::new(sim, device, storage).map_err(|e| e.to_string())?;
        let config = ClientConfig {
            retries: self.retries,
            ..ClientConfig::sim(compute)
        };
        Ok((AnyLink::Sim(Box::new(link)), config))
    }
}

/// Arguments of `quadctl stream`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Stream body poses (rad, m) to the device (--sim or --port) and check every readback",
    long_about = LONG_ABOUT
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Stance height H set on the device, metres; default: the device's own.
    #[arg(long, value_name = "H", value_parser = super::parse_positive_m)]
    pub stance_height_m: Option<f32>,
    /// Rotation order set on the device; default: the device's own.
    #[arg(long, value_enum)]
    pub rotation_order: Option<Order>,
    /// Compare the device's angles within this bound (rad) instead of bit for bit; default:
    /// exact with --sim, 5e-5 rad with --emulator and --port (the AVR's math differs from the
    /// host's).
    #[arg(long, value_name = "RAD")]
    pub angle_tolerance_rad: Option<f32>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: InputArgs,
}

/// Runs `quadctl stream` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let stdout = io::stdout();
    let mut out = stdout.lock();
    let stderr = io::stderr();
    let mut diag = stderr.lock();
    match run(args, &mut out, &mut diag) {
        Ok(code) => ExitCode::from(code),
        Err(message) => {
            let _ = writeln!(diag, "quadctl: error: {message}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}

/// Runs the stream, writing the JSON summary to `out` and the per-pose reports to `diag`;
/// returns the exit status, or a message when nothing or not everything could be streamed.
///
/// # Errors
/// A message for the user.
pub fn run(args: &Args, out: &mut dyn Write, diag: &mut dyn Write) -> Result<u8, String> {
    let preset = RobotPreset::from_name(args.robot.robot.trim()).ok_or_else(|| {
        format!(
            "--robot {}: the device link needs a preset robot (shahriar2023, fernando2025): the \
             device reports its preset and both sides must run the same geometry",
            args.robot.robot
        )
    })?;
    let robot = args.robot.load(None).map_err(|e| e.to_string())?;
    let input = Input::open(&args.input.input).map_err(|e| e.to_string())?;
    let (link, config) = args.target.open(preset)?;
    let check = match args.angle_tolerance_rad {
        Some(t) if t.is_finite() && t >= 0.0 => AngleCheck::Within(t),
        Some(t) => return Err(format!("--angle-tolerance-rad {t} must be finite and >= 0")),
        None => link.default_check(),
    };
    let setup = StreamSetup {
        robot,
        preset,
        stance_height_m: args.stance_height_m,
        order: args.rotation_order.map(Into::into),
        check,
    };
    let mut stream =
        PoseStream::connect(Client::new(link, config), setup).map_err(|e| e.to_string())?;
    let name = input.name.clone();
    let mut failure: Option<ClientError> = None;
    // Malformed records (reported by `for_each_row`) and pose reports share `diag`, in order.
    let diag = RefCell::new(diag);
    let summary = csv_io::for_each_row(
        input,
        pose::INPUT,
        &mut io::sink(),
        &mut Shared(&diag),
        None,
        |row, _| {
            let mut v = [0.0f32; 6];
            for (i, slot) in v.iter_mut().enumerate() {
                *slot = row.number(i)?;
            }
            let result = match stream.send(&Pose::from_array(v)) {
                Ok(r) => r,
                Err(e) => {
                    failure = Some(e);
                    return Err(AnswerError::Io(io::Error::other("link failed")));
                }
            };
            let line = row.line;
            let report = match result {
                PoseResult::Acked { .. } => None,
                PoseResult::Nacked(reason) => {
                    Some(format!("nacked: {reason} (the host's kin-core agrees)"))
                }
                PoseResult::Lost => Some("lost: no answer after every retry".to_owned()),
                PoseResult::Mismatch(what) => Some(format!("READBACK MISMATCH: {what}")),
            };
            if let Some(r) = report {
                writeln!(diag.borrow_mut(), "{name}:{line}: {r}")?;
            }
            Ok(())
        },
    );
    if let Some(e) = failure {
        return Err(e.to_string());
    }
    let summary = summary.map_err(|e| e.to_string())?;
    let stats = stream.stats();
    let mut json = serde_json::to_string(&stats).map_err(|e| e.to_string())?;
    let mut pulse_errors = 0;
    if let Some(emu) = stream.client_mut().link_mut().emulator() {
        let pulses = emu.pulse_stats();
        pulse_errors = pulses.errors;
        if let Some(e) = &pulses.first_error {
            writeln!(diag.borrow_mut(), "{name}: PULSE WIDTH ERROR: {e}")
                .map_err(|e| e.to_string())?;
        }
        // Appended after the stream's own fields, which keep their order.
        json.pop();
        json.push_str(&format!(
            ",\"pulses_checked\":{},\"pulse_width_errors\":{}}}",
            pulses.checked, pulses.errors
        ));
    }
    writeln!(out, "{json}").map_err(|e| e.to_string())?;
    out.flush().map_err(|e| e.to_string())?;
    Ok(
        if stats.readback_mismatches > 0 || stats.pulses_out_of_range > 0 || pulse_errors > 0 {
            EXIT_CHECK_FAILED
        } else if summary.malformed > 0 {
            EXIT_MALFORMED
        } else {
            EXIT_OK
        },
    )
}

/// A `Write` through a shared `RefCell`.
struct Shared<'a, 'b>(&'a RefCell<&'b mut dyn Write>);

impl Write for Shared<'_, '_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.borrow_mut().flush()
    }
}
