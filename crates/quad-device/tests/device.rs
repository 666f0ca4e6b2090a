//! The controller's behaviour, request by request, and its invariants.

mod common;

use common::*;
use kin_core::body::{self, Pose};
use kin_core::{BodyConfig, Joint, LegId, ReachPolicy, Vec3};
use quad_device::config::DEFAULT_CENTER_US;
use quad_device::sim::PwmPeriods;
use quad_device::{Config, Device};
use quad_protocol::servo::{self, Calibration};
use quad_protocol::{
    DeviceToHost, Field, Flags, LinkLossAction, LinkTimeout, NackReason, PoseConfig, ReachFault,
    Readback, Request, ServoId, Setting,
};

/// The readback of an answer that carried the request out: an `Ack`, or the `Configured` echo
/// of a configuration request.
fn ack(answer: DeviceToHost) -> Readback {
    match answer {
        DeviceToHost::Ack { readback, .. } | DeviceToHost::Configured { readback, .. } => readback,
        other => panic!("expected an ack, got {other:?}"),
    }
}

fn nack_reason(answer: DeviceToHost) -> NackReason {
    match answer {
        DeviceToHost::Nack { reason, .. } => reason,
        other => panic!("expected a nack, got {other:?}"),
    }
}

/// Host-side expectation for a body pose with the device's configuration.
fn expected_angles(config: &Config, pose: &Pose) -> [f32; 12] {
    body::Solver::new(&config.robot)
        .inverse_at_stance(
            pose,
            &BodyConfig {
                order: config.pose_config.order,
                pivot_m: Vec3::ZERO,
            },
            config.pose_config.stance_height_m,
            config.pose_config.policy,
        )
        .unwrap()
        .flat()
}

const POSE: Pose = Pose {
    roll_rad: 0.1,
    pitch_rad: -0.05,
    yaw_rad: 0.08,
    x_m: 0.02,
    y_m: -0.01,
    z_m: -0.05,
};

#[test]
fn outputs_start_disabled_and_nothing_is_written_until_enabled() {
    let mut dev = device(Config::fernando2025());
    assert_eq!(dev.outputs().enables(), [false]);
    assert!(dev.outputs().writes().is_empty());
    hello(&mut dev);
    let rb = ack(ask(&mut dev, 1, Request::SetBodyPose(POSE)));
    assert!(!rb.flags.contains(Flags::OUTPUTS_ENABLED));
    assert_eq!(rb.pulses_half_us, [0; 12], "stopped outputs read back as 0");
    assert!(dev.outputs().writes().is_empty(), "no write while stopped");
    let rb = ack(ask(&mut dev, 2, Request::SetOutputs { enabled: true }));
    assert!(rb.flags.contains(Flags::OUTPUTS_ENABLED));
    assert_eq!(dev.outputs().enables(), [false, true]);
    // Enabling starts from the target held while stopped.
    assert_eq!(dev.outputs().writes().len(), 1);
    assert_eq!(dev.outputs().writes()[0], rb.pulses_half_us);
    assert_eq!(rb.angles_rad, expected_angles(dev.config(), &POSE));
}

#[test]
fn the_power_on_target_is_the_stance_at_the_servo_centres() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    let rb = ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    assert_eq!(rb.pulses_half_us, [2 * DEFAULT_CENTER_US; 12]);
    assert!(rb.flags.contains(Flags::CALIBRATION_DEFAULT));
}

#[test]
fn requests_before_hello_are_refused_except_reads() {
    let mut dev = device(Config::fernando2025());
    for (seq, req) in [
        (1, Request::SetBodyPose(POSE)),
        (2, Request::SetOutputs { enabled: true }),
        (3, Request::SaveCalibration),
        (
            4,
            Request::SetLinkTimeout(LinkTimeout {
                timeout_ms: 10,
                action: LinkLossAction::Disable,
            }),
        ),
    ] {
        assert_eq!(
            nack_reason(ask(&mut dev, seq, req)),
            NackReason::HelloRequired
        );
    }
    ack(ask(&mut dev, 5, Request::GetState));
    assert!(matches!(
        ask(&mut dev, 6, Request::GetCalibration { servo: ServoId::ALL[4] }),
        DeviceToHost::Calibration { servo, .. } if servo == ServoId::ALL[4]
    ));
    assert!(dev.outputs().writes().is_empty() && !dev.outputs_enabled());
}

