//! The host link end to end through the simulated UART: readback checks, nacks, rates, the
//! failsafe and a device reset.

mod stream_common;

use kin_core::body::Pose;
use kin_core::LegId;
use quad_host::client::{Expected, PoseResult};
use quad_host::link::sim::{SimConfig, SimLink};
use quad_host::link::{byte_time, Link};
use quad_protocol::{LinkLossAction, LinkTimeout, NackReason, ReachFault, Request};
use std::time::Duration;
use stream_common::*;

/// The simulator must deliver at least this share of the wire-limited rate without faults.
const MIN_WIRE_EFFICIENCY: f64 = 0.90;

#[test]
fn poses_are_acked_with_the_hosts_angles_and_the_outputs_follow() {
    let mut stream = connect(SimConfig::default(), Robo::Fernando);
    let mut rng = seeded_rng::SplitMix64::new(11);
    for _ in 0..50 {
        let pose = reachable_pose(&stream, &mut rng);
        let Expected::Angles(want) = stream.expected(&pose) else {
            unreachable!()
        };
        assert_eq!(
            stream.send(&pose).unwrap(),
            PoseResult::Acked { max_err_rad: 0.0 }
        );
        let dev = stream.client().link().device();
        let rb = dev.readback();
        assert_eq!(rb.angles_rad, want);
        assert!(dev.outputs().enabled);
        // The outputs follow through the joint-speed limiter: never more than its step per
        // servo frame, and at the target within the frames that step implies.
        let step = dev.limiter().max_step_rad();
        let mut out = *dev.output_angles().expect("outputs on");
        let far = out
            .iter()
            .zip(&want)
            .map(|(o, w)| (o - w).abs())
            .fold(0.0f32, f32::max);
        let frames = (far / step).ceil() as u32 + 1;
        for _ in 0..frames {
            let mut buf = [0u8; 64];
            stream
                .client_mut()
                .link_mut()
                .recv(&mut buf, Duration::from_millis(20))
                .unwrap();
            let now = *stream.client().link().device().output_angles().unwrap();
            for (a, b) in now.iter().zip(&out) {
                assert!(
                    (a - b).abs() <= step * (1.0 + 1e-6),
                    "{a} after {b} > {step}"
                );
            }
            out = now;
        }
        let dev = stream.client().link().device();
        assert_eq!(dev.outputs().pulses_half_us, rb.pulses_half_us);
    }
    let s = stream.stats();
    assert_eq!((s.sent, s.acked, s.retries, s.lost), (50, 50, 0, 0));
    assert_eq!(s.readback_mismatches, 0);
}

#[test]
fn an_unreachable_pose_is_nacked_with_the_hosts_reason_and_moves_nothing() {
    for robot in [Robo::Fernando, Robo::Shahriar] {
        let mut stream = connect(SimConfig::default(), robot);
        stream.send(&Pose::rotation(0.05, 0.0, 0.0)).unwrap();
        let before = stream.client().link().device().outputs().pulses_half_us;
        let up = Pose {
            z_m: 0.3,
            ..Pose::default()
        };
        assert_eq!(
            stream.expected(&up),
            Expected::Nack(NackReason::Unreachable {
                leg: LegId::FL,
                fault: ReachFault::TooFar
            })
        );
        assert_eq!(
            stream.send(&up).unwrap(),
            PoseResult::Nacked(NackReason::Unreachable {
                leg: LegId::FL,
                fault: ReachFault::TooFar
            })
        );
        let nan = Pose {
            yaw_rad: f32::NAN,
            ..Pose::default()
        };
        assert_eq!(
            stream.send(&nan).unwrap(),
            PoseResult::Nacked(NackReason::NonFinite)
        );
        assert_eq!(
            stream.client().link().device().outputs().pulses_half_us,
            before
        );
        let s = stream.stats();
        assert_eq!(
            (s.acked, s.nacked, s.lost, s.readback_mismatches),
            (1, 2, 0, 0)
        );
    }
}

/// Wire-limited rate of the stream: the bytes actually sent per pose, both directions, one
/// after the other (stop-and-wait), at 10 bits per byte.
fn throughput(baud: u32, compute: Duration) -> (f64, f64, u64, u64) {
    let cfg = SimConfig {
        baud,
        compute,
        ..SimConfig::default()
    };
    let mut stream = connect(cfg, Robo::Fernando);
    let mut rng = seeded_rng::SplitMix64::new(5);
    let poses: Vec<Pose> = (0..400)
        .map(|_| reachable_pose(&stream, &mut rng))
        .collect();
    let before = stream.client().link().stats();
    for p in &poses {
        assert!(matches!(stream.send(p).unwrap(), PoseResult::Acked { .. }));
    }
    let after = stream.client().link().stats();
    let n = poses.len() as u64;
    let req = (after.h2d_bytes - before.h2d_bytes) / n;
    let ack = (after.d2h_bytes - before.d2h_bytes) / n;
    let per_pose = byte_time(baud).as_secs_f64()
        * (after.h2d_bytes - before.h2d_bytes + after.d2h_bytes - before.d2h_bytes) as f64
        / n as f64;
    (stream.stats().poses_per_s, 1.0 / per_pose, req, ack)
}

