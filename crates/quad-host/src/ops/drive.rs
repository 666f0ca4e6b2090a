//! Teleoperation of the onboard walk: keys (or a script of them) become a velocity command and
//! a body height, the operation behind `quadctl drive`.
//!
//! The keys ([`Key`]) change the command by fixed steps ([`Steps`]); the command is what the
//! device's walk is asked for, every [`SEND_PERIOD`] (≥ 10 Hz, well within the walk's velocity
//! timeout). A command the device refuses (beyond the gait's reach) is taken back to the last
//! one it accepted, and the refusal is shown. Space stops (zero velocity, the stride finishes);
//! `q` sits and quits.
//!
//! Frames: body frame, x forward, y left, yaw counter-clockwise positive (REP 103).

use std::time::Duration;

/// How often the command is sent: 20 Hz.
pub const SEND_PERIOD: Duration = Duration::from_millis(50);

/// One key of the teleop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Key {
    /// ↑ or `w`: faster forward.
    Forward,
    /// ↓ or `s`: faster backward.
    Backward,
    /// `a`: faster to the left.
    Left,
    /// `d`: faster to the right.
    Right,
    /// ←: faster counter-clockwise.
    TurnLeft,
    /// →: faster clockwise.
    TurnRight,
    /// `+`: body higher.
    Higher,
    /// `-`: body lower.
    Lower,
    /// Space: velocity zero.
    Stop,
    /// `q`: sit and quit.
    Quit,
}

impl Key {
    /// The key named `name` in a key script: `w a s d up down left right + - space q`.
    pub fn parse(name: &str) -> Option<Key> {
        Some(match name {
            "w" | "up" => Key::Forward,
            "s" | "down" => Key::Backward,
            "a" => Key::Left,
            "d" => Key::Right,
            "left" => Key::TurnLeft,
            "right" => Key::TurnRight,
            "+" | "=" => Key::Higher,
            "-" => Key::Lower,
            "space" | " " => Key::Stop,
            "q" => Key::Quit,
            _ => return None,
        })
    }
}

/// Steps of one key press.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Steps {
    /// Forward and lateral speed, m/s.
    pub speed_m_s: f32,
    /// Yaw rate, rad/s.
    pub yaw_rate_rad_s: f32,
    /// Body height, m.
    pub height_m: f32,
}

impl Default for Steps {
    fn default() -> Self {
        Steps {
            speed_m_s: 0.02,
            yaw_rate_rad_s: 0.1,
            height_m: 0.01,
        }
    }
}

/// The velocity command, body frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Command {
    /// Forward speed, m/s.
    pub forward_m_s: f32,
    /// Lateral speed (left positive), m/s.
    pub lateral_m_s: f32,
    /// Yaw rate, rad/s, counter-clockwise positive.
    pub yaw_rate_rad_s: f32,
}

/// What a key changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// The velocity command.
    Velocity,
    /// The body height (the walk restarts at it).
    Height,
    /// Sit and quit.
    Quit,
}

/// The teleop's state: the command asked for, the last one the device accepted, the height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Teleop {
    /// The command to send.
    pub command: Command,
    /// The last command the device accepted.
    pub accepted: Command,
    /// Body height of the walk, m.
    pub body_height_m: f32,
    /// Key steps.
    pub steps: Steps,
}

impl Teleop {
    /// At rest, walking at `body_height_m`.
    pub fn new(body_height_m: f32, steps: Steps) -> Teleop {
        Teleop {
            command: Command::default(),
            accepted: Command::default(),
            body_height_m,
            steps,
        }
    }