#[test]
fn hello_checks_the_major_version() {
    let mut dev = device(Config::fernando2025());
    assert_eq!(
        nack_reason(ask(&mut dev, 1, Request::Hello { version: 0x0100 })),
        NackReason::UnknownVersion {
            supported: quad_protocol::PROTOCOL_VERSION
        }
    );
    assert_eq!(
        nack_reason(ask(&mut dev, 2, Request::SetBodyPose(POSE))),
        NackReason::HelloRequired
    );
    match ask(&mut dev, 3, Request::Hello { version: 0x0207 }) {
        DeviceToHost::HelloAck { info, .. } => {
            assert_eq!(info.version, quad_protocol::PROTOCOL_VERSION);
            assert_eq!(info.robot, quad_protocol::RobotPreset::Fernando2025);
            assert_eq!(info.pose_config, Config::fernando2025().pose_config);
            assert_eq!(info.max_frame_len, 128);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn body_pose_readback_is_kin_core_and_the_calibration_mapping() {
    for config in [Config::fernando2025(), Config::shahriar2023()] {
        let mut dev = device(config);
        hello(&mut dev);
        ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
        let rb = ack(ask(&mut dev, 2, Request::SetBodyPose(POSE)));
        let want = expected_angles(&config, &POSE);
        for (i, (&got, &w)) in rb.angles_rad.iter().zip(&want).enumerate() {
            assert_eq!(got.to_bits(), w.to_bits(), "joint {i}");
            assert_eq!(
                Ok(rb.pulses_half_us[i]),
                dev.calibration()[i].pulse_half_us(w)
            );
        }
        assert_eq!(dev.outputs().writes().last(), Some(&rb.pulses_half_us));
        assert!(!rb.flags.contains(Flags::CLAMPED));
        assert_writes_in_travel(&dev);
    }
}

#[test]
fn set_feet_runs_the_body_ik_at_the_zero_pose() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    let feet = config.robot.stance_feet(0.85);
    let rb = ack(ask(
        &mut dev,
        1,
        Request::SetFeet {
            feet_in_body_m: feet.map(|v| [v.x + 0.03, v.y, v.z]),
        },
    ));
    let want = body::Solver::new(&config.robot)
        .inverse(
            &Pose::default(),
            &BodyConfig {
                order: config.pose_config.order,
                pivot_m: Vec3::ZERO,
            },
            &feet.map(|v| Vec3::new(v.x + 0.03, v.y, v.z)),
            ReachPolicy::Reject,
        )
        .unwrap()
        .flat();
    assert_eq!(rb.angles_rad, want);
}

#[test]
fn set_joints_bypasses_the_ik_but_not_the_limits() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let before = *dev.outputs().writes().last().unwrap();
    let mut q = expected_angles(&config, &Pose::default());
    q[4] += 0.1;
    let rb = ack(ask(&mut dev, 2, Request::SetJoints { angles_rad: q }));
    assert_eq!(rb.angles_rad, q);
    // Knee of RL above its limit of -0.05 rad.
    let mut bad = q;
    bad[8] = 0.0;
    assert_eq!(
        nack_reason(ask(&mut dev, 3, Request::SetJoints { angles_rad: bad })),
        NackReason::JointLimit {
            leg: LegId::RL,
            joint: Joint::Knee
        }
    );
    bad = q;
    bad[0] = f32::NAN;
    assert_eq!(
        nack_reason(ask(&mut dev, 4, Request::SetJoints { angles_rad: bad })),
        NackReason::NonFinite
    );
    let rb2 = ack(ask(&mut dev, 5, Request::GetState));
    assert_eq!(rb2.angles_rad, q, "refused requests moved nothing");
    assert_ne!(before, rb.pulses_half_us);
    assert_eq!(dev.outputs().writes().len(), 2);
}

#[test]
fn invalid_or_unreachable_requests_move_nothing() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let good = ack(ask(&mut dev, 2, Request::SetBodyPose(POSE)));
    let writes = dev.outputs().writes().len();
    let cases = [
        (
            Pose {
                z_m: 0.15,
                ..Pose::default()
            },
            NackReason::Unreachable {
                leg: LegId::FL,
                fault: ReachFault::TooFar,
            },
        ),
        (
            Pose {
                pitch_rad: f32::INFINITY,
                ..Pose::default()
            },
            NackReason::NonFinite,
        ),
        (
            Pose {
                roll_rad: f32::NAN,
                ..Pose::default()
            },
            NackReason::NonFinite,
        ),
    ];
    for (i, (pose, reason)) in cases.into_iter().enumerate() {
        let host = body::Solver::new(&config.robot).inverse_at_stance(
            &pose,
            &BodyConfig {
                order: config.pose_config.order,
                pivot_m: Vec3::ZERO,
            },
            config.pose_config.stance_height_m,
            ReachPolicy::Reject,
        );
        assert_eq!(NackReason::from(host.unwrap_err()), reason);
        assert_eq!(
            nack_reason(ask(&mut dev, 10 + i as u16, Request::SetBodyPose(pose))),
            reason
        );
    }
    // Reachable by the IK but beyond a servo's travel: a 100 µs travel on FL's hip.
    let narrow = Calibration {
        min_us: 1450,
        max_us: 1550,
        ..dev.calibration()[1]
    };
    let narrow = Calibration {
        zero_rad: good.angles_rad[1],
        ..narrow
    };
    ack(ask(
        &mut dev,
        20,
        Request::SetCalibration {
            servo: ServoId::ALL[1],
            calibration: narrow,
        },
    ));
    let writes_after_cal = dev.outputs().writes().len();
    assert_eq!(
        writes_after_cal,
        writes + 1,
        "the calibration change drives once"
    );
    // The body 15 cm forward: FL's hip swings by about 0.17 rad, beyond the ±0.079 rad travel.
    let far = Pose { x_m: 0.15, ..POSE };
    let reason = nack_reason(ask(&mut dev, 21, Request::SetBodyPose(far)));
    assert!(
        matches!(
            reason,
            NackReason::ServoRange {
                leg: LegId::FL,
                joint: Joint::Hip,
                fault: servo::Error::AboveMax | servo::Error::BelowMin
            }
        ),
        "{reason:?}"
    );
    assert_eq!(dev.outputs().writes().len(), writes_after_cal);
    let rb = ack(ask(&mut dev, 22, Request::GetState));
    assert_eq!(rb.angles_rad, good.angles_rad);
    assert_writes_in_travel(&dev);
}

