//! The firmware in the loop: the firmware ELF runs in simavr (quad-host's emulator link) and
//! the twin's frames are the pulses measured on its twelve servo pins, mapped back to angles
//! through the calibration the firmware reports.
//!
//! Every frame, the motion's feet go to the firmware as a `SetFeet` request over its emulated
//! UART; once it has answered, the link runs the MCU until each servo pin has shown a complete
//! pulse that started afterwards (the hardware takes new compare values over at the start of a
//! period, so these pulses carry the request). The firmware's own IK, pulse mapping and timer
//! code make the frame.
//!
//! Onboard ([`Emulated::boot`] with `onboard`), the firmware runs the motion itself: it gets
//! `StartMotion` once and, for a walk, the velocity command at 10 Hz
//! ([`crate::source::onboard_request`]). Its engine keeps time by the MCU's clock, so the
//! emulator runs exactly one PWM period of MCU time per frame (a request's exchange included)
//! and the frame is the last complete pulse of each pin.
//!
//! The twin's IMU samples go into a [`TwinImu`] ([`Emulated::imu_feed`]) timed on the MCU's
//! clock: the twin holds a frame's pulses from the MCU time at which they were measured (run
//! onboard: the end of the frame's PWM period, exactly one period after the last), so a sample
//! taken `δ` into that frame is due at that time plus `δ`. The samples of frame `k` arrive
//! before the MCU runs on for frame `k + 1`, so a sensor that reads the feed as the MCU runs
//! finds the samples up to its time. Host-driven, a frame's exchange can take the MCU less
//! than a period; the next frame's samples then replace the overlapped ones. The emulator's
//! virtual MPU-6050 at 0x68 on the chip's TWI reads them through a callback source
//! (`Feed(move |t_s| feed.sample_at(t_s))`, `t_s` the MCU's cycle count over [`F_CPU_HZ`]): the
//! firmware's own TWI driver reads the twin's accelerometer and gyroscope, with the
//! MPU-6050's noise added ([`Noisy::mpu6050`]: noiseless readings that repeat exactly, as the
//! robot at rest before the twin's first sample, are what the firmware's stuck-sensor check
//! catches).
//!
//! With balance settings ([`Emulated::set_balance`]) the firmware gets them as a `SetBalance`
//! request at the first frame (retried each frame while it answers that its sensor is absent),
//! and every frame, after the frame's own request, a `GetImu`: its estimated roll and pitch go
//! into the frame ([`DeviceFrame::estimated_rpy_rad`], the firmware's estimate from the
//! samples it read up to that exchange: the physics about one frame old) with its fall flag.

use crate::device::DeviceError;
use crate::imu::{TwinImu, GRAVITY_M_S2};
use crate::link::BodyState;
use crate::motions::Plan;
use crate::scenario::Scenario;
use crate::source::{imu_readings, onboard_request, DeviceFrame, FrameSource};
use kin_core::motion::gait::Velocity;
use quad_device::sim::imu::{Feed, Noisy};
use quad_device::Config;
use quad_device::{ImuReading, ImuSample};
use quad_host::client::{Client, ClientConfig};
use quad_host::emu::SharedImuSource;
use quad_host::emu::{CYCLES_PER_TICK, F_CPU_HZ, PERIOD_CYCLES};
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::servo::Calibration;
use quad_protocol::{BalanceConfig, DeviceToHost, MotionCommand, NackReason, Request, ServoId};
use std::path::Path;

/// The line rate of the firmware the emulated source boots (`firmware.elf`), bit/s.
pub const FIRMWARE_BAUD: u32 = 115_200;

/// The seed of the emulated MPU-6050's noise ([`Noisy::mpu6050`] on the twin's samples).
pub const IMU_NOISE_SEED: u64 = 22;

