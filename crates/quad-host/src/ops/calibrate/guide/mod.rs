//! The guided calibration: one step machine behind `quadctl calibrate guide` and the panel's
//! calibration tab. Keys in, device actions out, so that it runs without a terminal (and is
//! tested so).
//!
//! ## Steps
//! 1. **Posture** ([`Step::Posture`]): the device moves every joint to the calibration
//!    posture ([`posture_rad`]: abduction 0, the femur 45° from vertical with the knee behind
//!    the hip, the knee bent at a right angle, so each foot lies about below its hip). The
//!    outputs come on through the device's own stand-up when they are off
//!    ([`Action::OutputsOn`]), then the posture is one `SetJoints`, approached through the
//!    device's joint-speed limiter.
//! 2. **Jog** ([`Step::Jog`]), the twelve servos in turn (FL abduction, hip, knee, FR, RL,
//!    RR): each jog moves the servo's **centre pulse** `center_us` by [`FINE_JOG_US`] or
//!    [`COARSE_JOG_US`] microseconds, signed so that `+` turns the joint towards positive
//!    angles (the pulse moves by `s·Δ`, `s = −1` for a reversed servo): one `SetCalibration` to
//!    the device's RAM (nothing is saved yet), then the posture again (`SetJoints`), so that
//!    the limb moves while the joint angle stays the posture's. Jog until the limb sits on its
//!    mark; next, back, or skip the remaining servos.
//! 3. **Test poses** ([`Step::Test`]): the device's own motions, each run to its end and
//!    confirmed by the user: rest (`Sit`: the rest pose, held), stand (`StandUp`), a step in
//!    place (a trot at velocity zero for [`STEP_IN_PLACE_S`], then stopped: the feet step on
//!    their footholds and park on the stance).
//! 4. **Save** ([`Step::Save`]): `SaveCalibration` persists the calibration in RAM, or abort.
//!
//! **Abort** (`q`, Ctrl-C) at any step sends the calibration read at the start back to the
//! device's RAM ([`Step::Aborted`]): nothing is saved. Every refusal of the device is shown
//! with its reason ([`Refusal`]) and changes nothing: a refused jog leaves the calibration as
//! it was, a refused test pose can be run again.
//!
//! ## Driving it
//! [`Guide::key`] takes a key; [`Guide::next_action`] hands out the actions it queued, one at
//! a time, and [`Guide::answer`] takes the device's answer to each; [`settle`] runs that loop
//! on a [`Device`]. [`Guide::view`] is what a front end shows (the step, the servo, its
//! pulses, the keys of the step, the last message).

use crate::ops::onboard::{self, VelocityStep};
use kin_core::motion::gait::Pattern;
use kin_core::{Joint, KneeBend, Robot};
use quad_protocol::servo::Calibration;
use quad_protocol::{MotionCommand, NackReason, ServoId};
use serde::Serialize;
use std::collections::VecDeque;
use std::fmt;

mod device;

pub use device::{settle, Device, SessionDevice};

/// A fine jog: the centre pulse moves by this much, µs.
pub const FINE_JOG_US: u16 = 2;

/// A coarse jog, µs.
pub const COARSE_JOG_US: u16 = 20;

/// How long the test's step in place runs before it is stopped, s.
pub const STEP_IN_PLACE_S: f32 = 3.0;

/// The calibration posture's hip angle for the backward knee, rad (π/4: the femur 45° from
/// vertical, the knee behind the hip).
pub const POSTURE_HIP_RAD: f32 = core::f32::consts::FRAC_PI_4;

/// The calibration posture's knee angle for the backward knee, rad (−π/2: a right angle
/// between femur and tibia, the tibia 45° from vertical towards the front).
pub const POSTURE_KNEE_RAD: f32 = -core::f32::consts::FRAC_PI_2;