#[test]
fn clamp_policy_reports_the_clamp() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    let p = PoseConfig {
        policy: ReachPolicy::Clamp,
        ..config.pose_config
    };
    ack(ask(&mut dev, 1, Request::SetPoseConfig(p)));
    let rb = ack(ask(
        &mut dev,
        2,
        Request::SetBodyPose(Pose {
            z_m: 0.15,
            ..Pose::default()
        }),
    ));
    assert!(rb.flags.contains(Flags::CLAMPED));
    assert!(rb.angles_rad.iter().all(|a| a.is_finite()));
    let rb = ack(ask(&mut dev, 3, Request::SetBodyPose(Pose::default())));
    assert!(!rb.flags.contains(Flags::CLAMPED));
}

#[test]
fn pose_config_changes_the_stance_and_is_validated() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    for bad in [0.0, -0.5, f32::NAN, f32::INFINITY] {
        let p = PoseConfig {
            stance_height_m: bad,
            ..config.pose_config
        };
        assert_eq!(
            nack_reason(ask(&mut dev, 1, Request::SetPoseConfig(p))),
            NackReason::InvalidArgument
        );
    }
    let p = PoseConfig {
        stance_height_m: 0.8,
        order: kin_core::RotationOrder::Xyz,
        ..config.pose_config
    };
    ack(ask(&mut dev, 2, Request::SetPoseConfig(p)));
    let rb = ack(ask(&mut dev, 3, Request::SetBodyPose(POSE)));
    let mut c2 = config;
    c2.pose_config = p;
    assert_eq!(rb.angles_rad, expected_angles(&c2, &POSE));
    assert_ne!(rb.angles_rad, expected_angles(&config, &POSE));
}

