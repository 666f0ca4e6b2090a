//! The step machine's tests, on a device that records the actions.

use super::*;

fn table() -> [Calibration; 12] {
    let c = Calibration {
        zero_rad: 0.0,
        reversed: false,
        us_per_rad: 636.62,
        center_us: 1500,
        min_us: 500,
        max_us: 2500,
    };
    let mut t = [c; 12];
    t[1].reversed = true;
    t
}

/// Answers every action with `Ok`, records them.
#[derive(Default)]
struct Recorder {
    actions: Vec<Action>,
    refuse: Option<fn(&Action) -> bool>,
}

impl Device for Recorder {
    type Error = std::convert::Infallible;
    fn act(&mut self, action: &Action) -> Result<Result<(), Refusal>, Self::Error> {
        self.actions.push(*action);
        if self.refuse.is_some_and(|f| f(action)) {
            return Ok(Err(Refusal {
                request: "SetCalibration",
                reason: NackReason::ServoRange {
                    leg: kin_core::LegId::FL,
                    joint: Joint::Abduction,
                    fault: quad_protocol::servo::Error::AboveMax,
                },
                sent: true,
            }));
        }
        Ok(Ok(()))
    }
}

fn press(g: &mut Guide, d: &mut Recorder, keys: &[Key]) {
    settle(g, d).unwrap();
    for k in keys {
        g.key(*k);
        settle(g, d).unwrap();
    }
}

#[test]
fn the_posture_is_the_robots_and_within_its_limits() {
    let p = posture_rad(&Robot::shahriar2023()).unwrap();
    assert_eq!(&p[..3], &[0.0, POSTURE_HIP_RAD, POSTURE_KNEE_RAD]);
    assert_eq!(&p[9..], &p[..3]);
    let forward = Robot::fernando2025().with_knee_bend(KneeBend::Forward);
    let p = posture_rad(&forward).unwrap();
    assert_eq!(&p[..3], &[0.0, -POSTURE_HIP_RAD, -POSTURE_KNEE_RAD]);
    let mut narrow = Robot::shahriar2023();
    narrow.limits.max_rad[1] = 0.5;
    assert!(matches!(
        posture_rad(&narrow),
        Err(PostureError::JointLimit {
            joint: Joint::Hip,
            ..
        })
    ));
}

#[test]
fn a_jog_sets_the_centre_pulse_in_ram_and_commands_the_posture_again() {
    let mut g = Guide::new(&Robot::shahriar2023(), table()).unwrap();
    let mut d = Recorder::default();
    settle(&mut g, &mut d).unwrap();
    let posture = Action::SetJoints {
        angles_rad: *g.posture(),
    };
    assert_eq!(d.actions, [Action::OutputsOn, posture]);
    press(&mut g, &mut d, &[Key::Next, Key::FineUp, Key::CoarseUp]);
    assert_eq!(g.calibration()[0].center_us, 1522);
    assert_eq!(d.actions.len(), 6);
    assert_eq!(d.actions[5], posture);
    // FL hip is reversed: `+` is a shorter pulse.
    press(&mut g, &mut d, &[Key::Next, Key::FineUp]);
    assert_eq!(g.step(), Step::Jog(ServoId::ALL[1]));
    assert_eq!(g.calibration()[1].center_us, 1498);
    assert_eq!(g.view().changed, ["FL_abduction", "FL_hip"]);
    assert_eq!(g.jogs(), 3);
}

#[test]
fn a_refused_jog_changes_nothing_and_shows_the_reason() {
    let mut g = Guide::new(&Robot::shahriar2023(), table()).unwrap();
    let mut d = Recorder {
        refuse: Some(|a| matches!(a, Action::SetCalibration { .. })),
        ..Recorder::default()
    };
    press(&mut g, &mut d, &[Key::Next, Key::CoarseDown]);
    assert_eq!(g.calibration()[0].center_us, 1500);
    assert_eq!(g.refusals(), 1);
    let m = g.view().message.unwrap();
    assert!(
        m.contains("refused SetCalibration") && m.contains("travel"),
        "{m}"
    );
    // The posture queued after the refused calibration was dropped.
    assert_eq!(d.actions.len(), 3);
    assert!(matches!(d.actions[2], Action::SetCalibration { .. }));
}

#[test]
fn the_tests_run_in_order_and_save_persists() {
    let mut g = Guide::new(&Robot::fernando2025(), table()).unwrap();
    let mut d = Recorder::default();
    press(&mut g, &mut d, &[Key::Next, Key::FineUp, Key::Skip]);
    assert_eq!(g.step(), Step::Test(TestPose::Rest));
    press(
        &mut g,
        &mut d,
        &[Key::Next, Key::Next, Key::Retry, Key::Next],
    );
    assert_eq!(g.step(), Step::Save);
    let tests: Vec<_> = d
        .actions
        .iter()
        .filter_map(|a| match a {
            Action::Test(p) => Some(*p),
            _ => None,
        })
        .collect();
    assert_eq!(
        tests,
        [
            TestPose::Rest,
            TestPose::Stand,
            TestPose::StepInPlace,
            TestPose::StepInPlace
        ]
    );
    press(&mut g, &mut d, &[Key::Save]);
    assert_eq!(g.step(), Step::Saved);
    assert_eq!(d.actions.last(), Some(&Action::Save));
    // Nothing more after the end.
    press(&mut g, &mut d, &[Key::Abort]);
    assert_eq!(g.step(), Step::Saved);
}

#[test]
fn abort_restores_the_calibration_read_at_the_start() {
    let start = table();
    let mut g = Guide::new(&Robot::shahriar2023(), start).unwrap();
    let mut d = Recorder::default();
    press(
        &mut g,
        &mut d,
        &[
            Key::Next,
            Key::CoarseUp,
            Key::Next,
            Key::FineDown,
            Key::Abort,
        ],
    );
    assert_eq!(g.step(), Step::Aborted);
    assert_eq!(g.calibration(), &start);
    let restores: Vec<_> = d.actions.iter().rev().take(2).collect();
    assert!(restores
        .iter()
        .all(|a| matches!(a, Action::SetCalibration { calibration, servo } if *calibration == start[servo.index()])));
    assert!(g.not_restored().is_empty());
}

#[test]
fn back_from_the_tests_returns_to_the_posture_and_the_last_servo() {
    let mut g = Guide::new(&Robot::shahriar2023(), table()).unwrap();
    let mut d = Recorder::default();
    press(
        &mut g,
        &mut d,
        &[Key::Next, Key::Next, Key::Next, Key::Skip],
    );
    let before = d.actions.len();
    press(&mut g, &mut d, &[Key::Back]);
    assert_eq!(g.step(), Step::Jog(ServoId::ALL[2]));
    assert_eq!(d.actions[before], Action::OutputsOn);
    assert!(matches!(d.actions[before + 1], Action::SetJoints { .. }));
    // Back from the first servo: the posture step.
    press(&mut g, &mut d, &[Key::Back, Key::Back, Key::Back]);
    assert_eq!(g.step(), Step::Posture);
}

#[test]
fn keys_parse_by_name() {
    for k in Key::ALL {
        assert_eq!(Key::parse(k.name()), Some(k));
    }
    assert_eq!(Key::parse("enter"), Some(Key::Next));
    assert_eq!(Key::parse("x"), None);
    let k: Key = serde_json::from_str("\"]\"").unwrap();
    assert_eq!(k, Key::CoarseUp);
    assert_eq!(serde_json::to_string(&Key::FineDown).unwrap(), "\"-\"");
    assert!(serde_json::from_str::<Key>("\"x\"").is_err());
}