/// Why the calibration posture does not exist for a robot.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PostureError {
    /// A joint's posture angle lies beyond the robot's joint limits.
    #[error(
        "the calibration posture puts every {joint} at {angle_rad} rad, beyond the robot's \
         joint limits [{min_rad}, {max_rad}] rad"
    )]
    JointLimit {
        /// The joint.
        joint: Joint,
        /// Its posture angle, rad.
        angle_rad: f32,
        /// The robot's lower limit, rad.
        min_rad: f32,
        /// The robot's upper limit, rad.
        max_rad: f32,
    },
}

/// The calibration posture of `robot`, twelve angles in the canonical order, rad: abduction 0,
/// hip [`POSTURE_HIP_RAD`], knee [`POSTURE_KNEE_RAD`] for the backward knee (both mirrored for
/// the forward knee: hip −π/4, knee +π/2). The same on every leg.
///
/// # Errors
/// [`PostureError::JointLimit`] when a joint's limits exclude it (nothing would move).
pub fn posture_rad(robot: &Robot) -> Result<[f32; 12], PostureError> {
    let mirror = match robot.knee_bend {
        KneeBend::Backward => 1.0,
        KneeBend::Forward => -1.0,
    };
    let leg = [0.0, mirror * POSTURE_HIP_RAD, mirror * POSTURE_KNEE_RAD];
    for joint in Joint::ALL {
        let angle_rad = leg[joint as usize];
        if !robot.limits.admits(joint, angle_rad) {
            return Err(PostureError::JointLimit {
                joint,
                angle_rad,
                min_rad: robot.limits.min_rad[joint as usize],
                max_rad: robot.limits.max_rad[joint as usize],
            });
        }
    }
    let mut out = [0.0; 12];
    for (i, a) in out.iter_mut().enumerate() {
        *a = leg[i % 3];
    }
    Ok(out)
}

/// A key of the guide. Every front end names them alike ([`Key::parse`], [`Key::name`]; serde
/// reads and writes the name too).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Key {
    /// `+`: fine jog towards positive angles.
    FineUp,
    /// `-`: fine jog towards negative angles.
    FineDown,
    /// `]`: coarse jog towards positive angles.
    CoarseUp,
    /// `[`: coarse jog towards negative angles.
    CoarseDown,
    /// `n` (also `y`, Enter): go on — the posture is reached, the limb is on its mark, the
    /// test pose looks right.
    Next,
    /// `b`: one step back (the previous servo; from the test poses, back to jogging).
    Back,
    /// `t`: skip the remaining servos, on to the test poses.
    Skip,
    /// `r`: run the posture or the test pose again.
    Retry,
    /// `s`: save (on the save step).
    Save,
    /// `q` (also Ctrl-C): abort, the calibration read at the start restored.
    Abort,
}

impl Key {
    /// Every key, in the order the help lists them.
    pub const ALL: [Key; 10] = [
        Key::FineUp,
        Key::FineDown,
        Key::CoarseUp,
        Key::CoarseDown,
        Key::Next,
        Key::Back,
        Key::Skip,
        Key::Retry,
        Key::Save,
        Key::Abort,
    ];

    /// The key's name in scripts and messages: `+ - ] [ n b t r s q`.
    pub const fn name(self) -> &'static str {
        match self {
            Key::FineUp => "+",
            Key::FineDown => "-",
            Key::CoarseUp => "]",
            Key::CoarseDown => "[",
            Key::Next => "n",
            Key::Back => "b",
            Key::Skip => "t",
            Key::Retry => "r",
            Key::Save => "s",
            Key::Abort => "q",
        }
    }

    /// A key by name: its [`Key::name`], or `y` and `enter` for [`Key::Next`].
    pub fn parse(name: &str) -> Option<Key> {
        match name {
            "y" | "enter" => Some(Key::Next),
            other => Key::ALL.into_iter().find(|k| k.name() == other),
        }
    }
}

