//! Golden vectors from the independent f64 reference `scripts/gen_golden.py` (checked in under
//! `tests/data/`; this test does not run Python): foot targets → expected angles or status, and
//! angles → expected feet, for both papers' robots.

mod common;

use common::*;
use kin_core::{leg, Joint, JointAngles, KneeBend, LegId, ReachPolicy, Robot, Unreachable, Vec3};

/// Largest allowed difference between the crate's f32 IK angles and the f64 reference.
const GOLDEN_ANGLE_TOL_RAD: f64 = 2.0e-5;
/// Largest allowed difference between the crate's f32 FK and the f64 reference foot.
const GOLDEN_FOOT_TOL_M: f64 = 1.0e-6;
/// Minimum rows per robot and file.
const MIN_ROWS_PER_ROBOT: usize = 50;

const IK_CSV: &str = include_str!("data/golden_ik.csv");
const FK_CSV: &str = include_str!("data/golden_fk.csv");

fn robot(name: &str, bend: &str) -> Robot {
    let r = Robot::preset(name).unwrap_or_else(|| panic!("unknown robot {name}"));
    match bend {
        "backward" => r,
        "forward" => r.with_knee_bend(KneeBend::Forward),
        other => panic!("unknown knee bend {other}"),
    }
}

fn status_of(res: &Result<leg::LegSolution, kin_core::IkError>) -> String {
    match res {
        Ok(_) => "ok".into(),
        Err(e) => match e.kind {
            Unreachable::JointLimit(j) => format!("joint_limit:{}", j.name()),
            k => k.code().into(),
        },
    }
}

fn rows(csv: &str, header: &str) -> Vec<Vec<String>> {
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(header));
    lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

#[test]
fn golden_ik() {
    let rows = rows(
        IK_CSV,
        "robot,knee_bend,leg,x_m,y_m,z_m,status,abduction_rad,hip_rad,knee_rad",
    );
    let mut per_robot = std::collections::BTreeMap::<String, usize>::new();
    let mut kinds = std::collections::BTreeSet::new();
    for (i, r) in rows.iter().enumerate() {
        let line = i + 2;
        let robot = robot(&r[0], &r[1]);
        let leg_id = LegId::parse(&r[2]).expect("leg");
        let p: [f32; 3] = [3, 4, 5].map(|c| r[c].parse().expect("f32 coordinate"));
        let target = Vec3::from_array(p);
        let res = leg::Solver::new(&robot).inverse(leg_id, target, ReachPolicy::Reject);
        assert_eq!(status_of(&res), r[6], "line {line}: {res:?}");
        kinds.insert(r[6].clone());
        *per_robot.entry(r[0].clone()).or_default() += 1;
        if r[6] == "ok" {
            let want: [f64; 3] = [7, 8, 9].map(|c| r[c].parse().expect("f64 angle"));
            let got = q64(res.unwrap().angles);
            for j in 0..3 {
                assert!(
                    ang_diff(got[j], want[j]) <= GOLDEN_ANGLE_TOL_RAD,
                    "line {line}: {} {} vs {}",
                    Joint::ALL[j],
                    got[j],
                    want[j]
                );
            }
            let foot = fk64(&robot.leg, leg_id, got);
            assert!((foot - v64(target)).norm() <= FOOT_TOL_M, "line {line}");
        } else {
            assert!(r[7].is_empty() && r[8].is_empty() && r[9].is_empty());
        }
    }
    for (name, n) in &per_robot {
        assert!(*n >= MIN_ROWS_PER_ROBOT, "{name}: {n} rows");
    }
    assert_eq!(per_robot.len(), 2);
    // Every kind the generator can express appears.
    for k in [
        "ok",
        "too_far",
        "too_close",
        "inside_offset",
        "joint_limit:abduction",
        "joint_limit:hip",
        "joint_limit:knee",
    ] {
        assert!(kinds.contains(k), "no {k} row");
    }
}

#[test]
fn golden_fk() {
    let rows = rows(
        FK_CSV,
        "robot,leg,abduction_rad,hip_rad,knee_rad,x_m,y_m,z_m",
    );
    let mut per_robot = std::collections::BTreeMap::<String, usize>::new();
    for (i, r) in rows.iter().enumerate() {
        let line = i + 2;
        let robot = robot(&r[0], "backward");
        let leg_id = LegId::parse(&r[1]).expect("leg");
        let q: [f32; 3] = [2, 3, 4].map(|c| r[c].parse().expect("f32 angle"));
        let want: [f64; 3] = [5, 6, 7].map(|c| r[c].parse().expect("f64 coordinate"));
        let want = nalgebra::Vector3::from(want);
        let q = JointAngles::from_array(q);
        for (form, got) in [
            ("closed", leg::forward(&robot.leg, leg_id, q)),
            ("dh", leg::forward_dh(&robot.leg, leg_id, q)),
        ] {
            let err = (v64(got) - want).norm();
            assert!(err <= GOLDEN_FOOT_TOL_M, "line {line} ({form}): {err:e}");
        }
        // The oracle of the other tests agrees with the reference to f64 rounding.
        assert!((fk64(&robot.leg, leg_id, q64(q)) - want).norm() < 1e-12);
        *per_robot.entry(r[0].clone()).or_default() += 1;
    }
    assert_eq!(per_robot.len(), 2);
    for (name, n) in &per_robot {
        assert!(*n >= MIN_ROWS_PER_ROBOT, "{name}: {n} rows");
    }
}
