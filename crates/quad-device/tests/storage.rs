//! Calibration persistence: a save cut by a power loss after any number of bytes keeps the
//! previous calibration; a damaged bank falls back to the other one.

mod common;

use common::*;
use quad_device::store::{Bank, Store, BANK_STRIDE, STORAGE_LEN};
use quad_device::{default_calibration, Config, Device};
use quad_protocol::servo::Calibration;
use quad_protocol::{DeviceToHost, Flags, NackReason, Request, ServoId};

type Table = [Calibration; 12];

fn boot(mem: RamEeprom) -> Dev {
    Device::new(
        Config::fernando2025(),
        Outputs::logging(),
        VirtualClock::default(),
        mem,
    )
    .unwrap()
}

/// A table distinct for each `tag`: every centre moved by `tag` µs.
fn table(tag: u16) -> Table {
    let c = Config::fernando2025();
    default_calibration::<kin_core::DefaultMath>(&c.robot, &c.pose_config).map(|cal| Calibration {
        center_us: 1500 - tag,
        ..cal
    })
}

/// Boots on `mem`, sets `t` and saves; returns the answer to the save and the storage.
fn save(mem: RamEeprom, t: &Table) -> (DeviceToHost, RamEeprom) {
    let mut dev = boot(mem);
    hello(&mut dev);
    // Nothing held that the new table could exclude: centre moves only, within travel.
    for (i, c) in t.iter().enumerate() {
        let a = ask(
            &mut dev,
            1 + i as u16,
            Request::SetCalibration {
                servo: ServoId::ALL[i],
                calibration: *c,
            },
        );
        assert!(
            matches!(
                a,
                DeviceToHost::Configured {
                    setting: quad_protocol::Setting::Calibration { calibration, .. },
                    ..
                } if calibration == *c
            ),
            "{a:?}"
        );
    }
    let answer = ask(&mut dev, 100, Request::SaveCalibration);
    let (_, _, mem) = dev.into_parts();
    (answer, mem)
}

fn saved(mem: RamEeprom, t: &Table) -> RamEeprom {
    let (answer, mut mem) = save(mem, t);
    assert!(matches!(answer, DeviceToHost::Ack { .. }));
    mem.write_budget = None;
    mem
}

#[test]
fn a_save_cut_at_every_byte_keeps_the_previous_calibration() {
    let defaults = table(0);
    for prior in 0..3u16 {
        // prior = 0: nothing stored; 1: bank A active; 2: bank B active.
        let mut base = RamEeprom::erased();
        for k in 1..=prior {
            base = saved(base, &table(10 * k));
        }
        let previous = if prior == 0 {
            defaults
        } else {
            table(10 * prior)
        };
        let new = table(77);
        let total = {
            let mut mem = base.clone();
            mem.written = 0;
            let (_, mem) = save(mem, &new);
            mem.written
        };
        assert_eq!(total, 191, "bytes written by one save");
        for cut in 0..=total {
            let mut mem = base.clone();
            mem.write_budget = Some(cut);
            let (answer, mut mem) = save(mem, &new);
            mem.write_budget = None;
            let dev = boot(mem);
            if cut < total {
                assert!(
                    matches!(
                        answer,
                        DeviceToHost::Nack {
                            reason: NackReason::Storage,
                            ..
                        }
                    ),
                    "cut {cut}"
                );
                assert_eq!(
                    dev.calibration(),
                    &previous,
                    "prior {prior}, cut after {cut} bytes"
                );
                assert_eq!(
                    dev.readback().flags.contains(Flags::CALIBRATION_DEFAULT),
                    prior == 0
                );
            } else {
                assert!(matches!(answer, DeviceToHost::Ack { .. }));
                assert_eq!(dev.calibration(), &new);
            }
            // The next save after the power cut completes and is loaded.
            let (_, _, mem) = dev.into_parts();
            let later = table(99);
            let mem = saved(mem, &later);
            assert_eq!(boot(mem).calibration(), &later, "prior {prior}, cut {cut}");
        }
    }
}

#[test]
fn a_damaged_bank_falls_back_to_the_other() {
    let first = table(5);
    let second = table(6);
    let mem = saved(saved(RamEeprom::erased(), &first), &second);
    // `second` went to bank B (generation 2).
    let mut store = Store::new(0);
    let mut t = table(0);
    let mut probe = mem.clone();
    assert!(store.load(&mut probe, &mut t));
    assert_eq!(store.active(), Some((Bank::B, 2)));
    for offset in 0..quad_device::store::BANK_LEN {
        let mut damaged = mem.clone();
        damaged.bytes[BANK_STRIDE as usize + offset] ^= 0x10;
        assert_eq!(
            boot(damaged).calibration(),
            &first,
            "byte {offset} of bank B"
        );
    }
    // Both damaged: the defaults, flagged.
    let mut both = mem.clone();
    both.bytes[10] ^= 1;
    both.bytes[BANK_STRIDE as usize + 10] ^= 1;
    let dev = boot(both);
    assert_eq!(dev.calibration(), &table(0));
    assert!(dev.readback().flags.contains(Flags::CALIBRATION_DEFAULT));
}

#[test]
fn erased_and_zeroed_storage_give_the_defaults() {
    for fill in [0xFF, 0x00] {
        let mut mem = RamEeprom::erased();
        mem.bytes = vec![fill; STORAGE_LEN as usize];
        let dev = boot(mem);
        assert_eq!(dev.calibration(), &table(0));
        assert!(dev.readback().flags.contains(Flags::CALIBRATION_DEFAULT));
    }
}
