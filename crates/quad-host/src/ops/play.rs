//! A timed setpoint file played to the device, paced by its `t_s` column, every answer checked
//! against the host's own kin-core: the operation behind `quadctl play`. Its summary is one
//! JSON object ([`Summary`]).
//!
//! ## Pacing
//! Row `i` is due at `start + (t_i − t_0) / speed` on the link's clock: the virtual clock of
//! the simulated and the emulated device (nothing sleeps), the wall clock of a port. The host
//! waits for the due time, sends the row and waits for its answer (retried as every request
//! is, [`crate::client`]). A row is **late** by the time between its due time and its
//! sending; when the next row is already due before a row could be sent, the row is
//! **skipped** (the device holds the latest setpoint; a backlog would only grow), except the
//! last one. Both are in the summary.
//!
//! ## What is sent
//! The file's kinds ([`crate::csv::play`]): joint angles as `SetJoints`, feet as `SetFeet`
//! (in the body frame: feet given in the world frame together with a body pose are moved into
//! the body frame by kin-core, in the rotation order in force), a body pose as `SetBodyPose`
//! (feet at the device's stance). With several kinds, joint angles come first, then feet,
//! then the pose, unless [`Request::send`] names one.

use crate::client::{self, PoseStream, Setpoint, StreamStats};
use crate::csv;
use crate::csv::play::{self as play_csv, ColumnKind, PlayFile};
use crate::link::Link;
use crate::ops::session::{self, Pins, Session};
use kin_core::body;
use kin_core::{BodyConfig, LegId, Robot, RotationOrder, Vec3};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

/// What [`run`] is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The device, the robot and the answers' check; its rotation order `None`: the file's
    /// (a `rotation_order=` comment), else the device's own.
    pub session: Session,
    /// Time scale: 2 plays twice as fast (finite, > 0).
    pub speed: f64,
    /// The kind of columns to send; `None`: joints, else feet, else pose.
    pub send: Option<ColumnKind>,
    /// The file (`-`: stdin).
    pub input: PathBuf,
}

/// Why nothing or not everything could be played.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The session could not start (robot, tolerance, link, handshake), or the link failed.
    #[error(transparent)]
    Session(#[from] session::Error),
    /// The file cannot be played.
    #[error(transparent)]
    File(#[from] play_csv::Error),
    /// `--send` names a kind the file does not have.
    #[error("--send {kind}: {input} has no {kind} columns (it has: {has})")]
    KindAbsent {
        /// The kind asked for.
        kind: &'static str,
        /// The file.
        input: String,
        /// The kinds it has.
        has: String,
    },
    /// A speed that is not finite and > 0.
    #[error("--speed {0} must be finite and > 0")]
    Speed(f64),
    /// The report could not be written.
    #[error(transparent)]
    Report(#[from] csv::Error),
}

impl From<client::Error> for Error {
    fn from(e: client::Error) -> Error {
        Error::Session(e.into())
    }
}

/// How late the rows were sent, and how long their answers took.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    /// Mean over the rows sent of (sending − due time), ms.
    pub late_mean_ms: f64,
    /// Largest (sending − due time), ms.
    pub late_max_ms: f64,
    /// Rows skipped because the next one was already due.
    pub skipped: u64,
    /// Mean time from sending a row to its accepted answer (retries included), ms.
    pub answer_mean_ms: f64,
    /// Largest time from sending a row to its answer, ms.
    pub answer_max_ms: f64,
    /// The file's span divided by the speed, s.
    pub motion_s: f64,
}

/// `quadctl play`'s JSON summary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    /// The kind of columns sent.
    pub kind: ColumnKind,
    /// Rows in the file.
    pub rows: u64,
    /// Pacing and answer times.
    #[serde(flatten)]
    pub timing: Timing,
    /// The requests, their answers and the readback check.
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

/// The kind [`run`] sends for `file`: `wanted`, or the first of joints, feet, pose present.
///
/// # Errors
/// [`Error::KindAbsent`].
pub fn kind_to_send(file: &PlayFile, wanted: Option<ColumnKind>) -> Result<ColumnKind, Error> {
    let kinds = file.kinds();
    match wanted {
        Some(k) if kinds.contains(&k) => Ok(k),
        Some(k) => Err(Error::KindAbsent {
            kind: k.name(),
            input: file.name.clone(),
            has: kinds
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", "),
        }),
        // `read` refuses a file without any kind.
        None => Ok(kinds.first().copied().unwrap_or(ColumnKind::Joints)),
    }
}

