//! A soak of the onboard motions through a damaged line, on the firmware in simavr: stand up,
//! roll and pitch sways, a trot steered at 20 Hz, sit — over and over for `QUAD_SOAK_S` seconds
//! of emulated time (default [`SOAK_S`]; `QUAD_SOAK_S=600` for the ten minutes of
//! BENCHMARKS.md) — with 1 % of the bytes in both directions dropped or flipped. Every command
//! is acked or reported lost by the host's client (never refused, never answered wrongly), no
//! joint moves more than the limiter allows between two consecutive servo periods, every pulse
//! lies within its servo's calibrated travel, and the chip neither resets nor loses a byte to
//! its receive buffer.

use integration_tests::pins::step_and_bound_rad;
use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S;
use quad_host::client::{self, Client, ClientConfig};
use quad_host::emu::{build, CYCLES_PER_TICK, CYCLES_PER_US};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::{Faults, Link};
use quad_protocol::servo::Calibration;
use quad_protocol::{DeviceToHost, MotionCommand, Request, ServoId};
use std::time::Duration;

/// Default soak, s of emulated time (CI on two cores).
const SOAK_S: f32 = 60.0;

/// Half of the 1 % of damaged bytes dropped, half flipped.
const FAULTS: &str = "drop=0.005,flip=0.005";

#[derive(Debug, Default)]
struct Counts {
    sent: u64,
    acked: u64,
    lost: u64,
}

fn send(client: &mut Client<EmulatorLink>, counts: &mut Counts, request: Request) {
    counts.sent += 1;
    match client.request(request) {
        Ok(DeviceToHost::Nack { .. }) => panic!("{request:?} refused"),
        Ok(_) => counts.acked += 1,
        Err(client::Error::NoAnswer { .. }) => counts.lost += 1,
        Err(e) => panic!("{request:?}: {e}"),
    }
}

/// `request` every `gap` for `span` (emulated time).
fn repeat(
    client: &mut Client<EmulatorLink>,
    counts: &mut Counts,
    request: Request,
    gap: Duration,
    span: Duration,
) {
    let end = client.link().now() + span;
    while client.link().now() < end {
        client.link_mut().idle(gap).expect("runs");
        send(client, counts, request);
    }
}

/// Stops the motion (retrying a lost stop) and waits until the device is idle.
fn stop_and_settle(client: &mut Client<EmulatorLink>, counts: &mut Counts, request: Request) {
    send(client, counts, request);
    for _ in 0..400 {
        client
            .link_mut()
            .idle(Duration::from_millis(50))
            .expect("runs");
        counts.sent += 1;
        match client.request(Request::GetMotion) {
            Ok(DeviceToHost::MotionAck { status, .. }) => {
                counts.acked += 1;
                if status.kind.is_none() {
                    return;
                }
            }
            Ok(other) => panic!("GetMotion: {other:?}"),
            Err(client::Error::NoAnswer { .. }) => counts.lost += 1,
            Err(e) => panic!("GetMotion: {e}"),
        }
    }
    panic!("the motion did not end");
}