#[test]
fn the_latest_valid_setpoint_wins() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let poses: Vec<Pose> = (0..4)
        .map(|i| Pose {
            roll_rad: 0.05 * i as f32,
            ..Pose::default()
        })
        .collect();
    // Three valid poses and an unreachable one, back to back in one read.
    let mut wire = Vec::new();
    for (i, p) in poses.iter().enumerate() {
        wire.extend(frame(10 + i as u16, Request::SetBodyPose(*p)));
    }
    wire.extend(frame(
        20,
        Request::SetBodyPose(Pose {
            z_m: 0.2,
            ..Pose::default()
        }),
    ));
    let answers = feed(&mut dev, &wire);
    assert_eq!(answers.len(), 5);
    assert!(matches!(
        answers[4],
        DeviceToHost::Nack { seq: Some(20), .. }
    ));
    let last = expected_angles(&config, &poses[3]);
    let rb = ack(ask(&mut dev, 30, Request::GetState));
    assert_eq!(rb.angles_rad, last);
    assert_eq!(dev.outputs().writes().last(), Some(&rb.pulses_half_us));
    // One write per accepted pose (plus the enable), none for the refused one.
    assert_eq!(dev.outputs().writes().len(), 1 + 4);
}

fn failsafe_case(action: LinkLossAction) -> (Dev, VirtualClock) {
    let (mut dev, clock) = clocked_device();
    hello(&mut dev);
    ack(ask(
        &mut dev,
        1,
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 200,
            action,
        }),
    ));
    ack(ask(&mut dev, 2, Request::SetOutputs { enabled: true }));
    ack(ask(&mut dev, 3, Request::SetBodyPose(POSE)));
    (dev, clock)
}

#[test]
fn link_loss_disables_the_outputs_when_configured() {
    let (mut dev, clock) = failsafe_case(LinkLossAction::Disable);
    clock.set_ms(1_199);
    dev.poll();
    assert!(dev.outputs_enabled(), "not before the timeout");
    clock.set_ms(1_200);
    dev.poll();
    assert!(!dev.outputs_enabled() && !dev.outputs().enabled);
    let rb = ack(ask(&mut dev, 4, Request::GetState));
    assert!(rb.flags.contains(Flags::FAILSAFE_ACTIVE));
    assert!(!rb.flags.contains(Flags::OUTPUTS_ENABLED));
    assert_eq!(rb.pulses_half_us, [0; 12]);
    // Reported once; the outputs stay stopped until enabled again.
    let rb = ack(ask(&mut dev, 5, Request::SetBodyPose(Pose::default())));
    assert!(!rb.flags.contains(Flags::FAILSAFE_ACTIVE));
    assert!(!dev.outputs_enabled());
    let rb = ack(ask(&mut dev, 6, Request::SetOutputs { enabled: true }));
    assert!(rb.flags.contains(Flags::OUTPUTS_ENABLED));
}

#[test]
fn link_loss_holds_the_pose_when_configured() {
    let (mut dev, clock) = failsafe_case(LinkLossAction::Hold);
    let writes = dev.outputs().writes().to_vec();
    clock.set_ms(5_000);
    dev.poll();
    assert!(dev.outputs_enabled() && dev.outputs().enabled);
    assert_eq!(dev.outputs().writes(), writes, "holding writes nothing new");
    let rb = ack(ask(&mut dev, 4, Request::GetState));
    assert!(rb
        .flags
        .contains(Flags::FAILSAFE_ACTIVE | Flags::OUTPUTS_ENABLED));
    assert_eq!(Some(&rb.pulses_half_us), writes.last());
}

#[test]
fn frames_keep_the_link_alive_and_timeout_zero_never_fires() {
    let (mut dev, clock) = failsafe_case(LinkLossAction::Disable);
    for t in (1_000..3_000).step_by(150) {
        clock.set_ms(t);
        ack(ask(&mut dev, 7, Request::GetState));
        dev.poll();
        assert!(dev.outputs_enabled(), "at {t} ms");
    }
    ack(ask(
        &mut dev,
        8,
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 0,
            action: LinkLossAction::Disable,
        }),
    ));
    clock.set_ms(u32::MAX);
    dev.poll();
    assert!(dev.outputs_enabled());
}

