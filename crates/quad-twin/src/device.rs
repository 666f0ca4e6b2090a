//! The device controller (`quad-device`) on the host, as the twin drives it: RAM storage, a
//! clock the loop advances by one servo frame at a time, outputs that keep the last pulses.

use quad_device::store::STORAGE_LEN;
use quad_device::{Clock, Config, ConfigError, Device, ServoOutputs, Storage};
use quad_protocol::servo::Error as ServoError;
use quad_protocol::{DeviceToHost, HostToDevice, NackReason, Request, ServoId, PROTOCOL_VERSION};
use std::cell::Cell;
use std::rc::Rc;

/// The servo outputs as the twin reads them.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Outputs {
    /// True while the device drives the outputs.
    pub enabled: bool,
    /// The last pulses written, half-µs (zeros before the first write).
    pub pulses_half_us: [u16; 12],
}

impl ServoOutputs for Outputs {
    fn set_pulses(&mut self, pulses_half_us: &[u16; 12]) {
        self.pulses_half_us = *pulses_half_us;
    }
    fn set_enabled(&mut self, enabled: bool) {
        self.enabled = enabled;
    }
}

/// The device's millisecond clock, advanced by the loop.
#[derive(Debug, Clone, Default)]
pub struct FrameClock(Rc<Cell<u32>>);

impl FrameClock {
    /// Advances the clock by `ms`.
    pub fn advance(&self, ms: u32) {
        self.0.set(self.0.get().wrapping_add(ms));
    }
}

impl Clock for FrameClock {
    fn now_ms(&self) -> u32 {
        self.0.get()
    }
}

/// Erased RAM "EEPROM" (the device then boots on its default calibration).
#[derive(Debug, Clone)]
pub struct Ram(Vec<u8>);

impl Default for Ram {
    fn default() -> Self {
        Ram(vec![0xFF; usize::from(STORAGE_LEN)])
    }
}

impl Storage for Ram {
    type Error = ();
    fn read(&mut self, addr: u16, buf: &mut [u8]) -> Result<(), ()> {
        let a = usize::from(addr);
        buf.copy_from_slice(self.0.get(a..a + buf.len()).ok_or(())?);
        Ok(())
    }
    fn write(&mut self, addr: u16, data: &[u8]) -> Result<(), ()> {
        let a = usize::from(addr);
        self.0
            .get_mut(a..a + data.len())
            .ok_or(())?
            .copy_from_slice(data);
        Ok(())
    }
}

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

/// A powered-on device with its outputs enabled.
pub struct SimDevice {
    device: Device<Outputs, FrameClock, Ram>,
    clock: FrameClock,
    seq: u16,
}

impl SimDevice {
    /// Powers the device of `config` on, says hello and enables its outputs (on the nominal
    /// stance it holds at power-on).
    ///
    /// # Errors
    /// [`DeviceError`].
    pub fn start(config: Config) -> Result<SimDevice, DeviceError> {
        let clock = FrameClock::default();
        let device = Device::new(config, Outputs::default(), clock.clone(), Ram::default())
            .map_err(DeviceError::Config)?;
        let mut d = SimDevice {
            device,
            clock,
            seq: 0,
        };
        d.request(Request::Hello {
            version: PROTOCOL_VERSION,
        })?;
        d.request(Request::SetOutputs { enabled: true })?;
        Ok(d)
    }

    /// Sends one request at message level and checks it is acknowledged (`Ack`, `HelloAck`,
    /// or `MotionAck` for the motion engine's requests).
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
            | DeviceToHost::MotionAck { .. } => Ok(()),
            DeviceToHost::Nack { reason, .. } => Err(DeviceError::Nack(reason)),
            _ => Err(DeviceError::Unexpected),
        }
    }

    /// Advances the device clock by one frame and runs its main-loop poll.
    pub fn tick(&mut self, frame_ms: u32) {
        self.clock.advance(frame_ms);
        self.device.poll();
    }

    /// The outputs now.
    pub fn outputs(&self) -> Outputs {
        *self.device.outputs()
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
