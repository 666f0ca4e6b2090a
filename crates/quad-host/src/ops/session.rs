//! What the operations that stream setpoints to a device (`quadctl stream`, `quadctl play`)
//! share: the device and robot they run on, how the answers are checked, the connected
//! stream, the report of one answer and the emulator's checks of the chip.

use crate::client::{
    self, AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, StreamStats,
};
use crate::link::{self, Link, Target};
use crate::robot_file;
use kin_core::RotationOrder;
use quad_protocol::{RobotDescription, RobotPreset};
use serde::Serialize;
use std::io::{self, Write};

/// The device side of a stream: robot, device, retries and the configuration set on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Session {
    /// The robot: a preset, a TOML or a URDF robot file. A device of protocol 2.4 or later
    /// must hold it (compared by hash); an older device must run the preset named. `None`:
    /// the robot the device holds (an older device: its preset).
    pub robot: Option<String>,
    /// The device.
    pub target: Target,
    /// Resends per setpoint after the first attempt.
    pub retries: u32,
    /// Stance height H set on the device, m; `None`: the device's own.
    pub stance_height_m: Option<f32>,
    /// Rotation order set on the device; `None`: the operation's default, else the device's
    /// own.
    pub rotation_order: Option<RotationOrder>,
    /// Compare angles within this bound (rad); `None`: [`AngleCheck::for_target`].
    pub angle_tolerance_rad: Option<f32>,
}

