//! A robot of its own on the release firmware in simavr (protocol 2.4): a TOML robot whose
//! lengths are unlike both presets' (`examples/robots/bench-pup.toml`) is sent, saved, the
//! chip reset (a fresh chip booted from the EEPROM it left), and then
//! - the hello's hash is the host's hash of that robot, the robot reported `Custom`;
//! - it stands, sways and trots, and sits, with every readback and every PWM period on the
//!   twelve pins checked against the host's kin-core for that robot (the onboard tour's
//!   checks, `quad_host::ops::demo_motions`: the sway against the host's law at the reported
//!   time, stand-up, the trot and sit against the host's replay of the device's engine);
//! - a host that plans with another robot is refused, naming both robots and hashes;
//! - a robot the device cannot hold is refused by the host before sending and, sent anyway as
//!   raw bytes, by the device, naming the field, and nothing is stored;
//! - a save cut by a reset at every byte boots the old robot or the new one, never another.
//!
//! All times are simulated.

use integration_tests::wire;
use quad_host::client::{self, AngleCheck, Client, ClientConfig, AVR_ANGLE_TOLERANCE_RAD};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::ops::demo_motions;
use quad_host::ops::onboard::{self, Session};
use quad_host::robot_file;
use quad_protocol::{
    DeviceToHost, NackReason, Request, RobotDescription, RobotField, RobotPreset, PROTOCOL_VERSION,
};
use std::path::{Path, PathBuf};
use std::time::Duration;

fn robot_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/robots/bench-pup.toml")
}

