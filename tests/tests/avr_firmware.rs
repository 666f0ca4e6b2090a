//! The release firmware ELF in simavr: boot, memory, servo outputs on all twelve channels
//! (Timer5 on port L included), outputs low until enabled, the avr-libc link, and the IK's
//! agreement with the host.
//!
//! The outputs are driven through the firmware's interim binary command set
//! (`firmware-avr/src/interim.rs`) until the device controller and its protocol replace it.
//! These tests build the firmware themselves and fail when it cannot be built.

use integration_tests::avr::{
    firmware_elf, Emu, BOOT_US, CYCLES_PER_TICK, PERIOD_TICKS, SERVO_PINS,
};
use integration_tests::avr_bench::{self, elf_sizes, STANCE_HEIGHT_M};
use kin_core::math::Libm;
use kin_core::{body, BodyConfig, ReachPolicy};
use std::process::Command;

/// A measured pulse edge may lag by up to one timer tick (the host samples the pins between
/// instructions): the "within one 0.5 µs tick".
const EDGE_TOLERANCE_CYCLES: u64 = CYCLES_PER_TICK;

/// Cycles of one servo period (20 ms).
const PERIOD_CYCLES: u64 = PERIOD_TICKS * CYCLES_PER_TICK;

/// Largest difference between the firmware's angles (`AvrFast`: avr-libc `sqrt`, kin-core's
/// `poly::atan2_deg9` and `poly::sin_cos_deg5`) and the host's kin-core `Libm` angles for the
/// same pose, rad: the degree-9 arctangent's error (≤ 1.2e-5 rad) plus rounding (measured over
/// the benchmark targets: 1.3e-5).
const READBACK_BOUND_RAD: f64 = 2e-5;

/// Budget of static SRAM plus stack, bytes.
const SRAM_BUDGET_BYTES: u64 = 2048;

fn boot() -> Emu {
    let mut emu = Emu::new(&firmware_elf("firmware"));
    emu.run_us(BOOT_US);
    emu
}

fn request(emu: &mut Emu, bytes: &[u8], answer_len: usize) -> Vec<u8> {
    emu.write(bytes);
    emu.read_exact(answer_len, 10_000_000)
        .unwrap_or_else(|got| panic!("no answer to {:?}: got {got:?}", bytes[0] as char))
}

fn write_pulses(emu: &mut Emu, ticks: &[u16; 12]) {
    let mut req = vec![b'W'];
    for t in ticks {
        req.extend(t.to_le_bytes());
    }
    assert_eq!(request(emu, &req, 2), b"w\0", "pulses accepted");
}

/// Distinct pulse widths, 1000 µs + 125 µs per channel, in ticks.
fn distinct_ticks() -> [u16; 12] {
    std::array::from_fn(|i| 2 * (1000 + 125 * i as u16))
}

#[test]
fn avr_libc_math_is_linked_not_the_weak_fallbacks() {
    let elf = firmware_elf("firmware");
    let out = Command::new("avr-nm")
        .arg(&elf)
        .output()
        .expect("avr-nm (binutils-avr) runs");
    assert!(out.status.success());
    let symbols = String::from_utf8_lossy(&out.stdout);
    let kind_of = |name: &str| {
        symbols.lines().find_map(|l| {
            let mut f = l.split_whitespace();
            let (_, kind, sym) = (f.next()?, f.next()?, f.next()?);
            (sym == name).then(|| kind.to_string())
        })
    };
    for name in ["atan2", "sqrt", "__mulsf3", "__addsf3", "__divsf3"] {
        let kind = kind_of(name).unwrap_or_else(|| panic!("{name} not in the firmware"));
        assert_eq!(
            kind, "T",
            "{name} must be avr-libc's strong symbol, not a weak fallback"
        );
    }
    // The firmware's backend takes sin/cos from kin-core's polynomials; if they are linked at
    // all, they must not be compiler-builtins' 64-bit fallbacks.
    for name in ["sin", "cos", "acos"] {
        assert_ne!(
            kind_of(name).as_deref(),
            Some("W"),
            "{name} is a weak fallback"
        );
    }
}