impl Serialize for Key {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Key {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Key, D::Error> {
        let name = String::deserialize(d)?;
        Key::parse(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "`{name}` is no key of the guide (+ - ] [ n b t r s q, y, enter)"
            ))
        })
    }
}

/// A test pose: one of the device's own motions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TestPose {
    /// The rest pose, held (`Sit`).
    Rest,
    /// The stance (`StandUp`).
    Stand,
    /// A trot at velocity zero for [`STEP_IN_PLACE_S`], then stopped.
    StepInPlace,
}

impl TestPose {
    /// The test poses in the order they are run.
    pub const ALL: [TestPose; 3] = [TestPose::Rest, TestPose::Stand, TestPose::StepInPlace];

    /// Its name: `rest`, `stand`, `step_in_place`.
    pub const fn name(self) -> &'static str {
        match self {
            TestPose::Rest => "rest",
            TestPose::Stand => "stand",
            TestPose::StepInPlace => "step_in_place",
        }
    }

    /// The motion of the device it runs, with `stance_height_m` (the device's) for the step in
    /// place, and the velocity held meanwhile (none for the others).
    pub fn motion(self, stance_height_m: f32) -> (MotionCommand, Option<VelocityStep>) {
        match self {
            TestPose::Rest => (MotionCommand::Sit, None),
            TestPose::Stand => (MotionCommand::StandUp, None),
            TestPose::StepInPlace => (
                MotionCommand::walk(Pattern::Trot, stance_height_m),
                Some(VelocityStep {
                    forward_m_s: 0.0,
                    lateral_m_s: 0.0,
                    yaw_rate_rad_s: 0.0,
                    duration_s: STEP_IN_PLACE_S,
                }),
            ),
        }
    }
}

/// Where the guide is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Moving to (or holding) the calibration posture.
    Posture,
    /// Jogging one servo.
    Jog(ServoId),
    /// A test pose.
    Test(TestPose),
    /// Waiting for save or abort.
    Save,
    /// Saved: the device persisted the calibration.
    Saved,
    /// Aborted: the calibration read at the start was sent back (nothing saved).
    Aborted,
}

impl Step {
    /// Its name: `posture`, `jog`, `test`, `save`, `saved`, `aborted`.
    pub const fn name(self) -> &'static str {
        match self {
            Step::Posture => "posture",
            Step::Jog(_) => "jog",
            Step::Test(_) => "test",
            Step::Save => "save",
            Step::Saved => "saved",
            Step::Aborted => "aborted",
        }
    }

    /// True once the guide has ended (saved or aborted).
    pub const fn is_done(self) -> bool {
        matches!(self, Step::Saved | Step::Aborted)
    }
}

/// What the guide asks of the device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Switch the outputs on when they are off, through the device's stand-up (outputs on at
    /// the rest pose, a ramp to the stance); nothing when they are on.
    OutputsOn,
    /// Hold these twelve joint angles (`SetJoints`), rad.
    SetJoints {
        /// The angles, canonical order, rad.
        angles_rad: [f32; 12],
    },
    /// Replace one servo's calibration in the device's RAM (`SetCalibration`).
    SetCalibration {
        /// The servo.
        servo: ServoId,
        /// Its new calibration.
        calibration: Calibration,
    },
    /// Run a test pose to its end.
    Test(TestPose),
    /// Persist the calibration in RAM (`SaveCalibration`).
    Save,
}

/// A request the device refused, or the host's range check refused before sending (the
/// device's own check, run first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refusal {
    /// The request.
    pub request: &'static str,
    /// The reason the device gives.
    pub reason: NackReason,
    /// False when the host's range check refused it before sending.
    pub sent: bool,
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.sent {
            write!(
                f,
                "the device refused {}: {}",
                self.request,
                onboard::words(&self.reason)
            )
        } else {
            write!(
                f,
                "{} not sent: {} (the host's check, which the device runs alike)",
                self.request,
                onboard::words(&self.reason)
            )
        }
    }
}

