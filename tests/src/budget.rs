//! The firmware's flash and SRAM budget, measured: flash and static SRAM from the release ELF's
//! sections, the stack as the deepest of the firmware's own paint mark and the stack pointer's
//! low-water mark in simavr, after a workload that sends every request type and runs every
//! onboard motion with the MPU-6050 on the bus and read throughout (`cargo xtask ci
//! budget`, `cargo run -p integration-tests --bin firmware-budget`).
//!
//! The budget leaves most of the ATmega2560 (248 KB of flash for the application, 8 KB of SRAM)
//! for what comes next, and keeps an eye on growth: flash ≤ [`FLASH_BUDGET_BYTES`], static SRAM
//! plus the worst stack ≤ [`SRAM_BUDGET_BYTES`]. The flash line is the reach of the AVR's 16-bit
//! word-addressed function pointers (128 KB) without EIND trampolines; the SRAM line leaves
//! 2 KB of the 8 KB free. Data the firmware reads with `lpm` (its tables in flash) must lie in
//! the lowest 64 KB, `lpm`'s reach through the 16-bit Z pointer ([`LPM_REACH_BYTES`],
//! [`lpm_reach_violations`]).

use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{LegId, Pose, ReachPolicy, RotationOrder};
use quad_device::sim::imu::{LevelStill, Noisy};
use quad_host::client::{Client, ClientConfig};
use quad_host::emu::{elf, SharedImuSource};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::{
    DeviceToHost, LegSet, LinkLossAction, LinkTimeout, MotionCommand, PoseConfig, Request, ServoId,
    PROTOCOL_VERSION,
};
use std::fmt;
use std::path::Path;

/// Firmware flash budget (`.text + .data`), bytes: 128 KB, the reach of a 16-bit word address
/// (a function pointer without EIND trampolines).
pub const FLASH_BUDGET_BYTES: u64 = 128 * 1024;

/// Firmware SRAM budget (static `.data + .bss + .noinit` plus the worst stack), bytes: 6 KB of
/// the chip's 8 KB.
pub const SRAM_BUDGET_BYTES: u64 = 6 * 1024;

/// The flash bytes `lpm` reads through the 16-bit Z pointer (without RAMPZ): 64 KB.
pub const LPM_REACH_BYTES: u32 = 64 * 1024;

/// The firmware's data objects in flash (read with `lpm`) that end beyond [`LPM_REACH_BYTES`]:
/// each would be read from the wrong address. Empty when all lie in the lowest 64 KB.
///
/// # Panics
/// When the ELF cannot be read.
pub fn lpm_reach_violations(elf_path: &Path) -> Vec<elf::FlashObject> {
    elf::Elf::read(elf_path)
        .unwrap_or_else(|e| panic!("{e}"))
        .flash_objects()
        .into_iter()
        .filter(|o| o.end() > LPM_REACH_BYTES)
        .collect()
}

/// The stack paint byte of the firmware (`firmware_avr::stack::PAINT`).
pub const STACK_PAINT: u8 = 0xC5;

/// What the firmware uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Figures {
    /// `.text + .data`, bytes.
    pub flash_bytes: u64,
    /// `.data + .bss + .noinit`, bytes.
    pub sram_static_bytes: u64,
    /// Deepest stack byte written since boot (the firmware's paint), bytes.
    pub stack_paint_bytes: u64,
    /// Deepest stack pointer since boot (simavr), bytes.
    pub stack_pointer_bytes: u64,
}

impl Figures {
    /// The worst stack: the deeper of the two marks, bytes.
    pub fn stack_bytes(&self) -> u64 {
        self.stack_paint_bytes.max(self.stack_pointer_bytes)
    }

    /// Static SRAM plus the worst stack, bytes.
    pub fn sram_bytes(&self) -> u64 {
        self.sram_static_bytes + self.stack_bytes()
    }

