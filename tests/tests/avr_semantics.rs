//! What docs/protocol.md ("Device behaviour") says the device does, on the firmware in simavr:
//! the version a `HelloAck` reports, what may start while the outputs are off, the rest pose,
//! the joint-speed limiter (per joint for a direct setpoint, one synchronised ramp for a
//! motion's start), seen on the pins, which frame a readback describes, the idle motion status
//! (2.2 and older hosts), the frame numbers of 2.3 (to a 2.3 host only) and a watchdog reset
//! mid-trot. Simulated time.

use integration_tests::wire;
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::{DeviceToHost, LegSet, MotionCommand, NackReason, Request, PROTOCOL_VERSION};
use std::time::Duration;

const PATIENCE: Duration = Duration::from_millis(500);

fn boot() -> EmulatorLink {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    EmulatorLink::boot(&elf, EmulatorConfig::new(115_200)).unwrap_or_else(|e| panic!("{e}"))
}

/// Sends `request` with sequence number `seq` and returns its one answer.
fn ask(link: &mut EmulatorLink, seq: u16, request: Request) -> DeviceToHost {
    wire::ask(link, seq, request, PATIENCE)
}

fn hello(link: &mut EmulatorLink) -> quad_protocol::DeviceInfo {
    match ask(
        link,
        0,
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
    ) {
        DeviceToHost::HelloAck { info, .. } => info,
        other => panic!("Hello: {other:?}"),
    }
}

/// Polls `GetMotion` (sequence numbers from `seq` on) until no motion runs.
fn wait_idle(link: &mut EmulatorLink, seq: &mut u16) {
    for _ in 0..400 {
        link.idle(Duration::from_millis(50)).expect("runs");
        *seq += 1;
        match ask(link, *seq, Request::GetMotion) {
            DeviceToHost::MotionAck { status, .. } if status.kind.is_none() => return,
            DeviceToHost::MotionAck { .. } => {}
            other => panic!("GetMotion: {other:?}"),
        }
    }
    panic!("the motion did not end");
}

#[test]
fn hello_ack_reports_the_device_version_whatever_the_host_minor() {
    let mut link = boot();
    for (seq, host) in [(1, 0x0200u16), (2, 0x0201), (3, 0x02ff)] {
        match ask(&mut link, seq, Request::Hello { version: host }) {
            DeviceToHost::HelloAck { info, .. } => assert_eq!(info.version, PROTOCOL_VERSION),
            other => panic!("Hello {host:#06x}: {other:?}"),
        }
    }
    assert_eq!(
        ask(&mut link, 4, Request::Hello { version: 0x0100 }),
        DeviceToHost::Nack {
            seq: Some(4),
            reason: NackReason::UnknownVersion {
                supported: PROTOCOL_VERSION
            }
        }
    );
}

#[test]
fn with_the_outputs_off_only_stand_up_starts_and_setpoints_are_held_with_no_pulse() {
    let mut link = boot();
    hello(&mut link);
    let refused = [
        MotionCommand::Sit,
        MotionCommand::Rest,
        MotionCommand::Sway {
            axis: kin_core::motion::laws::Axis::Roll,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: None,
        },
        MotionCommand::YawTurn {
            yaw_rate_rad_s: 0.2,
            step_period_s: 1.0,
            lift_height_m: 0.03,
            duration_s: None,
        },
        MotionCommand::FootPath {
            path: kin_core::motion::path::PathKind::Ellipse,
            legs: LegSet::All,
            stride_m: 0.05,
            step_height_m: 0.03,
            duty_factor: 0.5,
            cycle_s: 2.0,
            duration_s: None,
        },
        MotionCommand::Walk {
            gait: kin_core::motion::gait::Pattern::Trot,
            body_height_m: 0.277,
            step_height_m: 0.04,
            cycle_s: 0.6,
            velocity_timeout_ms: 500,
        },
    ];
    let mut seq = 10;
    for m in refused {
        seq += 1;
        assert_eq!(
            ask(&mut link, seq, Request::StartMotion(m)),
            DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::OutputsDisabled
            },
            "{m:?} with the outputs off"
        );
    }
    seq += 1;
    match ask(
        &mut link,
        seq,
        Request::SetBodyPose(kin_core::Pose::default()),
    ) {
        DeviceToHost::Ack { readback, .. } => {
            assert!(readback.angles_rad.iter().any(|a| *a != 0.0));
            assert_eq!(readback.pulses_half_us, [0; 12]);
            assert!(!readback
                .flags
                .contains(quad_protocol::Flags::OUTPUTS_ENABLED));
        }
        other => panic!("SetBodyPose with the outputs off: {other:?}"),
    }
    seq += 1;
    match ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp)) {
        DeviceToHost::MotionAck { readback, .. } => {
            assert!(readback
                .flags
                .contains(quad_protocol::Flags::OUTPUTS_ENABLED));
        }
        other => panic!("StandUp with the outputs off: {other:?}"),
    }
}