/// One key and what it does at the current step, for the help line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct KeyHelp {
    /// The key ([`Key::name`]).
    pub key: &'static str,
    /// What it does, in words.
    pub does: &'static str,
}

/// What a front end shows of the guide.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct View {
    /// The step: `posture`, `jog`, `test`, `save`, `saved`, `aborted`.
    pub step: &'static str,
    /// What to do now, in words.
    pub prompt: String,
    /// The servo being jogged (`FL_hip`), on the jog step.
    pub servo: Option<String>,
    /// Its index in the canonical order (0..12).
    pub servo_index: Option<u8>,
    /// Its centre pulse in the device's RAM, µs.
    pub center_us: Option<u16>,
    /// Its centre pulse when the guide started, µs.
    pub start_center_us: Option<u16>,
    /// The test pose (`rest`, `stand`, `step_in_place`), on the test step.
    pub test: Option<&'static str>,
    /// The calibration posture, canonical order, rad.
    pub posture_rad: [f32; 12],
    /// The servos whose calibration in RAM differs from the one read at the start.
    pub changed: Vec<String>,
    /// The keys of this step.
    pub keys: Vec<KeyHelp>,
    /// The last message: a refusal with its reason, or what the last key did.
    pub message: Option<String>,
    /// True when the message is a refusal (of the device, or of the host's check before
    /// sending).
    pub refused: bool,
}

/// The guided calibration's step machine (module docs).
#[derive(Debug, Clone)]
pub struct Guide {
    posture_rad: [f32; 12],
    /// The calibration read at the start (restored by an abort).
    start: [Calibration; 12],
    /// The calibration in the device's RAM, as far as the device acked it.
    calibration: [Calibration; 12],
    step: Step,
    /// The servo of the jog step last visited (where "back" from the test poses returns).
    servo: ServoId,
    /// The posture was acked since the step was entered.
    posture_held: bool,
    /// The test pose of the step ran to its end.
    test_ran: bool,
    queue: VecDeque<Action>,
    in_flight: Option<Action>,
    message: Option<String>,
    /// The message is a refusal.
    refused: bool,
    /// Refusals so far.
    refusals: u32,
    /// Jogs the device acked.
    jogs: u32,
    /// The servos an abort could not restore.
    not_restored: Vec<ServoId>,
}

/// The servo after (or before) `s` in the canonical order.
fn neighbour(s: ServoId, forward: bool) -> Option<ServoId> {
    let i = s.index();
    let j = if forward {
        i.checked_add(1)?
    } else {
        i.checked_sub(1)?
    };
    ServoId::from_index(j)
}

impl Guide {
    /// A guide for `robot`, whose device holds `calibration` in RAM now; it starts at the
    /// posture step with its actions queued.
    ///
    /// # Errors
    /// [`PostureError`] when the robot's joint limits exclude the calibration posture.
    pub fn new(robot: &Robot, calibration: [Calibration; 12]) -> Result<Guide, PostureError> {
        let posture_rad = posture_rad(robot)?;
        let mut guide = Guide {
            posture_rad,
            start: calibration,
            calibration,
            step: Step::Posture,
            servo: ServoId::ALL[0],
            posture_held: false,
            test_ran: false,
            queue: VecDeque::new(),
            in_flight: None,
            message: None,
            refused: false,
            refusals: 0,
            jogs: 0,
            not_restored: Vec::new(),
        };
        guide.queue_posture();
        Ok(guide)
    }

    /// The step.
    pub fn step(&self) -> Step {
        self.step
    }

    /// The calibration posture, rad.
    pub fn posture(&self) -> &[f32; 12] {
        &self.posture_rad
    }

    /// The calibration in the device's RAM, as far as the device acked it.
    pub fn calibration(&self) -> &[Calibration; 12] {
        &self.calibration
    }

