//! The panel's device session on the simulated device, without a browser: the checks before
//! sending, the jog, and the link-loss rule when the controlling page goes away.

use kin_core::body::Pose;
use kin_core::Robot;
use quad_host::client::{AngleCheck, Client, ClientConfig};
use quad_host::link::{self, sim::SimConfig, Link, Target};
use quad_protocol::{LinkLossAction, LinkTimeout, Request, RobotPreset, ServoId};
use quad_web::device::{Error, Session};
use std::time::Duration;

fn session(action: LinkLossAction) -> Session<Box<dyn Link>> {
    let target = Target::Sim {
        preset: RobotPreset::Shahriar2023,
        config: SimConfig::default(),
        storage: None,
    };
    let mut client = Client::new(
        link::open(&target).unwrap(),
        ClientConfig::sim(Duration::ZERO),
    );
    client.hello().unwrap();
    client
        .ack(Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 0,
            action,
        }))
        .unwrap();
    Session::connect(
        client,
        Robot::shahriar2023(),
        RobotPreset::Shahriar2023,
        AngleCheck::Exact,
    )
    .unwrap()
}

#[test]
fn a_pose_the_host_rejects_is_not_sent() {
    let mut s = session(LinkLossAction::Hold);
    let before = s.state(0.0);
    let err = s.set_pose(Pose::rotation(1.5, 0.0, 0.0), 1).unwrap_err();
    assert!(matches!(err, Error::HostRejects(_)), "{err}");
    let after = s.state(0.0);
    assert_eq!(after.poses_sent, 0);
    assert_eq!(after.link.frames_sent, before.link.frames_sent);
    assert_eq!(after.angles_rad, before.angles_rad);
    s.set_pose(Pose::rotation(0.1, 0.0, 0.0), 2).unwrap();
    assert_eq!(s.state(0.0).pose_id, 2);
    assert_eq!(s.state(0.0).poses_sent, 1);
}

#[test]
fn a_jog_moves_the_pulse_by_its_step() {
    let mut s = session(LinkLossAction::Hold);
    s.set_outputs(true).unwrap();
    let servo = ServoId::ALL[1];
    let p0 = s.state(0.0).pulses_us[1];
    s.jog(servo, 10).unwrap();
    s.jog(servo, -1).unwrap();
    assert_eq!(s.state(0.0).pulses_us[1] - p0, 9.0);
    // A centre beyond the travel is refused before it is sent.
    let frames = s.state(0.0).link.frames_sent;
    let err = s.set_center(servo, 2700).unwrap_err();
    assert!(matches!(err, Error::BadCalibration { .. }), "{err}");
    assert_eq!(s.state(0.0).link.frames_sent, frames);
}

#[test]
fn losing_the_controlling_page_applies_the_link_loss_rule() {
    let mut s = session(LinkLossAction::Disable);
    s.set_outputs(true).unwrap();
    assert!(s.state(0.0).flags.outputs_enabled);
    s.control_lost().unwrap();
    assert!(!s.state(0.0).flags.outputs_enabled);

    let mut s = session(LinkLossAction::Hold);
    s.set_outputs(true).unwrap();
    s.control_lost().unwrap();
    assert!(s.state(0.0).flags.outputs_enabled);
}

#[test]
fn a_motion_the_protocol_cannot_carry_is_not_sent() {
    use quad_web::motion::{MotionMsg, VelocityMsg};
    use quad_web::msg::ClientMsg;
    let mut s = session(LinkLossAction::Hold);
    s.set_outputs(true).unwrap();
    let before = s.state(0.0);
    for cmd in [
        ClientMsg::StartMotion {
            motion: MotionMsg::Stand,
        },
        ClientMsg::SetVelocity {
            velocity: VelocityMsg {
                forward_m_s: 0.1,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.0,
            },
        },
        ClientMsg::StopMotion,
    ] {
        let err = s.command(&cmd).unwrap_err();
        assert!(matches!(err, Error::Motion(_)), "{err}");
        assert!(err.to_string().contains("not sent"), "{err}");
    }
    let after = s.state(0.0);
    assert_eq!(after.link.frames_sent, before.link.frames_sent);
    assert_eq!(after.angles_rad, before.angles_rad);
    s.control_lost().unwrap();
    assert!(
        s.state(0.0).flags.outputs_enabled,
        "hold keeps the outputs on"
    );
}