    /// Applies one key.
    pub fn press(&mut self, key: Key) -> Effect {
        let c = &mut self.command;
        let s = self.steps;
        match key {
            Key::Forward => c.forward_m_s += s.speed_m_s,
            Key::Backward => c.forward_m_s -= s.speed_m_s,
            Key::Left => c.lateral_m_s += s.speed_m_s,
            Key::Right => c.lateral_m_s -= s.speed_m_s,
            Key::TurnLeft => c.yaw_rate_rad_s += s.yaw_rate_rad_s,
            Key::TurnRight => c.yaw_rate_rad_s -= s.yaw_rate_rad_s,
            Key::Stop => *c = Command::default(),
            Key::Higher => {
                self.body_height_m += s.height_m;
                return Effect::Height;
            }
            Key::Lower => {
                self.body_height_m -= s.height_m;
                return Effect::Height;
            }
            Key::Quit => return Effect::Quit,
        }
        // Steps of f32 sums: a command back at zero is exactly zero.
        for v in [
            &mut c.forward_m_s,
            &mut c.lateral_m_s,
            &mut c.yaw_rate_rad_s,
        ] {
            if v.abs() < 1e-6 {
                *v = 0.0;
            }
        }
        Effect::Velocity
    }

    /// The device accepted the command sent.
    pub fn accept(&mut self) {
        self.accepted = self.command;
    }

    /// The device refused the command sent: back to the last accepted one.
    pub fn refuse(&mut self) {
        self.command = self.accepted;
    }
}

/// One key of a script: when (link time since the start) and which.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptedKey {
    /// Time since the start, on the link's clock.
    pub at: Duration,
    /// The key.
    pub key: Key,
}

/// Why a key script cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScriptError {
    /// A line that is not `<ms> <key>`.
    #[error(
        "{input}:{line}: `{text}` is not `<ms> <key>` (key: w a s d up down left right + - \
         space q)"
    )]
    Syntax {
        /// The script's name.
        input: String,
        /// 1-based line.
        line: usize,
        /// The line.
        text: String,
    },
    /// Times that go back.
    #[error("{input}:{line}: {at_ms} ms comes before the previous key")]
    Order {
        /// The script's name.
        input: String,
        /// 1-based line.
        line: usize,
        /// The time given, ms.
        at_ms: u64,
    },
}

/// Reads a key script: one `<ms> <key>` per line (ms since the start, non-decreasing), `#`
/// comments and blank lines skipped.
///
/// # Errors
/// [`ScriptError`] naming the line.
pub fn parse_script(input: &str, text: &str) -> Result<Vec<ScriptedKey>, ScriptError> {
    let mut keys: Vec<ScriptedKey> = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let syntax = || ScriptError::Syntax {
            input: input.to_owned(),
            line: i + 1,
            text: t.to_owned(),
        };
        let (ms, key) = t.split_once(char::is_whitespace).ok_or_else(syntax)?;
        let at_ms: u64 = ms.parse().map_err(|_| syntax())?;
        let key = Key::parse(key.trim()).ok_or_else(syntax)?;
        let at = Duration::from_millis(at_ms);
        if keys.last().is_some_and(|k| k.at > at) {
            return Err(ScriptError::Order {
                input: input.to_owned(),
                line: i + 1,
                at_ms,
            });
        }
        keys.push(ScriptedKey { at, key });
    }
    Ok(keys)
}

/// What the device answers to a velocity command (or a walk's start).
#[derive(Debug, Clone, PartialEq)]
pub enum Answer<S> {
    /// Accepted; the device's state after it.
    Accepted(S),
    /// Refused, with the reason in words.
    Refused(String),
}

/// The device end of the teleop: the onboard walk and the link's clock.
pub trait Walker {
    /// The device's state as shown live (motion, phase, readback).
    type State;
    /// A failure that ends the teleop (the link).
    type Error;
    /// Starts the walk at `body_height_m` (standing up first when needed), velocity zero.
    ///
    /// # Errors
    /// Link failures.
    fn start(&mut self, body_height_m: f32) -> Result<Answer<Self::State>, Self::Error>;
    /// Sends the velocity command.
    ///
    /// # Errors
    /// Link failures.
    fn velocity(&mut self, command: &Command) -> Result<Answer<Self::State>, Self::Error>;
    /// Stops the walk and waits until the device has finished its strides and stands.
    ///
    /// # Errors
    /// Link failures.
    fn stop(&mut self) -> Result<(), Self::Error>;
    /// Sits down (the teleop's end).
    ///
    /// # Errors
    /// Link failures.
    fn sit(&mut self) -> Result<(), Self::Error>;
    /// The link's clock.
    fn now(&self) -> Duration;
    /// Lets the link's time run until `deadline`.
    ///
    /// # Errors
    /// Link failures.
    fn idle_until(&mut self, deadline: Duration) -> Result<(), Self::Error>;
}