fn custom() -> RobotDescription {
    robot_file::device_description(robot_file().to_str().expect("a UTF-8 path"))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn boot(eeprom: Option<Vec<u8>>) -> EmulatorLink {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let config = EmulatorConfig {
        eeprom,
        ..EmulatorConfig::new(115_200)
    };
    EmulatorLink::boot(&elf, config).unwrap_or_else(|e| panic!("{e}"))
}

/// Sends `robot` and saves it; returns the EEPROM the chip then holds.
fn send_and_save(robot: &RobotDescription) -> Vec<u8> {
    let mut client = Client::new(boot(None), ClientConfig::emulator());
    client.hello().unwrap_or_else(|e| panic!("{e}"));
    client.set_robot(robot).unwrap_or_else(|e| panic!("{e}"));
    client.save_robot().unwrap_or_else(|e| panic!("{e}"));
    client.link_mut().mcu_mut().eeprom()
}

#[test]
fn a_custom_robot_sent_and_saved_stands_sways_and_trots_checked_on_the_pins() {
    let robot = custom();
    let compiled = quad_device::Config::shahriar2023().description();
    // Lengths unlike both presets'.
    for preset in [
        kin_core::Robot::shahriar2023(),
        kin_core::Robot::fernando2025(),
    ] {
        assert_ne!(robot.robot.leg.femur_m, preset.leg.femur_m);
        assert_ne!(robot.robot.leg.tibia_m, preset.leg.tibia_m);
        assert_ne!(robot.robot.body_length_m, preset.body_length_m);
    }
    let eeprom = send_and_save(&robot);

    // The reset: a fresh chip from that EEPROM.
    let mut client = Client::new(boot(Some(eeprom)), ClientConfig::emulator());
    let info = client.hello().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(info.robot, RobotPreset::Custom);
    assert_eq!(info.robot_hash, Some(robot.hash()));
    assert_ne!(robot.hash(), compiled.hash());
    assert_eq!(info.pose_config.stance_height_m, robot.stance_height_m);

    // Planned with that robot: the tour's stand-up, roll sway, trot and sit.
    let mut session =
        Session::connect_robot(client, Some(&robot)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(session.robot(), Some(&robot));
    let legs = demo_motions::run_tour(
        &mut session,
        &robot.robot,
        AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
        |h| {
            demo_motions::tour(h)
                .into_iter()
                .filter(|(name, ..)| {
                    ["stand up", "roll sway", "trot", "sit"]
                        .iter()
                        .any(|p| name.starts_with(p))
                })
                .collect()
        },
        |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(legs.len(), 4);
    for leg in &legs {
        println!(
            "{}: {} answers, {} angles (max err {:.2e} rad), {} pin pulses, {} frames replayed",
            leg.motion,
            leg.answers,
            leg.angles_checked,
            leg.max_angle_err_rad,
            leg.pins_checked,
            leg.frames_checked
        );
        assert_eq!(leg.errors, 0, "{leg:?}");
        assert!(leg.angles_checked > 0, "{leg:?}");
    }
    // The sway's pins against the host's law; stand-up's, the trot's and sit's against the
    // replay.
    assert!(legs[1].pins_checked >= 12 * 100, "{:?}", legs[1]);
    for (i, least) in [(0, 10), (2, 100), (3, 10)] {
        assert!(legs[i].frames_checked >= least, "{:?}", legs[i]);
        assert!(legs[i].pins_checked >= 12 * least, "{:?}", legs[i]);
    }

    // A host planning with another robot is refused, with both names and hashes.
    let mut client = session_client(session);
    let info = client.hello().unwrap_or_else(|e| panic!("{e}"));
    let device = client.get_robot().unwrap_or_else(|e| panic!("{e}"));
    let err = onboard::check_same_robot(&device, info.robot_hash, Some(&compiled))
        .expect_err("another robot");
    let text = err.to_string();
    for part in [
        "bench-pup".to_owned(),
        "shahriar2023".to_owned(),
        format!("{:08x}", robot.hash()),
        format!("{:08x}", compiled.hash()),
        "quadctl robot send".to_owned(),
    ] {
        assert!(text.contains(&part), "{part} missing in: {text}");
    }
    assert!(matches!(err, client::Error::RobotMismatch { .. }));
    assert!(matches!(
        Session::connect_robot(client, Some(&compiled)),
        Err(onboard::Error::Client(client::Error::RobotMismatch { .. }))
    ));
}

/// The client back from a session (its link stays up).
fn session_client(session: Session<EmulatorLink>) -> Client<EmulatorLink> {
    session.into_client()
}

#[test]
fn a_robot_the_device_cannot_hold_is_refused_by_the_host_and_by_the_device() {
    let mut link = boot(None);
    let mut seq = 0u16;
    let mut ask = |link: &mut EmulatorLink, request| {
        seq += 1;
        wire::ask(link, seq, request, Duration::from_secs(2))
    };
    assert!(matches!(
        ask(
            &mut link,
            Request::Hello {
                version: PROTOCOL_VERSION
            }
        ),
        DeviceToHost::HelloAck { .. }
    ));
    let before = link.mcu_mut().eeprom();
    let mut cases = Vec::new();
    let mut r = custom();
    r.robot.leg.tibia_m = 2.5;
    cases.push((r, RobotField::TibiaM));
    let mut r = custom();
    r.robot.limits.min_rad[2] = -3.5;
    cases.push((r, RobotField::Limit(kin_core::Joint::Knee)));
    let mut r = custom();
    r.stance_height_m = 0.6;
    cases.push((r, RobotField::Stance(kin_core::LegId::FL)));
    for (robot, field) in cases {
        // The host: not sent.
        let mut client = Client::new(boot(None), ClientConfig::emulator());
        client.hello().unwrap_or_else(|e| panic!("{e}"));
        let frames_before = client.counters();
        match client.set_robot(&robot) {
            Err(client::Error::Refused { reason, .. }) => {
                assert_eq!(reason, NackReason::BadRobot(field))
            }
            other => panic!("{field}: {other:?}"),
        }
        assert_eq!(
            client.counters(),
            frames_before,
            "{field}: something was sent"
        );
        // The device, sent the raw request anyway.
        match ask(&mut link, Request::SetRobot(robot)) {
            DeviceToHost::Nack { reason, .. } => {
                assert_eq!(reason, NackReason::BadRobot(field), "{field}")
            }
            other => panic!("{field}: {other:?}"),
        }
    }
    // Nothing changed, nothing stored.
    match ask(&mut link, Request::GetRobot) {
        DeviceToHost::Robot { robot, .. } => {
            assert_eq!(robot, quad_device::Config::shahriar2023().description())
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        ask(&mut link, Request::SaveRobot),
        DeviceToHost::Ack { .. }
    ));
    let after = link.mcu_mut().eeprom();
    // Only the robot's bank A was written, with the compiled robot.
    let changed: Vec<usize> = (0..before.len())
        .filter(|&i| before[i] != after[i])
        .collect();
    let bank = usize::from(quad_device::store::ROBOT_OFFSET);
    assert!(
        changed
            .iter()
            .all(|&i| (bank..bank + quad_device::store::ROBOT_BANK_LEN).contains(&i)),
        "{changed:?}"
    );
}

#[test]
fn a_reset_at_every_byte_of_a_robot_save_boots_the_old_or_the_new_robot() {
    let first = custom();
    let mut second = custom();
    second.name = RobotDescription::name_bytes("bench-pup-2").unwrap();
    second.robot.leg.femur_m = 0.21;
    let eeprom = send_and_save(&first);
    // Record the second save byte by byte.
    let mut client = Client::new(boot(Some(eeprom)), ClientConfig::emulator());
    client.hello().unwrap_or_else(|e| panic!("{e}"));
    client.set_robot(&second).unwrap_or_else(|e| panic!("{e}"));
    let link = client.link_mut();
    let mut images = vec![link.mcu_mut().eeprom()];
    let bytes = wire::frame(900, Request::SaveRobot);
    quad_host::link::Link::send(link, &bytes).expect("send");
    let mut waited = Duration::ZERO;
    while waited < Duration::from_millis(500) {
        link.idle(Duration::from_micros(500)).expect("runs");
        waited += Duration::from_micros(500);
        let now = link.mcu_mut().eeprom();
        if &now != images.last().expect("an image") {
            images.push(now);
        }
    }
    assert_eq!(
        images.len() - 1,
        quad_device::store::ROBOT_BANK_LEN + 2,
        "the save's bytes"
    );
    for (k, image) in images.iter().enumerate() {
        let mut link = boot(Some(image.clone()));
        let mut seq = 0;
        let mut ask = |request| {
            seq += 1;
            wire::ask(&mut link, seq, request, Duration::from_secs(2))
        };
        let DeviceToHost::HelloAck { info, .. } = ask(Request::Hello {
            version: PROTOCOL_VERSION,
        }) else {
            panic!("hello")
        };
        let DeviceToHost::Robot { robot, .. } = ask(Request::GetRobot) else {
            panic!("GetRobot")
        };
        let expected = if k == images.len() - 1 { second } else { first };
        assert_eq!(robot, expected, "after {k} bytes");
        assert_eq!(info.robot_hash, Some(expected.hash()), "after {k} bytes");
    }
}
