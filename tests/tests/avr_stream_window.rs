//! The host's window of two requests in flight ([`PoseStream::submit`], `quadctl stream` and
//! `play` by default) against the firmware in simavr at 115,200 baud: body poses with full
//! readback reach 95 % of the wire limit (request and answer one after the other on the
//! line), every pose acked with its readback checked, no byte lost in the chip's two-byte
//! receive buffer.
//!
//! `cargo test --release -p integration-tests --test avr_stream_window -- --nocapture`

use integration_tests::avr_bench::{self, STANCE_HEIGHT_M};
use kin_core::body::Pose;
use kin_core::RotationOrder;
use quad_host::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, Setpoint, StreamSetup,
    AVR_ANGLE_TOLERANCE_RAD, MAX_WINDOW,
};
use quad_host::emu::build;
use quad_host::link::byte_time;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::RobotPreset;

/// Poses per run.
const POSES: usize = 300;

/// The share of the wire limit two requests in flight must reach.
const MIN_SHARE_OF_WIRE_LIMIT: f64 = 0.95;

/// (poses/s, the wire limit in sequence, the full-duplex limit, overruns) of `POSES` body
/// poses with `window` requests in flight.
fn run(window: usize) -> (f64, f64, f64, u64) {
    let baud = 115_200;
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(baud)).unwrap_or_else(|e| panic!("{e}"));
    let setup = StreamSetup {
        robot: avr_bench::robot(),
        preset: RobotPreset::Shahriar2023,
        stance_height_m: Some(STANCE_HEIGHT_M),
        order: Some(RotationOrder::Zyx),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    let mut stream = PoseStream::connect(Client::new(link, ClientConfig::emulator()), setup)
        .unwrap_or_else(|e| panic!("{e}"));
    stream
        .set_window(window)
        .expect("a window the device takes");
    let before = stream.client().link().line_stats();
    let mut settled = Vec::new();
    for k in 0..POSES {
        let t = k as f32 / POSES as f32 * std::f32::consts::TAU;
        let pose = Pose::rotation(0.15 * t.sin(), 0.1 * t.cos(), 0.05 * (2.0 * t).sin());
        settled.extend(
            stream
                .submit(&Setpoint::Pose(pose), k as u64)
                .expect("link"),
        );
    }
    settled.extend(stream.flush().expect("link"));
    assert_eq!(settled.len(), POSES);
    for s in &settled {
        assert!(
            matches!(s.result, PoseResult::Acked { .. }),
            "pose {}: {:?}",
            s.tag,
            s.result
        );
    }
    let stats = stream.stats();
    assert_eq!((stats.retries, stats.readback_mismatches), (0, 0));
    let after = stream.client().link().line_stats();
    let (h2d, d2h) = (
        (after.h2d_bytes - before.h2d_bytes) as f64 / POSES as f64,
        (after.d2h_bytes - before.d2h_bytes) as f64 / POSES as f64,
    );
    let byte_s = byte_time(baud).as_secs_f64();
    let overruns = stream.client_mut().link_mut().rx_overruns();
    println!(
        "{window} in flight: {:.1} body poses/s; request {h2d:.1} B, answer {d2h:.1} B per pose",
        stats.poses_per_s
    );
    (
        stats.poses_per_s,
        1.0 / (byte_s * (h2d + d2h)),
        1.0 / (byte_s * h2d.max(d2h)),
        overruns,
    )
}

#[test]
fn two_requests_in_flight_reach_95_percent_of_the_wire_limit_at_115200_baud() {
    let (one, limit, _, overruns_one) = run(1);
    let (two, limit_two, duplex, overruns_two) = run(MAX_WINDOW);
    println!(
        "115,200 baud: one at a time {one:.1} poses/s ({:.1} % of the wire limit {limit:.1}); \
         two in flight {two:.1} ({:.1} % of {limit_two:.1}; full duplex at most {duplex:.1})",
        100.0 * one / limit,
        100.0 * two / limit_two
    );
    assert_eq!((overruns_one, overruns_two), (0, 0));
    assert!(
        two >= MIN_SHARE_OF_WIRE_LIMIT * limit_two,
        "{two:.1} poses/s < 95 % of {limit_two:.1}"
    );
}
