//! Shared by the stream tests: a connected stream on the simulated UART and random reachable
//! poses.

#![allow(dead_code)]

use kin_core::body::Pose;
use quad_device::Config;
use quad_host::client::{AngleCheck, Client, ClientConfig, Expected, PoseStream, StreamSetup};
use quad_host::link::sim::{EepromImage, SimConfig, SimLink};
use quad_protocol::RobotPreset;
use seeded_rng::SplitMix64 as Rng;

/// The two presets.
#[derive(Debug, Clone, Copy)]
pub enum Robo {
    Fernando,
    Shahriar,
}

/// A stream connected to a fresh simulated device with `cfg`.
pub fn connect(cfg: SimConfig, robot: Robo) -> PoseStream<SimLink> {
    let (config, preset) = match robot {
        Robo::Fernando => (Config::fernando2025(), RobotPreset::Fernando2025),
        Robo::Shahriar => (Config::shahriar2023(), RobotPreset::Shahriar2023),
    };
    let link = SimLink::new(cfg, config, EepromImage::erased()).unwrap();
    let client = Client::new(link, ClientConfig::sim(cfg.compute));
    PoseStream::connect(
        client,
        StreamSetup {
            robot: config.robot,
            preset,
            stance_height_m: None,
            order: None,
            check: AngleCheck::Exact,
        },
    )
    .unwrap()
}

/// A random pose the host's kin-core solves and the device's calibration maps: rotations within
/// ±0.25 rad, translations within ±6 cm (z ±8 cm), redrawn until reachable.
pub fn reachable_pose<L: quad_host::link::Link>(stream: &PoseStream<L>, rng: &mut Rng) -> Pose {
    loop {
        let r = |rng: &mut Rng, a: f64| rng.range(-a, a) as f32;
        let pose = Pose {
            roll_rad: r(rng, 0.25),
            pitch_rad: r(rng, 0.25),
            yaw_rad: r(rng, 0.25),
            x_m: r(rng, 0.06),
            y_m: r(rng, 0.06),
            z_m: r(rng, 0.08),
        };
        if matches!(stream.expected(&pose), Expected::Angles(_)) {
            return pose;
        }
    }
}
