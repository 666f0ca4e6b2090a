//! `quadctl drive`: keyboard teleop of the onboard trot or walk in the terminal, or a key
//! script; velocity commands at 20 Hz, the device's state shown live; a JSON summary at the end.

use crate::args::{self, DeviceRobotArgs, TargetArgs, EXIT_OK};
use crossterm::event::{self, Event, KeyCode, KeyEventKind};
use crossterm::terminal;
use kin_core::motion::gait::Pattern;
use quad_host::ops::drive::{self, Key, ScriptedKey, Steps, Teleop};
use quad_host::ops::onboard::{self, MotionAnswer, SessionWalker};
use std::collections::VecDeque;
use std::io::{self, IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

const LONG_ABOUT: &str = "\
Drives the device's own trot (or walk) from the keyboard: the robot stands up when its outputs
are off, starts the gait at velocity zero, and the keys change the velocity command, sent at
20 Hz (the walk stops by itself when commands stop coming for its timeout, 500 ms):

  up / w      forward +0.02 m/s        down / s   forward -0.02 m/s
  a           left +0.02 m/s           d          right (lateral -0.02 m/s)
  left        turn counter-clockwise (yaw rate +0.1 rad/s)
  right       turn clockwise (yaw rate -0.1 rad/s)
  + / -       body height +-0.01 m (the gait stops and starts again at the new height)
  space       velocity zero (the strides finish, the feet park on the stance)
  q           sit down and quit

A command the device refuses (beyond the gait's reach) is shown in words and taken back. The
line at the bottom shows the command and the device's answer (motion stage, gait phase, the
outputs' pulses).

--keys FILE runs a key script instead of the keyboard (for tests and demonstrations): one
`<ms> <key>` per line, ms since the start on the link's clock, keys named w a s d up down
left right + - space q (a script without q ends with one 1 s after its last key).

Output: the last line of stdout is one JSON object: commands_sent, refused, keys,
height_changes, max_gap_ms, elapsed_s, last (the last accepted command). Exit status: 0 done;
2 the link failed or the script is malformed.";

/// `--help`'s examples (run from the repository root).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl drive --robot shahriar2023 --sim --keys examples/drive.keys";

/// Arguments of `quadctl drive`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Keyboard teleop of the onboard trot: arrows/WASD velocity, +/- height, space stop, q sit and quit",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Walk (one leg at a time) instead of trot.
    #[arg(long)]
    pub walk: bool,
    /// Stance height (the body's height above the feet) to walk at, m; default: the device's.
    /// `--body-height-m` is the same option (its former name).
    #[arg(long = "stance-height-m", alias = "body-height-m", value_name = "M", value_parser = args::parse_positive_m)]
    pub body_height_m: Option<f32>,
    /// A key script instead of the keyboard.
    #[arg(long, value_name = "FILE")]
    pub keys: Option<PathBuf>,
}

/// A malformed or unreadable key script.
#[derive(Debug, thiserror::Error)]
enum KeysError {
    #[error("cannot read {0}: {1}")]
    Read(String, io::Error),
    #[error(transparent)]
    Script(#[from] drive::ScriptError),
    #[error("the terminal: {0}")]
    Terminal(io::Error),
    #[error("no terminal to read keys from: give --keys FILE")]
    NoTerminal,
}

/// Restores the terminal when dropped.
struct RawMode;

impl Drop for RawMode {
    fn drop(&mut self) {
        let _ = terminal::disable_raw_mode();
    }
}

/// The key of a terminal event, if it is one of the teleop's.
fn key_of(code: KeyCode) -> Option<Key> {
    match code {
        KeyCode::Up => Some(Key::Forward),
        KeyCode::Down => Some(Key::Backward),
        KeyCode::Left => Some(Key::TurnLeft),
        KeyCode::Right => Some(Key::TurnRight),
        KeyCode::Char(' ') => Some(Key::Stop),
        KeyCode::Char(c) => Key::parse(&c.to_ascii_lowercase().to_string()),
        KeyCode::Esc => Some(Key::Quit),
        _ => None,
    }
}

/// One status line.
fn line(t: &Teleop, state: Option<&MotionAnswer>, refusal: Option<&str>) -> String {
    let c = t.command;
    let head = format!(
        "vx {:+.2} m/s  vy {:+.2} m/s  yaw {:+.2} rad/s  height {:.3} m",
        c.forward_m_s, c.lateral_m_s, c.yaw_rate_rad_s, t.body_height_m
    );
    match (state, refusal) {
        (_, Some(why)) => format!("{head}  | refused: {why}"),
        (Some(a), None) => format!(
            "{head}  | {:?} {:?} phase {:.2}  pulses {:?}",
            a.status.kind.map_or("idle", onboard::kind_name),
            a.status.stage,
            a.status.phase,
            a.readback.pulses_half_us.map(|p| p / 2)
        ),
        (None, None) => head,
    }
}

/// Runs `quadctl drive` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let script: Option<VecDeque<ScriptedKey>> = match &args.keys {
        None => None,
        Some(path) => {
            let read = std::fs::read_to_string(path)
                .map_err(|e| KeysError::Read(path.display().to_string(), e))
                .and_then(|text| Ok(drive::parse_script(&path.display().to_string(), &text)?));
            match read {
                Ok(mut keys) => {
                    // A script ends as the keyboard does: with q, 1 s after its last key
                    // when it has none.
                    if keys.last().is_none_or(|k| k.key != Key::Quit) {
                        let at = keys.last().map_or(Duration::ZERO, |k| k.at);
                        keys.push(ScriptedKey {
                            at: at + Duration::from_secs(1),
                            key: Key::Quit,
                        });
                    }
                    Some(keys.into())
                }
                Err(e) => return args::fail("quadctl", &e),
            }
        }
    };
    if script.is_none() && !io::stdin().is_terminal() {
        return args::fail("quadctl", &KeysError::NoTerminal);
    }
    let device = args.target.target(args.robot.sim_preset());
    let opened = match &args.robot.robot {
        Some(r) => onboard::open(r, &device, args.target.retries),
        None => onboard::open_device_robot(&device, args.target.retries),
    };
    let mut session = match opened {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    let height = args
        .body_height_m
        .unwrap_or(session.info().pose_config.stance_height_m);
    let mut walker = SessionWalker {
        session: &mut session,
        pattern: if args.walk {
            Pattern::Walk
        } else {
            Pattern::Trot
        },
        limit: Duration::from_secs(60),
    };
    let teleop = Teleop::new(height, Steps::default());
    let interactive = script.is_none();
    let _raw = if interactive {
        if let Err(e) = terminal::enable_raw_mode() {
            return args::fail("quadctl", &KeysError::Terminal(e));
        }
        Some(RawMode)
    } else {
        None
    };
    let mut script = script.unwrap_or_default();
    let wall = std::time::Instant::now();
    let keys = |at: Duration| -> Option<Key> {
        if interactive {
            // A person at the keyboard: the link's clock must not run ahead of the wall clock
            // (it does on the simulated and emulated links, which run as fast as they can).
            if let Some(ahead) = at.checked_sub(wall.elapsed()) {
                std::thread::sleep(ahead);
            }
        }
        if !interactive {
            let next = script.front().filter(|k| k.at <= at)?;
            let key = next.key;
            script.pop_front();
            return Some(key);
        }
        while event::poll(Duration::ZERO).ok()? {
            if let Ok(Event::Key(k)) = event::read() {
                if k.kind != KeyEventKind::Release {
                    if let Some(key) = key_of(k.code) {
                        return Some(key);
                    }
                }
            }
        }
        None
    };
    let mut err = io::stderr();
    let show = |t: &Teleop, state: Option<&MotionAnswer>, refusal: Option<&str>| {
        if interactive {
            let _ = write!(err, "\r\x1b[2K{}", line(t, state, refusal));
            let _ = err.flush();
        } else if let Some(why) = refusal {
            let _ = writeln!(err, "quadctl: refused: {why}");
        }
    };
    let result = drive::run(&mut walker, teleop, keys, show);
    drop(_raw);
    if interactive {
        let _ = writeln!(io::stderr());
    }
    let summary = match result {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    match args::print_json_line(&summary) {
        Ok(()) => ExitCode::from(EXIT_OK),
        Err(status) => status,
    }
}
