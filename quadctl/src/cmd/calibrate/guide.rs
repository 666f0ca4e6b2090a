//! `quadctl calibrate guide`: the guided calibration in the terminal, or from a key script
//! (the step machine is `quad_host::ops::calibrate::guide`'s).

use crate::args::{self, EXIT_OK};
use crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use crossterm::terminal;
use kin_core::Robot;
use quad_host::link::Target;
use quad_host::ops::calibrate::guide::{self, Guide, Key, SessionDevice, Step, View};
use quad_host::ops::calibrate::{self, servo_name, to_toml};
use quad_host::ops::onboard::MotionAnswer;
use std::collections::VecDeque;
use std::io::{self, IsTerminal, Read, Write};
use std::process::ExitCode;
use std::time::Duration;

/// `calibrate guide --help`.
pub const LONG_ABOUT: &str = "\
The guided calibration, step by step, on the device's own robot (keys in brackets):

  1. posture   the device moves every joint to the calibration posture: abduction 0, each
               femur 45 degrees from vertical with the knee behind the hip, each knee bent at a
               right angle (each foot about below its hip). Outputs that are off come on
               through the device's stand-up; every move passes its joint-speed limiter.
               [n] posture reached, [r] move there again
  2. jog       the twelve servos in turn (FL abduction, hip, knee, FR ..., RL ..., RR ...):
               move each one's CENTRE PULSE (center_us, MICROSECONDS) until the limb sits on
               its mark: [+]/[-] 2 us, []]/[[] 20 us; + turns the joint towards positive
               angles. Each jog is sent to the device's RAM (nothing saved yet) and the
               posture commanded again, so the limb moves at once. [n] next servo, [b]
               previous, [t] skip to the test poses, [r] posture again
  3. test      the device's own motions, each confirmed: rest (the rest pose, held), stand,
               a step in place (a trot at velocity zero for 3 s, then stopped).
               [n] looks right, [r] run it again, [b] back to jogging
  4. save      [s] save to the EEPROM, [b] the test poses again

[q] (or Ctrl-C, Esc) aborts at any step: the calibration read at the start goes back to the
device's RAM and nothing is saved. Every refusal of the device is shown with its reason and
changes nothing. In the terminal, Enter and the right arrow also go on, the left arrow goes
back, up/down and PageUp/PageDown jog.

--script KEYS runs without a terminal (scripts, tests): the keys by name, separated by commas
or spaces (`n,+,+,n,t,n,n,n,s`; `y` and `enter` are n too), or `-` to read them from standard
input. A script that ends before `s` or `q` aborts.

Robot: the device's own (its handshake reports it); --robot FILE.toml for a device whose
robot is no preset. Output: the calibration in the device's RAM at the end as TOML (the format
of `calibrate get`), after a first line `# saved` or `# aborted: nothing saved`; the steps on
stderr. Exit status: 0 saved or aborted; 2 the link failed, the device is not known, or an
abort could not restore every servo.";

/// `calibrate guide --help`'s examples (run from the repository root).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl calibrate --sim --robot shahriar2023 guide --script n,+,+,n,t,n,n,n,s
  quadctl calibrate --sim --robot fernando2025 guide --script n,],q";

/// Arguments of `quadctl calibrate guide`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct Args {
    /// Keys by name instead of the keyboard (`n,+,+,n,t,n,n,n,s`; `-`: read from standard
    /// input).
    #[arg(long, value_name = "KEYS|-")]
    pub script: Option<String>,
}

