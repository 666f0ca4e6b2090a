//! The serial link end to end on a pseudo-terminal: `SerialLink` opens the pty's slave by its
//! path, as it would open `/dev/ttyACM0`; a thread runs the device controller on the master
//! side on the wall clock. Exercises the real-port code path of `quadctl stream --port`
//! without hardware.

#![cfg(unix)]

use kin_core::body::Pose;
use quad_device::sim::{Outputs, RamEeprom, VirtualClock};
use quad_device::{Config, Device};
use quad_host::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, AVR_ANGLE_TOLERANCE_RAD,
};
use quad_host::link::serial::SerialLink;
use quad_host::link::Link;
use quad_protocol::{NackReason, RobotPreset};
use serialport::{SerialPort, TTYPort};
use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Runs the device on `master` until `stop`, its clock following the wall clock.
fn serve(mut master: TTYPort, stop: Arc<AtomicBool>) {
    master.set_timeout(Duration::from_millis(5)).unwrap();
    let start = Instant::now();
    let clock = VirtualClock::default();
    let mut device: Device<_, _, _> = Device::new(
        Config::fernando2025(),
        Outputs::default(),
        &clock,
        RamEeprom::erased(),
    )
    .unwrap();
    let wall = || clock.set_ns(start.elapsed().as_nanos() as u64);
    let mut buf = [0u8; 256];
    while !stop.load(Ordering::Relaxed) {
        match master.read(&mut buf) {
            Ok(n) => {
                wall();
                let mut out = Vec::new();
                device.receive(&buf[..n], |f| out.extend_from_slice(f));
                master.write_all(&out).unwrap();
            }
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("pty master: {e}"),
        }
        wall();
        device.poll();
    }
}

#[test]
fn a_stream_over_a_pseudo_terminal() {
    let (master, slave) = TTYPort::pair().expect("a pty pair");
    let path = slave.name().expect("the slave's path");
    let stop = Arc::new(AtomicBool::new(false));
    let server = {
        let stop = stop.clone();
        std::thread::spawn(move || serve(master, stop))
    };
    let link = SerialLink::open(&path, 115_200).expect("the pty opens like a serial port");
    assert_eq!(link.baud(), 115_200);
    let config = Config::fernando2025();
    let mut stream = PoseStream::connect(
        Client::new(link, ClientConfig::serial()),
        StreamSetup {
            robot: config.robot,
            preset: RobotPreset::Fernando2025,
            stance_height_m: None,
            order: None,
            // Same math on both ends here; the bound of a real AVR applies.
            check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
        },
    )
    .expect("handshake over the pty");
    for i in 0..20 {
        let pose = Pose::rotation(0.01 * i as f32, -0.005 * i as f32, 0.0);
        match stream.send(&pose).unwrap() {
            PoseResult::Acked { max_err_rad } => assert_eq!(max_err_rad, 0.0),
            other => panic!("pose {i}: {other:?}"),
        }
    }
    let up = Pose {
        z_m: 0.3,
        ..Pose::default()
    };
    assert!(matches!(
        stream.send(&up).unwrap(),
        PoseResult::Nacked(NackReason::Unreachable { .. })
    ));
    let s = stream.stats();
    assert_eq!(
        (s.acked, s.nacked, s.lost, s.readback_mismatches),
        (20, 1, 0, 0)
    );
    assert!(s.poses_per_s > 0.0);
    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
    drop(slave);
}

#[test]
fn a_missing_port_is_an_open_error() {
    let e = SerialLink::open("/dev/this-port-does-not-exist", 115_200)
        .err()
        .unwrap();
    assert!(e.to_string().contains("cannot open"), "{e}");
}