/// The firmware in simavr, driven by a host sending `SetFeet` every frame.
pub struct Emulated {
    plan: Plan,
    client: Client<EmulatorLink>,
    calibration: [Calibration; 12],
    /// The onboard motion and a walk's velocity; `None`: `SetFeet` every frame.
    onboard: Option<(MotionCommand, Option<Velocity>)>,
    /// The MCU cycle at which an onboard run's frame 0 began.
    start_cycle: Option<u64>,
    /// The twin's IMU samples on the MCU's clock.
    imu: TwinImu,
    /// The MCU cycle at which the last frame's pulses were measured: when the twin began to
    /// hold them.
    frame_cycle: Option<u64>,
    /// Balance settings not yet accepted.
    pending_balance: Option<BalanceConfig>,
    /// Read the firmware's balance report every frame.
    read_imu: bool,
    /// Hold the pose while the plan holds the stance (host-driven, leveling on).
    hold_pose: bool,
    /// The pose was sent.
    pose_held: bool,
    /// The outputs are to be enabled again with the first frame's request.
    enable_at_start: bool,
}

impl Emulated {
    /// Boots `elf` (none: the firmware built from `firmware-avr/` at [`FIRMWARE_BAUD`]), says
    /// hello, reads its calibration, sets its joint-speed limit to `config`'s and enables its
    /// outputs.
    ///
    /// # Errors
    /// [`crate::Error::Emulator`] when the emulator or the link fails,
    /// [`crate::Error::FirmwareConfig`] when the firmware runs another robot or stance than
    /// `config`, [`crate::Error::NotOnboard`] when `onboard` asks for a plan without an
    /// onboard form.
    pub fn boot(
        plan: Plan,
        config: &Config,
        elf: Option<&Path>,
        onboard: bool,
    ) -> Result<Emulated, crate::Error> {
        Emulated::boot_on(plan, config, elf, onboard, &Scenario::default())
    }