#[test]
fn calibration_changes_are_checked_against_the_held_angle() {
    let mut dev = device(Config::fernando2025());
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let s = ServoId {
        leg: LegId::RR,
        joint: Joint::Knee,
    };
    let old = dev.calibration()[s.index()];
    let bad = Calibration {
        us_per_rad: f32::NAN,
        ..old
    };
    assert_eq!(
        nack_reason(ask(
            &mut dev,
            2,
            Request::SetCalibration {
                servo: s,
                calibration: bad
            }
        )),
        NackReason::BadCalibration(servo::Error::BadGain)
    );
    // A travel that excludes the held knee angle.
    let excluding = Calibration {
        zero_rad: old.zero_rad + 1.0,
        min_us: 1400,
        max_us: 1600,
        ..old
    };
    assert!(matches!(
        nack_reason(ask(
            &mut dev,
            3,
            Request::SetCalibration {
                servo: s,
                calibration: excluding
            }
        )),
        NackReason::ServoRange {
            leg: LegId::RR,
            joint: Joint::Knee,
            ..
        }
    ));
    assert_eq!(dev.calibration()[s.index()], old);
    // A 20 µs trim is taken and drives at once.
    let trimmed = Calibration {
        center_us: 1520,
        ..old
    };
    let rb = ack(ask(
        &mut dev,
        4,
        Request::SetCalibration {
            servo: s,
            calibration: trimmed,
        },
    ));
    assert_eq!(rb.pulses_half_us[s.index()], 3040);
    assert!(rb.flags.contains(Flags::CALIBRATION_UNSAVED));
    assert_eq!(dev.outputs().writes().last(), Some(&rb.pulses_half_us));
    match ask(&mut dev, 5, Request::GetCalibration { servo: s }) {
        DeviceToHost::Calibration { calibration, .. } => assert_eq!(calibration, trimmed),
        other => panic!("{other:?}"),
    }
    assert_writes_in_travel(&dev);
}

#[test]
fn a_refused_calibration_leaves_the_held_pulses_as_they_were() {
    // The outputs on their way to a new knee target: a travel that admits the target but not
    // where the output is now is refused, and the readback's pulses stay the old mapping's.
    let clock = VirtualClock::default();
    let mut dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        clock.clone(),
        RamEeprom::erased(),
    )
    .unwrap();
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    clock.set_ms(25); // Past the enabling frame: new targets go through the limiter.
    dev.poll();
    let s = ServoId {
        leg: LegId::RR,
        joint: Joint::Knee,
    };
    let i = s.index();
    let mut angles_rad = ack(ask(&mut dev, 2, Request::GetState)).angles_rad;
    let now_rad = angles_rad[i];
    angles_rad[i] = now_rad - 0.5;
    let before = ack(ask(&mut dev, 3, Request::SetJoints { angles_rad }));
    assert_eq!(dev.output_angles().unwrap()[i], now_rad, "not there yet");
    let old = dev.calibration()[i];
    // Zero at the target: the target maps to the centre, the output's angle 0.5 rad away.
    let narrow = Calibration {
        zero_rad: angles_rad[i],
        min_us: old.center_us - 100,
        max_us: old.center_us + 100,
        ..old
    };
    assert!(narrow.pulse_half_us(angles_rad[i]).is_ok());
    assert!(narrow.pulse_half_us(now_rad).is_err());
    assert!(matches!(
        nack_reason(ask(
            &mut dev,
            4,
            Request::SetCalibration {
                servo: s,
                calibration: narrow
            }
        )),
        NackReason::ServoRange { .. }
    ));
    let after = ack(ask(&mut dev, 5, Request::GetState));
    assert_eq!(after.pulses_half_us, before.pulses_half_us);
    assert_eq!(dev.calibration()[i], old);
}

#[test]
fn saved_calibration_survives_a_power_cycle() {
    let mut dev = device(Config::fernando2025());
    hello(&mut dev);
    let s = ServoId::ALL[7];
    let trimmed = Calibration {
        center_us: 1480,
        ..dev.calibration()[7]
    };
    ack(ask(
        &mut dev,
        1,
        Request::SetCalibration {
            servo: s,
            calibration: trimmed,
        },
    ));
    let rb = ack(ask(&mut dev, 2, Request::SaveCalibration));
    assert!(!rb
        .flags
        .contains(Flags::CALIBRATION_UNSAVED | Flags::CALIBRATION_DEFAULT));
    let table = *dev.calibration();
    let (_, clock, storage) = dev.into_parts();
    let mut dev2 = Device::new(Config::fernando2025(), Outputs::logging(), clock, storage).unwrap();
    assert_eq!(dev2.calibration(), &table);
    let rb = ack(ask(&mut dev2, 3, Request::GetState));
    assert!(!rb.flags.contains(Flags::CALIBRATION_DEFAULT));
}

