//! Body poses from a CSV to the device, every answer checked against the host's own kin-core:
//! the operation behind `quadctl stream`. Its summary is one JSON object ([`Summary`]).

use crate::client::{self, Setpoint, Settled, StreamStats};
use crate::csv::{self, AnswerError, FirstColumn, Input, Schema};
use crate::ops::session::{self, Pins, Session};
use kin_core::body::Pose;
use serde::Serialize;
use std::cell::RefCell;
use std::collections::VecDeque;
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
    /// The device, the robot and the answers' check.
    pub session: Session,
    /// The poses, CSV (`-`: stdin).
    pub input: PathBuf,
    /// Requests kept in flight (1: one at a time; [`client::DEFAULT_WINDOW`] by default, at
    /// most [`client::MAX_WINDOW`]).
    pub window: usize,
}

/// Why nothing or not everything could be streamed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The session could not start (robot, tolerance, link, handshake), or the link failed.
    #[error(transparent)]
    Session(#[from] session::Error),
    /// The input could not be read, or the output written.
    #[error(transparent)]
    Csv(#[from] csv::Error),
}

impl From<client::Error> for Error {
    fn from(e: client::Error) -> Error {
        Error::Session(e.into())
    }
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
    /// See [`session::check_failed`].
    pub fn check_failed(&self) -> bool {
        session::check_failed(&self.stream, self.pins)
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
    let checked = args.session.check()?;
    let input = Input::open(&args.input)?;
    let mut stream = args.session.connect(checked, None)?;
    stream.set_window(args.window)?;
    let name = input.name.clone();
    // The poses in flight: their line and rotation angles, for the reports of their results.
    let mut in_flight: VecDeque<(u64, [f32; 3])> = VecDeque::new();
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
            let line = row.line as u64;
            in_flight.push_back((line, [v[0], v[1], v[2]]));
            match stream.submit(&Setpoint::Pose(Pose::from_array(v)), line) {
                Ok(settled) => report(&name, &settled, &mut in_flight, &diag)?,
                Err(e) => {
                    failure = Some(e);
                    return Err(AnswerError::Io(io::Error::other("link failed")));
                }
            }
            Ok(())
        },
    );
    if let Some(e) = failure {
        return Err(e.into());
    }
    let rows = rows?;
    let settled = stream.flush()?;
    report(&name, &settled, &mut in_flight, &diag)
        .map_err(|source| csv::Error::Write { path: None, source })?;
    let pins = Pins::after(&mut stream, &name, &mut Shared(&diag))
        .map_err(|source| csv::Error::Write { path: None, source })?;
    Ok(Outcome {
        summary: Summary {
            stream: stream.stats(),
            pins,
        },
        malformed: rows.malformed,
    })
}

/// Reports every pose of `settled` that was nacked, lost or mismatched as `<input>:<line>: …`
/// (with a hint when its angles look like degrees), taking them out of `in_flight`.
fn report(
    name: &str,
    settled: &[Settled],
    in_flight: &mut VecDeque<(u64, [f32; 3])>,
    diag: &RefCell<&mut dyn Write>,
) -> io::Result<()> {
    for s in settled {
        let mut angles = [0.0f32; 3];
        while let Some((line, a)) = in_flight.pop_front() {
            if line == s.tag {
                angles = a;
                break;
            }
        }
        if let Some(r) = session::report(&s.result) {
            let named = [
                ("roll_rad", angles[0]),
                ("pitch_rad", angles[1]),
                ("yaw_rad", angles[2]),
            ];
            match session::degrees_hint(&named) {
                Some(hint) => writeln!(diag.borrow_mut(), "{name}:{}: {r}; {hint}", s.tag)?,
                None => writeln!(diag.borrow_mut(), "{name}:{}: {r}", s.tag)?,
            }
        }
    }
    Ok(())
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
            rx_overruns: 0,
            pulses_checked: 7,
            pulse_width_errors: 0,
        });
        let json = serde_json::to_string(&summary).unwrap();
        assert!(
            json.ends_with(",\"pulses_checked\":7,\"pulse_width_errors\":0}"),
            "{json}"
        );
        assert!(json.contains(",\"rx_overruns\":0,"), "{json}");
    }
}