/// What a teleop session did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Velocity commands sent.
    pub commands_sent: u64,
    /// Commands the device refused.
    pub refused: u64,
    /// Keys applied.
    pub keys: u64,
    /// Walk restarts for a new body height.
    pub height_changes: u64,
    /// Largest gap between two velocity commands, ms.
    pub max_gap_ms: f64,
    /// Link time from the start to the end, s.
    pub elapsed_s: f64,
    /// The last accepted command.
    pub last: Command,
}

/// Runs the teleop: every [`SEND_PERIOD`] the keys that came (`keys(now)` returns them one at
/// a time until `None`), then the command; `show` sees the state after every answer and every
/// refusal's words. Ends with `q` (sit), or when `keys` says so by returning [`Key::Quit`].
///
/// # Errors
/// The walker's failures.
pub fn run<W: Walker>(
    walker: &mut W,
    mut teleop: Teleop,
    mut keys: impl FnMut(Duration) -> Option<Key>,
    mut show: impl FnMut(&Teleop, Option<&W::State>, Option<&str>),
) -> Result<Summary, W::Error> {
    let start = walker.now();
    let mut summary = Summary::default();
    if let Answer::Refused(why) = walker.start(teleop.body_height_m)? {
        show(&teleop, None, Some(&why));
        walker.sit()?;
        summary.refused += 1;
        return Ok(summary);
    }
    let mut next = walker.now();
    let mut last_sent: Option<Duration> = None;
    loop {
        walker.idle_until(next)?;
        let now = walker.now();
        let mut quit = false;
        while let Some(key) = keys(now - start) {
            summary.keys += 1;
            match teleop.press(key) {
                Effect::Velocity => {}
                Effect::Height => {
                    summary.height_changes += 1;
                    walker.stop()?;
                    if let Answer::Refused(why) = walker.start(teleop.body_height_m)? {
                        // Back to the height that walked.
                        let undo = if key == Key::Higher {
                            Key::Lower
                        } else {
                            Key::Higher
                        };
                        teleop.press(undo);
                        summary.refused += 1;
                        show(&teleop, None, Some(&why));
                        walker.start(teleop.body_height_m)?;
                    }
                    last_sent = None;
                }
                Effect::Quit => quit = true,
            }
            if quit {
                break;
            }
        }
        if quit {
            break;
        }
        let sent_at = walker.now();
        if let Some(t) = last_sent {
            let gap_ms = (sent_at - t).as_secs_f64() * 1e3;
            summary.max_gap_ms = summary.max_gap_ms.max(gap_ms);
        }
        last_sent = Some(sent_at);
        summary.commands_sent += 1;
        match walker.velocity(&teleop.command)? {
            Answer::Accepted(state) => {
                teleop.accept();
                show(&teleop, Some(&state), None);
            }
            Answer::Refused(why) => {
                teleop.refuse();
                summary.refused += 1;
                show(&teleop, None, Some(&why));
            }
        }
        next = sent_at + SEND_PERIOD;
    }
    walker.sit()?;
    summary.last = teleop.accepted;
    summary.elapsed_s = (walker.now() - start).as_secs_f64();
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_step_the_command_and_space_stops() {
        let mut t = Teleop::new(0.2, Steps::default());
        assert_eq!(t.press(Key::Forward), Effect::Velocity);
        t.press(Key::Forward);
        t.press(Key::TurnLeft);
        t.press(Key::Right);
        assert!((t.command.forward_m_s - 0.04).abs() < 1e-6);
        assert!(
            t.command.yaw_rate_rad_s > 0.0,
            "left turns counter-clockwise"
        );
        assert!(t.command.lateral_m_s < 0.0, "right is -y");
        t.accept();
        t.press(Key::Forward);
        t.refuse();
        assert_eq!(t.command, t.accepted);
        t.press(Key::Backward);
        t.press(Key::Forward);
        t.press(Key::Stop);
        assert_eq!(t.command, Command::default());
        assert_eq!(t.press(Key::Higher), Effect::Height);
        assert!((t.body_height_m - 0.21).abs() < 1e-6);
        assert_eq!(t.press(Key::Quit), Effect::Quit);
    }

    /// A walker on a virtual clock that refuses forward speeds above 0.05 m/s.
    #[derive(Default)]
    struct Fake {
        now: Duration,
        log: Vec<String>,
    }

    impl Walker for Fake {
        type State = Command;
        type Error = ();
        fn start(&mut self, h: f32) -> Result<Answer<Command>, ()> {
            self.log.push(format!("start {h:.2}"));
            Ok(Answer::Accepted(Command::default()))
        }
        fn velocity(&mut self, c: &Command) -> Result<Answer<Command>, ()> {
            self.now += Duration::from_millis(10);
            Ok(if c.forward_m_s > 0.05 {
                Answer::Refused("forward_m_s beyond reach".to_owned())
            } else {
                Answer::Accepted(*c)
            })
        }
        fn stop(&mut self) -> Result<(), ()> {
            self.log.push("stop".to_owned());
            Ok(())
        }
        fn sit(&mut self) -> Result<(), ()> {
            self.log.push("sit".to_owned());
            Ok(())
        }
        fn now(&self) -> Duration {
            self.now
        }
        fn idle_until(&mut self, t: Duration) -> Result<(), ()> {
            self.now = self.now.max(t);
            Ok(())
        }
    }

    #[test]
    fn the_loop_sends_at_20_hz_takes_refusals_back_and_sits_at_the_end() {
        let script = parse_script("k", "0 w\n0 w\n100 w\n200 w\n300 +\n1000 q\n").unwrap();
        let mut at = 0;
        let mut fake = Fake::default();
        let mut refusals = Vec::new();
        let s = run(
            &mut fake,
            Teleop::new(0.2, Steps::default()),
            |t| {
                let k = script.get(at).filter(|k| k.at <= t)?;
                at += 1;
                Some(k.key)
            },
            |_, _, why| refusals.extend(why.map(str::to_owned)),
        )
        .unwrap();
        assert!(s.commands_sent >= 19, "{s:?}");
        assert!(s.max_gap_ms <= 50.0 + 1e-9, "{s:?}");
        assert!(
            s.refused >= 1 && refusals[0].contains("forward_m_s"),
            "{refusals:?}"
        );
        assert!((s.last.forward_m_s - 0.04).abs() < 1e-6, "{s:?}");
        assert_eq!(fake.log, ["start 0.20", "stop", "start 0.21", "sit"]);
    }

    #[test]
    fn a_script_names_its_bad_lines() {
        let keys = parse_script("k", "# drive\n0 w\n500 up\n\n500 space\n900 q\n").unwrap();
        assert_eq!(keys.len(), 4);
        assert_eq!(keys[1].at, Duration::from_millis(500));
        assert_eq!(keys[3].key, Key::Quit);
        assert!(matches!(
            parse_script("k", "0 w\nx w\n"),
            Err(ScriptError::Syntax { line: 2, .. })
        ));
        assert!(matches!(
            parse_script("k", "0 jump\n"),
            Err(ScriptError::Syntax { line: 1, .. })
        ));
        assert!(matches!(
            parse_script("k", "100 w\n50 w\n"),
            Err(ScriptError::Order { line: 2, .. })
        ));
    }
}
