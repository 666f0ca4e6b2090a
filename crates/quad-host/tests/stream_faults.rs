//! Random reachable poses through the simulated UART with line faults: every pose is either
//! acked with a correct readback or reported lost after its retries; no mismatch, no pulse out
//! of its travel.
//!
//! The figure of the issue: 10,000 poses with `drop=0.01,flip=0.001` at 115200 baud (about
//! 3 s in a debug build: the simulation runs on a virtual clock).

mod stream_common;

use quad_host::client::PoseResult;
use quad_host::link::sim::SimConfig;
use seeded_rng::SplitMix64 as Rng;
use std::time::Duration;
use stream_common::*;

/// Poses of the main run.
const POSES: usize = 10_000;

/// Poses of the run with every fault kind.
const POSES_EVERY_FAULT: usize = 2_000;

/// Largest share of lost poses accepted with `drop=0.01,flip=0.001` and 10 retries: an attempt
/// (≈ 31 + 84 bytes) gets through with probability ≈ 0.28, so 11 attempts all fail with
/// probability ≈ 0.03.
const MAX_LOST_SHARE: f64 = 0.06;

fn run(faults: &str, seed: u64, baud: u32, poses: usize) -> quad_host::client::StreamStats {
    let cfg = SimConfig {
        baud,
        faults: faults.parse().unwrap(),
        seed,
        compute: Duration::ZERO,
        ..SimConfig::default()
    };
    let mut stream = connect(cfg, Robo::Fernando);
    let mut rng = Rng::new(seed ^ 0x5EED);
    let mut results = [0usize; 2];
    for _ in 0..poses {
        let pose = reachable_pose(&stream, &mut rng);
        match stream.send(&pose).unwrap() {
            PoseResult::Acked { max_err_rad } => {
                assert_eq!(max_err_rad, 0.0);
                results[0] += 1;
            }
            PoseResult::Lost => results[1] += 1,
            other => panic!("a reachable pose got {other:?}"),
        }
    }
    let s = stream.stats();
    println!("{faults} @ {baud}: {}", serde_json::to_string(&s).unwrap());
    assert_eq!(s.sent, poses as u64);
    assert_eq!((s.acked, s.lost), (results[0] as u64, results[1] as u64));
    assert_eq!(s.acked + s.lost, poses as u64);
    assert_eq!(s.nacked, 0);
    assert_eq!(s.readback_mismatches, 0);
    assert_eq!(s.pulses_out_of_range, 0);
    assert_eq!(s.max_angle_err_rad, 0.0);
    let sim = stream.client().link().stats();
    assert!(
        sim.dropped > 0 && sim.flipped > 0,
        "faults were injected: {sim:?}"
    );
    s
}

#[test]
fn random_poses_with_drops_and_flips() {
    let s = run("drop=0.01,flip=0.001", 2026, 115_200, POSES);
    assert!(s.retries > 0);
    assert!(
        (s.lost as f64) < MAX_LOST_SHARE * POSES as f64,
        "{} of {POSES} lost",
        s.lost
    );
}

#[test]
fn random_poses_with_every_fault() {
    let s = run(
        "drop=0.005,flip=0.002,dup=0.02,trunc=0.02,stall=0.005,stall_ms=30",
        7,
        1_000_000,
        POSES_EVERY_FAULT,
    );
    assert!(s.timeouts > 0);
}
