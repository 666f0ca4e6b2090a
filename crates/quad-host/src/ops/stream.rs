//! Body poses from a CSV to the device, every answer checked against the host's own kin-core:
//! the operation behind `quadctl stream`. Its summary is one JSON object ([`Summary`]).

use crate::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, StreamStats,
};
use crate::csv::{self, AnswerError, FirstColumn, Input, Schema};
use crate::link::{self, Link, Target};
use crate::{client, robot_file};
use kin_core::body::Pose;
use kin_core::RotationOrder;
use quad_protocol::RobotPreset;
use serde::Serialize;
use std::cell::RefCell;
use std::io::{self, Write};
use std::path::PathBuf;

/// The body-pose columns (`quadctl pose`'s input): rotation in rad, translation in m.
pub const POSE_COLUMNS: Schema = Schema {
    columns: &["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"],
    first: FirstColumn::Number,
};

/// What [`run`] is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The robot: a preset name (the device reports its preset and both sides must run the
    /// same geometry).
    pub robot: String,
    /// The device.
    pub target: Target,
    /// Resends per pose after the first attempt.
    pub retries: u32,
    /// Stance height H set on the device, m; `None`: the device's own.
    pub stance_height_m: Option<f32>,
    /// Rotation order set on the device; `None`: the device's own.
    pub rotation_order: Option<RotationOrder>,
    /// Compare angles within this bound (rad); `None`: [`AngleCheck::for_target`].
    pub angle_tolerance_rad: Option<f32>,
    /// The poses, CSV (`-`: stdin).
    pub input: PathBuf,
}

/// Why nothing or not everything could be streamed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The robot is not a preset.
    #[error(
        "--robot {0}: the device link needs a preset robot (shahriar2023, fernando2025): the \
         device reports its preset and both sides must run the same geometry"
    )]
    NotAPreset(String),
    /// The robot could not be resolved.
    #[error(transparent)]
    Robot(#[from] robot_file::Error),
    /// The input could not be read, or the output written.
    #[error(transparent)]
    Csv(#[from] csv::Error),
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// The handshake or the link failed.
    #[error(transparent)]
    Client(#[from] client::Error),
    /// A negative or non-finite angle tolerance.
    #[error("--angle-tolerance-rad {0} must be finite and >= 0")]
    Tolerance(f32),
}

/// The pin check of the emulator, in the summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Pins {
    /// Pulses measured on the 12 servo pins and compared with the readbacks.
    pub pulses_checked: u64,
    /// Pulses off their readback by more than one 0.5 µs timer tick.
    pub pulse_width_errors: u64,
}

/// `quadctl stream`'s JSON summary: the stream's statistics, then the pin check with
/// `--emulator`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    /// The stream.
    #[serde(flatten)]
    pub stream: StreamStats,
    /// The pins, on the emulator.
    #[serde(flatten)]
    pub pins: Option<Pins>,
}

impl Summary {
    /// True when a readback disagreed with the host, a pulse left its travel or a pulse on
    /// the pins matched no readback.
    pub fn check_failed(&self) -> bool {
        self.stream.readback_mismatches > 0
            || self.stream.pulses_out_of_range > 0
            || self.pins.is_some_and(|p| p.pulse_width_errors > 0)
    }
}

/// How a stream ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// The summary.
    pub summary: Summary,
    /// Malformed input records (reported, not streamed).
    pub malformed: usize,
}

/// Streams the poses of `args.input`, reporting malformed records and every pose that was
/// nacked, lost or mismatched on `diag` as `<input>:<line>: …`.
///
/// # Errors
/// See [`Error`]; a link failure in the middle stops the stream.
pub fn run(args: &Request, diag: &mut dyn Write) -> Result<Outcome, Error> {
    let preset = RobotPreset::from_name(args.robot.trim())
        .ok_or_else(|| Error::NotAPreset(args.robot.clone()))?;
    let robot = robot_file::resolve(&args.robot)?;
    let input = Input::open(&args.input)?;
    let link = link::open(&args.target)?;
    let check = match args.angle_tolerance_rad {
        Some(t) if t.is_finite() && t >= 0.0 => AngleCheck::Within(t),
        Some(t) => return Err(Error::Tolerance(t)),
        None => AngleCheck::for_target(&args.target),
    };
    let setup = StreamSetup {
        robot,
        preset,
        stance_height_m: args.stance_height_m,
        order: args.rotation_order,
        check,
    };
    let config = ClientConfig::for_target(&args.target, args.retries);
    let mut stream = PoseStream::connect(Client::new(link, config), setup)?;
    let name = input.name.clone();
    let mut failure: Option<client::Error> = None;
    // Malformed records (reported by `for_each_row`) and pose reports share `diag`, in order.
    let diag = RefCell::new(diag);
    let rows = csv::for_each_row(
        input,
        POSE_COLUMNS,
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
        return Err(e.into());
    }
    let rows = rows?;
    let mut pins = None;
    if let Some(emu) = stream.client_mut().link_mut().emulator() {
        let pulses = emu.pulse_stats();
        if let Some(e) = &pulses.first_error {
            writeln!(diag.borrow_mut(), "{name}: PULSE WIDTH ERROR: {e}")
                .map_err(|source| csv::Error::Write { path: None, source })?;
        }
        pins = Some(Pins {
            pulses_checked: pulses.checked,
            pulse_width_errors: pulses.errors,
        });
    }
    Ok(Outcome {
        summary: Summary {
            stream: stream.stats(),
            pins,
        },
        malformed: rows.malformed,
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pins_follow_the_stream_in_the_json_and_only_with_the_emulator() {
        let mut summary = Summary {
            stream: StreamStats {
                sent: 2,
                ..StreamStats::default()
            },
            pins: None,
        };
        let json = serde_json::to_string(&summary).unwrap();
        assert!(
            json.starts_with("{\"sent\":2,") && !json.contains("pulses_checked"),
            "{json}"
        );
        summary.pins = Some(Pins {
            pulses_checked: 7,
            pulse_width_errors: 0,
        });
        let json = serde_json::to_string(&summary).unwrap();
        assert!(
            json.ends_with(",\"pulses_checked\":7,\"pulse_width_errors\":0}"),
            "{json}"
        );
    }
}
