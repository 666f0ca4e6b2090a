//! The statically stable yaw turn (`laws::StableTurn`): reachable, its static stability
//! margin positive throughout with a stated minimum, turning by its yaw per cycle, stance feet
//! fixed; and seed 001's crossed-pair yaw turn, by the same measure, without support.

use kin_core::motion::laws::{
    StableTurn, StableTurnParams, YawTurn, YawTurnParams, STABLE_TURN_ORDER,
};
use kin_core::motion::{Contact, Error, Expected, Motion, Param};
use kin_core::preflight::{self, Sweep};
use kin_core::stability::MassModel;
use kin_core::{DefaultMath, Robot};

const SPEED: [f32; 3] = [preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S; 3];
/// The least static stability margin the turn keeps with its defaults on both presets, m
/// (measured: 0.055 m on seed 000's robot, 0.078 m on seed 001's).
const STABLE_TURN_MIN_MARGIN_M: f32 = 0.050;
/// Largest movement of a foot in stance between two samples, m.
const STANCE_DRIFT_M: f32 = 1e-5;
/// The stance heights of the device's presets (quad-device's configuration), m.
const PRESETS: [(&str, f32); 2] = [("shahriar2023", 0.40), ("fernando2025", 0.9294)];

fn turn(name: &str, h: f32) -> (StableTurn, MassModel) {
    let robot = Robot::preset(name).unwrap();
    let t = StableTurn::new(StableTurnParams::new(robot, h)).unwrap();
    (t, MassModel::preset(name).unwrap())
}

#[test]
fn the_stable_turn_keeps_its_centre_of_mass_inside_the_support_polygon_on_both_presets() {
    for (name, h) in PRESETS {
        let (t, mass) = turn(name, h);
        let cycle = t.period_s().unwrap();
        let sweep = Sweep::new(0.0, 3.0 * cycle, 200.0).unwrap();
        let r = preflight::check_with_mass(&t, &sweep, SPEED, &mass).unwrap();
        assert!(r.ok(), "{name}: {:?}", r.first_failure);
        let m = r.static_margin_m.unwrap();
        println!(
            "{name}: minimum static margin {:.4} m at {:.2} s",
            m.value, m.t_s
        );
        assert!(m.value >= STABLE_TURN_MIN_MARGIN_M, "{name}: {m:?}");
    }
}

#[test]
fn seed_001s_crossed_pair_turn_has_no_support_polygon() {
    for (name, h) in PRESETS {
        let robot = Robot::preset(name).unwrap();
        let base = YawTurnParams::seed001();
        let p = YawTurnParams {
            robot,
            stance_feet: robot.stance_feet(h),
            lift_height_m: base.lift_height_m * h / 0.9294,
            ..base
        };
        let t = YawTurn::new(p).unwrap();
        let sweep = Sweep::new(0.0, p.step_period_s, 100.0).unwrap();
        let mass = MassModel::preset(name).unwrap();
        let r = preflight::check_with_mass(&t, &sweep, SPEED, &mass).unwrap();
        let m = r.static_margin_m.unwrap();
        println!(
            "{name}: crossed-pair yaw turn, minimum static margin {:.4} m at {:.2} s",
            m.value, m.t_s
        );
        // Two feet down: a line, at best.
        assert!(m.value <= 0.0, "{name}: {m:?}");
    }
}

#[test]
fn the_stable_turn_turns_by_its_yaw_per_cycle_with_its_stance_feet_fixed() {
    for (name, h) in PRESETS {
        let (t, _) = turn(name, h);
        let p = t.params();
        let cycle = p.cycle_s;
        for k in 1..=3u8 {
            let f = t.frame::<DefaultMath>(f32::from(k) * cycle).unwrap();
            let want = kin_core::math::wrap_pi(f32::from(k) * p.yaw_per_cycle_rad);
            assert!((f.pose.yaw_rad - want).abs() < 1e-5, "{name}: {f:?}");
        }
        let dt = 0.005;
        let mut prev = t.frame::<DefaultMath>(0.0).unwrap();
        let mut swings = [0u32; 4];
        for i in 1..=(3.0 * cycle / dt) as u32 {
            let f = t.frame::<DefaultMath>(i as f32 * dt).unwrap();
            let lifted = f.contact.iter().filter(|c| **c == Contact::Swing).count();
            assert!(lifted <= 1, "{name}: one leg at a time");
            for (leg, swung) in swings.iter_mut().enumerate() {
                if f.contact[leg] == Contact::Swing {
                    *swung += 1;
                } else if prev.contact[leg] == Contact::Stance {
                    let d = (f.feet_in_world[leg] - prev.feet_in_world[leg]).norm();
                    assert!(d < STANCE_DRIFT_M, "{name}: leg {leg} drifts {d} m");
                }
            }
            prev = f;
        }
        assert!(swings.iter().all(|&n| n > 0), "{swings:?}");
        assert_eq!(STABLE_TURN_ORDER.len(), 4);
    }
}

#[test]
fn bad_stable_turn_parameters_are_refused_by_name() {
    let robot = Robot::shahriar2023();
    let good = StableTurnParams::new(robot, 0.4);
    let cases = [
        (
            StableTurnParams {
                yaw_per_cycle_rad: 2.0,
                ..good
            },
            Error::OutOfRange {
                parameter: Param::YawPerCycleRad,
                expected: Expected::QuarterTurnPerCycle,
            },
        ),
        (
            StableTurnParams {
                shift_fraction: 0.0,
                ..good
            },
            Error::OutOfRange {
                parameter: Param::ShiftFraction,
                expected: Expected::UnitIntervalOpenBelow,
            },
        ),
        (
            StableTurnParams {
                cycle_s: -1.0,
                ..good
            },
            Error::NotPositive(Param::CycleS),
        ),
        (
            StableTurnParams {
                lift_height_m: 0.5,
                ..good
            },
            Error::OutOfRange {
                parameter: Param::LiftHeightM,
                expected: Expected::BelowStanceHeight,
            },
        ),
        (
            StableTurnParams {
                yaw_per_cycle_rad: f32::NAN,
                ..good
            },
            Error::NonFinite(Param::YawPerCycleRad),
        ),
    ];
    for (p, want) in cases {
        assert_eq!(StableTurn::new(p).unwrap_err(), want);
    }
    // At 0.55 m of its 0.557 m reach, seed 000's robot cannot shift its body.
    assert!(matches!(
        StableTurn::new(StableTurnParams::new(robot, 0.55)),
        Err(Error::BeyondReach {
            parameter: Param::ShiftFraction,
            ..
        })
    ));
}