    /// [`Emulated::boot`] for a run on `scenario`'s floor: the IMU feed reads the robot at
    /// rest on it until the twin's first sample.
    ///
    /// # Errors
    /// As [`Emulated::boot`].
    pub fn boot_on(
        plan: Plan,
        config: &Config,
        elf: Option<&Path>,
        onboard: bool,
        scenario: &Scenario,
    ) -> Result<Emulated, crate::Error> {
        let onboard = match onboard {
            false => None,
            true => Some(plan.onboard().ok_or(crate::Error::NotOnboard {
                motion: plan.kind().name(),
            })?),
        };
        // The feed the emulated sensor reads; the robot at rest on the floor until the twin's
        // first sample.
        let imu = TwinImu::new(ImuSample {
            accel_m_s2: scenario.at_rest_accel_m_s2(GRAVITY_M_S2),
            gyro_rad_s: [0.0; 3],
        });
        let feed = imu.clone();
        let emulator = EmulatorConfig {
            // With the MPU-6050's own noise: a noiseless reading repeats exactly (the robot at
            // rest before the twin's first sample), which the firmware rightly takes for a
            // stuck sensor.
            imu: Some(SharedImuSource::new(Noisy::mpu6050(
                Feed(move |t_s| feed.sample_at(t_s)),
                IMU_NOISE_SEED,
            ))),
            ..EmulatorConfig::new(FIRMWARE_BAUD)
        };
        let link = match elf {
            Some(path) => EmulatorLink::boot(path, emulator),
            None => EmulatorLink::boot_built(emulator),
        }
        .map_err(|e| crate::Error::Emulator(quad_host::client::Error::Link(e.into())))?;
        let mut client = Client::new(link, ClientConfig::emulator());
        let info = client.hello().map_err(crate::Error::Emulator)?;
        if info.robot != config.preset || info.pose_config != config.pose_config {
            return Err(crate::Error::FirmwareConfig {
                firmware: info.robot,
            });
        }
        let calibration = client.calibrations().map_err(crate::Error::Emulator)?;
        client
            .ack(Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s: config.joint_speed_limit_rad_s,
            })
            .map_err(crate::Error::Emulator)?;
        client
            .ack(Request::SetOutputs { enabled: true })
            .map_err(crate::Error::Emulator)?;
        Ok(Emulated {
            plan,
            client,
            calibration,
            onboard,
            start_cycle: None,
            imu,
            frame_cycle: None,
            pending_balance: None,
            read_imu: false,
            hold_pose: false,
            pose_held: false,
            enable_at_start: false,
        })
    }

    /// Configures the firmware's balance functions with `config` (a `SetBalance` at the next
    /// frame, retried each frame while the firmware has no reading yet) and reads its balance
    /// report (`GetImu`) every frame from then on: its attitude estimate and fall flag go into
    /// the frames.
    /// Host-driven with leveling on, the zero pose is held while the plan holds the stance
    /// ([`crate::source::host_request`]): leveling acts on a held pose.
    ///
    /// The MCU first runs [`crate::device::REST_BEFORE_RUN_FRAMES`] servo frames idle with
    /// its outputs off, its sensor reading the robot at rest (the feed before the twin's first
    /// sample), for its gyro-bias measurement; the outputs are enabled again just before the
    /// first frame's request.
    ///
    /// # Errors
    /// [`crate::Error::Emulator`] when the emulator fails meanwhile.
    pub fn set_balance(&mut self, config: BalanceConfig) -> Result<(), crate::Error> {
        self.pending_balance = Some(config);
        self.read_imu = true;
        self.hold_pose = config.leveling;
        self.client
            .ack(Request::SetOutputs { enabled: false })
            .map_err(crate::Error::Emulator)?;
        self.client
            .link_mut()
            .idle(std::time::Duration::from_millis(
                u64::from(crate::device::REST_BEFORE_RUN_FRAMES) * 20,
            ))
            .map_err(|e| crate::Error::Emulator(e.into()))?;
        self.enable_at_start = true;
        Ok(())
    }

    /// The firmware's balance report now (`GetImu`).
    ///
    /// # Errors
    /// [`crate::Error::Emulator`] when the exchange fails, [`crate::Error::Protocol`] for
    /// another answer.
    pub fn imu_report(&mut self) -> Result<quad_protocol::ImuReport, crate::Error> {
        match self
            .client
            .request(Request::GetImu)
            .map_err(crate::Error::Emulator)?
        {
            DeviceToHost::Imu { report, .. } => Ok(report),
            _ => Err(crate::Error::Protocol("expected the IMU report")),
        }
    }

    /// Sends the pending balance settings and reads the balance report: the frame's estimate
    /// and fall flag (none, false: no report read).
    fn balance_exchange(&mut self) -> Result<(Option<[f32; 3]>, bool), crate::Error> {
        if let Some(config) = self.pending_balance {
            // The firmware answers with its balance report.
            match self.client.request(Request::SetBalance(config)) {
                Ok(DeviceToHost::Imu { .. }) => self.pending_balance = None,
                Ok(_) => return Err(crate::Error::Protocol("expected the IMU report")),
                Err(quad_host::client::Error::Refused {
                    reason: NackReason::ImuAbsent,
                    ..
                }) => {}
                Err(e) => return Err(crate::Error::Emulator(e)),
            }
        }
        if !self.read_imu {
            return Ok((None, false));
        }
        let report = self.imu_report()?;
        Ok((
            crate::source::estimated_rpy_rad(&report),
            report.fall.is_some(),
        ))
    }

    /// The twin's IMU samples, timed on the MCU's clock (a clone sharing the queue): what the
    /// emulated sensor reads ([`TwinImu::read`] with the MCU's time).
    pub fn imu_feed(&self) -> TwinImu {
        self.imu.clone()
    }

    /// Queues the IMU samples of the frame the twin answered with `state`: due at the MCU
    /// time the frame's pulses were measured plus their time into the frame.
    fn queue_imu(&mut self, state: &BodyState) -> Result<(), crate::Error> {
        let Some(cycle) = self.frame_cycle else {
            return Ok(());
        };
        let frame_start_s = cycle as f64 / f64::from(F_CPU_HZ);
        for (after_ns, reading) in imu_readings(state)? {
            if let ImuReading::Sample(sample) = reading {
                self.imu
                    .push(frame_start_s + after_ns as f64 * 1e-9, sample)
                    .map_err(|_| crate::Error::Protocol("an IMU sample's time is not finite"))?;
            }
        }
        Ok(())
    }
}

