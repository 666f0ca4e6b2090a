//! Message functions: the handshake rule, kin-core error conversion, servo indices, flags.

use kin_core::{IkError, Joint, LegId, ReachPolicy, Robot, RotationOrder, Unreachable};
use quad_protocol::{
    negotiated_minor, DeviceInfo, DeviceToHost, FirmwareVersion, Flags, LinkTimeout, NackReason,
    PoseConfig, ReachFault, RobotPreset, ServoId, PROTOCOL_VERSION,
};

fn info(version: u16) -> DeviceInfo {
    DeviceInfo {
        version,
        firmware: FirmwareVersion::default(),
        robot: RobotPreset::Shahriar2023,
        max_frame_len: 128,
        pose_config: PoseConfig {
            stance_height_m: 0.4,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        },
        link_timeout: LinkTimeout::default(),
        robot_hash: None,
    }
}

#[test]
fn hello_with_the_same_major_is_acked_whatever_the_minor() {
    let dev = info(0x0103);
    for host in [0x0100, 0x0103, 0x01FF] {
        assert_eq!(
            dev.answer_hello(9, host),
            DeviceToHost::HelloAck { seq: 9, info: dev }
        );
    }
    assert_eq!(negotiated_minor(0x0103, 0x0101), 1);
    assert_eq!(negotiated_minor(0x0100, 0x0105), 0);
}

#[test]
fn hello_with_another_major_is_nacked_with_the_device_version() {
    let dev = info(PROTOCOL_VERSION);
    for host in [0x0000, 0x00FF, 0x0100, 0x0300, 0xFF00] {
        assert_eq!(
            dev.answer_hello(3, host),
            DeviceToHost::Nack {
                seq: Some(3),
                reason: NackReason::UnknownVersion {
                    supported: PROTOCOL_VERSION
                },
            }
        );
    }
}

#[test]
fn kin_core_ik_errors_map_to_typed_nacks() {
    let cases = [
        (
            Unreachable::TooFar,
            NackReason::Unreachable {
                leg: LegId::RL,
                fault: ReachFault::TooFar,
            },
        ),
        (
            Unreachable::TooClose,
            NackReason::Unreachable {
                leg: LegId::RL,
                fault: ReachFault::TooClose,
            },
        ),
        (
            Unreachable::InsideOffset,
            NackReason::Unreachable {
                leg: LegId::RL,
                fault: ReachFault::InsideOffset,
            },
        ),
        (
            Unreachable::JointLimit(Joint::Knee),
            NackReason::JointLimit {
                leg: LegId::RL,
                joint: Joint::Knee,
            },
        ),
        (Unreachable::NonFinite, NackReason::NonFinite),
    ];
    for (kind, expected) in cases {
        let e = IkError {
            leg: LegId::RL,
            kind,
        };
        assert_eq!(NackReason::from(e), expected, "{kind:?}");
    }
}

#[test]
fn servo_ids_follow_the_canonical_order() {
    for (i, s) in ServoId::ALL.iter().enumerate() {
        assert_eq!(s.index(), i);
        assert_eq!(ServoId::from_index(i), Some(*s));
        assert_eq!(s.leg, LegId::ALL[i / 3]);
        assert_eq!(s.joint, Joint::ALL[i % 3]);
    }
    assert_eq!(ServoId::from_index(12), None);
    assert_eq!(ServoId::ALL[5].to_string(), "FR.knee");
}

#[test]
fn flags_set_and_clear_single_bits() {
    let f = Flags::EMPTY
        .with(Flags::OUTPUTS_ENABLED, true)
        .with(Flags::CLAMPED, true)
        .with(Flags::CLAMPED, false);
    assert_eq!(f, Flags(0x04));
    assert!(f.contains(Flags::OUTPUTS_ENABLED));
    assert!(!f.contains(Flags::CLAMPED));
    let all = [
        Flags::CLAMPED,
        Flags::LIMITED,
        Flags::OUTPUTS_ENABLED,
        Flags::FAILSAFE_ACTIVE,
        Flags::CALIBRATION_UNSAVED,
        Flags::CALIBRATION_DEFAULT,
    ];
    assert_eq!(all.iter().fold(0, |a, b| a | b), 0x3F);
    // 2.2 appended bit 6.
    assert_eq!(Flags::WATCHDOG_RESET, 0x40);
}

#[test]
fn presets_are_kin_core_presets() {
    assert_eq!(
        RobotPreset::Shahriar2023.robot(),
        Some(Robot::shahriar2023())
    );
    assert_eq!(
        RobotPreset::Fernando2025.robot(),
        Some(Robot::fernando2025())
    );
    assert_eq!(RobotPreset::Custom.robot(), None);
    for name in Robot::PRESETS {
        let p = RobotPreset::from_name(name).unwrap();
        assert_eq!(p.robot(), Robot::preset(name));
    }
    assert_eq!(RobotPreset::from_name("spot"), None);
}

#[test]
fn answers_expose_their_seq() {
    let nack = DeviceToHost::Nack {
        seq: None,
        reason: NackReason::BadFrame,
    };
    assert_eq!(nack.seq(), None);
    let hello = info(PROTOCOL_VERSION).answer_hello(77, PROTOCOL_VERSION);
    assert_eq!(hello.seq(), Some(77));
}

#[test]
fn nack_reasons_display() {
    let r = NackReason::Unreachable {
        leg: LegId::FR,
        fault: ReachFault::TooFar,
    };
    assert_eq!(r.to_string(), "unreachable: FR too_far");
    let v = NackReason::UnknownVersion { supported: 0x0102 };
    assert_eq!(v.to_string(), "unknown version (device speaks 1.2)");
}
