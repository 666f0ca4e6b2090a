//! `quadctl play`: a timed setpoint file (joint angles, feet or body poses, or `quadctl motion`'s
//! output) played to the device in real time, every answer checked; a JSON summary as the last
//! line of stdout.

use crate::args::{self, SessionArgs};
use quad_host::csv::play::ColumnKind;
use quad_host::ops::play::{self, Request};
use std::io;
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Plays a timed setpoint file to the device, paced by its t_s column, and checks every answer.

Input: `quadctl motion` output as it is (every row must be `ok`), or a CSV with t_s (s, strictly
increasing) and the columns of one or more kinds: joint angles FL_abduction_rad ... RR_knee_rad
(rad, canonical convention), feet FL_x_m ... RR_z_m (m, world frame of `quadctl motion` = body
frame of the nominal pose), body pose roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m (rad, m; feet at
the stance). A comment `# ... rotation_order=zxy ...` before the header names the pose's rotation
order. The file is read and checked whole first: a missing t_s, a time that does not increase, a
column of no known kind, a kind with a column missing or a field that is not a number stops the
run with <file>:<line>: <what is wrong>, before the link is opened.

What is sent: joint angles as SetJoints, else feet as SetFeet (moved into the body frame through
the row's pose when the file has one), else the pose as SetBodyPose; --send picks a kind.

Pacing: row i is due at start + (t_i - t_0) / --speed on the link's clock: simulated time with
--sim and --emulator (nothing sleeps), wall time with --port. A row is sent at its due time,
with up to two requests in flight (--one-at-a-time: each answer before the next row); when the
next row is already due before a row could be sent, the row is skipped (never the last). Each answer is checked as `quadctl stream` checks it (angles against the host's
kin-core and joint limits, pulses against the calibration's mapping; the pins with
--emulator). Nacked, lost and mismatching rows are reported on stderr as <file>:<line>: ...

The device's joint-speed limiter (3 rad/s) slows a row that asks a joint to move faster from
the row before: such rows are counted in slowed_rows, the first named on stderr
(<file>:<line>: <joint> at <speed> rad/s > the limit ...); `quadctl check` finds them first.

Output: the last line of stdout is one JSON object: kind, rows, late_mean_ms, late_max_ms
(sending after the due time), skipped, answer_mean_ms, answer_max_ms (sending to answer),
motion_s, slowed_rows, then the fields of `quadctl stream`'s summary (sent, acked, nacked, retries, lost,
readback_mismatches, ...) and with --emulator pulses_checked and pulse_width_errors.

Exit status: 0 every row sent was acked, every check passed (skipped rows do not count); 2
nothing or not everything could be played (arguments, robot, file, link, handshake); 3 a
readback mismatch, a pulse out of its travel or a pulse width error on the pins; 4 every check
passed but at least one row was refused by the device (nacked, e.g. unreachable) or lost (no
answer after every retry). --allow-refused: nacked and lost rows leave the status 0.";

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl play examples/stance.csv --robot shahriar2023 --sim
  quadctl motion roll-sway --robot shahriar2023 --duration-s 4 --rate-hz 50 --output roll.csv
  quadctl play roll.csv --robot shahriar2023 --emulator
  quadctl play roll.csv --robot shahriar2023 --port /dev/ttyACM0";

/// Arguments of `quadctl play`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Play a timed file of joint angles, feet or body poses to the device in real time",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    /// The file: `quadctl motion` output or a t_s + joints/feet/pose CSV; `-` for stdin.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub session: SessionArgs,
    /// Time scale: 2 plays twice as fast, 0.5 half as fast.
    #[arg(long, value_name = "X", default_value_t = 1.0)]
    pub speed: f64,
    /// The kind of columns to send [default: joints, else feet, else pose].
    #[arg(long, value_parser = args::column_kind())]
    pub send: Option<ColumnKind>,
}

/// Runs `quadctl play` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let request = Request {
        session: args.session.session(),
        speed: args.speed,
        send: args.send,
        input: args.file.clone(),
        window: args.session.window(),
    };
    let summary = match play::run(&request, &mut io::stderr().lock()) {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    if let Err(status) = args::print_json_line(&summary) {
        return status;
    }
    ExitCode::from(args::stream_status(
        &summary.stream,
        summary.check_failed(),
        0,
        args.session.allow_refused,
    ))
}
