//! One example of every message with its postcard bytes written by hand from the postcard wire
//! format: varint u16/u32 (7 bits per byte, least significant group first, high bit = more),
//! f32 as 4 bytes little-endian, enum variant index as a varint, bool and option tags as one
//! byte, fixed arrays without a length, struct fields in declaration order.
//! Shared by the golden tests.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{Joint, LegId, Pose, ReachPolicy, RotationOrder};
use quad_protocol::{
    servo, BalanceConfig, DeviceInfo, DeviceToHost, FallKind, FaultAction, Field, FirmwareVersion,
    Flags, HostToDevice, ImuFaultKind, ImuHealth, ImuReport, LegSet, LinkLossAction, LinkTimeout,
    MotionCommand, MotionKind, MotionParam, MotionStage, MotionStatus, NackReason, ParamProblem,
    PoseConfig, PreflightFault, ReachFault, Readback, Request, RobotPreset, SafeState, ServoId,
    Setting,
};

pub fn h2d(seq: u16, request: Request) -> HostToDevice {
    HostToDevice { seq, request }
}

/// A calibration with exactly representable values.
pub const CAL: servo::Calibration = servo::Calibration {
    zero_rad: 0.0625,
    reversed: true,
    us_per_rad: 640.0,
    center_us: 1520,
    min_us: 1000,
    max_us: 2000,
};