impl FrameSource for Emulated {
    fn frame_count(&self) -> u32 {
        crate::source::frame_count(&self.plan)
    }

    fn next(&mut self, k: u32, feedback: Option<&BodyState>) -> Result<DeviceFrame, crate::Error> {
        if let Some(state) = feedback {
            self.queue_imu(state)?;
        }
        let t_s = k as f32 * crate::source::FRAME_S;
        let target = self.plan.target(t_s).map_err(crate::Error::Motion)?;
        if std::mem::take(&mut self.enable_at_start) {
            self.client
                .ack(Request::SetOutputs { enabled: true })
                .map_err(crate::Error::Emulator)?;
        }
        // The MCU cycle from which the twin holds this frame's pulses: the end of its PWM
        // period onboard, else when they were measured.
        let mut held_from = None;
        let balance;
        let pulses = match self.onboard {
            None => {
                if let Some(request) = crate::source::host_request(
                    &self.plan,
                    k,
                    &target,
                    self.hold_pose,
                    &mut self.pose_held,
                ) {
                    self.client.ack(request).map_err(crate::Error::Emulator)?;
                }
                balance = self.balance_exchange()?;
                self.client
                    .link_mut()
                    .next_pulses()
                    .map_err(|e| crate::Error::Emulator(e.into()))?
            }
            Some((command, velocity)) => {
                let start = *self
                    .start_cycle
                    .get_or_insert(self.client.link().mcu().cycle());
                if let Some(request) = onboard_request(k, command, velocity) {
                    self.client
                        .request(request)
                        .map_err(crate::Error::Emulator)?;
                }
                balance = self.balance_exchange()?;
                let end = start + (u64::from(k) + 1) * PERIOD_CYCLES;
                held_from = Some(end);
                let now = self.client.link().mcu().cycle();
                if now < end {
                    let idle = std::time::Duration::from_nanos(
                        (end - now) * 1_000_000_000 / u64::from(F_CPU_HZ),
                    );
                    self.client
                        .link_mut()
                        .idle(idle)
                        .map_err(|e| crate::Error::Emulator(e.into()))?;
                }
                self.client.link().last_pulses()
            }
        };
        let mut pulses_half_us = [0; 12];
        let mut angles_rad = [0.0; 12];
        for s in ServoId::ALL {
            let i = s.index();
            let Some(pulse) = pulses[i] else {
                return Err(crate::Error::NoPulse { frame: k, servo: s });
            };
            // Timer ticks (0.5 µs) to the nearest tick: the edges are seen up to one
            // instruction late.
            let ticks = (pulse.high_cycles + CYCLES_PER_TICK / 2) / CYCLES_PER_TICK;
            let half_us =
                u16::try_from(ticks).map_err(|_| crate::Error::NoPulse { frame: k, servo: s })?;
            pulses_half_us[i] = half_us;
            angles_rad[i] =
                self.calibration[i]
                    .angle_rad(half_us)
                    .map_err(|fault| crate::Error::Device {
                        frame: k,
                        error: DeviceError::Unmappable { servo: s, fault },
                    })?;
        }
        self.frame_cycle = Some(held_from.unwrap_or_else(|| self.client.link().mcu().cycle()));
        Ok(DeviceFrame {
            t_s,
            enabled: true,
            pulses_half_us,
            angles_rad,
            commanded_pose: target.pose,
            stance: target.stance,
            estimated_rpy_rad: balance.0,
            fall_detected: balance.1,
            // The firmware's report is read once a frame: the sample is not known.
            fall_latched_t_s: None,
        })
    }
}