#[test]
fn boots_with_static_sram_and_stack_within_budget() {
    let sizes = elf_sizes(&firmware_elf("firmware"));
    let mut emu = boot();
    let a = request(&mut emu, b"S", 12);
    assert_eq!(a[0], b's');
    let static_bytes = u16::from_le_bytes([a[1], a[2]]) as u64;
    let stack_bytes = u16::from_le_bytes([a[3], a[4]]) as u64;
    let mcusr = a[5];
    let ms = u32::from_le_bytes([a[8], a[9], a[10], a[11]]) as u64;
    let elapsed_ms = emu.cycle() / 16_000;
    assert_eq!(
        static_bytes, sizes.sram_static_bytes,
        "static SRAM: firmware vs ELF"
    );
    assert!(stack_bytes > 0 && static_bytes + stack_bytes <= SRAM_BUDGET_BYTES);
    assert_eq!(mcusr & 0x01, 0x01, "power-on reset flag after boot");
    assert_eq!(mcusr & 0x08, 0, "no watchdog reset");
    // The clock starts after the SRAM painting (a few ms) and the status answer is sent
    // after the stack scan.
    assert!(
        ms >= 5 && ms <= elapsed_ms,
        "clock {ms} ms after {elapsed_ms} ms"
    );

    // The clock runs at 1 kHz: 100 ms later it advanced by the elapsed simulated time.
    let (cycle0, ms0) = (emu.cycle(), ms);
    emu.run_us(100_000);
    let b = request(&mut emu, b"S", 12);
    let ms1 = u32::from_le_bytes([b[8], b[9], b[10], b[11]]) as u64;
    let elapsed = (emu.cycle() - cycle0) as f64 / 16_000.0;
    assert!(
        ((ms1 - ms0) as f64 - elapsed).abs() <= 2.0,
        "clock advanced {} ms in {elapsed:.1} ms",
        ms1 - ms0
    );
    assert!(
        sizes.flash_bytes <= 32 * 1024,
        "flash {} B",
        sizes.flash_bytes
    );
}

#[test]
fn outputs_stay_low_until_enabled() {
    let mut emu = boot();
    for (port, bit) in SERVO_PINS {
        assert!(emu.is_output(port, bit), "P{port}{bit} is an output");
    }
    let idle = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    assert!(idle.iter().all(|(_, high)| !high), "no pulse at power-on");
    write_pulses(&mut emu, &distinct_ticks());
    let written = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    assert!(
        written.iter().all(|(_, high)| !high),
        "pulses written but not enabled: still low"
    );
    assert_eq!(request(&mut emu, b"E", 1), b"e");
    let enabled = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    assert!(
        enabled.iter().all(|(_, high)| *high),
        "enabled: every channel pulses"
    );
}

#[test]
fn all_twelve_channels_pulse_at_50_hz_with_the_written_widths() {
    let mut emu = boot();
    let ticks = distinct_ticks();
    write_pulses(&mut emu, &ticks);
    assert_eq!(request(&mut emu, b"E", 1), b"e");
    // Skip the period in progress, then observe two full periods.
    emu.run_cycles(PERIOD_CYCLES);
    let seen = emu.watch_servos(2 * PERIOD_CYCLES + PERIOD_CYCLES / 4);
    for (ch, ((port, bit), (pulse, _))) in SERVO_PINS.iter().zip(seen).enumerate() {
        let p = pulse.unwrap_or_else(|| panic!("channel {ch} (P{port}{bit}): no pulse"));
        let want = ticks[ch] as u64 * CYCLES_PER_TICK;
        assert!(
            p.high_cycles.abs_diff(want) <= EDGE_TOLERANCE_CYCLES,
            "channel {ch} (P{port}{bit}): high {} cycles, want {want}",
            p.high_cycles
        );
        let period = p
            .period_cycles
            .unwrap_or_else(|| panic!("channel {ch}: no second period"));
        assert!(
            period.abs_diff(PERIOD_CYCLES) <= EDGE_TOLERANCE_CYCLES,
            "channel {ch} (P{port}{bit}): period {period} cycles"
        );
    }
}