#[test]
fn sit_ends_at_the_documented_rest_pose() {
    let mut link = boot();
    let info = hello(&mut link);
    let robot = info.robot.robot().expect("a preset robot");
    let rest = quad_device::engine::rest_angles(&robot).expect("a rest pose");
    // The documented rule: abduction 0, the knee 0.2 rad short of the folded end of its range,
    // the hip at minus half the knee.
    let knee = robot.limits.min_rad[2] + 0.2;
    for leg in rest.chunks_exact(3) {
        assert_eq!(leg, [0.0, -0.5 * knee, knee]);
    }
    let mut seq = 1;
    for m in [MotionCommand::StandUp, MotionCommand::Sit] {
        seq += 1;
        assert!(matches!(
            ask(&mut link, seq, Request::StartMotion(m)),
            DeviceToHost::MotionAck { .. }
        ));
        wait_idle(&mut link, &mut seq);
    }
    seq += 1;
    match ask(&mut link, seq, Request::GetState) {
        DeviceToHost::Ack { readback, .. } => assert_eq!(readback.angles_rad, rest),
        other => panic!("GetState: {other:?}"),
    }
}

/// The pulse width of every channel, period by period, for `periods` periods.
fn pulse_periods(link: &mut EmulatorLink, periods: usize) -> Vec<[u64; 12]> {
    (0..periods)
        .map(|_| {
            let p = link.next_pulses().expect("runs");
            core::array::from_fn(|c| p[c].map_or(0, |p| p.high_cycles))
        })
        .collect()
}

/// The first period from which channel `c` no longer changes (by more than the emulator's
/// edge resolution), or `None` if it moved less than ten times that in all (too little to
/// tell when it arrived).
fn arrival(periods: &[[u64; 12]], c: usize) -> Option<usize> {
    const SLACK_CYCLES: u64 = 40;
    let last = periods.last().expect("periods")[c];
    let settled = |p: &[u64; 12]| p[c].abs_diff(last) <= SLACK_CYCLES;
    if periods[0][c].abs_diff(last) < 10 * SLACK_CYCLES {
        return None;
    }
    let i = periods.iter().rposition(|p| !settled(p)).expect("moved");
    Some(i + 1)
}

#[test]
fn a_direct_setpoint_moves_each_joint_at_the_limit_and_a_motion_starts_with_one_ramp() {
    let mut link = boot();
    hello(&mut link);
    let mut seq = 1;
    let stance = |abd: f32| {
        let leg = [abd, 0.7, -1.4];
        core::array::from_fn::<f32, 12, _>(|i| leg[i % 3])
    };
    for request in [
        Request::SetOutputs { enabled: true },
        Request::SetJoints {
            angles_rad: stance(0.0),
        },
    ] {
        seq += 1;
        assert!(!matches!(
            ask(&mut link, seq, request),
            DeviceToHost::Nack { .. }
        ));
    }
    link.idle(Duration::from_secs(2)).expect("runs");
    // Direct: the abductions 0.3 rad away (5 limiter steps at 3 rad/s), FL's hip 0.06 (one).
    let mut target = stance(0.3);
    target[1] += 0.06;
    let mut periods = pulse_periods(&mut link, 1);
    seq += 1;
    assert!(matches!(
        ask(&mut link, seq, Request::SetJoints { angles_rad: target }),
        DeviceToHost::Ack { .. }
    ));
    periods.extend(pulse_periods(&mut link, 12));
    let abduction = arrival(&periods, 0).expect("FL abduction moves");
    let hip = arrival(&periods, 1).expect("FL hip moves");
    assert!(
        abduction >= hip + 3,
        "per joint: the hip's small step arrives first (abduction {abduction}, hip {hip})"
    );
    // A motion's start: StandUp ramps from here to the stance, every moving joint together.
    let mut periods = pulse_periods(&mut link, 1);
    seq += 1;
    assert!(matches!(
        ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp)),
        DeviceToHost::MotionAck { .. }
    ));
    periods.extend(pulse_periods(&mut link, 40));
    let arrivals: Vec<usize> = (0..12).filter_map(|c| arrival(&periods, c)).collect();
    assert!(
        arrivals.len() >= 8,
        "the ramp moves the joints: {arrivals:?}"
    );
    let (first, last) = (
        arrivals.iter().min().unwrap(),
        arrivals.iter().max().unwrap(),
    );
    assert!(
        last - first <= 1,
        "synchronised: every joint arrives in the same period: {arrivals:?}"
    );
    wait_idle(&mut link, &mut seq);
}