#[test]
fn a_failing_storage_is_nacked_and_keeps_the_ram_table() {
    let mut mem = RamEeprom::erased();
    mem.write_budget = Some(3);
    let mut dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        VirtualClock::default(),
        mem,
    )
    .unwrap();
    hello(&mut dev);
    let table = *dev.calibration();
    assert_eq!(
        nack_reason(ask(&mut dev, 1, Request::SaveCalibration)),
        NackReason::Storage
    );
    assert_eq!(dev.calibration(), &table);
    let rb = ack(ask(&mut dev, 2, Request::GetState));
    assert!(rb.flags.contains(Flags::CALIBRATION_DEFAULT));
}

#[test]
fn readback_angles_are_finite_and_zero_when_nothing_is_held() {
    // A calibration whose travel excludes the stance: nothing is held at power-on.
    let mut mem = RamEeprom::erased();
    {
        let mut dev = Device::new(
            Config::fernando2025(),
            Outputs::logging(),
            VirtualClock::default(),
            &mut mem,
        )
        .unwrap();
        let mut seq = 0;
        let mut send = |dev: &mut Device<_, _, _>, r| {
            seq += 1;
            let mut wire = Vec::new();
            dev.receive(&frame(seq, r), |f| wire.extend_from_slice(f));
            decode_all(&wire)
        };
        send(
            &mut dev,
            Request::Hello {
                version: quad_protocol::PROTOCOL_VERSION,
            },
        );
        // Move the held knee first so that the new calibration admits it, then save a travel
        // that excludes the stance knee.
        let mut q = dev.readback().angles_rad;
        q[2] = -2.0;
        send(&mut dev, Request::SetJoints { angles_rad: q });
        let c = Calibration {
            zero_rad: -2.0,
            min_us: 1400,
            max_us: 1600,
            ..Calibration::STANDARD
        };
        let a = send(
            &mut dev,
            Request::SetCalibration {
                servo: ServoId::ALL[2],
                calibration: c,
            },
        );
        assert!(
            matches!(
                a[0],
                DeviceToHost::Configured {
                    setting: quad_protocol::Setting::Calibration { calibration, .. },
                    ..
                } if calibration == c
            ),
            "{a:?}"
        );
        let a = send(&mut dev, Request::SaveCalibration);
        assert!(matches!(a[0], DeviceToHost::Ack { .. }), "{a:?}");
    }
    let mut dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        VirtualClock::default(),
        mem,
    )
    .unwrap();
    hello(&mut dev);
    let rb = ack(ask(&mut dev, 1, Request::GetState));
    assert_eq!(rb.angles_rad, [0.0; 12]);
    assert_eq!(
        nack_reason(ask(&mut dev, 2, Request::SetOutputs { enabled: true })),
        NackReason::InvalidArgument
    );
    assert!(dev.outputs().writes().is_empty() && !dev.outputs().enabled);
}

#[test]
fn configuration_requests_echo_what_was_applied() {
    let config = Config::fernando2025();
    let mut dev = device(config);
    hello(&mut dev);
    let t = LinkTimeout {
        timeout_ms: 321,
        action: LinkLossAction::Disable,
    };
    let p = PoseConfig {
        stance_height_m: 0.8,
        ..config.pose_config
    };
    let servo = ServoId::ALL[7];
    let c = Calibration {
        center_us: 1510,
        ..dev.calibration()[servo.index()]
    };
    let cases = [
        (Request::SetLinkTimeout(t), Setting::LinkTimeout(t)),
        (Request::SetPoseConfig(p), Setting::PoseConfig(p)),
        (
            Request::SetCalibration {
                servo,
                calibration: c,
            },
            Setting::Calibration {
                servo,
                calibration: c,
            },
        ),
    ];
    for (seq, (request, want)) in (10..).zip(cases) {
        assert_eq!(Setting::of_request(&request), Some(want));
        match ask(&mut dev, seq, request) {
            DeviceToHost::Configured {
                seq: s,
                setting,
                readback,
            } => {
                assert_eq!((s, setting), (seq, want));
                assert_eq!(readback, dev.readback());
            }
            other => panic!("{request:?}: {other:?}"),
        }
    }
    assert_eq!(dev.config().link_timeout, t);
    assert_eq!(dev.config().pose_config, p);
    assert_eq!(dev.calibration()[servo.index()], c);
}