/// Every request with its postcard bytes.
pub fn requests() -> Vec<(&'static str, HostToDevice, &'static str)> {
    vec![
        (
            "Hello",
            // seq 1 | variant 0 | version 0x0100 = varint 80 02
            h2d(1, Request::Hello { version: 0x0100 }),
            "01 00 80 02",
        ),
        (
            "GetState",
            // seq 300 = varint ac 02 | variant 1
            h2d(300, Request::GetState),
            "ac 02 01",
        ),
        (
            "SetBodyPose",
            // seq 2 | variant 2 | roll 0.1, pitch -0.05, yaw 0, x 0.5, y -0.25, z 0.125
            h2d(
                2,
                Request::SetBodyPose(Pose {
                    roll_rad: 0.1,
                    pitch_rad: -0.05,
                    yaw_rad: 0.0,
                    x_m: 0.5,
                    y_m: -0.25,
                    z_m: 0.125,
                }),
            ),
            "02 02 cd cc cc 3d cd cc 4c bd 00 00 00 00 00 00 00 3f 00 00 80 be 00 00 00 3e",
        ),
        (
            "SetFeet",
            // seq 3 | variant 3 | FL (0.5, 0.25, -1), FR (0.5, -0.25, -1), RL (-0.5, 0.25, -1),
            // RR (-0.5, -0.25, -1)
            h2d(
                3,
                Request::SetFeet {
                    feet_in_body_m: [
                        [0.5, 0.25, -1.0],
                        [0.5, -0.25, -1.0],
                        [-0.5, 0.25, -1.0],
                        [-0.5, -0.25, -1.0],
                    ],
                },
            ),
            "03 03 \
             00 00 00 3f 00 00 80 3e 00 00 80 bf \
             00 00 00 3f 00 00 80 be 00 00 80 bf \
             00 00 00 bf 00 00 80 3e 00 00 80 bf \
             00 00 00 bf 00 00 80 be 00 00 80 bf",
        ),
        (
            "SetJoints",
            // seq 4 | variant 4 | per leg (0, 0.5, -1)
            h2d(
                4,
                Request::SetJoints {
                    angles_rad: [
                        0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
                    ],
                },
            ),
            "04 04 \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf",
        ),
        (
            "SetOutputs",
            // seq 5 | variant 5 | true
            h2d(5, Request::SetOutputs { enabled: true }),
            "05 05 01",
        ),
        (
            "SetLinkTimeout",
            // seq 6 | variant 6 | 500 ms = varint f4 03 | Disable = 1
            h2d(
                6,
                Request::SetLinkTimeout(LinkTimeout {
                    timeout_ms: 500,
                    action: LinkLossAction::Disable,
                }),
            ),
            "06 06 f4 03 01",
        ),
        (
            "SetCalibration",
            // seq 7 | variant 7 | FR = 1, knee = 2 | zero 0.0625 | reversed | 640.0 |
            // center 1520 = f0 0b | min 1000 = e8 07 | max 2000 = d0 0f
            h2d(
                7,
                Request::SetCalibration {
                    servo: ServoId {
                        leg: LegId::FR,
                        joint: Joint::Knee,
                    },
                    calibration: CAL,
                },
            ),
            "07 07 01 02 00 00 80 3d 01 00 00 20 44 f0 0b e8 07 d0 0f",
        ),
        (
            "GetCalibration",
            // seq 8 | variant 8 | RL = 2, hip = 1
            h2d(
                8,
                Request::GetCalibration {
                    servo: ServoId {
                        leg: LegId::RL,
                        joint: Joint::Hip,
                    },
                },
            ),
            "08 08 02 01",
        ),
        (
            "SaveCalibration",
            // seq 9 | variant 9
            h2d(9, Request::SaveCalibration),
            "09 09",
        ),
        (
            "SetPoseConfig",
            // seq 10 | variant 10 | 0.25 m | Zxy = 4 | Clamp = 1
            h2d(
                10,
                Request::SetPoseConfig(PoseConfig {
                    stance_height_m: 0.25,
                    order: RotationOrder::Zxy,
                    policy: ReachPolicy::Clamp,
                }),
            ),
            "0a 0a 00 00 80 3e 04 01",
        ),
        (
            "StartMotion StandUp",
            // seq 11 | variant 11 | StandUp = 0
            h2d(11, Request::StartMotion(MotionCommand::StandUp)),
            "0b 0b 00",
        ),
        (
            "StartMotion Sway",
            // seq 12 | variant 11 | Sway = 3 | Pitch = 1 | A 0.25 | T 20 | Some = 1, 40 s
            h2d(
                12,
                Request::StartMotion(MotionCommand::Sway {
                    axis: Axis::Pitch,
                    amplitude_rad: 0.25,
                    period_s: 20.0,
                    duration_s: Some(40.0),
                }),
            ),
            "0c 0b 03 01 00 00 80 3e 00 00 a0 41 01 00 00 20 42",
        ),
        (
            "StartMotion YawTurn",
            // seq 13 | variant 11 | YawTurn = 4 | 0.125 rad/s | T1 6 s | lift 0.0625 m | None
            h2d(
                13,
                Request::StartMotion(MotionCommand::YawTurn {
                    yaw_rate_rad_s: 0.125,
                    step_period_s: 6.0,
                    lift_height_m: 0.0625,
                    duration_s: None,
                }),
            ),
            "0d 0b 04 00 00 00 3e 00 00 c0 40 00 00 80 3d 00",
        ),
        (
            "StartMotion FootPath",
            // seq 14 | variant 11 | FootPath = 5 | Rectangle = 0 | One = 1, RL = 2 | stride
            // 0.125 m | lift 0.0625 m | duty 0.75 | cycle 3 s | Some = 1, 6 s
            h2d(
                14,
                Request::StartMotion(MotionCommand::FootPath {
                    path: PathKind::Rectangle,
                    legs: LegSet::One(LegId::RL),
                    stride_m: 0.125,
                    step_height_m: 0.0625,
                    duty_factor: 0.75,
                    cycle_s: 3.0,
                    duration_s: Some(6.0),
                }),
            ),
            "0e 0b 05 00 01 02 00 00 00 3e 00 00 80 3d 00 00 40 3f 00 00 40 40 01 00 00 c0 40",
        ),
        (
            "StartMotion Walk",
            // seq 15 | variant 11 | Walk = 6 | Trot = 0 | body 0.25 m | step 0.0625 m | cycle
            // 0.5 s | timeout 500 ms = f4 03
            h2d(
                15,
                Request::StartMotion(MotionCommand::Walk {
                    gait: Pattern::Trot,
                    body_height_m: 0.25,
                    step_height_m: 0.0625,
                    cycle_s: 0.5,
                    velocity_timeout_ms: 500,
                }),
            ),
            "0f 0b 06 00 00 00 80 3e 00 00 80 3d 00 00 00 3f f4 03",
        ),
        (
            "StopMotion",
            // seq 16 | variant 12
            h2d(16, Request::StopMotion),
            "10 0c",
        ),
        (
            "GetMotion",
            // seq 17 | variant 13
            h2d(17, Request::GetMotion),
            "11 0d",
        ),
        (
            "SetVelocity",
            // seq 18 | variant 14 | forward 0.125 m/s | lateral -0.0625 m/s | yaw 0.25 rad/s
            h2d(
                18,
                Request::SetVelocity {
                    forward_m_s: 0.125,
                    lateral_m_s: -0.0625,
                    yaw_rate_rad_s: 0.25,
                },
            ),
            "12 0e 00 00 00 3e 00 00 80 bd 00 00 80 3e",
        ),
        (
            "SetJointSpeedLimit",
            // seq 19 | variant 15 | 2.5 rad/s
            h2d(
                19,
                Request::SetJointSpeedLimit {
                    joint_speed_limit_rad_s: 2.5,
                },
            ),
            "13 0f 00 00 20 40",
        ),
        (
            "SetBalance",
            // seq 20 | variant 16 | leveling 1 | kp 0.25 | ki 4 | bound 0.25 | detection 1 |
            // angle 1 | Off = 1 | Stop = 1
            h2d(20, Request::SetBalance(BALANCE)),
            "14 10 01 00 00 80 3e 00 00 80 40 00 00 80 3e 01 00 00 80 3f 01 01",
        ),
        (
            "GetImu",
            // seq 21 | variant 17
            h2d(21, Request::GetImu),
            "15 11",
        ),
    ]
}

