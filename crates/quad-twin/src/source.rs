//! Where the frames come from: a host sending every frame's feet ([`HostDriven`]), or the
//! device running the motion itself ([`Onboard`]). Both hand the twin's IMU samples of the
//! previous frame to the in-process device at their times before its next frame boundary
//! ([`imu_readings`], [`InProcess::tick_with_imu`]).

use crate::device::{DeviceError, InProcess};
use crate::link::{BodyState, ToTwin};
use crate::motions::Plan;
use kin_core::motion::gait::Velocity;
use kin_core::Pose;
use quad_device::ImuReading;
use quad_protocol::{MotionCommand, Request};

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
    /// The device's estimate of the body's roll, pitch, yaw, rad, once its sensor is
    /// healthy ([`estimated_rpy_rad`]); the twin scores roll and pitch against the true
    /// attitude. The device estimates no yaw: 0.
    pub estimated_rpy_rad: Option<[f32; 3]>,
    /// The device reports a fall (latched; [`quad_protocol::ImuReport::fall`]); false when the
    /// source does not read the report.
    pub fall_detected: bool,
    /// The time, on the twin's clock, of the IMU sample at which the device latched the fall,
    /// s: set on the frame after whose samples the report first shows the fall (the sample
    /// `BodyState::imu[i]` of the feedback, `i` = [`InProcess::fall_latched_reading`]); `None`
    /// on every other frame, and always when the source sees the report only once a frame
    /// (the emulated firmware).
    pub fall_latched_t_s: Option<f64>,
}

impl DeviceFrame {
    /// The message that hands this frame, frame `k` of the run, to the twin.
    pub fn to_twin(&self, k: u32) -> ToTwin<'static> {
        ToTwin::Frame {
            k,
            t_s: self.t_s,
            enabled: self.enabled,
            pulses_half_us: self.pulses_half_us,
            angles_rad: self.angles_rad,
            commanded_pose: self.commanded_pose.to_array(),
            stance: self.stance,
            estimated_rpy_rad: self.estimated_rpy_rad,
        }
    }
}

/// The attitude a device's balance report gives: roll and pitch (yaw 0: not estimated)
/// while its sensor is healthy, else none.
pub fn estimated_rpy_rad(report: &quad_protocol::ImuReport) -> Option<[f32; 3]> {
    (report.health == quad_protocol::ImuHealth::Ok).then_some([
        report.roll_rad,
        report.pitch_rad,
        0.0,
    ])
}

/// The IMU samples of the frame the twin answered with `state`, as readings for the device:
/// `(ns after the frame's start, reading)`, the frame starting [`FRAME_S`] before
/// `state.t_s` (the twin's frames last one servo period).
///
/// # Errors
/// [`crate::Error::Protocol`] when a sample lies outside its frame.
pub fn imu_readings(state: &BodyState) -> Result<Vec<(u64, ImuReading)>, crate::Error> {
    let frame_start_s = state.t_s - f64::from(FRAME_S);
    state
        .imu
        .iter()
        .map(|s| {
            let after_s = s.t_s - frame_start_s;
            // A microsecond's slack for the sum of the twin's time steps.
            if !(-1e-6..=f64::from(FRAME_S) + 1e-6).contains(&after_s) {
                return Err(crate::Error::Protocol("an IMU sample outside its frame"));
            }
            let after_ns = (after_s.max(0.0) * 1e9).round() as u64;
            Ok((after_ns, ImuReading::Sample(s.sample())))
        })
        .collect()
}

/// A producer of servo frames, given the twin's answer to the previous one (the body state
/// and the IMU's samples during that frame, which the source hands to its device).
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
    device: InProcess,
    /// Hold the pose on the device while the plan holds the stance ([`HostDriven::hold_pose`]).
    hold_pose: bool,
    /// The pose was sent.
    pose_held: bool,
}

impl HostDriven {
    /// Drives `device` (started, outputs enabled) through `plan`.
    pub fn new(plan: Plan, device: InProcess) -> HostDriven {
        HostDriven {
            plan,
            device,
            hold_pose: false,
            pose_held: false,
        }
    }

    /// While the plan holds the stance ([`Plan::holds_stance`]), sends the device the zero
    /// pose once (`SetBodyPose`) and no feet: the device holds the pose itself, and its
    /// leveling corrects it (leveling acts on a held pose, not on feet set directly).
    pub fn hold_pose(mut self) -> HostDriven {
        self.hold_pose = true;
        self
    }

    /// The device.
    pub fn device(&self) -> &InProcess {
        &self.device
    }
}

impl Onboard {
    /// The device.
    pub fn device(&self) -> &InProcess {
        &self.device
    }
}

