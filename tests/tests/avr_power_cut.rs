//! Power cuts at every byte of a calibration save, on the firmware in simavr. The EEPROM is
//! recorded after each byte the save writes (the emulated EEPROM completes a byte at once, see
//! `quad_host::emu::Mega2560`), and for each prefix — and for each byte caught between its erase
//! and its write (read back as `0xFF`) — a fresh chip boots from that EEPROM. It must hold the
//! old calibration or the new one, all twelve servos from the same save and CRC-valid (never
//! the defaults, never a mix), and boot with its outputs off. Both banks are cut: the first save
//! goes to one, the second to the other. Simulated time.

use integration_tests::wire::{self, frame};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::servo::Calibration;
use quad_protocol::{DeviceToHost, Flags, Request, ServoId, PROTOCOL_VERSION};
use std::path::PathBuf;
use std::time::Duration;

type Table = [Calibration; 12];

/// Longer than a save of 191 bytes at 3.4 ms each.
const SAVE_TIME: Duration = Duration::from_millis(900);

/// How often the EEPROM is read during a save: well below one byte's 3.4 ms.
const SNAPSHOT_EVERY: Duration = Duration::from_micros(500);

fn elf() -> PathBuf {
    build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"))
}

struct Board {
    link: EmulatorLink,
    seq: u16,
}

impl Board {
    fn boot(eeprom: Option<Vec<u8>>) -> Board {
        let config = EmulatorConfig {
            eeprom,
            ..EmulatorConfig::new(115_200)
        };
        let link = EmulatorLink::boot(&elf(), config).unwrap_or_else(|e| panic!("{e}"));
        let mut board = Board { link, seq: 0 };
        match board.ask(Request::Hello {
            version: PROTOCOL_VERSION,
        }) {
            DeviceToHost::HelloAck { .. } => {}
            other => panic!("Hello: {other:?}"),
        }
        board
    }

    fn ask(&mut self, request: Request) -> DeviceToHost {
        self.seq += 1;
        wire::ask(&mut self.link, self.seq, request, Duration::from_secs(2))
    }

    fn flags(&mut self) -> Flags {
        match self.ask(Request::GetState) {
            DeviceToHost::Ack { readback, .. } => readback.flags,
            other => panic!("GetState: {other:?}"),
        }
    }

    fn table(&mut self) -> Table {
        core::array::from_fn(|i| {
            match self.ask(Request::GetCalibration {
                servo: ServoId::ALL[i],
            }) {
                DeviceToHost::Calibration { calibration, .. } => calibration,
                other => panic!("GetCalibration: {other:?}"),
            }
        })
    }

    fn set_table(&mut self, table: &Table) {
        for (i, c) in table.iter().enumerate() {
            let answer = self.ask(Request::SetCalibration {
                servo: ServoId::ALL[i],
                calibration: *c,
            });
            assert!(
                matches!(answer, DeviceToHost::Configured { .. }),
                "{answer:?}"
            );
        }
    }

    /// Saves, recording the EEPROM after every byte written: the images from before the first
    /// byte to after the last.
    fn save_recording(&mut self) -> Vec<Vec<u8>> {
        self.seq += 1;
        let bytes = frame(self.seq, Request::SaveCalibration);
        let mut images = vec![self.link.mcu_mut().eeprom()];
        quad_host::link::Link::send(&mut self.link, &bytes).expect("send");
        let mut waited = Duration::ZERO;
        while waited < SAVE_TIME {
            self.link.idle(SNAPSHOT_EVERY).expect("runs");
            waited += SNAPSHOT_EVERY;
            let now = self.link.mcu_mut().eeprom();
            let last = images.last().expect("an image");
            if &now != last {
                let changed = now.iter().zip(last).filter(|(a, b)| a != b).count();
                assert_eq!(changed, 1, "one byte per snapshot");
                images.push(now);
            }
        }
        let answers = wire::answers(&mut self.link, &[], Duration::from_millis(50), None);
        assert!(
            matches!(answers.as_slice(), [DeviceToHost::Ack { .. }]),
            "SaveCalibration: {answers:?}"
        );
        images
    }
}

/// Every servo's centre moved by `delta_us` from `base`.
fn shifted(base: &Table, delta_us: i16) -> Table {
    core::array::from_fn(|i| Calibration {
        center_us: base[i]
            .center_us
            .checked_add_signed(delta_us)
            .expect("in range"),
        ..base[i]
    })
}

/// The EEPROM images a power cut can leave during the save recorded as `images`: each prefix,
/// and each byte between its erase and its write.
fn cuts(images: &[Vec<u8>]) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for (k, image) in images.iter().enumerate() {
        out.push((format!("after {k} bytes"), image.clone()));
        if let Some(next) = images.get(k + 1) {
            let at = next
                .iter()
                .zip(image)
                .position(|(a, b)| a != b)
                .expect("a byte changed");
            let mut torn = image.clone();
            torn[at] = 0xFF;
            out.push((
                format!("byte {} of the save erased, not written", k + 1),
                torn,
            ));
        }
    }
    out
}

#[test]
fn a_power_cut_at_every_byte_of_a_save_keeps_the_old_or_the_new_calibration() {
    let mut board = Board::boot(None);
    let defaults = board.table();
    let first = shifted(&defaults, 8);
    let second = shifted(&defaults, -8);
    // The first save: defaults → `first` (into one bank).
    board.set_table(&first);
    let images_1 = board.save_recording();
    // The second: `first` → `second` (into the other).
    board.set_table(&second);
    let images_2 = board.save_recording();
    assert!(
        images_1.len() > 150 && images_2.len() > 150,
        "a save writes a bank: {} and {} images",
        images_1.len(),
        images_2.len()
    );

    let mut checked = 0;
    for (old, new, images, default_ok) in [
        (&defaults, &first, &images_1, true),
        (&first, &second, &images_2, false),
    ] {
        for (when, image) in cuts(images) {
            let mut after = Board::boot(Some(image));
            let flags = after.flags();
            assert!(
                !flags.contains(Flags::OUTPUTS_ENABLED),
                "{when}: the outputs are on at boot"
            );
            let table = after.table();
            // Before the first save ever completes, the chip has no valid bank: the defaults,
            // reported as such.
            let from_defaults = default_ok && flags.contains(Flags::CALIBRATION_DEFAULT);
            assert!(
                (table == *old && (from_defaults || !flags.contains(Flags::CALIBRATION_DEFAULT)))
                    || (table == *new && !flags.contains(Flags::CALIBRATION_DEFAULT)),
                "{when}: neither the old nor the new calibration (flags {flags:?}): {table:?}"
            );
            checked += 1;
        }
    }
    println!(
        "power cuts: {checked} EEPROM states booted ({} + {} bytes written by the two saves), \
         each with the old or the new calibration",
        images_1.len() - 1,
        images_2.len() - 1
    );
}