#[test]
fn onboard_motions_through_a_damaged_line_keep_every_pulse_and_every_byte() {
    let soak_s: f32 = std::env::var("QUAD_SOAK_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(SOAK_S);
    let faults: Faults = FAULTS.parse().expect("faults");
    let config = EmulatorConfig {
        faults,
        seed: 11,
        ..EmulatorConfig::new(115_200)
    };
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let link = EmulatorLink::boot(&elf, config).unwrap_or_else(|e| panic!("{e}"));
    let mut client = Client::new(link, ClientConfig::emulator());
    let info = client.hello().unwrap_or_else(|e| panic!("{e}"));
    let h = info.pose_config.stance_height_m;
    let calibration: Vec<Calibration> = ServoId::ALL
        .iter()
        .map(
            |&servo| match client.request(Request::GetCalibration { servo }) {
                Ok(DeviceToHost::Calibration { calibration, .. }) => calibration,
                other => panic!("GetCalibration: {other:?}"),
            },
        )
        .collect();
    client.link_mut().reset_pulse_steps();

    let mut counts = Counts::default();
    let start = client.link().now();
    let mut rounds = 0;
    while (client.link().now() - start).as_secs_f32() < soak_s {
        send(
            &mut client,
            &mut counts,
            Request::StartMotion(MotionCommand::StandUp),
        );
        stop_and_settle(&mut client, &mut counts, Request::GetState);
        for axis in [Axis::Roll, Axis::Pitch] {
            send(
                &mut client,
                &mut counts,
                Request::StartMotion(MotionCommand::Sway {
                    axis,
                    amplitude_rad: 0.1,
                    period_s: 2.0,
                    duration_s: None,
                }),
            );
            repeat(
                &mut client,
                &mut counts,
                Request::GetMotion,
                Duration::from_millis(100),
                Duration::from_secs(2),
            );
            stop_and_settle(&mut client, &mut counts, Request::StopMotion);
        }
        send(
            &mut client,
            &mut counts,
            Request::StartMotion(MotionCommand::Walk {
                gait: Pattern::Trot,
                body_height_m: h,
                step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
                cycle_s: GaitParams::DEFAULT_CYCLE_S,
                velocity_timeout_ms: 500,
            }),
        );
        repeat(
            &mut client,
            &mut counts,
            Request::SetVelocity {
                forward_m_s: 0.04,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: if rounds % 2 == 0 { 0.05 } else { -0.05 },
            },
            Duration::from_millis(50),
            Duration::from_secs(4),
        );
        stop_and_settle(&mut client, &mut counts, Request::StopMotion);
        send(
            &mut client,
            &mut counts,
            Request::StartMotion(MotionCommand::Sit),
        );
        stop_and_settle(&mut client, &mut counts, Request::GetState);
        rounds += 1;
    }

    let link = client.link_mut();
    let line = link.line_stats();
    assert!(
        line.dropped > 0 && line.flipped > 0,
        "faults were injected: {line:?}"
    );
    let steps = link.pulse_steps();
    let mut largest_rad: f64 = 0.0;
    for (c, pair) in steps.largest.iter().enumerate() {
        let (a, b) = pair.expect("every channel pulsed");
        let cal = &calibration[c];
        let (step, bound) = step_and_bound_rad(
            &a,
            &b,
            f64::from(cal.us_per_rad),
            f64::from(DEFAULT_JOINT_SPEED_LIMIT_RAD_S),
        );
        assert!(
            step <= bound,
            "{:?}: {step} rad between two periods > {bound}",
            ServoId::ALL[c]
        );
        // Every pulse within the servo's travel: the narrowest and the widest, each as wide
        // as the travel's end at most (edges seen up to a simavr step late, one timer tick).
        let (narrowest, widest) = steps.extremes[c].expect("every channel pulsed");
        let cycles = |us: u16| u64::from(us) * CYCLES_PER_US;
        assert!(
            narrowest.high_cycles + narrowest.fall_step_cycles + CYCLES_PER_TICK
                >= cycles(cal.min_us)
                && widest
                    .high_cycles
                    .saturating_sub(widest.rise_step_cycles + CYCLES_PER_TICK)
                    <= cycles(cal.max_us),
            "{:?}: pulses of {:.1}–{:.1} µs beyond its travel [{}, {}] µs",
            ServoId::ALL[c],
            narrowest.high_us(),
            widest.high_us(),
            cal.min_us,
            cal.max_us
        );
        largest_rad = largest_rad.max(step);
    }
    assert_eq!(link.mcu().resets().count, 0, "no reset");
    assert_eq!(link.rx_overruns(), 0, "no byte lost to the receive buffer");
    assert_eq!(counts.acked + counts.lost, counts.sent);
    println!(
        "soak: {soak_s} s emulated, {rounds} rounds, {} commands: {} acked, {} reported lost; \
         line {line:?}; {} period-to-period steps compared, largest {largest_rad:.4} rad, {} \
         gaps; 0 resets, 0 overruns",
        counts.sent, counts.acked, counts.lost, steps.compared, steps.gaps
    );
}
