//! `quadctl stream`: body poses to the device, simulated (`--sim`), emulated (`--emulator`) or
//! real (`--port`), every answer checked against the host's own kin-core; a JSON summary as the
//! last line of stdout.

use crate::args::{self, InputArgs, SessionArgs};
use quad_host::ops::stream::{self, Request};
use std::io;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Streams body poses to the device and checks every answer.

Input: the CSV of `quadctl pose` (roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m: rotation in RADIANS,
translation in METRES of the body relative to the world frame; feet held at the nominal stance).

Target: --sim runs the device controller in-process behind a simulated UART with the timing of
a real line at --baud (virtual time: nothing sleeps) and optional --faults; --emulator runs the
real ATmega2560 firmware (built from firmware-avr/ if needed, or --elf PATH) in simavr
in-process at 16 MHz, in simulated time, with the same --faults, and checks the pulses on its
twelve servo pins; --port PATH talks to an Arduino Mega running the firmware.

Two requests are kept in flight (the device solves the next pose while the answer to the
previous one is on the wire: about twice the poses per second of one at a time at 115,200
baud; --one-at-a-time waits for each answer before the next request). Each pose is sent as one
SetBodyPose request and retried (same sequence number) on a timeout, on
a nack of an unreadable frame, or when its answer fails the check: the device's 12 angles must
equal the host's kin-core result (the same bits with --sim; within --angle-tolerance-rad with
--emulator and --port) and its 12 pulses the device calibration's mapping of those angles; an unreachable pose
must be nacked with the host's own leg and reason. Nacked, lost and mismatching poses are reported
on stderr as <input>:<line>: ...

Output: the last line of stdout is one JSON object:
{\"sent\",\"acked\",\"nacked\",\"retries\",\"lost\",\"readback_mismatches\",\"max_angle_err_rad\",
\"pulses_out_of_range\",\"poses_per_s\", then transient_mismatches (answers a retry corrected),
timeouts, elapsed_s (link time) and reenabled}; with --emulator also rx_overruns (bytes the
chip's two-byte receive buffer lost because the firmware did not read them in time), pulses_checked
and pulse_width_errors: every pulse measured on the 12 servo pins compared with the readback in
force when it started (the last one sent before it, or the next), an error when it differs by
more than one 0.5 us timer tick. poses_per_s counts acked + nacked poses per second of link time
(simulated time with --sim and --emulator).

Exit status: 0 every pose acked, every check passed; 1 malformed input records (the others were
streamed and acked); 2 nothing or not everything could be streamed (arguments, robot, input,
link, firmware build, handshake); 3 a readback mismatch, a pulse out of its travel, a pulse
width error on the pins or a receive overrun; 4 every check passed but at least one pose was
refused by the device (nacked, e.g. unreachable) or lost (no answer after every retry). When
several apply, the first of 3, 4, 1. --allow-refused: nacked and lost poses leave the status
0 (or 1).";

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl stream --robot shahriar2023 --sim --input examples/poses.csv
  quadctl stream --robot shahriar2023 --sim --faults drop=0.01,flip=0.001 --seed 7 --input examples/poses.csv
  quadctl stream --robot shahriar2023 --emulator --input examples/poses.csv
  quadctl stream --robot shahriar2023 --port /dev/ttyACM0 --input examples/poses.csv";

/// Arguments of `quadctl stream`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Stream body poses (rad, m) to the device (--sim or --port) and check every readback",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES,
    allow_negative_numbers = true
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub session: SessionArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: InputArgs,
}

/// Runs `quadctl stream` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let request = Request {
        session: args.session.session(),
        input: args.input.input.clone(),
        window: args.session.window(),
    };
    let outcome = match stream::run(&request, &mut io::stderr().lock()) {
        Ok(o) => o,
        Err(e) => return args::fail("quadctl", &e),
    };
    if let Err(status) = args::print_json_line(&outcome.summary) {
        return status;
    }
    ExitCode::from(args::stream_status(
        &outcome.summary.stream,
        outcome.summary.check_failed(),
        outcome.malformed,
        args.session.allow_refused,
    ))
}
