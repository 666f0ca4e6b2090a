//! A timed setpoint file played to the device, paced by its `t_s` column, every answer checked
//! against the host's own kin-core: the operation behind `quadctl play`. Its summary is one
//! JSON object ([`Summary`]).
//!
//! ## Pacing
//! Row `i` is due at `start + (t_i − t_0) / speed` on the link's clock: the virtual clock of
//! the simulated and the emulated device (nothing sleeps), the wall clock of a port. The host
//! waits for the due time and sends the row, with up to [`Request::window`] requests in
//! flight ([`PoseStream::submit`]: each answer checked and retried as every request is,
//! [`crate::client`]). A row is **late** by the time between its due time and its
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

use crate::client::{self, Expected, PoseStream, Setpoint, Settled, StreamStats};
use crate::csv;
use crate::csv::play::{self as play_csv, ColumnKind, PlayFile};
use crate::link::Link;
use crate::names;
use crate::ops::defaults;
use crate::ops::session::{self, Pins, Session};
use kin_core::body;
use kin_core::{BodyConfig, LegId, Robot, RotationOrder, Vec3};
use quad_protocol::ServoId;
use serde::Serialize;
use std::fmt;
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
    /// Requests kept in flight (1: one at a time; [`client::DEFAULT_WINDOW`] by default, at
    /// most [`client::MAX_WINDOW`]).
    pub window: usize,
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
    /// Rows that ask a joint to move faster than the device's joint-speed limit (its power-on
    /// limit, 3 rad/s: [`defaults::joint_speed_limit_rad_s`]) from the row before: the device slows
    /// them, and its outputs lag the file ([`slowed`]).
    pub slowed_rows: u64,
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
    stream.set_window(args.window)?;
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
    let limit_rad_s =
        defaults::joint_speed_limit_rad_s(names::robot_preset_name(stream.stream_setup().preset));
    let frames = &file.frames;
    let t_first = frames.first().map_or(0.0, |f| f.t_s);
    let start = stream.client().link().now();
    let due = |t_s: f64| start + Duration::from_secs_f64((t_s - t_first) / speed);
    let mut timing = Timing {
        motion_s: frames.last().map_or(0.0, |f| f.t_s - t_first) / speed,
        ..Timing::default()
    };
    let mut sums = Sums::default();
    // The angles and time of the last row sent, for the limiter's count.
    let mut last: Option<([f32; 12], f64)> = None;
    for (i, frame) in frames.iter().enumerate() {
        let at = due(frame.t_s);
        let now = stream.client().link().now();
        if frames.get(i + 1).is_some_and(|next| now >= due(next.t_s)) {
            timing.skipped += 1;
            continue;
        }
        let settled = stream.idle_until(at)?;
        sums.take(&settled, file, &due, &mut timing, diag)?;
        let sp = setpoint(&robot, order, frame, kind);
        if let Expected::Angles(angles) = stream.expected_for(&sp) {
            let t_s = frame.t_s / speed;
            if let Some((before, t_before)) = last {
                if let Some(slowed) = slowed(&before, &angles, t_s - t_before, limit_rad_s) {
                    if timing.slowed_rows == 0 {
                        writeln!(
                            diag,
                            "{}:{}: {slowed}; the device's joint-speed limiter slows this row \
                             (and every row counted in slowed_rows)",
                            file.name, frame.line
                        )
                        .map_err(|source| csv::Error::Write { path: None, source })?;
                    }
                    timing.slowed_rows += 1;
                }
            }
            last = Some((angles, t_s));
        }
        let settled = stream.submit(&sp, i as u64)?;
        sums.take(&settled, file, &due, &mut timing, diag)?;
    }
    let settled = stream.flush()?;
    sums.take(&settled, file, &due, &mut timing, diag)?;
    if sums.sent > 0 {
        timing.late_mean_ms = sums.late / sums.sent as f64;
        timing.answer_mean_ms = sums.answer / sums.sent as f64;
    }
    Ok(timing)
}

/// Why a row is slowed by the device's joint-speed limiter: a joint whose change from the
/// previous row (`dt_s` earlier) asks more than `limit_rad_s` of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slowed {
    /// The joint, canonical index.
    pub servo: ServoId,
    /// The speed the row asks of it, rad/s.
    pub speed_rad_s: f32,
    /// The limit, rad/s.
    pub limit_rad_s: f32,
}

impl fmt::Display for Slowed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} at {:.3} rad/s > the limit {} rad/s",
            self.servo, self.speed_rad_s, self.limit_rad_s
        )
    }
}

/// The fastest joint between two rows of angles `dt_s` apart when it moves faster than
/// `limit_rad_s` (the device then takes longer than the rows allow: the outputs lag the file).
/// Rows at the same time (or out of order) compare their change with one servo frame.
pub fn slowed(
    before: &[f32; 12],
    after: &[f32; 12],
    dt_s: f64,
    limit_rad_s: f32,
) -> Option<Slowed> {
    let dt_s = dt_s.max(f64::from(quad_device::engine::FRAME_MS) * 1e-3) as f32;
    ServoId::ALL
        .into_iter()
        .map(|s| (s, (after[s.index()] - before[s.index()]).abs() / dt_s))
        .filter(|&(_, v)| v > limit_rad_s * (1.0 + SLOWED_MARGIN))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(servo, speed_rad_s)| Slowed {
            servo,
            speed_rad_s,
            limit_rad_s,
        })
}

/// Relative margin above the limit before a row counts as slowed: the rows' times and angles
/// are rounded in the file.
pub const SLOWED_MARGIN: f32 = 1e-3;

/// Lateness and answer-time sums of the rows sent.
#[derive(Default)]
struct Sums {
    late: f64,
    answer: f64,
    sent: u64,
}

impl Sums {
    /// Counts the rows in `settled` (tagged with their index in `file`) and reports those
    /// nacked, lost or mismatched on `diag`.
    fn take(
        &mut self,
        settled: &[Settled],
        file: &PlayFile,
        due: &dyn Fn(f64) -> Duration,
        timing: &mut Timing,
        diag: &mut dyn Write,
    ) -> Result<(), Error> {
        for s in settled {
            let Some(frame) = file.frames.get(s.tag as usize) else {
                continue;
            };
            let late_ms = ms(s.sent_at.saturating_sub(due(frame.t_s)));
            let answer_ms = ms(s.answered_at.saturating_sub(s.sent_at));
            self.late += late_ms;
            self.answer += answer_ms;
            self.sent += 1;
            timing.late_max_ms = timing.late_max_ms.max(late_ms);
            timing.answer_max_ms = timing.answer_max_ms.max(answer_ms);
            if let Some(r) = session::report(&s.result) {
                writeln!(diag, "{}:{}: {r}", file.name, frame.line)
                    .map_err(|source| csv::Error::Write { path: None, source })?;
            }
        }
        Ok(())
    }
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
