//! The firmware in the loop: the frames the firmware ELF makes in simavr (its measured pin
//! pulses) against those of the device controller in-process, for the same motion. Bounded:
//! one second of a trot (50 frames) on the emulated MCU.
//!
//! The firmware's timers double-buffer their compare registers: a pulse written during a PWM
//! period is on the pin from the next one. The pulses measured after the firmware answered
//! frame `k`'s request are therefore those the in-process device had after frame `k − 1`:
//! the comparison pairs them so (one frame apart), and a lag of more than one frame, or any
//! other difference, fails it.

use quad_device::Config;
use quad_twin::device::SimDevice;
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
    let config = Config::shahriar2023();
    let plan = Plan::new(MotionKind::Trot, &config).unwrap();
    let mut device = HostDriven::new(plan, SimDevice::start(config).unwrap());
    let mut firmware = Emulated::boot(plan, &config, None, false).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(firmware.frame_count(), device.frame_count());
    let mut worst = 0;
    let mut previous: Option<[u16; 12]> = None;
    for k in 0..FRAMES {
        let a = device.next(k, None).unwrap();
        let b = firmware.next(k, None).unwrap_or_else(|e| panic!("{e}"));
        assert!(b.enabled);
        let Some(expected) = previous.replace(a.pulses_half_us) else {
            continue;
        };
        for (i, (&want, &got)) in expected.iter().zip(&b.pulses_half_us).enumerate() {
            let d = want.abs_diff(got);
            worst = worst.max(d);
            assert!(
                d <= PULSE_TOLERANCE_HALF_US,
                "frame {k} servo {i}: device (frame {}) {want} firmware {got} half-µs",
                k - 1,
            );
        }
    }
    eprintln!("largest pulse difference over {FRAMES} frames: {worst} half-µs");
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
