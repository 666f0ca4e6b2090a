//! Two requests in flight ([`PoseStream::submit`]) through the simulated UART: the same results
//! as one at a time, in order, faster when the device takes time per request, and under line
//! faults every pose acked with a correct readback or reported lost, the device holding the
//! last pose at the end.

mod stream_common;

use kin_core::body::Pose;
use quad_host::client::{Expected, PoseResult, Setpoint, Settled, MAX_WINDOW};
use quad_host::link::sim::SimConfig;
use seeded_rng::SplitMix64 as Rng;
use std::time::Duration;
use stream_common::*;

/// Submits `poses` with `window` requests in flight; the results in submission order.
fn submit_all(
    stream: &mut quad_host::client::PoseStream<quad_host::link::sim::SimLink>,
    poses: &[Pose],
    window: usize,
) -> Vec<Settled> {
    assert!(stream.set_window(window).unwrap().is_empty());
    let mut settled = Vec::new();
    for (i, p) in poses.iter().enumerate() {
        settled.extend(stream.submit(&Setpoint::Pose(*p), i as u64).unwrap());
    }
    settled.extend(stream.flush().unwrap());
    settled
}

fn poses(seed: u64, n: usize, cfg: SimConfig) -> Vec<Pose> {
    let stream = connect(cfg, Robo::Fernando);
    let mut rng = Rng::new(seed);
    (0..n).map(|_| reachable_pose(&stream, &mut rng)).collect()
}

#[test]
fn two_in_flight_give_the_results_of_one_at_a_time_in_order_and_faster() {
    let cfg = SimConfig {
        compute: Duration::from_millis(3),
        ..SimConfig::default()
    };
    let mut poses = poses(3, 200, cfg);
    // Unreachable poses between them: nacked with the host's reason, in their place.
    for i in (0..poses.len()).step_by(17) {
        poses[i].z_m = 0.5;
    }
    let mut rates = Vec::new();
    let mut results = Vec::new();
    for window in [1, MAX_WINDOW] {
        let mut stream = connect(cfg, Robo::Fernando);
        let settled = submit_all(&mut stream, &poses, window);
        let tags: Vec<u64> = settled.iter().map(|s| s.tag).collect();
        assert_eq!(tags, (0..poses.len() as u64).collect::<Vec<_>>());
        for (s, p) in settled.iter().zip(&poses) {
            match (&s.result, stream.expected(p)) {
                (PoseResult::Acked { max_err_rad }, Expected::Angles(_)) => {
                    assert_eq!(*max_err_rad, 0.0)
                }
                (PoseResult::Nacked(got), Expected::Nack(want)) => assert_eq!(*got, want),
                (got, want) => panic!("pose {}: {got:?}, host expects {want:?}", s.tag),
            }
            assert!(s.answered_at > s.sent_at);
        }
        let stats = stream.stats();
        assert_eq!(
            stats.retries,
            0,
            "window {window}: {:?} {:?}",
            stream.client().counters(),
            stream.client().link().stats()
        );
        assert_eq!(stats.acked + stats.nacked, poses.len() as u64);
        rates.push(stats.poses_per_s);
        results.push(settled.into_iter().map(|s| s.result).collect::<Vec<_>>());
    }
    assert_eq!(results[0], results[1]);
    println!(
        "one at a time {:.1} poses/s, two in flight {:.1}",
        rates[0], rates[1]
    );
    // 3 ms of device time per request: the second request hides it behind the wire.
    assert!(rates[1] > 1.2 * rates[0], "{rates:?}");
}

#[test]
fn under_line_faults_every_pose_is_acked_or_lost_and_the_device_ends_at_the_last() {
    for seed in 1..=3u64 {
        let cfg = SimConfig {
            faults: "drop=0.01,flip=0.001,dup=0.01,trunc=0.01".parse().unwrap(),
            seed,
            ..SimConfig::default()
        };
        let poses = poses(seed, 1500, cfg);
        let mut stream = connect(cfg, Robo::Fernando);
        let settled = submit_all(&mut stream, &poses, MAX_WINDOW);
        assert_eq!(settled.len(), poses.len());
        for s in &settled {
            assert!(
                matches!(
                    s.result,
                    PoseResult::Acked { max_err_rad: 0.0 } | PoseResult::Lost
                ),
                "seed {seed} pose {}: {:?}",
                s.tag,
                s.result
            );
        }
        let stats = stream.stats();
        println!("seed {seed}: {}", serde_json::to_string(&stats).unwrap());
        assert_eq!(stats.acked + stats.lost, poses.len() as u64);
        assert_eq!(
            (stats.readback_mismatches, stats.pulses_out_of_range),
            (0, 0)
        );
        assert!(stats.retries > 0);
        // The device holds the last pose, whatever was resent in between.
        let Expected::Angles(last) = stream.expected(poses.last().unwrap()) else {
            unreachable!()
        };
        assert_eq!(stream.client().link().device().readback().angles_rad, last);
    }
}

#[test]
fn a_window_the_device_does_not_take_is_refused() {
    let mut stream = connect(SimConfig::default(), Robo::Fernando);
    for window in [0, MAX_WINDOW + 1] {
        assert!(matches!(
            stream.set_window(window),
            Err(quad_host::client::Error::Window { window: w }) if w == window
        ));
    }
}
