//! The stateful stepper: it follows the closed-form gait under a constant command, keeps its
//! stance feet still in the world, stops at the neutral stance, keeps the feet in the stride disc
//! when the command changes, and refuses bad parameters and commands by name.

use kin_core::motion::gait::{Gait, Pattern, Velocity};
use kin_core::motion::walker::{Walker, WalkerParams};
use kin_core::motion::{Contact, Error};
use kin_core::{DefaultMath, LegId, Robot, Vec3};

/// One servo frame, s.
const DT_S: f32 = 0.02;
/// Largest allowed distance between the walker's and the closed form's feet, m (the stance is
/// integrated in f32 step by step).
const CLOSED_FORM_TOL_M: f32 = 2e-5;

fn robot() -> Robot {
    Robot::shahriar2023()
}

fn params(pattern: Pattern) -> WalkerParams {
    WalkerParams::new(pattern, 0.40)
}

fn horizontal(v: Vec3) -> f32 {
    (v.x * v.x + v.y * v.y).sqrt()
}

#[test]
fn a_constant_command_follows_the_closed_form_gait_from_the_second_stride() {
    for pattern in [Pattern::Trot, Pattern::Walk] {
        for v in [
            Velocity {
                forward_m_s: 0.15,
                lateral_m_s: 0.0,
                yaw_rad_s: 0.0,
            },
            Velocity {
                forward_m_s: 0.08,
                lateral_m_s: -0.04,
                yaw_rad_s: 0.3,
            },
        ] {
            let p = params(pattern);
            let mut w = Walker::new(&robot(), p).unwrap();
            w.set_velocity::<DefaultMath>(v).unwrap();
            let gait = Gait::new(p.gait_params(robot(), v)).unwrap();
            let frames = (3.0 * p.cycle_s / DT_S).round() as u32;
            let mut worst = 0.0f32;
            for k in 1..=frames {
                w.step::<DefaultMath>(DT_S).unwrap();
                let t = k as f32 * DT_S;
                if t < 2.0 * p.cycle_s {
                    continue;
                }
                for leg in LegId::ALL {
                    let (want, contact) =
                        gait.foot_in_body::<DefaultMath>(leg, gait.leg_phase(leg, t));
                    worst = worst.max((w.foot(leg) - want).norm());
                    // The walker's phase is a running sum: compare the contact away from the
                    // swing/stance switches.
                    let q = gait.leg_phase(leg, t);
                    let d = p.duty_factor;
                    if (q - (1.0 - d)).abs() > 1e-3 && q > 1e-3 && q < 1.0 - 1e-3 {
                        assert_eq!(w.frame().contact[leg.index()], contact, "{pattern:?} {t}");
                    }
                }
            }
            assert!(worst <= CLOSED_FORM_TOL_M, "{pattern:?} {v:?}: {worst} m");
        }
    }
}

#[test]
fn stance_feet_stay_still_in_the_world_while_the_command_changes() {
    let p = params(Pattern::Trot);
    let mut w = Walker::new(&robot(), p).unwrap();
    // Body pose in the world, integrated from the commands: (x, y, yaw).
    let (mut bx, mut by, mut byaw) = (0.0f64, 0.0f64, 0.0f64);
    let mut anchored: [Option<(f64, f64)>; 4] = [None; 4];
    let mut worst = 0.0f64;
    for k in 0..400u32 {
        let t = k as f32 * DT_S;
        // Amplitudes that keep the stance feet within the default trot's stride disc (duty
        // 0.75 of a 1 s cycle): no step saturates, so every stance foot must stay put.
        let v = Velocity {
            forward_m_s: 0.08 * (0.7 * t).sin(),
            lateral_m_s: 0.02 * (0.3 * t).cos(),
            yaw_rad_s: 0.16 * (0.5 * t).sin(),
        };
        w.set_velocity::<DefaultMath>(v).unwrap();
        let before = w.frame().contact;
        w.step::<DefaultMath>(DT_S).unwrap();
        assert!(!w.saturated());
        // Exact body motion over the step for the constant twist v (as the walker assumes).
        let d = kin_core::motion::gait::displace::<DefaultMath>(&v, DT_S, Vec3::ZERO);
        let (s, c) = byaw.sin_cos();
        bx += c * d.x as f64 - s * d.y as f64;
        by += s * d.x as f64 + c * d.y as f64;
        byaw += (v.yaw_rad_s * DT_S) as f64;
        let (s, c) = byaw.sin_cos();
        for leg in LegId::ALL {
            let i = leg.index();
            let f = w.foot(leg);
            let world = (
                bx + c * f.x as f64 - s * f.y as f64,
                by + s * f.x as f64 + c * f.y as f64,
            );
            let stance = before[i] == Contact::Stance && w.frame().contact[i] == Contact::Stance;
            match (stance, anchored[i]) {
                (true, Some(a)) => {
                    worst = worst.max(((world.0 - a.0).powi(2) + (world.1 - a.1).powi(2)).sqrt())
                }
                (true, None) => anchored[i] = Some(world),
                (false, _) => anchored[i] = None,
            }
        }
    }
    assert!(worst < 1e-5, "stance drift {worst} m");
}

