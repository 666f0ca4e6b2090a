//! The MPU-6050 on the firmware's TWI, in simavr: the flashed ELF with a virtual sensor at
//! 0x68 (`quad_host::emu`, `EmulatorConfig::imu`) fed by `quad_device::sim::imu` sources.
//!
//! - boot: `WHO_AM_I` read and `CONFIG_SEQUENCE` written, in order (the virtual sensor records
//!   the writes); no sensor → the firmware boots and an onboard motion runs as before; a
//!   wrong identity → `WrongId`;
//! - the trot steered at 20 Hz with the sensor read: the read rate from the bursts the sensor
//!   saw (≥ 100 Hz), no late servo frame, no UART byte lost, the longest main-loop pass
//!   (which holds the worst frame) ≤ 50 % of 20 ms, interrupts off within the UART's cover
//!   (the link checks it at every step);
//! - faults mid-run: NAK, stuck data, SDA held low → the right `ImuFault` reaches the device,
//!   and samples flow again once the fault clears.
//!
//! The device's sensor state is read from SRAM through the firmware's `IMU_WINDOW` symbol
//! (`firmware_avr::imu::Window`), the test's window until the protocol reports it.
//! `--nocapture` prints the figures of BENCHMARKS.md. All times are simulated.

use integration_tests::wire;
use kin_core::motion::gait::{GaitParams, Pattern};
use quad_device::imu::mpu6050::{CONFIG_SEQUENCE, READ_RATE_HZ};
use quad_device::imu::ImuFault;
use quad_device::sim::imu::{FaultWindow, Faulty, LevelStill, Noisy};
use quad_host::emu::elf::Elf;
use quad_host::emu::{build, SharedImuSource, CYCLES_PER_US, PERIOD_CYCLES};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_host::link::Link;
use quad_protocol::{DeviceToHost, MotionCommand, Request, PROTOCOL_VERSION};
use std::time::Duration;

/// The read rate the estimator needs, Hz.
const MIN_READ_RATE_HZ: f64 = 100.0;

/// The longest main-loop pass allowed: half a servo frame, µs.
const MAX_PASS_US: u16 = 10_000;

const STANCE_HEIGHT_M: f32 = 0.277;

/// The firmware's `imu::Window`, as read from SRAM.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Window {
    samples: u32,
    fault: u8,
    who_am_i: u8,
    recoveries: u16,
    longest_pass_us: u16,
    bursts_skipped: u16,
}

impl Window {
    /// The fault as the device holds it.
    fn fault(&self) -> Option<&'static str> {
        match self.fault {
            0 => None,
            1 => Some("Absent"),
            2 => Some("WrongId"),
            3 => Some("Nak"),
            4 => Some("Stuck"),
            5 => Some("BusHeld"),
            _ => Some("unknown code"),
        }
    }
}

fn name_of(f: ImuFault) -> &'static str {
    match f {
        ImuFault::Absent => "Absent",
        ImuFault::WrongId { .. } => "WrongId",
        ImuFault::Nak => "Nak",
        ImuFault::Stuck => "Stuck",
        ImuFault::BusHeld => "BusHeld",
    }
}

struct Board {
    link: EmulatorLink,
    window_addr: u16,
    seq: u16,
}

impl Board {
    fn boot(imu: Option<SharedImuSource>) -> Board {
        let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
        let window_addr = Elf::read(&elf)
            .expect("the ELF reads")
            .data_symbol("IMU_WINDOW")
            .expect("the firmware has its IMU_WINDOW");
        let config = EmulatorConfig {
            imu,
            ..EmulatorConfig::new(115_200)
        };
        let link = EmulatorLink::boot(&elf, config).unwrap_or_else(|e| panic!("{e}"));
        let mut board = Board {
            link,
            window_addr,
            seq: 0,
        };
        board.ask(Request::Hello {
            version: PROTOCOL_VERSION,
        });
        board
    }

    fn window(&self) -> Window {
        let b = self.link.mcu().data_bytes(self.window_addr, 12);
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        Window {
            samples: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            fault: b[4],
            who_am_i: b[5],
            recoveries: u16_at(6),
            longest_pass_us: u16_at(8),
            bursts_skipped: u16_at(10),
        }
    }

    fn ask(&mut self, request: Request) -> DeviceToHost {
        self.seq = self.seq.wrapping_add(1);
        let answer = wire::ask(&mut self.link, self.seq, request, Duration::from_secs(2));
        assert!(
            !matches!(answer, DeviceToHost::Nack { .. }),
            "{request:?}: {answer:?}"
        );
        answer
    }

    fn idle_s(&mut self, s: f64) {
        self.link
            .idle(Duration::from_secs_f64(s))
            .expect("the MCU runs");
    }

    fn now_s(&self) -> f64 {
        self.link.now().as_secs_f64()
    }

    fn wait_idle(&mut self) {
        for _ in 0..600 {
            self.idle_s(0.037);
            if let DeviceToHost::MotionAck { status, .. } = self.ask(Request::GetMotion) {
                if status.kind.is_none() {
                    return;
                }
            }
        }
        panic!("the motion did not end");
    }
}

fn noisy_level(seed: u64) -> SharedImuSource {
    SharedImuSource::new(Noisy::mpu6050(LevelStill, seed))
}

#[test]
fn boot_reads_who_am_i_and_writes_the_configuration_then_samples_flow() {
    let mut board = Board::boot(Some(noisy_level(1)));
    board.idle_s(0.5);
    let bus = board.link.imu_bus().expect("a sensor").clone();
    let w = board.window();
    println!(
        "{w:?}; writes {:x?}; {} bursts",
        bus.writes,
        bus.burst_cycles.len()
    );
    assert!(bus.who_am_i_reads >= 1, "WHO_AM_I read");
    assert_eq!(
        bus.writes,
        CONFIG_SEQUENCE.to_vec(),
        "the configuration, in order"
    );
    assert_eq!(w.who_am_i, 0x68);
    assert_eq!(w.fault(), None);
    assert!(w.samples > 40, "samples pushed: {}", w.samples);
    assert!(bus.burst_cycles.len() as u32 >= w.samples);
}
