//! The onboard tour of `quadctl demo` on the simulated device (the host's own math: every
//! angle the same bits as the host's kin-core).

use kin_core::Robot;
use quad_device::Config;
use quad_host::client::{AngleCheck, Client, ClientConfig};
use quad_host::link::sim::{EepromImage, SimConfig, SimLink};
use quad_host::ops::demo_motions;
use quad_host::ops::onboard::Session;
use quad_protocol::RobotPreset;
use std::time::Duration;

#[test]
fn the_tour_runs_and_every_check_passes_on_the_simulated_device() {
    let link = SimLink::new(
        SimConfig::default(),
        Config::shahriar2023(),
        EepromImage::erased(),
    )
    .unwrap();
    let client = Client::new(link, ClientConfig::sim(Duration::ZERO));
    let mut session = Session::connect(client, RobotPreset::Shahriar2023).unwrap();
    let mut names = Vec::new();
    let legs = demo_motions::run(
        &mut session,
        &Robot::shahriar2023(),
        AngleCheck::Exact,
        |n| names.push(n.to_owned()),
    )
    .unwrap();
    assert_eq!(legs.len(), 6, "{names:?}");
    for leg in &legs {
        assert_eq!(leg.errors, 0, "{leg:?}");
        assert!(leg.answers >= 2, "{leg:?}");
    }
    // Stand-up and sit end on the host's stance and rest pose; the sways and the turn are
    // compared at every answer while they run.
    assert_eq!(legs[0].angles_checked, 1);
    assert_eq!(legs[5].angles_checked, 1);
    for leg in &legs[1..4] {
        assert!(leg.angles_checked >= 30, "{leg:?}");
        assert_eq!(leg.max_angle_err_rad, 0.0, "{leg:?}");
    }
}

#[test]
fn the_full_tour_replays_every_frame_of_stand_up_the_walks_and_sit_exactly() {
    let link = SimLink::new(
        SimConfig::default(),
        Config::shahriar2023(),
        EepromImage::erased(),
    )
    .unwrap();
    let client = Client::new(link, ClientConfig::sim(Duration::ZERO));
    let mut session = Session::connect(client, RobotPreset::Shahriar2023).unwrap();
    let legs = demo_motions::run_tour(
        &mut session,
        &Robot::shahriar2023(),
        AngleCheck::Exact,
        demo_motions::full_tour,
        |_| {},
    )
    .unwrap();
    assert_eq!(legs.len(), 7);
    for leg in &legs {
        assert_eq!(leg.errors, 0, "{leg:?}");
    }
    // Stand-up, the trot, the walk and sit: every answer of the motion is a replayed frame.
    for i in [0, 4, 5, 6] {
        assert!(legs[i].frames_checked >= 3, "{:?}", legs[i]);
        assert!(legs[i].angles_checked > 0, "{:?}", legs[i]);
    }
    for i in [4, 5] {
        assert!(legs[i].angles_checked >= 20, "{:?}", legs[i]);
        assert_eq!(legs[i].max_angle_err_rad, 0.0, "{:?}", legs[i]);
    }
}

#[test]
fn a_perturbed_replay_fails_the_trot_naming_the_frame_and_the_joint() {
    // The host's robot a millimetre off the device's: its replay of the trot is not what the
    // device runs, and the check says where first.
    let link = SimLink::new(
        SimConfig::default(),
        Config::shahriar2023(),
        EepromImage::erased(),
    )
    .unwrap();
    let client = Client::new(link, ClientConfig::sim(Duration::ZERO));
    let mut session = Session::connect(client, RobotPreset::Shahriar2023).unwrap();
    let mut robot = Robot::shahriar2023();
    robot.leg.tibia_m += 1e-3;
    let legs = demo_motions::run_tour(
        &mut session,
        &robot,
        AngleCheck::Within(1e-5),
        |h| {
            demo_motions::tour(h)
                .into_iter()
                .filter(|(name, ..)| name.starts_with("trot"))
                .collect()
        },
        |_| {},
    )
    .unwrap();
    assert_eq!(legs.len(), 1);
    let trot = &legs[0];
    assert!(trot.errors > 0, "{trot:?}");
    // "trot: …: readback 1: Run frame 4: FR Knee is -1.5394 on the device, -1.5431 in the
    // replay".
    let first = trot.first_error.as_deref().unwrap();
    assert!(
        first.contains("readback") && first.contains("Run frame"),
        "{first}"
    );
    assert!(
        ["Abduction", "Hip", "Knee"]
            .iter()
            .any(|j| first.contains(j)),
        "{first}"
    );
}