#[test]
fn stop_finishes_the_strides_and_parks_on_the_neutral_stance() {
    for pattern in [Pattern::Trot, Pattern::Walk] {
        let p = params(pattern);
        let mut w = Walker::new(&robot(), p).unwrap();
        w.set_velocity::<DefaultMath>(Velocity {
            forward_m_s: 0.1,
            lateral_m_s: 0.0,
            yaw_rad_s: 0.2,
        })
        .unwrap();
        for _ in 0..37 {
            w.step::<DefaultMath>(DT_S).unwrap();
        }
        w.stop();
        let max_frames = (2.0 * p.cycle_s / DT_S).ceil() as u32 + 1;
        let mut frames = 0;
        while !w.is_stopped() {
            w.step::<DefaultMath>(DT_S).unwrap();
            frames += 1;
            assert!(
                frames <= max_frames,
                "{pattern:?}: not stopped in two cycles"
            );
        }
        assert_eq!(w.frame().feet_in_world, w.neutral_feet());
        assert_eq!(w.frame().contact, [Contact::Stance; 4]);
        // Stopped is final: more steps change nothing.
        w.step::<DefaultMath>(DT_S).unwrap();
        assert_eq!(w.frame().feet_in_world, w.neutral_feet());
    }
}

#[test]
fn a_reversed_command_keeps_the_stance_feet_in_their_discs() {
    let p = params(Pattern::Trot);
    let mut w = Walker::new(&robot(), p).unwrap();
    let vmax = 0.95 * w.max_forward_m_s();
    let mut saturated = false;
    for k in 0..300u32 {
        let sign = if (k / 13) % 2 == 0 { 1.0 } else { -1.0 };
        w.set_velocity::<DefaultMath>(Velocity {
            forward_m_s: sign * vmax,
            ..Velocity::default()
        })
        .unwrap();
        w.step::<DefaultMath>(DT_S).unwrap();
        saturated |= w.saturated();
        for leg in LegId::ALL {
            let off = w.foot(leg) - w.neutral_feet()[leg.index()];
            // The Bézier overshoot of a swing is within the disc by the admission rule.
            assert!(
                horizontal(off) <= p.reach_radius_m * 1.0001,
                "{leg} at {k}: {off:?}"
            );
        }
    }
    assert!(saturated, "the reversals exercise the saturation");
}

#[test]
fn bad_parameters_and_commands_are_refused_by_name() {
    let good = params(Pattern::Trot);
    type Edit = fn(&mut WalkerParams);
    let cases: [(Edit, &str); 6] = [
        (|p| p.cycle_s = 0.0, "cycle_s"),
        (|p| p.cycle_s = f32::NAN, "cycle_s"),
        (|p| p.stance_height_m = -0.3, "stance_height_m"),
        (|p| p.step_height_m = f32::INFINITY, "step_height_m"),
        (|p| p.reach_radius_m = 0.0, "reach_radius_m"),
        (|p| p.reach_radius_m = 0.5, "reach_radius_m"),
    ];
    for (edit, name) in cases {
        let mut p = good;
        edit(&mut p);
        let e = Walker::new(&robot(), p).unwrap_err();
        let named = match e {
            Error::NonFinite(n) | Error::NotPositive(n) | Error::Negative(n) => n,
            Error::OutOfRange { parameter, .. } | Error::BeyondReach { parameter, .. } => parameter,
            other => panic!("{other:?}"),
        };
        assert_eq!(named.name(), name, "{e}");
    }
    let mut w = Walker::new(&robot(), good).unwrap();
    let vmax = w.max_forward_m_s();
    for (v, name) in [
        (
            Velocity {
                forward_m_s: f32::NAN,
                ..Velocity::default()
            },
            "forward_m_s",
        ),
        (
            Velocity {
                forward_m_s: 1.01 * vmax,
                ..Velocity::default()
            },
            "forward_m_s",
        ),
        (
            Velocity {
                lateral_m_s: -1.01 * vmax,
                ..Velocity::default()
            },
            "lateral_m_s",
        ),
        (
            Velocity {
                yaw_rad_s: 50.0,
                ..Velocity::default()
            },
            "yaw_rad_s",
        ),
        (
            Velocity {
                forward_m_s: 0.8 * vmax,
                lateral_m_s: 0.8 * vmax,
                yaw_rad_s: 0.0,
            },
            "velocity",
        ),
    ] {
        match w.set_velocity::<DefaultMath>(v) {
            Err(Error::NonFinite(n)) | Err(Error::OutOfRange { parameter: n, .. }) => {
                assert_eq!(n.name(), name, "{v:?}")
            }
            other => panic!("{v:?}: {other:?}"),
        }
        assert_eq!(
            w.velocity(),
            Velocity::default(),
            "a refused command is not taken"
        );
    }
    assert!(w.step::<DefaultMath>(0.0).is_err());
    assert!(w.step::<DefaultMath>(f32::NAN).is_err());
    assert!(w
        .set_velocity::<DefaultMath>(Velocity {
            forward_m_s: 0.9 * vmax,
            ..Velocity::default()
        })
        .is_ok());
}