/// Why a session could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The robot is not a preset and the device is older than protocol 2.4.
    #[error(
        "--robot {0}: the device speaks a protocol older than 2.4 and needs a preset robot \
         (shahriar2023, fernando2025): it reports its preset and both sides must run the same \
         geometry"
    )]
    NotAPreset(String),
    /// The robot could not be resolved.
    #[error(transparent)]
    Robot(#[from] robot_file::Error),
    /// No robot was given and the device's robot is not one the host can plan with (an older
    /// device running a custom robot).
    #[error(transparent)]
    DeviceRobot(#[from] robot_file::DeviceRobotError),
    /// The robot was refused as a device's robot (before the link is opened).
    #[error(transparent)]
    Device(#[from] robot_file::DeviceError),
    /// A negative or non-finite angle tolerance.
    #[error("--angle-tolerance-rad {0} must be finite and >= 0")]
    Tolerance(f32),
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// The handshake or the link failed.
    #[error(transparent)]
    Client(#[from] client::Error),
}

/// A session whose arguments were checked ([`Session::check`]); nothing is opened yet.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The robot given, resolved (`None`: the device's own).
    given: Option<(RobotPreset, RobotDescription)>,
    check: AngleCheck,
}

impl Session {
    /// Checks the robot and the tolerance, before any file is read or link opened.
    ///
    /// # Errors
    /// [`Error::Device`], [`Error::Tolerance`].
    pub fn check(&self) -> Result<Checked, Error> {
        let given = match &self.robot {
            Some(name) => Some((
                RobotPreset::from_name(name.trim()).unwrap_or(RobotPreset::Custom),
                robot_file::device_description(name)?,
            )),
            None => None,
        };
        let check = match self.angle_tolerance_rad {
            Some(t) if t.is_finite() && t >= 0.0 => AngleCheck::Within(t),
            Some(t) => return Err(Error::Tolerance(t)),
            None => AngleCheck::for_target(&self.target),
        };
        Ok(Checked { given, check })
    }

    /// Opens the link and connects the stream (handshake, configuration); the rotation order
    /// is [`Session::rotation_order`], else `default_order`, else the device's own.
    ///
    /// A device of protocol 2.4 or later must hold the robot checked (the hashes are
    /// compared, [`crate::ops::onboard::check_same_robot`]); an older one must run its preset.
    /// Without a robot, the stream plans with the device's own.
    ///
    /// # Errors
    /// [`Error::Link`], [`Error::Client`] ([`client::Error::RobotMismatch`] for another
    /// robot), [`Error::NotAPreset`] for a robot file and a device older than 2.4,
    /// [`Error::DeviceRobot`] without a robot and an older device running a custom one.
    pub fn connect(
        &self,
        checked: Checked,
        default_order: Option<RotationOrder>,
    ) -> Result<PoseStream<Box<dyn Link>>, Error> {
        let link = link::open(&self.target)?;
        let config = ClientConfig::for_target(&self.target, self.retries);
        let mut client = Client::new(link, config);
        let info = client.hello()?;
        let given = checked.given.as_ref();
        let (robot, preset) = if quad_protocol::version_minor(info.version) >= 4 {
            let held = client.get_robot()?;
            crate::ops::onboard::check_same_robot(
                &held,
                info.robot_hash,
                given.map(|(_, description)| description),
            )?;
            (held.robot, info.robot)
        } else {
            match given {
                Some((RobotPreset::Custom, _)) => {
                    return Err(Error::NotAPreset(self.robot.clone().unwrap_or_default()));
                }
                Some((preset, description)) => (description.robot, *preset),
                None => (robot_file::device_robot(&info, None, None)?, info.robot),
            }
        };
        let setup = StreamSetup {
            robot,
            preset,
            stance_height_m: self.stance_height_m,
            order: self.rotation_order.or(default_order),
            check: checked.check,
        };
        Ok(PoseStream::connect(client, setup)?)
    }
}

/// True when `angle_rad` is most likely a value in degrees given where radians are asked: its
/// magnitude is beyond a full turn (2π) and within one in degrees (360). No angle of this
/// project means anything beyond one turn (joints are limited to [-π, π], body rotations and
/// sway amplitudes far less), whereas the angles people think of in degrees (10°, 30°, 45°,
/// 90°) are all beyond it. Below 2π the value is left to the ordinary range checks (5 could be
/// 5° as well as 5 rad), and so is a value beyond 360, which is no angle in degrees either.
pub fn looks_like_degrees(angle_rad: f32) -> bool {
    let magnitude = angle_rad.abs();
    magnitude > core::f32::consts::TAU && magnitude <= 360.0
}

/// The hint for the first of `angles` (column name, value in rad) that
/// [`looks_like_degrees`]: "`roll_rad` = 30 rad = 1719°; angles are in radians (30° = 0.5236
/// rad)".
pub fn degrees_hint(angles: &[(&str, f32)]) -> Option<String> {
    angles
        .iter()
        .find(|(_, v)| looks_like_degrees(*v))
        .map(|(name, v)| {
            format!(
                "`{name}` = {v} rad = {:.0}°; angles are in radians ({v}° = {:.4} rad)",
                v.to_degrees(),
                v.to_radians()
            )
        })
}

/// What to report of an answer: `None` when acked, else one line.
pub fn report(result: &PoseResult) -> Option<String> {
    match result {
        PoseResult::Acked { .. } => None,
        PoseResult::Nacked(reason) => {
            Some(format!("nacked: {reason} (the host's kin-core agrees)"))
        }
        PoseResult::Lost => Some("lost: no answer after every retry".to_owned()),
        PoseResult::Mismatch(what) => Some(format!("READBACK MISMATCH: {what}")),
    }
}

/// The emulator's checks of the chip, in the summary: the receive buffer and the pins.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Pins {
    /// Bytes the chip's two-byte receive buffer lost because the firmware did not read them in
    /// time (data overruns).
    pub rx_overruns: u64,
    /// Pulses measured on the 12 servo pins and compared with the readbacks.
    pub pulses_checked: u64,
    /// Pulses off their readback by more than one 0.5 µs timer tick.
    pub pulse_width_errors: u64,
}

impl Pins {
    /// The emulator's checks after a stream (`None` on other links); the first pulse width
    /// error and any receive overrun are reported on `diag` as `<name>: …`.
    ///
    /// # Errors
    /// A failing `diag`.
    pub fn after<L: Link>(
        stream: &mut PoseStream<L>,
        name: &str,
        diag: &mut dyn Write,
    ) -> io::Result<Option<Pins>> {
        let Some(emu) = stream.client_mut().link_mut().emulator() else {
            return Ok(None);
        };
        let pulses = emu.pulse_stats();
        if let Some(e) = &pulses.first_error {
            writeln!(diag, "{name}: PULSE WIDTH ERROR: {e}")?;
        }
        let rx_overruns = emu.rx_overruns();
        if rx_overruns > 0 {
            writeln!(
                diag,
                "{name}: RECEIVE OVERRUN: {rx_overruns} bytes lost by the chip's receive buffer"
            )?;
        }
        Ok(Some(Pins {
            rx_overruns,
            pulses_checked: pulses.checked,
            pulse_width_errors: pulses.errors,
        }))
    }
}

/// True when a readback disagreed with the host, a pulse left its travel, a pulse on the pins
/// matched no readback or the chip's receive buffer overran.
pub fn check_failed(stream: &StreamStats, pins: Option<Pins>) -> bool {
    stream.readback_mismatches > 0
        || stream.pulses_out_of_range > 0
        || pins.is_some_and(|p| p.pulse_width_errors > 0 || p.rx_overruns > 0)
}