/// `GetMotion`'s status and readback.
fn motion_status(
    link: &mut EmulatorLink,
    seq: u16,
) -> (quad_protocol::MotionStatus, quad_protocol::Readback) {
    match ask(link, seq, Request::GetMotion) {
        DeviceToHost::MotionAck {
            status, readback, ..
        } => (status, readback),
        other => panic!("GetMotion: {other:?}"),
    }
}

#[test]
fn an_idle_device_reports_the_idle_stage_to_a_two_two_host_and_run_at_zero_to_a_two_one_host() {
    let mut link = boot();
    hello(&mut link);
    let mut seq = 1;
    // A motion gone by: a 2.1 device kept reporting its time.
    for m in [MotionCommand::StandUp, MotionCommand::Sit] {
        seq += 1;
        assert!(matches!(
            ask(&mut link, seq, Request::StartMotion(m)),
            DeviceToHost::MotionAck { .. }
        ));
        wait_idle(&mut link, &mut seq);
    }
    let idle = |stage| quad_protocol::MotionStatus {
        kind: None,
        stage,
        t_s: 0.0,
        phase: 0.0,
        fault: None,
    };
    seq += 1;
    assert_eq!(
        motion_status(&mut link, seq).0,
        idle(quad_protocol::MotionStage::Idle)
    );
    for host in [0x0200u16, 0x0201] {
        seq += 1;
        assert!(matches!(
            ask(&mut link, seq, Request::Hello { version: host }),
            DeviceToHost::HelloAck { .. }
        ));
        seq += 1;
        assert_eq!(
            motion_status(&mut link, seq).0,
            idle(quad_protocol::MotionStage::Run),
            "to a {host:#06x} host"
        );
    }
}

/// The firmware's watchdog timeout, ms (as in `avr_firmware.rs`).
const WATCHDOG_TIMEOUT_MS: u64 = 256;
/// MCUSR's watchdog reset flag.
const MCUSR_WDRF: u8 = 1 << 3;

