//! The device controller (`quad-device`) in this process, as the twin drives it, on the shared
//! in-memory fakes (`quad_device::sim`): an erased EEPROM, a clock the loop advances by one
//! servo frame at a time (stopping at each IMU sample's time within the frame to hand the
//! sample over), outputs that keep the last pulses.

use quad_device::imu::ImuState;
use quad_device::sim::{Outputs, RamEeprom, VirtualClock};
use quad_device::{Config, ConfigError, Device, ImuReading};
use quad_protocol::servo::Error as ServoError;
use quad_protocol::{BalanceConfig, ImuHealth, ImuReport};
use quad_protocol::{DeviceToHost, HostToDevice, NackReason, Request, ServoId, PROTOCOL_VERSION};

/// Why the device refused a step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum DeviceError {
    /// The configuration was refused at power-on.
    Config(ConfigError),
    /// The device answered a request with a nack.
    Nack(NackReason),
    /// The device answered with something other than an ack.
    Unexpected,
    /// A pulse on the outputs does not map back through its servo's calibration (never for
    /// pulses the device wrote).
    Unmappable {
        /// The servo.
        servo: ServoId,
        /// Why.
        fault: ServoError,
    },
}

impl core::fmt::Display for DeviceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DeviceError::Config(e) => write!(f, "device configuration: {e}"),
            DeviceError::Nack(r) => write!(f, "the device refused the request: {r:?}"),
            DeviceError::Unexpected => f.write_str("the device answered with no ack"),
            DeviceError::Unmappable { servo, fault } => {
                write!(f, "servo {servo}: pulse does not map to an angle: {fault}")
            }
        }
    }
}

impl std::error::Error for DeviceError {}

/// Servo frames a device with balance settings runs, the robot still, before a run (1.1 s:
/// the gyro-bias measurement's second and a margin), so that it estimates and levels from the
/// run's first frame.
pub const REST_BEFORE_RUN_FRAMES: u32 = 55;

/// The device controller in this process, powered on, its outputs enabled: requests at message
/// level, its clock advanced one frame at a time by the loop.
pub struct InProcess {
    device: Device<Outputs, VirtualClock, RamEeprom>,
    clock: VirtualClock,
    seq: u16,
    /// Balance settings to send once the sensor has given a reading.
    pending_balance: Option<BalanceConfig>,
    /// The reading of the last [`InProcess::tick_with_imu`] at which the device latched a fall.
    fall_latched_reading: Option<usize>,
}

impl InProcess {
    /// Powers the device of `config` on, says hello and enables its outputs (on the nominal
    /// stance it holds at power-on).
    ///
    /// # Errors
    /// [`DeviceError`].
    pub fn start(config: Config) -> Result<InProcess, DeviceError> {
        let clock = VirtualClock::default();
        let device = Device::new(
            config,
            Outputs::default(),
            clock.clone(),
            RamEeprom::erased(),
        )
        .map_err(DeviceError::Config)?;
        let mut d = InProcess {
            device,
            clock,
            seq: 0,
            pending_balance: None,
            fall_latched_reading: None,
        };
        d.request(Request::Hello {
            version: PROTOCOL_VERSION,
        })?;
        d.request(Request::SetOutputs { enabled: true })?;
        Ok(d)
    }

    /// Sends one request at message level and checks it is acknowledged (`Ack`, `HelloAck`,
    /// `MotionAck` for the motion engine's requests, or the balance report that answers
    /// `SetBalance`).
    ///
    /// # Errors
    /// [`DeviceError::Nack`] or [`DeviceError::Unexpected`].
    pub fn request(&mut self, request: Request) -> Result<(), DeviceError> {
        self.seq = self.seq.wrapping_add(1);
        match self.device.handle(HostToDevice {
            seq: self.seq,
            request,
        }) {
            DeviceToHost::Ack { .. }
            | DeviceToHost::HelloAck { .. }
            | DeviceToHost::MotionAck { .. }
            | DeviceToHost::Imu { .. } => Ok(()),
            DeviceToHost::Nack { reason, .. } => Err(DeviceError::Nack(reason)),
            _ => Err(DeviceError::Unexpected),
        }
    }

    /// Advances the device clock by one frame and runs its main-loop poll.
    pub fn tick(&mut self, frame_ms: u32) {
        self.clock.advance_ms(frame_ms);
        self.device.poll();
    }

