//! The inertial sensor as the controller sees it: the target's driver reads the sensor and
//! pushes each reading, or the fault that kept it from reading one, into
//! [`Device::on_imu`](crate::Device::on_imu).
//!
//! Push rather than a fourth target trait: the firmware's TWI driver runs by interrupt and the
//! main loop hands over what it finished, as it does with the received bytes; the host's
//! simulator and the physics twin push what their sources produce. A board with no sensor
//! pushes [`ImuFault::Absent`] once at boot, and the controller runs every motion open loop.
//!
//! Frames: readings are in the **body frame** of kin-core (x forward, y left, z up), the sensor's
//! mounting already applied by the driver. At rest and level the accelerometer reads
//! `(0, 0, +g)` (it measures the reaction to gravity).
//!
//! The sensor itself, for the firmware's driver and the emulator's virtual chip alike:
//! [`mpu6050`].

pub mod mpu6050;

/// One reading of a six-axis inertial sensor, SI units, body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// Specific force (acceleration minus gravity), m/s²; `(0, 0, 9.81)` level and still.
    pub accel_m_s2: [f32; 3],
    /// Angular rate about the body axes, rad/s.
    pub gyro_rad_s: [f32; 3],
}

/// Why the driver has no reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImuFault {
    /// Nothing answers at the sensor's address (no ACK to the address byte at boot).
    Absent,
    /// Something answers, but its identity register is not the expected one.
    WrongId {
        /// The value read from the identity register.
        who_am_i: u8,
    },
    /// The sensor stopped acknowledging mid-run.
    Nak,
    /// The sensor answers with the same data for longer than its noise allows.
    Stuck,
    /// The bus is held (SDA low, or a transfer that never completes); the driver tries to free it.
    BusHeld,
}

/// What a driver pushes: a reading, or the fault that kept it from reading one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImuReading {
    /// A fresh sample.
    Sample(ImuSample),
    /// No sample: why.
    Fault(ImuFault),
}

/// What the controller knows of its sensor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuState {
    /// The last sample pushed (`None` before the first).
    pub last: Option<ImuSample>,
    /// The last fault pushed, cleared by the next sample (`None` while healthy or before any
    /// reading).
    pub fault: Option<ImuFault>,
    /// Samples pushed since the boot (wrapping).
    pub samples: u32,
}

impl ImuState {
    /// Takes one reading in.
    pub fn push(&mut self, reading: ImuReading) {
        match reading {
            ImuReading::Sample(sample) => {
                self.last = Some(sample);
                self.fault = None;
                self.samples = self.samples.wrapping_add(1);
            }
            ImuReading::Fault(fault) => self.fault = Some(fault),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_clears_a_fault_and_counts() {
        let mut state = ImuState::default();
        state.push(ImuReading::Fault(ImuFault::Nak));
        assert_eq!(state.fault, Some(ImuFault::Nak));
        assert_eq!(state.samples, 0);
        let sample = ImuSample {
            accel_m_s2: [0.0, 0.0, 9.81],
            gyro_rad_s: [0.0; 3],
        };
        state.push(ImuReading::Sample(sample));
        assert_eq!(state.fault, None);
        assert_eq!(state.last, Some(sample));
        assert_eq!(state.samples, 1);
    }
}