    /// The calibration read at the start.
    pub fn start_calibration(&self) -> &[Calibration; 12] {
        &self.start
    }

    /// Refusals of the device (or the host's range check) so far.
    pub fn refusals(&self) -> u32 {
        self.refusals
    }

    /// Jogs the device acked so far.
    pub fn jogs(&self) -> u32 {
        self.jogs
    }

    /// The servos an abort could not restore (the device refused their old calibration).
    pub fn not_restored(&self) -> &[ServoId] {
        &self.not_restored
    }

    /// True while actions are queued or one awaits its answer.
    pub fn busy(&self) -> bool {
        self.in_flight.is_some() || !self.queue.is_empty()
    }

    /// The last message.
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    fn queue_posture(&mut self) {
        self.posture_held = false;
        self.queue.push_back(Action::OutputsOn);
        self.queue.push_back(Action::SetJoints {
            angles_rad: self.posture_rad,
        });
    }

    fn enter_jog(&mut self, servo: ServoId, from_tests: bool) {
        self.servo = servo;
        self.step = Step::Jog(servo);
        if from_tests || !self.posture_held {
            self.queue_posture();
        }
    }

    fn enter_test(&mut self, pose: TestPose) {
        self.step = Step::Test(pose);
        self.test_ran = false;
        self.queue.push_back(Action::Test(pose));
    }

    fn jog(&mut self, servo: ServoId, up: bool, step_us: u16) {
        let c = self.calibration[servo.index()];
        // `+` turns the joint towards positive angles: the pulse moves by s·Δ.
        let towards = if up == c.reversed { -1 } else { 1 };
        let center = i32::from(c.center_us) + towards * i32::from(step_us);
        match u16::try_from(center) {
            Ok(center_us) => {
                self.queue.push_back(Action::SetCalibration {
                    servo,
                    calibration: Calibration { center_us, ..c },
                });
                self.queue.push_back(Action::SetJoints {
                    angles_rad: self.posture_rad,
                });
            }
            Err(_) => {
                self.message = Some(format!(
                    "{}: a centre pulse of {center} us is no pulse; not sent",
                    super::servo_name(servo)
                ));
            }
        }
    }

    /// Aborts: every servo whose calibration differs from the one read at the start gets that
    /// one back.
    fn abort(&mut self) {
        self.queue.clear();
        for s in ServoId::ALL {
            if self.calibration[s.index()] != self.start[s.index()] {
                self.queue.push_back(Action::SetCalibration {
                    servo: s,
                    calibration: self.start[s.index()],
                });
            }
        }
        self.step = Step::Aborted;
        self.message = Some(if self.queue.is_empty() {
            "aborted: the calibration is the one read at the start; nothing saved".to_owned()
        } else {
            "aborted: the calibration read at the start is sent back; nothing saved".to_owned()
        });
    }

