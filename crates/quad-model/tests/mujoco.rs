//! The MJCF in MuJoCo itself (the twin's Python environment; `scripts/install-deps.sh` creates
//! it, and its absence fails these tests): every preset loads, and MuJoCo's foot sites agree
//! with kin-core's forward kinematics at random joint angles.

use kin_core::{leg, JointAngles, LegId, Robot};
use quad_model::{mjcf, venv, Model};
use seeded_rng::SplitMix64;
use std::io::Write as _;
use std::process::Stdio;

/// Largest distance between a MuJoCo foot site and kin-core's foot, m.
const FK_TOLERANCE_M: f64 = 1e-6;
/// Random joint-angle samples per preset.
const SAMPLES: usize = 200;

fn run_check(module: &str, request: &serde_json::Value) -> serde_json::Value {
    let mut cmd =
        venv::python_module(&venv::workspace_root(), module).unwrap_or_else(|e| panic!("{e}"));
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the twin's Python");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(request.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{module} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON answer")
}

#[test]
fn every_preset_loads_and_its_feet_agree_with_kin_core() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = SplitMix64::new(0x7517);
    for name in Robot::PRESETS {
        let model = Model::preset(name).unwrap();
        let robot = *model.robot();
        let path = dir.path().join(format!("{name}.xml"));
        mjcf::write(&model, &path).unwrap();
        let angles: Vec<[f32; 12]> = (0..SAMPLES)
            .map(|_| {
                core::array::from_fn(|i| {
                    let j = i % 3;
                    rng.range(
                        f64::from(robot.limits.min_rad[j]),
                        f64::from(robot.limits.max_rad[j]),
                    ) as f32
                })
            })
            .collect();
        let request = serde_json::json!({
            "model": path,
            "angles_rad": angles.iter().map(|a| a.map(f64::from).to_vec()).collect::<Vec<_>>(),
        });
        let answer = run_check("check_fk", &request);
        assert_eq!(answer["nq"], 19, "{name}: free joint (7) + 12 hinges");
        assert_eq!(answer["nu"], 12, "{name}: one actuator per joint");
        assert_eq!(answer["servo_name"], model.physical().servo.name);
        let mass = answer["total_mass_kg"].as_f64().unwrap();
        assert!((mass - f64::from(model.physical().total_mass_kg())).abs() < 1e-6);
        let feet = answer["feet_m"].as_array().unwrap();
        assert_eq!(feet.len(), SAMPLES);
        let mut worst = 0.0f64;
        for (q, sample) in angles.iter().zip(feet) {
            for leg in LegId::ALL {
                let i = leg.index();
                let angles = JointAngles::new(q[3 * i], q[3 * i + 1], q[3 * i + 2]);
                let expected = robot.hip_in_body(leg) + leg::forward(&robot.leg, leg, angles);
                let got = &sample[i];
                let d: f64 = expected
                    .to_array()
                    .iter()
                    .enumerate()
                    .map(|(k, e)| (got[k].as_f64().unwrap() - f64::from(*e)).powi(2))
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(d);
            }
        }
        assert!(
            worst <= FK_TOLERANCE_M,
            "{name}: worst foot distance {worst:e} m > {FK_TOLERANCE_M:e} m"
        );
        eprintln!(
            "{name}: worst MuJoCo vs kin-core foot distance {worst:.3e} m over {SAMPLES} samples"
        );
    }
}

/// The servo law in MuJoCo: a knee servo stepping its unloaded tibia tops out at its no-load
/// speed (the back-EMF term is the speed limit), never exceeds its stall torque from rest, and
/// settles within its deadband plus the friction it cannot overcome.
#[test]
fn a_servo_step_is_speed_limited_and_torque_limited() {
    let dir = tempfile::tempdir().unwrap();
    for servo in quad_model::ServoModel::PRESETS {
        let model = Model::new(
            Robot::shahriar2023(),
            quad_model::Physical::shahriar2023()
                .with_servo(servo)
                .unwrap(),
        )
        .unwrap();
        let path = dir.path().join(format!("{servo}.xml"));
        mjcf::write(&model, &path).unwrap();
        let request = serde_json::json!({
            "model": path, "joint": "FL_knee", "from_rad": -2.0, "to_rad": -0.3, "duration_s": 1.5,
        });
        let a = run_check("check_servo", &request);
        let get = |k: &str| a[k].as_f64().unwrap();
        let (speed, top) = (get("max_speed_rad_s"), get("no_load_speed_rad_s"));
        eprintln!("{servo}: knee step top speed {speed:.3} rad/s (no-load {top:.3}), {a}");
        assert!(
            speed <= top * 1.02 && speed >= 0.8 * top,
            "{servo}: top speed {speed} rad/s against the no-load {top} rad/s"
        );
        assert!(
            get("max_torque_nm") <= get("stall_torque_nm") * 1.001,
            "{servo}: {a}"
        );
        // Settled: inside the deadband, or where the gear friction holds the link (the duty
        // at the residual error drives less than the friction).
        let friction_error = f64::from(model.physical().servo.friction_loss_nm)
            / get("stall_torque_nm")
            * get("full_duty_error_rad");
        assert!(
            get("final_error_rad").abs() <= get("deadband_rad").max(friction_error) + 1e-4,
            "{servo}: {a}"
        );
    }
}