#[test]
fn disable_drives_every_pin_low_and_a_new_width_applies() {
    let mut emu = boot();
    write_pulses(&mut emu, &distinct_ticks());
    assert_eq!(request(&mut emu, b"E", 1), b"e");
    emu.run_cycles(PERIOD_CYCLES / 2);
    assert_eq!(request(&mut emu, b"D", 1), b"d");
    let off = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    assert!(off.iter().all(|(_, high)| !high), "disabled: all low");
    assert_eq!(emu.servo_levels(), 0);

    // Re-enable with new widths (1500 µs everywhere, channel 11 at 2000 µs).
    let mut ticks = [3000u16; 12];
    ticks[11] = 4000;
    write_pulses(&mut emu, &ticks);
    assert_eq!(request(&mut emu, b"E", 1), b"e");
    emu.run_cycles(PERIOD_CYCLES);
    let seen = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    for (ch, (pulse, _)) in seen.iter().enumerate() {
        let p = pulse.expect("pulse after re-enabling");
        let want = ticks[ch] as u64 * CYCLES_PER_TICK;
        assert!(
            p.high_cycles.abs_diff(want) <= EDGE_TOLERANCE_CYCLES,
            "channel {ch}"
        );
    }
}

#[test]
fn pulse_longer_than_a_period_is_refused_and_nothing_moves() {
    let mut emu = boot();
    let mut ticks = distinct_ticks();
    write_pulses(&mut emu, &ticks);
    ticks[4] = (PERIOD_TICKS + 1) as u16;
    let mut req = vec![b'W'];
    for t in ticks {
        req.extend(t.to_le_bytes());
    }
    assert_eq!(request(&mut emu, &req, 2), b"w\x01", "refused");
    assert_eq!(request(&mut emu, b"E", 1), b"e");
    emu.run_cycles(PERIOD_CYCLES);
    let seen = emu.watch_servos(PERIOD_CYCLES + PERIOD_CYCLES / 4);
    let before = distinct_ticks();
    for (ch, (pulse, _)) in seen.iter().enumerate() {
        let p = pulse.expect("pulse");
        let want = before[ch] as u64 * CYCLES_PER_TICK;
        assert!(
            p.high_cycles.abs_diff(want) <= EDGE_TOLERANCE_CYCLES,
            "channel {ch}"
        );
    }
}

#[test]
fn onboard_ik_matches_the_host_within_the_readback_bound() {
    let mut emu = boot();
    let robot = avr_bench::robot();
    let targets = avr_bench::targets();
    let mut worst = 0.0f64;
    for pose in targets.poses.iter().take(20) {
        let mut req = vec![b'P'];
        for v in pose.to_array() {
            req.extend(v.to_le_bytes());
        }
        let a = request(&mut emu, &req, 2 + 48);
        assert_eq!(&a[..2], b"p\0", "firmware solves {pose:?}");
        let host = body::inverse_at_stance_with::<Libm>(
            &robot,
            pose,
            &BodyConfig::default(),
            STANCE_HEIGHT_M,
            ReachPolicy::Reject,
        )
        .expect("host solves the pose")
        .flat();
        for (i, h) in host.iter().enumerate() {
            let b = &a[2 + 4 * i..6 + 4 * i];
            let avr = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            assert!(avr.is_finite());
            worst = worst.max((avr as f64 - *h as f64).abs());
        }
    }
    assert!(
        worst <= READBACK_BOUND_RAD,
        "firmware vs host: {worst:e} rad > {READBACK_BOUND_RAD:e}"
    );

    // An unreachable pose (body lifted 1 m) is refused.
    let mut req = vec![b'P'];
    for v in [0.0f32, 0.0, 0.0, 0.0, 0.0, 1.0] {
        req.extend(v.to_le_bytes());
    }
    let a = request(&mut emu, &req, 2 + 48);
    assert_eq!(&a[..2], b"p\x01");
}