/// Why the guide could not run.
#[derive(Debug, thiserror::Error)]
enum Error {
    #[error("--script: `{0}` is no key of the guide (+ - ] [ n b t r s q, y, enter)")]
    Key(String),
    #[error("--script -: cannot read standard input: {0}")]
    Stdin(io::Error),
    #[error("no terminal to read keys from: give --script KEYS")]
    NoTerminal,
    #[error("the terminal: {0}")]
    Terminal(io::Error),
    #[error(transparent)]
    Open(#[from] calibrate::GuideError),
    #[error(transparent)]
    Device(#[from] quad_host::ops::onboard::Error),
    #[error("aborted, but the device refused the old calibration of {0}: it keeps the jogged one in RAM until its next power-on (nothing was saved)")]
    NotRestored(String),
}

/// Restores the terminal when dropped.
struct RawMode;

impl Drop for RawMode {
    fn drop(&mut self) {
        let _ = terminal::disable_raw_mode();
    }
}

/// The keys of a script.
fn parse_script(text: &str) -> Result<VecDeque<Key>, Error> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|k| !k.is_empty())
        .map(|k| Key::parse(k).ok_or_else(|| Error::Key(k.to_owned())))
        .collect()
}

/// The guide's key of a terminal key.
fn key_of(code: KeyCode, modifiers: KeyModifiers) -> Option<Key> {
    match code {
        KeyCode::Char('c') if modifiers.contains(KeyModifiers::CONTROL) => Some(Key::Abort),
        KeyCode::Char(c) => Key::parse(&c.to_ascii_lowercase().to_string()),
        KeyCode::Enter | KeyCode::Right => Some(Key::Next),
        KeyCode::Left => Some(Key::Back),
        KeyCode::Up => Some(Key::FineUp),
        KeyCode::Down => Some(Key::FineDown),
        KeyCode::PageUp => Some(Key::CoarseUp),
        KeyCode::PageDown => Some(Key::CoarseDown),
        KeyCode::Esc => Some(Key::Abort),
        _ => None,
    }
}

/// The screen of the terminal: the prompt, the servo, the keys, the message.
fn screen(v: &View) -> String {
    let mut lines = vec![format!("[{}] {}", v.step, v.prompt)];
    if let (Some(servo), Some(center), Some(start)) = (&v.servo, v.center_us, v.start_center_us) {
        lines.push(format!(
            "  {servo}: center_us {center} us ({:+} us from the start)",
            i32::from(center) - i32::from(start)
        ));
    }
    if !v.changed.is_empty() {
        lines.push(format!("  changed in RAM: {}", v.changed.join(", ")));
    }
    if !v.keys.is_empty() {
        let keys: Vec<String> = v
            .keys
            .iter()
            .map(|k| format!("[{}] {}", k.key, k.does))
            .collect();
        lines.push(format!("  keys: {}", keys.join("  ")));
    }
    if let Some(m) = &v.message {
        lines.push(format!("  > {m}"));
    }
    lines.join("\r\n")
}

/// One line of the script's log: the key, the step (with its servo or test pose) and the
/// message.
fn log_line(key: Option<Key>, v: &View) -> String {
    let what = match (&v.servo, v.test) {
        (Some(s), _) => format!(" {s}"),
        (None, Some(t)) => format!(" {t}"),
        _ => String::new(),
    };
    let key = key.map_or(String::new(), |k| format!("key {} -> ", k.name()));
    let message = v
        .message
        .as_deref()
        .map_or(String::new(), |m| format!(": {m}"));
    format!("quadctl: guide: {key}[{}{what}]{message}", v.step)
}

/// The next key of the terminal; the device's state is read every half second meanwhile, so
/// that a failing link shows.
fn next_terminal_key<L: quad_host::link::Link>(
    session: &mut quad_host::ops::onboard::Session<L>,
) -> Result<Key, Error> {
    loop {
        if event::poll(Duration::from_millis(500)).map_err(Error::Terminal)? {
            if let Event::Key(k) = event::read().map_err(Error::Terminal)? {
                if k.kind != KeyEventKind::Release {
                    if let Some(key) = key_of(k.code, k.modifiers) {
                        return Ok(key);
                    }
                }
            }
        } else {
            session.state()?;
        }
    }
}