/// The request a host sends at frame `k` of `plan` (target `target`): the feet; with
/// `hold_pose`, while the plan holds the stance, the zero pose once (`pose_held` remembers
/// it) and then nothing.
pub fn host_request(
    plan: &Plan,
    k: u32,
    target: &crate::motions::Target,
    hold_pose: bool,
    pose_held: &mut bool,
) -> Option<Request> {
    if hold_pose && plan.holds_stance(k as f32 * FRAME_S) {
        if *pose_held {
            return None;
        }
        *pose_held = true;
        return Some(Request::SetBodyPose(Pose::default()));
    }
    *pose_held = false;
    Some(Request::SetFeet {
        feet_in_body_m: target.feet_in_body_m,
    })
}

/// Frames of a run of `plan`: its duration in frames and the final one.
pub fn frame_count(plan: &Plan) -> u32 {
    (plan.duration_s() / FRAME_S).round() as u32 + 1
}

impl FrameSource for HostDriven {
    fn frame_count(&self) -> u32 {
        frame_count(&self.plan)
    }

    fn next(&mut self, k: u32, feedback: Option<&BodyState>) -> Result<DeviceFrame, crate::Error> {
        let target = self
            .plan
            .target(k as f32 * FRAME_S)
            .map_err(crate::Error::Motion)?;
        let request = host_request(&self.plan, k, &target, self.hold_pose, &mut self.pose_held);
        step(&mut self.device, k, request, &target, feedback)
    }
}

/// The device running the motion itself: `StartMotion` once (the plan's motion as the device's
/// engine runs it, [`Plan::onboard`]), a walk's velocity command at 10 Hz (as a teleoperating
/// host refreshes it, [`onboard_request`]), and otherwise only the device's clock advancing. The
/// commanded pose and the feet on the ground are the plan's, for the metrics.
pub struct Onboard {
    plan: Plan,
    device: InProcess,
    command: MotionCommand,
    velocity: Option<Velocity>,
}

impl Onboard {
    /// Runs `plan` on `device` (started, outputs enabled); `None` when the plan has no onboard
    /// form ([`Plan::onboard`]).
    pub fn new(plan: Plan, device: InProcess) -> Option<Onboard> {
        let (command, velocity) = plan.onboard()?;
        Some(Onboard {
            plan,
            device,
            command,
            velocity,
        })
    }
}

/// Frames between two velocity commands of an onboard walk: 10 Hz, as a teleoperating host
/// sends them (the device's timeout is five of them).
pub const VELOCITY_EVERY_FRAMES: u32 = 5;

/// The request of frame `k` of an onboard run: the start at frame 0, then a walk's velocity
/// every [`VELOCITY_EVERY_FRAMES`].
pub fn onboard_request(
    k: u32,
    command: MotionCommand,
    velocity: Option<Velocity>,
) -> Option<Request> {
    if k == 0 {
        return Some(Request::StartMotion(command));
    }
    if !k.is_multiple_of(VELOCITY_EVERY_FRAMES) {
        return None;
    }
    velocity.map(|v| Request::SetVelocity {
        forward_m_s: v.forward_m_s,
        lateral_m_s: v.lateral_m_s,
        yaw_rate_rad_s: v.yaw_rad_s,
    })
}

impl FrameSource for Onboard {
    fn frame_count(&self) -> u32 {
        frame_count(&self.plan)
    }

    fn next(&mut self, k: u32, feedback: Option<&BodyState>) -> Result<DeviceFrame, crate::Error> {
        let target = self
            .plan
            .target(k as f32 * FRAME_S)
            .map_err(crate::Error::Motion)?;
        let request = onboard_request(k, self.command, self.velocity);
        step(&mut self.device, k, request, &target, feedback)
    }
}

/// Frame `k` of an in-process run: `request` (if any) sent, one frame of the device's clock
/// with the IMU samples of `feedback` (the twin's answer to frame `k − 1`: the frame the
/// outputs held while the clock runs to the next boundary) pushed at their times, its outputs
/// read; the commanded pose and the feet on the ground are `target`'s.
fn step(
    device: &mut InProcess,
    k: u32,
    request: Option<Request>,
    target: &crate::motions::Target,
    feedback: Option<&BodyState>,
) -> Result<DeviceFrame, crate::Error> {
    let device_error = |error: DeviceError| crate::Error::Device { frame: k, error };
    if let Some(request) = request {
        device.request(request).map_err(device_error)?;
    }
    let readings = match feedback {
        Some(state) => imu_readings(state)?,
        None => Vec::new(),
    };
    device.tick_with_imu(FRAME_MS, &readings);
    let fall_latched_t_s = device
        .fall_latched_reading()
        .and_then(|i| feedback.and_then(|state| state.imu.get(i)))
        .map(|sample| sample.t_s);
    let outputs = device.outputs();
    let report = device.imu_report();
    Ok(DeviceFrame {
        t_s: k as f32 * FRAME_S,
        enabled: outputs.enabled,
        pulses_half_us: outputs.pulses_half_us,
        angles_rad: device.output_angles_rad().map_err(device_error)?,
        commanded_pose: target.pose,
        stance: target.stance,
        estimated_rpy_rad: estimated_rpy_rad(&report),
        fall_detected: report.fall.is_some(),
        fall_latched_t_s,
    })
}