    /// Advances the device clock by one frame of `frame_ms`, handing each of `readings` to the
    /// device at its time within the frame: the clock advanced to the reading's time, the
    /// reading pushed ([`Device::on_imu`]), the main loop polled; then the rest of the frame
    /// and its poll, as [`InProcess::tick`]. Readings are `(ns after the frame's start,
    /// reading)`, in time order; one at or past the frame's end is pushed at its end, before
    /// the frame boundary's poll. The reading at which the device latched a fall, if it did
    /// within this frame, is [`InProcess::fall_latched_reading`].
    pub fn tick_with_imu(&mut self, frame_ms: u32, readings: &[(u64, ImuReading)]) {
        let start_ns = self.clock.now_ns();
        let frame_ns = u64::from(frame_ms) * 1_000_000;
        let mut latched = self.device.imu_report().fall.is_some();
        self.fall_latched_reading = None;
        for (i, &(after_ns, reading)) in readings.iter().enumerate() {
            let t_ns = start_ns + after_ns.min(frame_ns);
            if t_ns > self.clock.now_ns() {
                self.clock.set_ns(t_ns);
            }
            self.device.on_imu(reading);
            // The device latches a fall on a reading ([`quad_device::Device::on_imu`]).
            if !latched && self.device.imu_report().fall.is_some() {
                latched = true;
                self.fall_latched_reading = Some(i);
            }
            if t_ns < start_ns + frame_ns {
                self.device.poll();
            }
        }
        self.clock.set_ns(start_ns + frame_ns);
        self.device.poll();
        self.send_pending_balance();
    }

    /// Runs the device for `frames` servo frames before the run with the robot still and its
    /// outputs off, its sensor reading `at_rest` at 200 Hz (as the robot at rest on the floor
    /// reads; the emulated sensor reads the same before the twin's first sample), then enables
    /// the outputs again: the device powered on before the motion starts, long enough for its
    /// gyro-bias measurement ([`quad_device::balance::BIAS_WINDOW_MS`];
    /// [`REST_BEFORE_RUN_FRAMES`]). The outputs off meanwhile, the run's first target is taken
    /// at once as after any enabling (no limiter ramp from the power-on pose).
    ///
    /// # Errors
    /// [`DeviceError`] when the device refuses to switch its outputs.
    pub fn rest_before_run(
        &mut self,
        at_rest: quad_device::ImuSample,
        frames: u32,
    ) -> Result<(), DeviceError> {
        let readings: Vec<(u64, ImuReading)> = (0..4)
            .map(|i| (i * 5_000_000 + 4_000_000, ImuReading::Sample(at_rest)))
            .collect();
        self.request(Request::SetOutputs { enabled: false })?;
        for _ in 0..frames {
            self.tick_with_imu(20, &readings);
        }
        self.request(Request::SetOutputs { enabled: true })
    }

    /// Configures the balance functions with `config` as a `SetBalance` request, at the end of
    /// the first frame after which the device has a reading from its sensor (leveling is
    /// refused while the sensor is absent; from the first reading the device measures the gyro
    /// bias for a second, then levels).
    pub fn set_balance_when_ready(&mut self, config: BalanceConfig) {
        self.pending_balance = Some(config);
        self.send_pending_balance();
    }

    fn send_pending_balance(&mut self) {
        let Some(config) = self.pending_balance else {
            return;
        };
        if self.device.imu_report().health == ImuHealth::Absent {
            return;
        }
        // A refusal (a sensor fault since) leaves it pending.
        if self.request(Request::SetBalance(config)).is_ok() {
            self.pending_balance = None;
        }
    }

    /// The index, among the readings of the last [`InProcess::tick_with_imu`], of the one at
    /// which the device latched a fall (its report's `fall` set by that reading); `None` when
    /// it latched none within that frame (none yet, or one latched before).
    pub fn fall_latched_reading(&self) -> Option<usize> {
        self.fall_latched_reading
    }

    /// The balance functions' report (what `GetImu` answers).
    pub fn imu_report(&self) -> ImuReport {
        self.device.imu_report()
    }

    /// What the device knows of its inertial sensor.
    pub fn imu(&self) -> &ImuState {
        self.device.imu()
    }

    /// The outputs now.
    pub fn outputs(&self) -> &Outputs {
        self.device.outputs()
    }

    /// The outputs' pulses mapped back to joint angles through the device's own calibration
    /// (`quad_protocol::servo::Calibration::angle_rad`), rad.
    ///
    /// # Errors
    /// [`DeviceError::Unmappable`].
    pub fn output_angles_rad(&self) -> Result<[f32; 12], DeviceError> {
        let pulses = self.device.outputs().pulses_half_us;
        let table = self.device.calibration();
        let mut out = [0.0; 12];
        for s in ServoId::ALL {
            let i = s.index();
            out[i] = table[i]
                .angle_rad(pulses[i])
                .map_err(|fault| DeviceError::Unmappable { servo: s, fault })?;
        }
        Ok(out)
    }
}
