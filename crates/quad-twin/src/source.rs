//! Where the frames come from: the one place to change when the device runs the motions
//! itself (then the source starts the onboard motion once and only steps the device).

use crate::device::{DeviceError, SimDevice};
use crate::link::BodyState;
use crate::motions::Plan;
use kin_core::Pose;
use quad_protocol::Request;

/// The device's servo period, s (50 Hz hobby-servo frames).
pub const FRAME_S: f32 = 0.02;
/// [`FRAME_S`] in the device clock's milliseconds.
pub const FRAME_MS: u32 = 20;

/// One servo frame: what the device's outputs carry for the next 20 ms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceFrame {
    /// Start of the frame on the motion's clock, s.
    pub t_s: f32,
    /// True while the outputs are driven.
    pub enabled: bool,
    /// The twelve pulses, half-µs.
    pub pulses_half_us: [u16; 12],
    /// The pulses mapped back through the device's calibration, rad.
    pub angles_rad: [f32; 12],
    /// The body pose the motion commands (for the metrics; the device does not see it).
    pub commanded_pose: Pose,
    /// The feet the motion has on the ground (for the slip metric).
    pub stance: [bool; 4],
}

/// A producer of servo frames, given the twin's answer to the previous one (the body state an
/// IMU would measure; unused while the loop is open).
pub trait FrameSource {
    /// Number of frames of the run.
    fn frame_count(&self) -> u32;

    /// Frame `k` (from 0), after the twin answered frame `k − 1` with `feedback`.
    ///
    /// # Errors
    /// [`crate::Error`] when the device or the motion refuses.
    fn next(&mut self, k: u32, feedback: Option<&BodyState>) -> Result<DeviceFrame, crate::Error>;
}

/// The device driven as a host would drive it: every frame, the motion's target sent as a
/// `SetFeet` request, then the device's outputs read.
pub struct HostDriven {
    plan: Plan,
    device: SimDevice,
}

impl HostDriven {
    /// Drives `device` (started, outputs enabled) through `plan`.
    pub fn new(plan: Plan, device: SimDevice) -> HostDriven {
        HostDriven { plan, device }
    }
}

impl FrameSource for HostDriven {
    fn frame_count(&self) -> u32 {
        (self.plan.duration_s() / FRAME_S).round() as u32 + 1
    }

    fn next(&mut self, k: u32, _feedback: Option<&BodyState>) -> Result<DeviceFrame, crate::Error> {
        let t_s = k as f32 * FRAME_S;
        let target = self.plan.target(t_s).map_err(crate::Error::Motion)?;
        let device_error = |error: DeviceError| crate::Error::Device { frame: k, error };
        self.device
            .request(Request::SetFeet {
                feet_in_body_m: target.feet_in_body_m,
            })
            .map_err(device_error)?;
        self.device.tick(FRAME_MS);
        let outputs = self.device.outputs();
        Ok(DeviceFrame {
            t_s,
            enabled: outputs.enabled,
            pulses_half_us: outputs.pulses_half_us,
            angles_rad: self.device.output_angles_rad().map_err(device_error)?,
            commanded_pose: target.pose,
            stance: target.stance,
        })
    }
}
