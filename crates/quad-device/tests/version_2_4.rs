//! What protocol 2.4 appended, through the device on the in-memory fakes: the robot sent
//! (`SetRobot`), read (`GetRobot`) and stored (`SaveRobot`), adopted at power-on, its hash in
//! the hello (to a host of minor 4 only), and the refusals: a robot the device cannot hold
//! (naming the field, nothing changed) and a robot change with the outputs on.

mod common;

use common::*;
use kin_core::body::{self, BodyConfig, Pose};
use kin_core::{
    Joint, JointLimits, KneeBend, LegGeometry, LegId, ReachPolicy, Robot, RotationOrder,
};
use quad_device::store::{RobotImage, RobotStore, USED_LEN};
use quad_device::{Config, Device};
use quad_protocol::{
    DeviceInfo, DeviceToHost, NackReason, Request, RobotDescription, RobotField, RobotPreset,
    PROTOCOL_VERSION,
};

/// A small robot whose lengths are unlike both presets'.
fn custom() -> RobotDescription {
    RobotDescription {
        name: RobotDescription::name_bytes("bench-pup").unwrap(),
        robot: Robot {
            leg: LegGeometry {
                d_lat_m: 0.03,
                d_ax_m: 0.02,
                femur_m: 0.12,
                tibia_m: 0.14,
            },
            body_length_m: 0.36,
            body_width_m: 0.16,
            limits: JointLimits {
                min_rad: [-0.7, -1.8, -2.6],
                max_rad: [0.7, 1.8, -0.1],
            },
            knee_bend: KneeBend::Backward,
        },
        stance_height_m: 0.18,
        order: RotationOrder::Zyx,
        joint_speed_limit_rad_s: 4.0,
    }
}

fn hello_info(dev: &mut Dev, version: u16) -> DeviceInfo {
    match ask(dev, 0, Request::Hello { version }) {
        DeviceToHost::HelloAck { info, .. } => info,
        other => panic!("hello refused: {other:?}"),
    }
}

fn held_robot(dev: &mut Dev) -> RobotDescription {
    match ask(dev, 9, Request::GetRobot) {
        DeviceToHost::Robot { robot, .. } => robot,
        other => panic!("not a robot: {other:?}"),
    }
}

/// Powers the device on again from the storage of `dev`.
fn power_cycle(dev: Dev, config: Config) -> Dev {
    let (outputs, clock, storage) = dev.into_parts();
    Device::new(config, outputs, clock, storage).unwrap()
}

#[test]
fn the_hash_is_in_the_hello_of_a_two_four_host_only() {
    let mut dev = device(Config::shahriar2023());
    let old = hello_info(&mut dev, 0x0203);
    assert_eq!(old.robot_hash, None);
    assert_eq!(old.robot, RobotPreset::Shahriar2023);
    let new = hello_info(&mut dev, PROTOCOL_VERSION);
    let preset = Config::shahriar2023().description();
    assert_eq!(new.robot_hash, Some(preset.hash()));
    assert_eq!(preset.name_str(), Some("shahriar2023"));
    assert_eq!(held_robot(&mut dev), preset);
    // The same bytes as 2.3 before the hash.
    assert_eq!(
        DeviceInfo {
            robot_hash: None,
            ..new
        },
        old
    );
}