/// Runs `quadctl calibrate guide` on `target` and returns its exit status.
pub fn main(args: &Args, target: &Target, retries: u32, robot: Option<&Robot>) -> ExitCode {
    let script = match args.script.as_deref() {
        None => None,
        Some("-") => {
            let mut text = String::new();
            match io::stdin().read_to_string(&mut text) {
                Ok(_) => Some(parse_script(&text)),
                Err(e) => Some(Err(Error::Stdin(e))),
            }
        }
        Some(keys) => Some(parse_script(keys)),
    };
    let script = match script.transpose() {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    // The device first: a missing port is the first thing to report.
    let (mut session, mut g) = match calibrate::open_guide(target, retries, robot) {
        Ok(x) => x,
        Err(e) => return args::fail("quadctl", &Error::from(e)),
    };
    let interactive = script.is_none();
    if interactive && !io::stdin().is_terminal() {
        return args::fail("quadctl", &Error::NoTerminal);
    }
    let raw = if interactive {
        if let Err(e) = terminal::enable_raw_mode() {
            return args::fail("quadctl", &Error::Terminal(e));
        }
        Some(RawMode)
    } else {
        None
    };
    let mut script = script.unwrap_or_default();
    let mut err = io::stderr();
    let show = |err: &mut io::Stderr, key: Option<Key>, g: &Guide| {
        let v = g.view();
        if interactive {
            let _ = write!(err, "\x1b[2J\x1b[H{}\r\n", screen(&v));
        } else {
            let _ = writeln!(err, "{}", log_line(key, &v));
        }
        let _ = err.flush();
    };
    let mut each = |a: &MotionAnswer| {
        if interactive {
            let _ = write!(
                io::stderr(),
                "\r\x1b[2K  {} {:?} {:.1} s",
                a.status
                    .kind
                    .map_or("idle", quad_host::ops::onboard::kind_name),
                a.status.stage,
                a.status.t_s
            );
        }
    };
    let limit = Duration::from_secs(60);
    let mut key: Option<Key> = None;
    let result: Result<(), Error> = loop {
        let mut device = SessionDevice {
            session: &mut session,
            limit,
            each: &mut each,
        };
        if let Err(e) = guide::settle(&mut g, &mut device) {
            break Err(e.into());
        }
        show(&mut err, key, &g);
        if g.step().is_done() {
            break Ok(());
        }
        let next = if interactive {
            next_terminal_key(&mut session)
        } else {
            // A script that ends before saving or aborting aborts.
            Ok(script.pop_front().unwrap_or(Key::Abort))
        };
        match next {
            Ok(k) => key = Some(k),
            Err(e) => break Err(e),
        }
        if let Some(k) = key {
            g.key(k);
        }
    };
    drop(raw);
    if let Err(e) = result {
        return args::fail("quadctl", &e);
    }
    if !g.not_restored().is_empty() {
        let names: Vec<String> = g.not_restored().iter().map(|s| servo_name(*s)).collect();
        return args::fail("quadctl", &Error::NotRestored(names.join(", ")));
    }
    let head = match g.step() {
        Step::Saved => "# saved\n",
        _ => "# aborted: nothing saved\n",
    };
    let text = format!("{head}{}", to_toml(g.calibration()));
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::from(EXIT_OK),
        Err(e) => args::fail("quadctl", &e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_and_terminal_keys_name_the_guides_keys() {
        let keys = parse_script("n,+ +\n] [ - t y enter r b s q").unwrap();
        assert_eq!(keys.len(), 13);
        assert_eq!(keys[0], Key::Next);
        assert_eq!(keys[3], Key::CoarseUp);
        assert!(matches!(parse_script("n,,x"), Err(Error::Key(k)) if k == "x"));
        assert_eq!(
            key_of(KeyCode::Char('c'), KeyModifiers::CONTROL),
            Some(Key::Abort)
        );
        assert_eq!(key_of(KeyCode::Char('c'), KeyModifiers::NONE), None);
        assert_eq!(
            key_of(KeyCode::Char('S'), KeyModifiers::SHIFT),
            Some(Key::Save)
        );
        assert_eq!(key_of(KeyCode::Enter, KeyModifiers::NONE), Some(Key::Next));
        assert_eq!(
            key_of(KeyCode::PageDown, KeyModifiers::NONE),
            Some(Key::CoarseDown)
        );
        assert_eq!(key_of(KeyCode::Esc, KeyModifiers::NONE), Some(Key::Abort));
    }
}