    /// True when both figures are within their budgets.
    pub fn within_budget(&self) -> bool {
        self.flash_bytes <= FLASH_BUDGET_BYTES && self.sram_bytes() <= SRAM_BUDGET_BYTES
    }
}

impl fmt::Display for Figures {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let line = |f: &mut fmt::Formatter<'_>, name: &str, used: u64, budget: u64| {
            let margin = budget as i64 - used as i64;
            writeln!(
                f,
                "{name:<6} {used:>6} B of {budget:>6} B ({:>5.1} %), margin {margin:>6} B{}",
                100.0 * used as f64 / budget as f64,
                if margin < 0 { "  OVER BUDGET" } else { "" }
            )
        };
        line(f, "flash", self.flash_bytes, FLASH_BUDGET_BYTES)?;
        line(f, "SRAM", self.sram_bytes(), SRAM_BUDGET_BYTES)?;
        write!(
            f,
            "       SRAM = static {} B + stack {} B (paint {} B, stack pointer {} B)",
            self.sram_static_bytes,
            self.stack_bytes(),
            self.stack_paint_bytes,
            self.stack_pointer_bytes
        )
    }
}

/// Every request type, in an order that lets each one act (handshake first, outputs on before
/// the calibration is replaced, the save last), with seed 000's robot's poses.
fn workload(poses: &[Pose]) -> Vec<Request> {
    let servo = ServoId {
        leg: LegId::RR,
        joint: kin_core::Joint::Knee,
    };
    let mut out = vec![
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
        Request::GetState,
        Request::SetPoseConfig(PoseConfig {
            stance_height_m: crate::avr_bench::STANCE_HEIGHT_M,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        }),
    ];
    out.extend(poses.iter().map(|p| Request::SetBodyPose(*p)));
    out.extend([
        Request::SetPoseConfig(PoseConfig {
            stance_height_m: crate::avr_bench::STANCE_HEIGHT_M,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Clamp,
        }),
        // Far out of reach: clamped.
        Request::SetBodyPose(Pose {
            z_m: 0.5,
            ..poses[0]
        }),
        Request::SetOutputs { enabled: true },
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 60_000,
            action: LinkLossAction::Hold,
        }),
        Request::GetCalibration { servo },
        Request::SaveCalibration,
        Request::SetOutputs { enabled: false },
        // The robot's requests (2.4), with the robot the firmware holds (nothing changes).
        Request::GetRobot,
        Request::SetRobot(quad_device::Config::shahriar2023().description()),
        Request::SaveRobot,
    ]);
    out
}

/// Boots the firmware `elf_path` in simavr, sends every request type (the body poses `poses`,
/// the joints the device reports back, the stance feet, a calibration written back) and
/// measures.
///
/// # Panics
/// When the ELF cannot be read or booted, or a request gets no answer.
pub fn measure(elf_path: &Path, poses: &[Pose]) -> Figures {
    // With the sensor read all along: its driver's path and the TWI interrupt count too.
    let config = EmulatorConfig {
        imu: Some(SharedImuSource::new(Noisy::mpu6050(LevelStill, 1))),
        ..EmulatorConfig::new(115_200)
    };
    let link = EmulatorLink::boot(elf_path, config).unwrap_or_else(|e| panic!("{e}"));
    let mut client = Client::new(link, ClientConfig::emulator());
    let mut last_angles = [0.0f32; 12];
    for request in workload(poses) {
        if let Request::SaveCalibration = request {
            // The joints of the last held pose, the stance feet, and a calibration written
            // back, before the save.
            let feet = crate::avr_bench::robot()
                .stance_feet(crate::avr_bench::STANCE_HEIGHT_M)
                .map(|f| f.to_array());
            for extra in [
                Request::SetJoints {
                    angles_rad: last_angles,
                },
                Request::SetFeet {
                    feet_in_body_m: feet,
                },
            ] {
                answer(&mut client, extra);
            }
            let servo = ServoId::ALL[11];
            let calibration = client.calibration(servo).unwrap_or_else(|e| panic!("{e}"));
            answer(&mut client, Request::SetCalibration { servo, calibration });
        }
        if let Request::SetOutputs { enabled: false } = request {
            // The onboard motions before the outputs go off: each start runs its start check,
            // the deepest calls of the firmware.
            run_motions(&mut client);
        }
        if let DeviceToHost::Ack { readback, .. } = answer(&mut client, request) {
            if readback.angles_rad.iter().any(|a| *a != 0.0) {
                last_angles = readback.angles_rad;
            }
        }
    }
    let image = elf::Elf::read(elf_path).unwrap_or_else(|e| panic!("{e}"));
    let heap_start = image
        .data_symbol("__heap_start")
        .expect("the ELF defines __heap_start");
    let sizes = image.sizes();
    let mcu = client.link().mcu();
    Figures {
        flash_bytes: sizes.flash_bytes,
        sram_static_bytes: sizes.sram_static_bytes,
        stack_paint_bytes: u64::from(mcu.painted_stack_bytes(heap_start, STACK_PAINT)),
        stack_pointer_bytes: u64::from(mcu.stack_peak_bytes()),
    }
}