    /// Takes a key. While actions are pending only [`Key::Abort`] is taken; after the end
    /// nothing is.
    pub fn key(&mut self, key: Key) {
        if self.step.is_done() {
            return;
        }
        if key == Key::Abort {
            self.abort();
            return;
        }
        if self.busy() {
            self.message = Some("busy: the device is still carrying out the last key".to_owned());
            return;
        }
        self.message = None;
        self.refused = false;
        match (self.step, key) {
            (Step::Posture, Key::Next) if self.posture_held => {
                self.enter_jog(self.servo, false);
            }
            (Step::Posture, Key::Next) => {
                self.message = Some(
                    "the device does not hold the posture: r tries again, q aborts".to_owned(),
                );
            }
            (Step::Posture, Key::Retry) => self.queue_posture(),
            (Step::Jog(s), Key::FineUp) => self.jog(s, true, FINE_JOG_US),
            (Step::Jog(s), Key::FineDown) => self.jog(s, false, FINE_JOG_US),
            (Step::Jog(s), Key::CoarseUp) => self.jog(s, true, COARSE_JOG_US),
            (Step::Jog(s), Key::CoarseDown) => self.jog(s, false, COARSE_JOG_US),
            (Step::Jog(s), Key::Next) => match neighbour(s, true) {
                Some(n) => self.enter_jog(n, false),
                None => self.enter_test(TestPose::ALL[0]),
            },
            (Step::Jog(s), Key::Back) => match neighbour(s, false) {
                Some(p) => self.enter_jog(p, false),
                None => {
                    self.step = Step::Posture;
                    self.queue_posture();
                }
            },
            (Step::Jog(_), Key::Skip) => self.enter_test(TestPose::ALL[0]),
            (Step::Jog(_), Key::Retry) => self.queue_posture(),
            (Step::Test(pose), Key::Next) if self.test_ran => {
                match TestPose::ALL.iter().position(|p| *p == pose) {
                    Some(i) if i + 1 < TestPose::ALL.len() => {
                        self.enter_test(TestPose::ALL[i + 1]);
                    }
                    _ => self.step = Step::Save,
                }
            }
            (Step::Test(_), Key::Next) => {
                self.message = Some(
                    "the test pose did not run: r runs it again, b goes back to jogging".to_owned(),
                );
            }
            (Step::Test(pose), Key::Retry) => self.enter_test(pose),
            (Step::Test(_), Key::Back) => self.enter_jog(self.servo, true),
            (Step::Save, Key::Save) => self.queue.push_back(Action::Save),
            (Step::Save, Key::Back) => self.enter_test(TestPose::ALL[0]),
            (step, key) => {
                self.message = Some(format!(
                    "`{}` does nothing on the {} step",
                    key.name(),
                    step.name()
                ));
            }
        }
    }

    /// The next action to carry out, if any; its answer goes to [`Guide::answer`].
    pub fn next_action(&mut self) -> Option<Action> {
        if self.in_flight.is_some() {
            return self.in_flight;
        }
        self.in_flight = self.queue.pop_front();
        self.in_flight
    }

    /// The device's answer to the action in flight. A refusal is kept as the message; it drops
    /// the actions queued after it, except while an abort restores the calibration (every
    /// servo is tried).
    pub fn answer(&mut self, result: Result<(), Refusal>) {
        let Some(action) = self.in_flight.take() else {
            return;
        };
        if result.is_ok() && self.step != Step::Aborted {
            self.refused = false;
        }
        match result {
            Ok(()) => match action {
                Action::SetCalibration { servo, calibration } => {
                    let jog = self.step != Step::Aborted;
                    self.calibration[servo.index()] = calibration;
                    if jog {
                        self.jogs += 1;
                        let start = self.start[servo.index()].center_us;
                        self.message = Some(format!(
                            "{}: center_us {} ({:+} us from the start)",
                            super::servo_name(servo),
                            calibration.center_us,
                            i32::from(calibration.center_us) - i32::from(start)
                        ));
                    }
                }
                Action::SetJoints { angles_rad } => {
                    self.posture_held = true;
                    if self.step == Step::Posture {
                        self.message = Some(format!(
                            "the device holds the calibration posture: abduction {} rad, hip {} \
                             rad, knee {} rad",
                            angles_rad[0], angles_rad[1], angles_rad[2]
                        ));
                    }
                }
                Action::Test(pose) => {
                    if self.step == Step::Test(pose) {
                        self.test_ran = true;
                    }
                }
                Action::Save => {
                    self.step = Step::Saved;
                    self.message = Some("saved: the device keeps this calibration".to_owned());
                }
                Action::OutputsOn => {}
            },
            Err(refusal) => {
                self.refusals += 1;
                self.refused = true;
                if self.step == Step::Aborted {
                    if let Action::SetCalibration { servo, .. } = action {
                        self.not_restored.push(servo);
                    }
                    self.message = Some(format!(
                        "aborted, but not every servo could be restored: {refusal}; nothing saved \
                         (the device's stored calibration comes back at its next power-on)"
                    ));
                    return;
                }
                self.queue.clear();
                if matches!(action, Action::SetJoints { .. } | Action::OutputsOn) {
                    self.posture_held = false;
                }
                self.message = Some(refusal.to_string());
            }
        }
    }

