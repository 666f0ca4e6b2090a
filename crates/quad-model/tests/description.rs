//! Robot description out and in: URDF round trips, shapes refused by name, files written whole
//! or not at all.

use kin_core::{Joint, JointLimits, KneeBend, Robot};
use quad_model::urdf::{self, ReadError};
use quad_model::{mjcf, Error, Model, Physical};

fn presets() -> Vec<Model> {
    Robot::PRESETS
        .iter()
        .map(|n| Model::preset(n).expect("preset"))
        .collect()
}

#[test]
fn robot_urdf_robot_round_trip_is_exact() {
    let mut models = presets();
    // A custom robot: knee forward, full-turn limits elsewhere, odd lengths.
    let mut custom = Robot::shahriar2023().with_knee_bend(KneeBend::Forward);
    custom.leg.d_ax_m = 0.0321;
    custom.leg.tibia_m = 0.3137;
    custom.body_width_m = 0.1999;
    models.push(Model::new(custom, Physical::shahriar2023()).unwrap());
    let mut full = Robot::fernando2025();
    full.limits = JointLimits::FULL_TURN;
    full.limits.min_rad[Joint::Knee as usize] = -3.0;
    full.limits.max_rad[Joint::Knee as usize] = -0.01;
    models.push(Model::new(full, Physical::fernando2025()).unwrap());
    for model in models {
        let text = urdf::to_string(&model).unwrap();
        let back = urdf::from_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(&back, model.robot(), "{text}");
    }
}

fn preset_urdf() -> String {
    urdf::to_string(&Model::preset("shahriar2023").unwrap()).unwrap()
}

fn refused(text: &str) -> ReadError {
    urdf::from_str(text).expect_err("a URDF of another shape")
}

#[test]
fn a_hip_about_x_is_refused_naming_the_joint_and_axis() {
    let text = preset_urdf();
    // The FR hip joint's axis: the second `0 1 0` axis after `FR_hip`.
    let at = text.find("name=\"FR_hip\"").unwrap();
    let (head, tail) = text.split_at(at);
    let tail = tail.replacen("xyz=\"0 1 0\"", "xyz=\"1 0 0\"", 1);
    let err = refused(&format!("{head}{tail}"));
    assert!(
        matches!(&err, ReadError::Axis { joint, .. } if joint == "FR_hip"),
        "{err}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("FR_hip") && msg.contains("[1.0, 0.0, 0.0]"),
        "{msg}"
    );
}

#[test]
fn a_missing_leg_and_a_prismatic_knee_are_named() {
    let text = preset_urdf();
    // Re-parent the RR abduction joint under the FL tibia: three legs on the body.
    let at = text.find("name=\"RR_abduction\"").unwrap();
    let (head, tail) = text.split_at(at);
    let tail = tail.replacen("link=\"body\"", "link=\"FL_tibia\"", 1);
    let err = refused(&format!("{head}{tail}"));
    assert!(matches!(err, ReadError::LegCount { found: 3 }), "{err}");

    let text = text.replace(
        "name=\"RL_knee\" type=\"revolute\"",
        "name=\"RL_knee\" type=\"prismatic\"",
    );
    let err = refused(&text);
    assert!(
        matches!(&err, ReadError::JointType { joint, .. } if joint == "RL_knee"),
        "{err}"
    );
}

#[test]
fn legs_of_different_lengths_are_refused() {
    let model = Model::preset("fernando2025").unwrap();
    let mut u = urdf::to_urdf(&model);
    let knee = u.joints.iter_mut().find(|j| j.name == "RL_knee").unwrap();
    knee.origin.xyz.0[2] = -0.5;
    let err = urdf::from_urdf(&u).expect_err("a longer femur on RL");
    assert!(
        matches!(
            err,
            ReadError::LegsDiffer {
                what: "femur_m",
                leg: kin_core::LegId::RL
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("femur_m"), "{err}");
}

#[test]
fn garbage_is_a_parse_error() {
    assert!(matches!(refused("<robot"), ReadError::Parse(_)));
}

#[test]
fn no_partial_file_on_error_and_whole_files_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("robot.xml");
    let model = Model::preset("shahriar2023").unwrap();
    mjcf::write(&model, &path).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        mjcf::to_string(&model)
    );
    let urdf_path = dir.path().join("robot.urdf");
    urdf::write(&model, &urdf_path).unwrap();
    assert_eq!(urdf::read_file(&urdf_path).unwrap(), *model.robot());

    // A model that fails validation never reaches the writer: nothing is created.
    let mut p = Physical::shahriar2023();
    p.tibia_mass_kg = 0.0;
    let err = Model::new(Robot::shahriar2023(), p).unwrap_err();
    assert!(matches!(
        err,
        Error::NonPositive {
            field: "tibia_mass_kg"
        }
    ));

    // A write into a missing directory fails naming the path and leaves nothing.
    let missing = dir.path().join("no/such/dir/robot.xml");
    let err = mjcf::write(&model, &missing).unwrap_err();
    assert!(err.to_string().contains("no/such/dir"), "{err}");
    assert!(!missing.exists());
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "only the two complete files: {names:?}");
}