#[test]
fn a_robot_sent_is_held_at_its_stance_and_reported_as_custom() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    let robot = custom();
    assert_eq!(
        ask(&mut dev, 1, Request::SetRobot(robot)),
        DeviceToHost::Robot { seq: 1, robot }
    );
    assert_eq!(held_robot(&mut dev), robot);
    let info = hello_info(&mut dev, PROTOCOL_VERSION);
    assert_eq!(info.robot, RobotPreset::Custom);
    assert_eq!(info.robot_hash, Some(robot.hash()));
    assert_eq!(info.pose_config.stance_height_m, robot.stance_height_m);
    assert_eq!(info.pose_config.order, robot.order);
    assert_eq!(dev.config().robot, robot.robot);
    assert_eq!(
        dev.limiter(),
        &quad_device::engine::Limiter::new(robot.joint_speed_limit_rad_s).unwrap()
    );
    // The stance of the new robot is held (the default calibration centred on it).
    let stance = body::Solver::new(&robot.robot)
        .inverse_at_stance(
            &Pose::default(),
            &BodyConfig::about_centre(robot.order),
            robot.stance_height_m,
            ReachPolicy::Reject,
        )
        .unwrap();
    match ask(&mut dev, 2, Request::GetState) {
        DeviceToHost::Ack { readback, .. } => {
            assert_eq!(readback.angles_rad, stance.angles_rad)
        }
        other => panic!("{other:?}"),
    }
    // Setting a preset's description back makes it that preset again.
    let preset = Config::fernando2025().description();
    ask(&mut dev, 3, Request::SetRobot(preset));
    assert_eq!(
        hello_info(&mut dev, PROTOCOL_VERSION).robot,
        RobotPreset::Fernando2025
    );
}

#[test]
fn a_robot_the_device_cannot_hold_is_refused_naming_the_field_and_nothing_changes() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    let before = held_robot(&mut dev);
    let mut cases: Vec<(RobotDescription, RobotField)> = Vec::new();
    let mut r = custom();
    r.name = [0; 16];
    cases.push((r, RobotField::Name));
    let mut r = custom();
    r.robot.leg.femur_m = 3.0;
    cases.push((r, RobotField::FemurM));
    let mut r = custom();
    r.robot.leg.tibia_m = f32::NAN;
    cases.push((r, RobotField::TibiaM));
    let mut r = custom();
    r.robot.body_width_m = -0.1;
    cases.push((r, RobotField::BodyWidthM));
    let mut r = custom();
    r.robot.limits.min_rad[1] = 2.0;
    cases.push((r, RobotField::Limit(Joint::Hip)));
    let mut r = custom();
    r.robot.limits.max_rad[0] = 4.0;
    cases.push((r, RobotField::Limit(Joint::Abduction)));
    let mut r = custom();
    r.joint_speed_limit_rad_s = 0.0;
    cases.push((r, RobotField::JointSpeedLimitRadS));
    let mut r = custom();
    r.stance_height_m = 5.0;
    cases.push((r, RobotField::StanceHeightM));
    // The rest pose's hip (half the folded knee) beyond a narrow hip range.
    let mut r = custom();
    r.robot.limits.max_rad[1] = 0.5;
    cases.push((r, RobotField::RestPose(Joint::Hip)));
    // A stance lower than the folded legs reach, and one beyond the stretched legs.
    let mut r = custom();
    r.stance_height_m = 0.3;
    cases.push((r, RobotField::Stance(LegId::FL)));
    for (seq, (robot, field)) in (10..).zip(cases) {
        assert_eq!(
            ask(&mut dev, seq, Request::SetRobot(robot)),
            DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::BadRobot(field)
            },
            "{field}"
        );
        // The host's check refuses it alike, before sending.
        assert_eq!(
            quad_protocol::check_robot::<kin_core::DefaultMath>(&robot).err(),
            Some(NackReason::BadRobot(field))
        );
    }
    assert_eq!(held_robot(&mut dev), before);
    assert_eq!(dev.config().robot, Robot::shahriar2023());
    // Nothing stored either.
    let (_, _, mut mem) = dev.into_parts();
    let mut image = RobotImage([0; RobotDescription::WIRE_LEN]);
    assert!(!RobotStore::robot(0).load(&mut mem, &mut image));
}