    /// The prompt of the current step.
    fn prompt(&self) -> String {
        match self.step {
            Step::Posture if self.posture_held => {
                "Calibration posture: every abduction at 0, every femur 45° from vertical (knee \
                 behind the hip), every knee bent at a right angle. n: jog the servos one by one"
                    .to_owned()
            }
            Step::Posture => "Moving to the calibration posture".to_owned(),
            Step::Jog(s) => format!(
                "Servo {}/12 {}: jog its centre pulse until the limb sits on its mark (+ turns the \
                 joint towards positive angles)",
                s.index() + 1,
                super::servo_name(s)
            ),
            Step::Test(pose) => match pose {
                TestPose::Rest => "Test pose: rest (the rest pose, held). n if it looks right",
                TestPose::Stand => "Test pose: stand (the stance). n if it looks right",
                TestPose::StepInPlace => {
                    "Test pose: a step in place (a trot at velocity zero, then stopped). n if \
                     it looks right"
                }
            }
            .to_owned(),
            Step::Save => "Save the calibration to the device's EEPROM, or abort".to_owned(),
            Step::Saved => "Saved".to_owned(),
            Step::Aborted => "Aborted: nothing saved".to_owned(),
        }
    }

    /// The keys of the current step.
    fn keys(&self) -> Vec<KeyHelp> {
        let k = |key: Key, does: &'static str| KeyHelp {
            key: key.name(),
            does,
        };
        let mut keys = match self.step {
            Step::Posture => vec![
                k(Key::Next, "posture reached: jog the servos"),
                k(Key::Retry, "move to the posture again"),
            ],
            Step::Jog(_) => vec![
                k(Key::FineUp, "+2 us (towards positive angles)"),
                k(Key::FineDown, "-2 us"),
                k(Key::CoarseUp, "+20 us"),
                k(Key::CoarseDown, "-20 us"),
                k(Key::Next, "next servo"),
                k(Key::Back, "previous servo"),
                k(Key::Skip, "skip to the test poses"),
                k(Key::Retry, "posture again"),
            ],
            Step::Test(_) => vec![
                k(Key::Next, "looks right: next"),
                k(Key::Retry, "run it again"),
                k(Key::Back, "back to jogging"),
            ],
            Step::Save => vec![
                k(Key::Save, "save to the EEPROM"),
                k(Key::Back, "test poses again"),
            ],
            Step::Saved | Step::Aborted => Vec::new(),
        };
        if !self.step.is_done() {
            keys.push(k(
                Key::Abort,
                "abort (restore the calibration, save nothing)",
            ));
        }
        keys
    }

    /// What a front end shows.
    pub fn view(&self) -> View {
        let servo = match self.step {
            Step::Jog(s) => Some(s),
            _ => None,
        };
        View {
            step: self.step.name(),
            prompt: self.prompt(),
            servo: servo.map(super::servo_name),
            servo_index: servo.and_then(|s| u8::try_from(s.index()).ok()),
            center_us: servo.map(|s| self.calibration[s.index()].center_us),
            start_center_us: servo.map(|s| self.start[s.index()].center_us),
            test: match self.step {
                Step::Test(p) => Some(p.name()),
                _ => None,
            },
            posture_rad: self.posture_rad,
            changed: ServoId::ALL
                .into_iter()
                .filter(|s| self.calibration[s.index()] != self.start[s.index()])
                .map(super::servo_name)
                .collect(),
            keys: self.keys(),
            message: self.message.clone(),
            refused: self.refused,
        }
    }
}

#[cfg(test)]
mod tests;
