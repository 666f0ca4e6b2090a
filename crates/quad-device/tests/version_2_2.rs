//! What protocol 2.2 appended, through the device on the in-memory fakes: the idle motion
//! stage (and what a 2.0/2.1 host gets instead), and the watchdog-reset flag, latched until a
//! host of minor 2 or later has read it.

mod common;

use common::*;
use kin_core::motion::laws::Axis;
use quad_device::{Config, Device};
use quad_protocol::{
    DeviceToHost, Flags, MotionCommand, MotionKind, MotionStage, MotionStatus, Request,
    PROTOCOL_VERSION,
};

fn rig(host_version: u16) -> (Dev, VirtualClock) {
    let (mut dev, clock) = clocked_device();
    assert!(matches!(
        ask(
            &mut dev,
            0,
            Request::Hello {
                version: host_version
            }
        ),
        DeviceToHost::HelloAck { info, .. } if info.version == PROTOCOL_VERSION
    ));
    (dev, clock)
}

fn flags(a: DeviceToHost) -> Flags {
    a.readback()
        .unwrap_or_else(|| panic!("no readback: {a:?}"))
        .flags
}

/// Stands up, sways for three seconds and stops: the engine is idle again with a motion
/// behind it (whose time a 2.1 device kept reporting).
fn a_motion_gone_by(dev: &mut Dev, clock: &VirtualClock) {
    ask(dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(dev, clock, 500);
    let sway = MotionCommand::Sway {
        axis: Axis::Roll,
        amplitude_rad: 0.1,
        period_s: 1.0,
        duration_s: None,
    };
    assert_eq!(
        status(ask(dev, 2, Request::StartMotion(sway))).kind,
        Some(MotionKind::Sway)
    );
    frames(dev, clock, 150);
    let running = status(ask(dev, 3, Request::GetMotion));
    assert_eq!(running.stage, MotionStage::Run);
    assert!(running.t_s > 1.0, "{running:?}");
    ask(dev, 4, Request::StopMotion);
    frames(dev, clock, 500);
}

#[test]
fn an_idle_device_reports_the_idle_stage_to_a_two_two_host() {
    let (mut dev, clock) = rig(0x0202);
    assert_eq!(dev.peer_minor(), 2);
    let idle = MotionStatus {
        kind: None,
        stage: MotionStage::Idle,
        t_s: 0.0,
        phase: 0.0,
        fault: None,
    };
    assert_eq!(status(ask(&mut dev, 10, Request::GetMotion)), idle);
    a_motion_gone_by(&mut dev, &clock);
    assert_eq!(status(ask(&mut dev, 11, Request::GetMotion)), idle);
    // StopMotion while idle answers the same.
    assert_eq!(status(ask(&mut dev, 12, Request::StopMotion)), idle);
}

#[test]
fn an_idle_device_reports_run_at_time_zero_to_a_two_zero_or_two_one_host() {
    for host in [0x0200, 0x0201] {
        let (mut dev, clock) = rig(host);
        assert_eq!(dev.peer_minor(), quad_protocol::version_minor(host));
        let idle = MotionStatus {
            kind: None,
            stage: MotionStage::Run,
            t_s: 0.0,
            phase: 0.0,
            fault: None,
        };
        assert_eq!(status(ask(&mut dev, 10, Request::GetMotion)), idle);
        a_motion_gone_by(&mut dev, &clock);
        // No stale time of the sway gone by, and no stage a 2.1 decoder cannot read.
        assert_eq!(
            status(ask(&mut dev, 11, Request::GetMotion)),
            idle,
            "{host:#06x}"
        );
    }
}

#[test]
fn the_watchdog_flag_is_latched_until_a_two_two_host_has_read_it() {
    let clock = VirtualClock::default();
    let mut dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        clock,
        RamEeprom::erased(),
    )
    .unwrap();
    dev.note_watchdog_reset();
    // Before any Hello the host's minor is unknown: not sent, still latched.
    assert!(!flags(ask(&mut dev, 1, Request::GetState)).contains(Flags::WATCHDOG_RESET));
    // A 2.1 host is not sent the bit (it would ignore it): still latched.
    ask(&mut dev, 2, Request::Hello { version: 0x0201 });
    for seq in 3..5 {
        let f = flags(ask(&mut dev, seq, Request::GetState));
        assert!(!f.contains(Flags::WATCHDOG_RESET), "{f:?}");
        assert!(!f.contains(Flags::OUTPUTS_ENABLED), "{f:?}");
    }
    // A 2.2 host reads it in its first answer with the flags, once; a HelloAck does not
    // carry the flags and does not clear it.
    ask(
        &mut dev,
        5,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    );
    let first = ask(&mut dev, 6, Request::GetMotion);
    assert!(flags(first).contains(Flags::WATCHDOG_RESET), "{first:?}");
    assert!(!flags(first).contains(Flags::OUTPUTS_ENABLED));
    // A retry of the request that reported it (its answer lost) gets that answer again.
    assert_eq!(ask(&mut dev, 6, Request::GetMotion), first);
    let second = flags(ask(&mut dev, 7, Request::GetState));
    assert!(!second.contains(Flags::WATCHDOG_RESET), "{second:?}");
}

#[test]
fn without_a_watchdog_reset_the_flag_is_never_set() {
    let (mut dev, _) = rig(PROTOCOL_VERSION);
    assert!(!flags(ask(&mut dev, 1, Request::GetState)).contains(Flags::WATCHDOG_RESET));
}