/// Balance settings with exactly representable values.
pub const BALANCE: BalanceConfig = BalanceConfig {
    leveling: true,
    level_kp: 0.25,
    level_ki_per_s: 4.0,
    max_correction_rad: 0.25,
    fall_detection: true,
    fall_angle_rad: 1.0,
    safe_state: SafeState::Off,
    on_fault: FaultAction::Stop,
};

/// Every answer (and the nack layouts with fields) with its postcard bytes.
pub fn answers() -> Vec<(&'static str, DeviceToHost, &'static str)> {
    vec![
        (
            "Nack UnknownVersion",
            // variant 0 | Some = 1, seq 1 | reason 0 | supported 0x0100 = 80 02
            DeviceToHost::Nack {
                seq: Some(1),
                reason: NackReason::UnknownVersion { supported: 0x0100 },
            },
            "00 01 01 00 80 02",
        ),
        (
            "Nack BadCrc",
            // variant 0 | None = 0 | reason 1
            DeviceToHost::Nack {
                seq: None,
                reason: NackReason::BadCrc,
            },
            "00 00 01",
        ),
        (
            "Nack Unreachable",
            // variant 0 | Some, seq 11 | reason 5 | RR = 3 | TooFar = 0
            DeviceToHost::Nack {
                seq: Some(11),
                reason: NackReason::Unreachable {
                    leg: LegId::RR,
                    fault: ReachFault::TooFar,
                },
            },
            "00 01 0b 05 03 00",
        ),
        (
            "Nack JointLimit",
            // variant 0 | Some, seq 13 | reason 6 | FR = 1 | hip = 1
            DeviceToHost::Nack {
                seq: Some(13),
                reason: NackReason::JointLimit {
                    leg: LegId::FR,
                    joint: Joint::Hip,
                },
            },
            "00 01 0d 06 01 01",
        ),
        (
            "Nack ServoRange",
            // variant 0 | Some, seq 12 | reason 7 | FL = 0 | knee = 2 | AboveMax = 2
            DeviceToHost::Nack {
                seq: Some(12),
                reason: NackReason::ServoRange {
                    leg: LegId::FL,
                    joint: Joint::Knee,
                    fault: servo::Error::AboveMax,
                },
            },
            "00 01 0c 07 00 02 02",
        ),
        (
            "Nack BadCalibration",
            // variant 0 | Some, seq 14 | reason 9 | BadGain = 4
            DeviceToHost::Nack {
                seq: Some(14),
                reason: NackReason::BadCalibration(servo::Error::BadGain),
            },
            "00 01 0e 09 04",
        ),
        (
            "Nack OutOfRange",
            // variant 0 | Some, seq 15 | reason 14 = 0e | Foot = 6 | RL = 2
            DeviceToHost::Nack {
                seq: Some(15),
                reason: NackReason::OutOfRange {
                    field: Field::Foot(LegId::RL),
                },
            },
            "00 01 0f 0e 06 02",
        ),
        (
            "HelloAck",
            // variant 1 | seq 1 | version 80 02 | fw 0.1.0 | Fernando2025 = 1 | 128 = 80 01 |
            // 0.5 m, Zyx = 5, Reject = 0 | 250 ms = fa 01, Hold = 0
            DeviceToHost::HelloAck {
                seq: 1,
                info: DeviceInfo {
                    version: 0x0100,
                    firmware: FirmwareVersion {
                        major: 0,
                        minor: 1,
                        patch: 0,
                    },
                    robot: RobotPreset::Fernando2025,
                    max_frame_len: 128,
                    pose_config: PoseConfig {
                        stance_height_m: 0.5,
                        order: RotationOrder::Zyx,
                        policy: ReachPolicy::Reject,
                    },
                    link_timeout: LinkTimeout {
                        timeout_ms: 250,
                        action: LinkLossAction::Hold,
                    },
                    robot_hash: None,
                },
            },
            "01 01 80 02 00 01 00 01 80 01 00 00 00 3f 05 00 fa 01 00",
        ),
        (
            "Ack",
            // variant 2 | seq 2 | 12 angles | pulses 3000 = b8 17, 4000 = a0 1f, 2000 = d0 0f,
            // 0 = 00 | flags 0x05 | frames_ok 1000 = e8 07 | frames_bad 3
            DeviceToHost::Ack {
                seq: 2,
                readback: Readback {
                    angles_rad: [
                        0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
                    ],
                    pulses_half_us: [
                        3000, 4000, 2000, 3000, 4000, 2000, 3000, 4000, 2000, 3000, 4000, 0,
                    ],
                    flags: Flags(Flags::CLAMPED | Flags::OUTPUTS_ENABLED),
                    frames_ok: 1000,
                    frames_bad: 3,
                },
            },
            "02 02 \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             00 00 00 00 00 00 00 3f 00 00 80 bf \
             b8 17 a0 1f d0 0f b8 17 a0 1f d0 0f b8 17 a0 1f d0 0f b8 17 a0 1f 00 \
             05 e8 07 03",
        ),
        (
            "Calibration",
            // variant 3 | seq 3 | FR = 1, knee = 2 | the calibration of SetCalibration
            DeviceToHost::Calibration {
                seq: 3,
                servo: ServoId {
                    leg: LegId::FR,
                    joint: Joint::Knee,
                },
                calibration: CAL,
            },
            "03 03 01 02 00 00 80 3d 01 00 00 20 44 f0 0b e8 07 d0 0f",
        ),
        (
            "Configured",
            // variant 4 | seq 6 | setting LinkTimeout = 0 | 250 ms = fa 01, Disable = 1 |
            // readback: 12 angles 0 | pulses 3000 = b8 17 | flags 0x08 | frames_ok 7 | bad 0
            DeviceToHost::Configured {
                seq: 6,
                setting: Setting::LinkTimeout(LinkTimeout {
                    timeout_ms: 250,
                    action: LinkLossAction::Disable,
                }),
                readback: Readback {
                    angles_rad: [0.0; 12],
                    pulses_half_us: [3000; 12],
                    flags: Flags(Flags::FAILSAFE_ACTIVE),
                    frames_ok: 7,
                    frames_bad: 0,
                },
            },
            "04 06 00 fa 01 01 \
             00 00 00 00 00 00 00 00 00 00 00 00 \
             00 00 00 00 00 00 00 00 00 00 00 00 \
             00 00 00 00 00 00 00 00 00 00 00 00 \
             00 00 00 00 00 00 00 00 00 00 00 00 \
             b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 \
             08 07 00",
        ),
        (
            "Nack InvalidParameter",
            // variant 0 | Some, seq 15 | reason 15 | CycleS = 9 | NotPositive = 1
            DeviceToHost::Nack {
                seq: Some(15),
                reason: NackReason::InvalidParameter {
                    param: MotionParam::CycleS,
                    problem: ParamProblem::NotPositive,
                },
            },
            "00 01 0f 0f 09 01",
        ),
        (
            "Nack Preflight",
            // variant 0 | Some, seq 16 | reason 16 | FR = 1 | JointLimit = 1, knee = 2
            DeviceToHost::Nack {
                seq: Some(16),
                reason: NackReason::Preflight {
                    leg: LegId::FR,
                    fault: PreflightFault::JointLimit(Joint::Knee),
                },
            },
            "00 01 10 10 01 01 02",
        ),
        (
            "Nack MotionRunning",
            // variant 0 | Some, seq 17 | reason 17
            DeviceToHost::Nack {
                seq: Some(17),
                reason: NackReason::MotionRunning,
            },
            "00 01 11 11",
        ),
        (
            "MotionAck",
            // variant 5 | seq 4 | Some = 1, Walk = 6 | Stopping = 2 | t 12.5 s | phase 0.25 |
            // fault None = 0 | 12 angles 0.5 | pulses 3000 = b8 17 | flags 0x04 | frames_ok 5 |
            // frames_bad 0
            DeviceToHost::MotionAck {
                seq: 4,
                status: MotionStatus {
                    kind: Some(MotionKind::Walk),
                    stage: MotionStage::Stopping,
                    t_s: 12.5,
                    phase: 0.25,
                    fault: None,
                },
                readback: Readback {
                    angles_rad: [0.5; 12],
                    pulses_half_us: [3000; 12],
                    flags: Flags(Flags::OUTPUTS_ENABLED),
                    frames_ok: 5,
                    frames_bad: 0,
                },
                frames: None,
            },
            "05 04 01 06 02 00 00 48 41 00 00 80 3e 00 \
             00 00 00 3f 00 00 00 3f 00 00 00 3f 00 00 00 3f \
             00 00 00 3f 00 00 00 3f 00 00 00 3f 00 00 00 3f \
             00 00 00 3f 00 00 00 3f 00 00 00 3f 00 00 00 3f \
             b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 b8 17 \
             04 05 00",
        ),
        (
            "Imu",
            // variant 6 | seq 5 | Fault = 3, Nak = 1 | roll 0.25 | pitch -0.5 | corrections
            // -0.25, 0.5 | active 1 | limited 0 | Some = 1, Tilt = 0 | samples 300 = ac 02 |
            // the settings of `BALANCE`
            DeviceToHost::Imu {
                seq: 5,
                report: ImuReport {
                    health: ImuHealth::Fault(ImuFaultKind::Nak),
                    roll_rad: 0.25,
                    pitch_rad: -0.5,
                    correction_roll_rad: -0.25,
                    correction_pitch_rad: 0.5,
                    leveling_active: true,
                    correction_limited: false,
                    fall: Some(FallKind::Tilt),
                    samples: 300,
                    config: BALANCE,
                },
            },
            "06 05 03 01 00 00 80 3e 00 00 00 bf 00 00 80 be 00 00 00 3f 01 00 01 00 ac 02 \
             01 00 00 80 3e 00 00 80 40 00 00 80 3e 01 00 00 80 3f 01 01",
        ),
        (
            "Nack NotUpright",
            // variant 0 | Some, seq 18 | reason 21
            DeviceToHost::Nack {
                seq: Some(18),
                reason: NackReason::NotUpright,
            },
            "00 01 12 15",
        ),
    ]
}