#[test]
fn a_robot_change_is_refused_while_the_outputs_are_on() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    ask(&mut dev, 1, Request::SetOutputs { enabled: true });
    assert_eq!(
        ask(&mut dev, 2, Request::SetRobot(custom())),
        DeviceToHost::Nack {
            seq: Some(2),
            reason: NackReason::OutputsEnabled
        }
    );
    assert_eq!(dev.config().robot, Robot::shahriar2023());
    ask(&mut dev, 3, Request::SetOutputs { enabled: false });
    assert!(matches!(
        ask(&mut dev, 4, Request::SetRobot(custom())),
        DeviceToHost::Robot { .. }
    ));
}

#[test]
fn a_saved_robot_is_adopted_at_power_on_and_an_unsaved_one_is_not() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    ask(&mut dev, 1, Request::SetRobot(custom()));
    // Not saved: the compiled robot after a reset.
    let mut dev = power_cycle(dev, Config::shahriar2023());
    assert_eq!(held_robot(&mut dev), Config::shahriar2023().description());
    hello(&mut dev);
    ask(&mut dev, 1, Request::SetRobot(custom()));
    assert!(matches!(
        ask(&mut dev, 2, Request::SaveRobot),
        DeviceToHost::Ack { .. }
    ));
    let mut dev = power_cycle(dev, Config::shahriar2023());
    assert_eq!(held_robot(&mut dev), custom());
    assert_eq!(dev.config().robot, custom().robot);
    let info = hello_info(&mut dev, PROTOCOL_VERSION);
    assert_eq!(info.robot, RobotPreset::Custom);
    assert_eq!(info.robot_hash, Some(custom().hash()));
    // The calibration's banks are untouched by the robot's.
    assert!(usize::from(USED_LEN) <= dev.storage().bytes.len());
    assert!(dev
        .readback()
        .flags
        .contains(quad_protocol::Flags::CALIBRATION_DEFAULT));
}

#[test]
fn a_save_cut_at_every_byte_keeps_the_previous_robot() {
    let second = {
        let mut r = custom();
        r.name = RobotDescription::name_bytes("bench-pup-2").unwrap();
        r.robot.leg.femur_m = 0.13;
        r
    };
    // With no robot stored before (the compiled preset back), and with one (that one back).
    for prior in [None, Some(custom())] {
        let mut dev = device(Config::shahriar2023());
        hello(&mut dev);
        if let Some(p) = prior {
            ask(&mut dev, 1, Request::SetRobot(p));
            ask(&mut dev, 2, Request::SaveRobot);
        }
        ask(&mut dev, 3, Request::SetRobot(second));
        let (_, _, mem) = dev.into_parts();
        let expected = prior.unwrap_or(Config::shahriar2023().description());
        let mut cut = 0;
        loop {
            let mut m = mem.clone();
            m.write_budget = Some(cut);
            let mut dev = Device::new(
                Config::shahriar2023(),
                quad_device::sim::Outputs::logging(),
                quad_device::sim::VirtualClock::default(),
                m,
            )
            .unwrap();
            hello(&mut dev);
            // The device adopts what is stored at boot: bring `second` back in RAM first.
            ask(&mut dev, 3, Request::SetRobot(second));
            let answer = ask(&mut dev, 4, Request::SaveRobot);
            let (_, _, mut m) = dev.into_parts();
            m.write_budget = None;
            let mut back = Device::new(
                Config::shahriar2023(),
                quad_device::sim::Outputs::logging(),
                quad_device::sim::VirtualClock::default(),
                m,
            )
            .unwrap();
            match answer {
                DeviceToHost::Ack { .. } => {
                    assert_eq!(held_robot(&mut back), second, "cut {cut}");
                    break;
                }
                DeviceToHost::Nack {
                    reason: NackReason::Storage,
                    ..
                } => assert_eq!(held_robot(&mut back), expected, "cut {cut}"),
                other => panic!("{other:?}"),
            }
            cut += 1;
        }
        // The whole bank (magic, version, generation, the robot, the CRC) and the magic
        // cleared first.
        assert_eq!(cut, quad_device::store::ROBOT_BANK_LEN + 2);
    }
}