#[test]
fn finite_values_out_of_range_are_named_and_move_nothing() {
    let mut dev = device(Config::fernando2025());
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let before = ack(ask(&mut dev, 2, Request::SetBodyPose(POSE)));
    let writes = dev.outputs().writes().len();
    let cases = [
        (
            Request::SetBodyPose(Pose {
                yaw_rad: 1e38,
                ..POSE
            }),
            Field::BodyYaw,
        ),
        (
            Request::SetBodyPose(Pose {
                x_m: -3.4e38,
                ..POSE
            }),
            Field::BodyX,
        ),
        (
            Request::SetFeet {
                feet_in_body_m: [
                    [0.5, 0.25, -0.9],
                    [0.5, -0.25, -0.9],
                    [9e9, 0.0, 0.0],
                    [-0.5, -0.25, -0.9],
                ],
            },
            Field::Foot(LegId::RL),
        ),
        (
            Request::SetJoints {
                angles_rad: [0.0, 0.0, 7.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            },
            Field::JointAngle {
                leg: LegId::FL,
                joint: Joint::Knee,
            },
        ),
        (
            Request::SetPoseConfig(PoseConfig {
                stance_height_m: 3.4e38,
                ..Config::fernando2025().pose_config
            }),
            Field::StanceHeight,
        ),
        (
            Request::SetPoseConfig(PoseConfig {
                stance_height_m: 1e-45,
                ..Config::fernando2025().pose_config
            }),
            Field::StanceHeight,
        ),
    ];
    for (seq, (request, field)) in (3..).zip(cases) {
        assert_eq!(
            nack_reason(ask(&mut dev, seq, request)),
            NackReason::OutOfRange { field },
            "{request:?}"
        );
        // The host's check gives the same answer.
        assert_eq!(
            quad_protocol::check_request(&request, &dev.config().robot),
            Err(NackReason::OutOfRange { field })
        );
    }
    let after = ack(ask(&mut dev, 20, Request::GetState));
    assert_eq!(after.angles_rad, before.angles_rad);
    assert_eq!(dev.outputs().writes().len(), writes);
    assert_eq!(dev.config().pose_config, Config::fernando2025().pose_config);
}

#[test]
fn the_failsafe_flag_is_latched_until_an_answer_reports_it() {
    let (mut dev, clock) = failsafe_case(LinkLossAction::Hold);
    clock.set_ms(5_000);
    dev.poll();
    // Answers without a readback do not clear it.
    assert!(matches!(
        ask(
            &mut dev,
            4,
            Request::GetCalibration {
                servo: ServoId::ALL[0]
            }
        ),
        DeviceToHost::Calibration { .. }
    ));
    assert!(matches!(
        ask(
            &mut dev,
            5,
            Request::Hello {
                version: quad_protocol::PROTOCOL_VERSION
            }
        ),
        DeviceToHost::HelloAck { .. }
    ));
    assert!(matches!(
        ask(
            &mut dev,
            6,
            Request::SetBodyPose(Pose {
                roll_rad: 9.0,
                ..POSE
            })
        ),
        DeviceToHost::Nack { .. }
    ));
    let rb = ack(ask(&mut dev, 7, Request::GetState));
    assert!(rb.flags.contains(Flags::FAILSAFE_ACTIVE), "{rb:?}");
    // Reported once.
    let rb = ack(ask(&mut dev, 8, Request::GetState));
    assert!(!rb.flags.contains(Flags::FAILSAFE_ACTIVE), "{rb:?}");
}

#[test]
fn nacks_of_unreadable_frames_are_rate_limited() {
    let clock = VirtualClock::default();
    let mut dev = Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        clock.clone(),
        RamEeprom::erased(),
    )
    .unwrap();
    hello(&mut dev);
    let garbage = [0x00, 0x07, 0x41, 0x42, 0x00];
    let mut burst = Vec::new();
    for _ in 0..50 {
        burst.extend_from_slice(&garbage);
    }
    burst.extend(frame(9, Request::GetState));
    let answers = feed(&mut dev, &burst);
    // One nack for the 50 bad frames, then the answer to the valid one.
    assert_eq!(answers.len(), 2, "{answers:?}");
    assert!(matches!(
        answers[0],
        DeviceToHost::Nack {
            seq: None,
            reason: NackReason::BadFrame
        }
    ));
    let DeviceToHost::Ack { seq: 9, readback } = answers[1] else {
        panic!("{answers:?}");
    };
    assert_eq!(readback.frames_bad, 50);
    // Within the interval: counted only; after it, answered again.
    clock.set_ms(quad_device::device::FRAMING_NACK_INTERVAL_MS - 1);
    assert!(feed(&mut dev, &garbage).is_empty());
    clock.set_ms(quad_device::device::FRAMING_NACK_INTERVAL_MS);
    assert_eq!(feed(&mut dev, &garbage).len(), 1);
}