#[test]
fn the_stream_reaches_90_percent_of_the_wire_limit() {
    for baud in [115_200, 1_000_000] {
        let (rate, limit, req, ack) = throughput(baud, Duration::ZERO);
        println!(
            "{baud} baud: request {req} B, ack {ack} B, {rate:.1} poses/s of {limit:.1} wire-limited ({:.1} %)",
            100.0 * rate / limit
        );
        assert!(
            rate >= MIN_WIRE_EFFICIENCY * limit,
            "{baud} baud: {rate} poses/s < 90 % of {limit}"
        );
        assert!(
            (31..=33).contains(&req) && (82..=92).contains(&ack),
            "{req} {ack}"
        );
    }
}

#[test]
fn a_modelled_device_time_adds_to_each_round_trip() {
    // 4 ms of IK per pose (the order of the ATmega2560's four-leg IK with avr-libc math).
    let compute = Duration::from_millis(4);
    let (rate, limit, _, _) = throughput(1_000_000, compute);
    let expected = 1.0 / (1.0 / limit + compute.as_secs_f64());
    println!("1 Mbaud with 4 ms device time: {rate:.1} poses/s (wire limit {limit:.1})");
    assert!(
        (rate - expected).abs() < 0.02 * expected,
        "{rate} vs {expected}"
    );
}

#[test]
fn link_loss_disables_the_outputs_and_the_stream_enables_them_again() {
    let mut stream = connect(SimConfig::default(), Robo::Fernando);
    stream
        .client_mut()
        .ack(Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 100,
            action: LinkLossAction::Disable,
        }))
        .unwrap();
    stream.send(&Pose::rotation(0.1, 0.0, 0.0)).unwrap();
    assert!(stream.client().link().device().outputs().enabled);
    // 300 ms of silence.
    let mut buf = [0u8; 16];
    let n = stream
        .client_mut()
        .link_mut()
        .recv(&mut buf, Duration::from_millis(300))
        .unwrap();
    assert_eq!(n, 0);
    assert!(!stream.client().link().device().outputs().enabled);
    // The next pose is acked with the outputs off (pulses 0, checked), then enabled again.
    assert!(matches!(
        stream.send(&Pose::rotation(0.0, 0.1, 0.0)).unwrap(),
        PoseResult::Acked { .. }
    ));
    assert!(stream.client().link().device().outputs().enabled);
    let s = stream.stats();
    assert_eq!((s.reenabled, s.readback_mismatches), (1, 0));
}

#[test]
fn a_device_reset_mid_stream_is_recovered() {
    let mut stream = connect(SimConfig::default(), Robo::Fernando);
    stream.send(&Pose::rotation(0.1, 0.0, 0.0)).unwrap();
    stream.client_mut().link_mut().reset_device().unwrap();
    assert!(!stream.client().link().device().outputs().enabled);
    let r = stream.send(&Pose::rotation(0.0, 0.0, 0.1)).unwrap();
    assert!(matches!(r, PoseResult::Acked { .. }), "{r:?}");
    assert!(stream.client().link().device().outputs().enabled);
    assert_eq!(stream.stats().readback_mismatches, 0);
}

#[test]
fn the_sim_is_deterministic_for_a_seed() {
    let run = |seed| {
        let cfg = SimConfig {
            faults: "drop=0.02,flip=0.01,dup=0.05,trunc=0.05,stall=0.01,stall_ms=20"
                .parse()
                .unwrap(),
            seed,
            ..SimConfig::default()
        };
        let mut stream = connect(cfg, Robo::Fernando);
        let mut rng = seeded_rng::SplitMix64::new(9);
        for _ in 0..100 {
            let p = reachable_pose(&stream, &mut rng);
            stream.send(&p).unwrap();
        }
        let s = stream.stats();
        (serde_json::to_string(&s).unwrap(), s)
    };
    let (a, sa) = run(3);
    assert_eq!(a, run(3).0);
    assert_ne!(a, run(4).0);
    assert!(sa.retries > 0 && sa.readback_mismatches == 0 && sa.pulses_out_of_range == 0);
    assert_eq!(sa.acked + sa.lost, 100);
}

#[test]
fn a_sim_link_with_no_device_answer_times_out_in_virtual_time() {
    let mut link = SimLink::new(
        SimConfig::default(),
        quad_device::Config::fernando2025(),
        quad_host::link::sim::EepromImage::erased(),
    )
    .unwrap();
    let t0 = std::time::Instant::now();
    let mut buf = [0u8; 8];
    assert_eq!(link.recv(&mut buf, Duration::from_secs(3600)).unwrap(), 0);
    assert_eq!(link.now(), Duration::from_secs(3600));
    assert!(t0.elapsed() < Duration::from_secs(1), "no real sleeping");
}