#[test]
fn a_watchdog_reset_while_trotting_brings_the_outputs_up_off_reports_it_and_waits_for_a_stand_up() {
    use quad_protocol::{Flags, MotionStage};
    let mut link = boot();
    hello(&mut link);
    let mut seq = 1;
    assert!(matches!(
        ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp)),
        DeviceToHost::MotionAck { .. }
    ));
    wait_idle(&mut link, &mut seq);
    let trot = MotionCommand::Walk {
        gait: kin_core::motion::gait::Pattern::Trot,
        body_height_m: 0.277,
        step_height_m: 0.04,
        cycle_s: 0.6,
        velocity_timeout_ms: 2_000,
    };
    seq += 1;
    assert!(matches!(
        ask(&mut link, seq, Request::StartMotion(trot)),
        DeviceToHost::MotionAck { .. }
    ));
    seq += 1;
    assert!(matches!(
        ask(
            &mut link,
            seq,
            Request::SetVelocity {
                forward_m_s: 0.03,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.0
            }
        ),
        DeviceToHost::MotionAck { .. }
    ));
    link.idle(Duration::from_millis(800)).expect("runs");
    seq += 1;
    let (trotting, _) = motion_status(&mut link, seq);
    assert_eq!(
        (trotting.kind, trotting.stage),
        (Some(quad_protocol::MotionKind::Walk), MotionStage::Run),
        "{trotting:?}"
    );
    assert!(link
        .next_pulses()
        .expect("runs")
        .iter()
        .all(Option::is_some));

    // Hang the CPU mid-trot (the C runtime's final `cli; rjmp .`): the watchdog resets it.
    let image = quad_host::emu::elf::Elf::read(link.elf()).expect("ELF");
    let exit = image.symbol("_exit").expect("_exit in the ELF");
    link.mcu_mut().jump(exit);
    link.idle(Duration::from_millis(WATCHDOG_TIMEOUT_MS * 3 / 2))
        .expect("runs");
    let resets = link.mcu().resets();
    assert_eq!(resets.count, 1, "the watchdog reset the MCU");
    assert_eq!(
        resets.last_mcusr & MCUSR_WDRF,
        MCUSR_WDRF,
        "by the watchdog"
    );

    // The outputs come up off, and stay off through the handshake and the status requests.
    assert_eq!(link.mcu().servo_levels(), 0);
    let before = pulse_periods(&mut link, 10);
    assert!(
        before.iter().flatten().all(|&p| p == 0),
        "no pulse after the reset"
    );
    hello(&mut link);
    let mut seq = 1;
    let (status, readback) = motion_status(&mut link, seq);
    assert!(
        readback.flags.contains(Flags::WATCHDOG_RESET),
        "{readback:?}"
    );
    assert!(
        !readback.flags.contains(Flags::OUTPUTS_ENABLED),
        "{readback:?}"
    );
    assert!(readback.pulses_half_us.iter().all(|&p| p == 0));
    assert_eq!((status.kind, status.stage), (None, MotionStage::Idle));
    seq += 1;
    match ask(&mut link, seq, Request::GetState) {
        DeviceToHost::Ack { readback, .. } => assert!(
            !readback.flags.contains(Flags::WATCHDOG_RESET),
            "cleared once reported: {readback:?}"
        ),
        other => panic!("GetState: {other:?}"),
    }
    let idle = pulse_periods(&mut link, 25);
    assert!(idle.iter().flatten().all(|&p| p == 0), "nothing moves");

    // The soft start: StandUp turns the outputs on at the rest pose and ramps to the stance,
    // every step within the joint-speed limiter.
    let mut us_per_rad = [0.0f32; 12];
    for (i, k) in us_per_rad.iter_mut().enumerate() {
        seq += 1;
        let servo = quad_protocol::ServoId::from_index(i).expect("a servo");
        match ask(&mut link, seq, Request::GetCalibration { servo }) {
            DeviceToHost::Calibration { calibration, .. } => *k = calibration.us_per_rad,
            other => panic!("GetCalibration: {other:?}"),
        }
    }
    seq += 1;
    assert!(matches!(
        ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp)),
        DeviceToHost::MotionAck { .. }
    ));
    let ramp = pulse_periods(&mut link, 60);
    let on: Vec<&[u64; 12]> = ramp.iter().filter(|p| p.iter().all(|&w| w > 0)).collect();
    assert!(on.len() >= 50, "the outputs came on: {} periods", on.len());
    // 16 cycles a µs; the limiter's step (3 rad/s × 20 ms) per period, plus the emulator's
    // edge resolution.
    const CYCLES_PER_US: f32 = 16.0;
    const SLACK_CYCLES: f32 = 40.0;
    let step_rad = 3.0 * 0.020;
    let mut moved = 0.0f32;
    for pair in on.windows(2) {
        for c in 0..12 {
            let d = pair[1][c].abs_diff(pair[0][c]) as f32;
            let bound = step_rad * us_per_rad[c].abs() * CYCLES_PER_US + SLACK_CYCLES;
            assert!(
                d <= bound,
                "channel {c}: {d} cycles in one period (≤ {bound})"
            );
            moved = moved.max(d);
        }
    }
    assert!(moved > SLACK_CYCLES, "the ramp moved the joints");
    wait_idle(&mut link, &mut seq);
}

/// Whether every channel of `pins` (high times, cycles) shows `readback` (half-µs) within one
/// timer tick and the emulator's edge resolution.
fn pins_show(pins: &[u64; 12], readback: &[u16; 12]) -> bool {
    const SLACK_CYCLES: u64 = 40;
    pins.iter()
        .zip(readback)
        .all(|(&p, &r)| p.abs_diff(u64::from(r) * 8) <= SLACK_CYCLES)
}

