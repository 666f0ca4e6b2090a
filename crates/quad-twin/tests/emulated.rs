//! The firmware in the loop: the frames the firmware ELF makes in simavr (its measured pin
//! pulses) against those of the device controller in-process, for the same motion. Bounded:
//! one second of a trot (50 frames) on the emulated MCU.
//!
//! The joint-speed limiter is set out of the way here (both sides at 100 rad/s): with it
//! binding, the two would differ by when their steps fall, not by their maths (the emulated
//! MCU's clock runs on while a request and its answer cross the line, the in-process device
//! advances exactly one frame per request; the limiter's own bound is checked on the pins by
//! the onboard motion tests). Even so the frames need not line up one to one: the timers
//! double-buffer their compare registers (a pulse written during a PWM period is on the pin
//! from the next one), so each frame of the firmware must match the device's frame `k − 1`,
//! `k` or `k + 1`; any other difference fails it.

use quad_device::Config;
use quad_twin::device::InProcess;
use quad_twin::emulated::Emulated;
use quad_twin::source::{FrameSource, HostDriven};
use quad_twin::{MotionKind, Plan};

/// Frames compared.
const FRAMES: u32 = 50;
/// A measured pulse may differ from the in-process device's by this much, half-µs: one timer
/// tick of edge uncertainty, plus one for the AVR's f32 maths against the host's.
const PULSE_TOLERANCE_HALF_US: u16 = 2;

#[test]
fn the_firmwares_pulses_equal_the_device_controllers() {
    let config = Config {
        joint_speed_limit_rad_s: 100.0,
        ..Config::shahriar2023()
    };
    let plan = Plan::new(MotionKind::Trot, &config).unwrap();
    let mut device = HostDriven::new(plan, InProcess::start(config).unwrap());
    let mut firmware = Emulated::boot(plan, &config, None, false).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(firmware.frame_count(), device.frame_count());
    let expected: Vec<[u16; 12]> = (0..=FRAMES)
        .map(|k| device.next(k, None).unwrap().pulses_half_us)
        .collect();
    let mut worst = 0;
    let mut shifted = 0;
    for k in 0..FRAMES {
        let b = firmware.next(k, None).unwrap_or_else(|e| panic!("{e}"));
        assert!(b.enabled);
        // The largest difference on the 12 pins against each neighbouring frame of the device.
        let off = |want: &[u16; 12]| -> u16 {
            want.iter()
                .zip(&b.pulses_half_us)
                .map(|(w, g)| w.abs_diff(*g))
                .max()
                .unwrap_or(0)
        };
        let k = k as usize;
        let neighbours = &expected[k.saturating_sub(1)..=k + 1];
        let (best, at) = neighbours
            .iter()
            .enumerate()
            .map(|(i, want)| (off(want), i))
            .min()
            .unwrap();
        if k.saturating_sub(1) + at != k {
            shifted += 1;
        }
        worst = worst.max(best);
        assert!(
            best <= PULSE_TOLERANCE_HALF_US,
            "frame {k}: firmware {:?}, device frames {}..={}: {neighbours:?} half-µs",
            b.pulses_half_us,
            k.saturating_sub(1),
            k + 1,
        );
    }
    eprintln!(
        "largest pulse difference over {FRAMES} frames: {worst} half-µs ({shifted} frames a \
         frame apart)"
    );
}

#[test]
fn the_firmwares_own_trot_walks_in_the_twin() {
    // The firmware's motion engine runs the trot (one PWM period of MCU time per frame);
    // the twin's physics carries the robot forward.
    let (config, physical) = (Config::shahriar2023(), quad_model::Physical::shahriar2023());
    let options = quad_twin::RunOptions {
        driver: quad_twin::Driver::Emulator { elf: None },
        onboard: true,
        ..quad_twin::RunOptions::default()
    };
    let s = quad_twin::run(&config, &physical, MotionKind::Trot, &options)
        .unwrap_or_else(|e| panic!("{e}"))
        .summary;
    assert!(!s.fell, "{:?}", s.fall_reason);
    let travel = s.travel.expect("a travelling motion");
    assert!(travel.ratio >= 0.5, "{travel:?}");
}