/// A host that sends a new, distant target early in every PWM period (each request's write is
/// then still pending when the device next polls) gets its targets through the joint-speed
/// limiter from the second period after enabling on: only the enabling frame writes a target at
/// once. (Once, the enabling frame lasted as long as such a stream: the frame that ends it
/// never ran while a write was pending, and every target was written at once.)
#[test]
fn a_target_every_period_goes_through_the_limiter_after_the_enabling_frame() {
    let periods = PwmPeriods::starting_at(100);
    let config = Config::fernando2025();
    let mut dev = Device::new(
        config,
        Outputs::logging().latched(periods.clone()),
        VirtualClock::default(),
        RamEeprom::erased(),
    )
    .unwrap();
    hello(&mut dev);
    let pose = |k: u32| Pose::rotation(if k.is_multiple_of(2) { 0.25 } else { -0.25 }, 0.0, 0.0);
    ack(ask(&mut dev, 1, Request::SetBodyPose(pose(0))));
    ack(ask(&mut dev, 2, Request::SetOutputs { enabled: true }));
    dev.poll();
    // The limiter's step in half-µs of the widest gain, with the rounding of both pulses.
    let gain = dev
        .calibration()
        .iter()
        .map(|c| c.us_per_rad)
        .fold(0.0f32, f32::max);
    let bound_half_us = 2.0 * gain * config.joint_speed_limit_rad_s * 0.02 + 1.0;
    for k in 1..40 {
        periods.begin();
        ack(ask(&mut dev, 2 + k as u16, Request::SetBodyPose(pose(k))));
        dev.poll();
    }
    let writes = &dev.outputs().writes();
    assert!(writes.len() > 10, "{} writes", writes.len());
    for (w, pair) in writes.windows(2).enumerate() {
        for (ch, (&a, &b)) in pair[0].iter().zip(&pair[1]).enumerate() {
            let step = (f32::from(b) - f32::from(a)).abs();
            assert!(
                step <= bound_half_us,
                "write {w}, channel {ch}: {step} half-µs at once (limiter {bound_half_us})"
            );
        }
    }
}

/// A retry (the same frame again, its answer lost) gets the same answer and does not act
/// again: the save writes the storage once, the motion starts once; a repeated `seq` with
/// other bytes, or the first frame again after another request, is a new request.
#[test]
fn an_exact_repeat_is_answered_again_without_acting() {
    let mut dev = device(Config::shahriar2023());
    hello(&mut dev);
    ack(ask(&mut dev, 1, Request::SetOutputs { enabled: true }));
    let save = frame(2, Request::SaveCalibration);
    let first = feed(&mut dev, &save);
    let written = dev.storage().written;
    assert!(written > 0, "the save wrote");
    let again = feed(&mut dev, &save);
    assert_eq!(again, first);
    assert_eq!(dev.storage().written, written, "the retry wrote again");
    let sway = |amplitude_rad| {
        Request::StartMotion(quad_protocol::MotionCommand::Sway {
            axis: kin_core::motion::laws::Axis::Roll,
            amplitude_rad,
            period_s: 2.0,
            duration_s: None,
        })
    };
    let start = frame(3, sway(0.05));
    let started = feed(&mut dev, &start);
    assert!(
        matches!(started[..], [DeviceToHost::MotionAck { .. }]),
        "{started:?}"
    );
    assert_eq!(feed(&mut dev, &start), started);
    assert_eq!(
        nack_reason(ask(&mut dev, 3, sway(0.06))),
        NackReason::MotionRunning
    );
    assert_eq!(
        nack_reason(feed(&mut dev, &start)[0]),
        NackReason::MotionRunning
    );
}