/// Every onboard motion once, each run for a second of emulated time and then stopped cleanly:
/// stand-up, seed 001's sways and yaw turn, the statically stable turn, seed 000's rectangle, a
/// trot with velocity commands, sit.
fn run_motions(client: &mut Client<EmulatorLink>) {
    let h = crate::avr_bench::STANCE_HEIGHT_M;
    let motions = [
        MotionCommand::StandUp,
        MotionCommand::Sway {
            axis: Axis::Roll,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: None,
        },
        MotionCommand::YawTurn {
            yaw_rate_rad_s: 0.085,
            step_period_s: 2.0,
            lift_height_m: 0.03,
            duration_s: None,
        },
        MotionCommand::StableTurn {
            yaw_per_cycle_rad: 0.2,
            cycle_s: 2.0,
            lift_height_m: 0.03,
            shift_fraction: 0.8,
            duration_s: None,
        },
        MotionCommand::FootPath {
            path: PathKind::Rectangle,
            legs: LegSet::All,
            stride_m: 0.03,
            step_height_m: 0.02,
            duty_factor: 0.75,
            cycle_s: 2.0,
            duration_s: None,
        },
        MotionCommand::Walk {
            gait: Pattern::Trot,
            body_height_m: h,
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
            cycle_s: GaitParams::DEFAULT_CYCLE_S,
            velocity_timeout_ms: 500,
        },
        MotionCommand::Sit,
    ];
    for m in motions {
        answer(client, Request::StartMotion(m));
        for frame in 0..50 {
            if frame % 5 == 0 && matches!(m, MotionCommand::Walk { .. }) {
                answer(
                    client,
                    Request::SetVelocity {
                        forward_m_s: 0.02,
                        lateral_m_s: 0.0,
                        yaw_rate_rad_s: 0.05,
                    },
                );
            }
            client.link_mut().next_pulses().expect("the MCU runs");
        }
        answer(client, Request::StopMotion);
        // Until the motion has ended (a period, the strides, the ramp home): at most 20 s.
        for _ in 0..1000 {
            match answer(client, Request::GetMotion) {
                DeviceToHost::MotionAck { status, .. } if status.kind.is_none() => break,
                _ => {
                    client.link_mut().next_pulses().expect("the MCU runs");
                }
            }
        }
    }
}

/// The answer to `request`, which must not be a nack (each request of the workload does its
/// work).
fn answer(client: &mut Client<EmulatorLink>, request: Request) -> DeviceToHost {
    let answer = client
        .request(request)
        .unwrap_or_else(|e| panic!("{request:?}: {e}"));
    assert!(
        !matches!(answer, DeviceToHost::Nack { .. }),
        "{request:?} refused: {answer:?}"
    );
    answer
}