#[test]
fn a_readback_reports_the_target_which_the_pins_show_from_the_next_periods() {
    let mut link = boot();
    hello(&mut link);
    let mut seq = 1;
    let readback = |answer: DeviceToHost| match answer {
        DeviceToHost::Ack { readback, .. } | DeviceToHost::MotionAck { readback, .. } => readback,
        other => panic!("{other:?}"),
    };
    seq += 1;
    ask(&mut link, seq, Request::SetOutputs { enabled: true });
    seq += 1;
    ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp));
    wait_idle(&mut link, &mut seq);
    // During a motion: the frame the engine computed at the last frame boundary before the
    // answer, on the pins from the period after it was computed (the compare registers are
    // staged and taken over at a period's start) — at 115,200 baud usually while the answer is
    // still on the wire, so the pins' last complete period or the next one shows it.
    seq += 1;
    ask(
        &mut link,
        seq,
        Request::StartMotion(MotionCommand::Sway {
            axis: kin_core::motion::laws::Axis::Roll,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: None,
        }),
    );
    link.idle(Duration::from_millis(500)).expect("runs");
    for poll in 0..20 {
        seq += 1;
        let r = readback(ask(&mut link, seq, Request::GetMotion));
        let last: [u64; 12] =
            core::array::from_fn(|c| link.last_pulses()[c].map_or(0, |p| p.high_cycles));
        let mut seen = vec![last];
        seen.extend(pulse_periods(&mut link, 1));
        assert!(
            seen.iter().any(|p| pins_show(p, &r.pulses_half_us)),
            "poll {poll}: the readback {:?} is on neither the last period nor the next {seen:?}",
            r.pulses_half_us
        );
        link.idle(Duration::from_millis(37)).expect("runs");
    }
    seq += 1;
    ask(&mut link, seq, Request::StopMotion);
    wait_idle(&mut link, &mut seq);
    // A direct setpoint: the target at once, while the pins still ramp under the limiter.
    let leg = [0.3f32, 0.7, -1.4];
    let target: [f32; 12] = core::array::from_fn(|i| leg[i % 3]);
    seq += 1;
    let r = readback(ask(
        &mut link,
        seq,
        Request::SetJoints { angles_rad: target },
    ));
    assert_eq!(r.angles_rad, target);
    let next = pulse_periods(&mut link, 2);
    assert!(
        !next.iter().any(|p| pins_show(p, &r.pulses_half_us)),
        "the pins reached a far target at once"
    );
    link.idle(Duration::from_secs(2)).expect("runs");
    let later = pulse_periods(&mut link, 1);
    assert!(
        pins_show(&later[0], &r.pulses_half_us),
        "the pins reach the target"
    );
}

/// `GetMotion`'s status and frame numbers.
fn motion_frames(
    link: &mut EmulatorLink,
    seq: u16,
    request: Request,
) -> (
    quad_protocol::MotionStatus,
    Option<quad_protocol::MotionFrames>,
) {
    match ask(link, seq, request) {
        DeviceToHost::MotionAck { status, frames, .. } => (status, frames),
        other => panic!("{request:?}: {other:?}"),
    }
}

#[test]
fn the_frame_numbers_end_the_motion_acks_to_a_two_three_host_only() {
    let mut link = boot();
    hello(&mut link);
    let mut seq = 1;
    ask(&mut link, seq, Request::StartMotion(MotionCommand::StandUp));
    wait_idle(&mut link, &mut seq);
    let info = hello(&mut link);
    let walk = MotionCommand::walk(
        kin_core::motion::gait::Pattern::Trot,
        info.pose_config.stance_height_m,
    );
    seq += 1;
    ask(&mut link, seq, Request::StartMotion(walk));
    let velocity = Request::SetVelocity {
        forward_m_s: 0.03,
        lateral_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    };
    // In the run: a velocity's answer names the run frame it applies from, its time.
    let mut in_run = 0;
    for _ in 0..20 {
        link.idle(Duration::from_millis(60)).expect("runs");
        seq += 1;
        let (status, frames) = motion_frames(&mut link, seq, velocity);
        let frames = frames.expect("frame numbers to a 2.3 host");
        if status.stage == quad_protocol::MotionStage::Run {
            assert_eq!(
                u32::from(frames.frame),
                (status.t_s / 0.02).round() as u32,
                "{status:?} {frames:?}"
            );
            assert_eq!(frames.stop_frame, None);
            in_run += 1;
        }
    }
    assert!(in_run > 10, "{in_run}");
    // A 2.2 host gets the answer of 2.2: nothing after the readback.
    seq += 1;
    ask(&mut link, seq, Request::Hello { version: 0x0202 });
    seq += 1;
    let (status, frames) = motion_frames(&mut link, seq, velocity);
    assert_eq!(status.stage, quad_protocol::MotionStage::Run);
    assert_eq!(frames, None);
    // Back to 2.3: the stop's answer names its frame.
    hello(&mut link);
    seq += 1;
    let (status, frames) = motion_frames(&mut link, seq, Request::StopMotion);
    let stop = frames.and_then(|f| f.stop_frame).expect("the stop frame");
    assert_eq!(u32::from(stop), (status.t_s / 0.02).round() as u32);
    wait_idle(&mut link, &mut seq);
}