/// A link that rewrites answers with a valid CRC: what a line corruption that passes the CRC
/// (or a faulty device) looks like to the host.
struct Tamper {
    inner: SimLink,
    acc: quad_protocol::Accumulator<{ quad_protocol::MAX_DECODED_LEN }>,
    out: std::collections::VecDeque<u8>,
    /// Acks to tamper with, counted down.
    acks_left: u32,
    /// Nacks to tamper with, counted down.
    nacks_left: u32,
}

impl Tamper {
    fn tamper(&mut self, msg: quad_protocol::DeviceToHost) -> quad_protocol::DeviceToHost {
        use quad_protocol::DeviceToHost;
        match msg {
            DeviceToHost::Ack { seq, mut readback } if self.acks_left > 0 => {
                self.acks_left -= 1;
                readback.angles_rad[4] = f32::from_bits(readback.angles_rad[4].to_bits() ^ 1);
                DeviceToHost::Ack { seq, readback }
            }
            DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::Unreachable { leg, .. },
            } if self.nacks_left > 0 => {
                self.nacks_left -= 1;
                DeviceToHost::Nack {
                    seq: Some(seq),
                    reason: NackReason::Unreachable {
                        leg,
                        fault: ReachFault::TooClose,
                    },
                }
            }
            other => other,
        }
    }
}

impl Link for Tamper {
    fn send(&mut self, bytes: &[u8]) -> Result<(), quad_host::link::Error> {
        self.inner.send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, quad_host::link::Error> {
        if self.out.is_empty() {
            let mut raw = [0u8; 256];
            let n = self.inner.recv(&mut raw, timeout)?;
            let mut rest = &raw[..n];
            loop {
                match self.acc.feed::<quad_protocol::DeviceToHost>(rest) {
                    quad_protocol::Feed::NeedMore => break,
                    quad_protocol::Feed::Frame { msg, remaining } => {
                        let msg = self.tamper(msg);
                        let mut f = [0u8; quad_protocol::MAX_FRAME_LEN];
                        self.out
                            .extend(quad_protocol::encode_frame(&msg, &mut f).unwrap());
                        rest = remaining;
                    }
                    other => rest = other.remaining(),
                }
            }
        }
        let n = buf.len().min(self.out.len());
        for b in buf.iter_mut().take(n) {
            *b = self.out.pop_front().unwrap();
        }
        Ok(n)
    }
    fn now(&self) -> Duration {
        self.inner.now()
    }
    fn baud(&self) -> u32 {
        self.inner.baud()
    }
}

/// A stream through a [`Tamper`] link, armed after the session set-up.
fn tampered(acks: u32, nacks: u32) -> quad_host::client::PoseStream<Tamper> {
    use quad_host::client::{AngleCheck, Client, ClientConfig, PoseStream, StreamSetup};
    let config = quad_device::Config::fernando2025();
    let inner = SimLink::new(
        SimConfig::default(),
        config,
        quad_host::link::sim::EepromImage::erased(),
    )
    .unwrap();
    let link = Tamper {
        inner,
        acc: quad_protocol::Accumulator::new(),
        out: Default::default(),
        acks_left: 0,
        nacks_left: 0,
    };
    let mut stream = PoseStream::connect(
        Client::new(link, ClientConfig::sim(Duration::ZERO)),
        StreamSetup {
            robot: config.robot,
            preset: quad_protocol::RobotPreset::Fernando2025,
            stance_height_m: None,
            order: None,
            check: AngleCheck::Exact,
        },
    )
    .unwrap();
    let link = stream.client_mut().link_mut();
    link.acks_left = acks;
    link.nacks_left = nacks;
    stream
}

#[test]
fn a_wrong_readback_is_retried_and_counted_when_it_persists() {
    let pose = Pose::rotation(0.1, 0.05, 0.0);
    // One wrong answer: the retry's answer is right.
    let mut s = tampered(1, 0);
    assert!(matches!(s.send(&pose).unwrap(), PoseResult::Acked { .. }));
    let st = s.stats();
    assert_eq!(
        (
            st.acked,
            st.retries,
            st.transient_mismatches,
            st.readback_mismatches
        ),
        (1, 1, 1, 0)
    );
    // Always wrong: a mismatch after every retry, exit status material.
    let mut s = tampered(u32::MAX, 0);
    match s.send(&pose).unwrap() {
        PoseResult::Mismatch(what) => assert!(what.to_string().contains("FR.hip"), "{what}"),
        other => panic!("{other:?}"),
    }
    let st = s.stats();
    assert_eq!((st.acked, st.readback_mismatches, st.retries), (0, 1, 10));
    // A nack whose reason differs from the host's kin-core.
    let mut s = tampered(0, u32::MAX);
    let up = Pose {
        z_m: 0.3,
        ..Pose::default()
    };
    match s.send(&up).unwrap() {
        PoseResult::Mismatch(what) => assert!(what.to_string().contains("too_close"), "{what}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(s.stats().readback_mismatches, 1);
}