/// The setpoint of a row: its columns of `kind` (feet moved into the body frame through its
/// pose, when it has one, in rotation order `order`).
pub fn setpoint(
    robot: &Robot,
    order: RotationOrder,
    frame: &play_csv::Frame,
    kind: ColumnKind,
) -> Setpoint {
    match kind {
        ColumnKind::Joints => Setpoint::Joints(frame.angles.unwrap_or([f32::NAN; 12])),
        ColumnKind::Pose => Setpoint::Pose(frame.pose.unwrap_or_default()),
        ColumnKind::Feet => {
            let feet = frame.feet.unwrap_or([Vec3::ZERO; 4]);
            match frame.pose {
                None => Setpoint::Feet(feet),
                Some(pose) => {
                    let config = BodyConfig {
                        order,
                        pivot_m: Vec3::ZERO,
                    };
                    let in_hips = body::Solver::new(robot).feet_in_hips(&pose, &config, &feet);
                    let mut in_body = [Vec3::ZERO; 4];
                    for (i, leg) in LegId::ALL.into_iter().enumerate() {
                        in_body[i] = robot.hip_in_body(leg) + in_hips[i];
                    }
                    Setpoint::Feet(in_body)
                }
            }
        }
    }
}

/// Plays `args.input`, reporting every row that was nacked, lost or mismatched on `diag` as
/// `<input>:<line>: …`. The file is read and checked whole before the link is opened.
///
/// # Errors
/// See [`Error`]; a link failure in the middle stops the playing.
pub fn run(args: &Request, diag: &mut dyn Write) -> Result<Summary, Error> {
    let checked = args.session.check()?;
    if !(args.speed.is_finite() && args.speed > 0.0) {
        return Err(Error::Speed(args.speed));
    }
    let file = play_csv::read(&args.input)?;
    let kind = kind_to_send(&file, args.send)?;
    let mut stream = args.session.connect(checked, file.rotation_order)?;
    let timing = play(&mut stream, &file, kind, args.speed, diag)?;
    let pins = Pins::after(&mut stream, &file.name, diag)
        .map_err(|source| csv::Error::Write { path: None, source })?;
    Ok(Summary {
        kind,
        rows: file.frames.len() as u64,
        timing,
        stream: stream.stats(),
        pins,
    })
}

/// Plays the rows of `file` on a connected stream (see the module docs); returns the timing.
///
/// # Errors
/// Link and session failures, and a failing `diag`.
pub fn play<L: Link>(
    stream: &mut PoseStream<L>,
    file: &PlayFile,
    kind: ColumnKind,
    speed: f64,
    diag: &mut dyn Write,
) -> Result<Timing, Error> {
    let robot = stream.stream_setup().robot;
    let order = stream.pose_config().order;
    let frames = &file.frames;
    let t_first = frames.first().map_or(0.0, |f| f.t_s);
    let start = stream.client().link().now();
    let due = |t_s: f64| start + Duration::from_secs_f64((t_s - t_first) / speed);
    let mut timing = Timing {
        motion_s: frames.last().map_or(0.0, |f| f.t_s - t_first) / speed,
        ..Timing::default()
    };
    let (mut late_sum, mut answer_sum, mut sent) = (0.0, 0.0, 0u64);
    for (i, frame) in frames.iter().enumerate() {
        let at = due(frame.t_s);
        let now = stream.client().link().now();
        if frames.get(i + 1).is_some_and(|next| now >= due(next.t_s)) {
            timing.skipped += 1;
            continue;
        }
        stream
            .client_mut()
            .idle_until(at)
            .map_err(client::Error::from)?;
        let sent_at = stream.client().link().now();
        let result = stream.send_setpoint(&setpoint(&robot, order, frame, kind))?;
        let answered = stream.client().link().now();
        let late_ms = ms(sent_at.saturating_sub(at));
        let answer_ms = ms(answered.saturating_sub(sent_at));
        late_sum += late_ms;
        answer_sum += answer_ms;
        sent += 1;
        timing.late_max_ms = timing.late_max_ms.max(late_ms);
        timing.answer_max_ms = timing.answer_max_ms.max(answer_ms);
        if let Some(r) = session::report(&result) {
            writeln!(diag, "{}:{}: {r}", file.name, frame.line)
                .map_err(|source| csv::Error::Write { path: None, source })?;
        }
    }
    if sent > 0 {
        timing.late_mean_ms = late_sum / sent as f64;
        timing.answer_mean_ms = answer_sum / sent as f64;
    }
    Ok(timing)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_names_the_kind_and_the_lateness() {
        let s = Summary {
            kind: ColumnKind::Joints,
            rows: 3,
            timing: Timing {
                late_max_ms: 1.5,
                ..Timing::default()
            },
            stream: StreamStats::default(),
            pins: None,
        };
        let json = serde_json::to_string(&s).unwrap();
        assert!(
            json.starts_with(
                "{\"kind\":\"joints\",\"rows\":3,\"late_mean_ms\":0.0,\"late_max_ms\":1.5,"
            ),
            "{json}"
        );
        assert!(!s.check_failed());
    }
}
