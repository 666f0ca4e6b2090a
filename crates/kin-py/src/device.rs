//! `quadkin.Device`: the device client (quad-host's [`Client`] over one of its links: the
//! simulated controller, the firmware in simavr, or a serial port).

use crate::bridge::BridgeLink;
use crate::errors;
use crate::robot::leg_arg;
use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{Joint, Pose};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quad_host::client::{Client, ClientConfig, DEFAULT_RETRIES};
use quad_host::link::serial::SerialLink;
use quad_host::link::sim::{EepromImage, SimConfig, SimLink};
use quad_host::link::{self, Link};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    DeviceInfo, DeviceToHost, Flags, LegSet, MotionCommand, MotionStatus, Readback, Request,
    RobotPreset, ServoId,
};
use std::path::PathBuf;

/// A connected device: requests are sent with retries under one sequence number; a refusal
/// raises ``quadkin.NackError`` carrying the device's reason (``reason``, ``field``, ``leg``,
/// ``joint``, ``param``, ``problem``), a silent device ``quadkin.NoAnswerError``, a link that
/// fails ``quadkin.LinkError`` naming the port.
///
/// Open one with :meth:`sim`, :meth:`emulator` or :meth:`serial`; the handshake runs on
/// opening (:meth:`hello` repeats it). Angles in rad, lengths in m, times in s; body poses
/// ``[roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m]``; twelve-value arrays in the canonical
/// order FL, FR, RL, RR × abduction, hip, knee.
#[pyclass(module = "quadkin", unsendable)]
pub struct Device {
    client: Client<Box<dyn Link>>,
    port: String,
    info: DeviceInfo,
}

impl Device {
    fn open(
        config: ClientConfig,
        link: Box<dyn Link>,
        port: String,
        retries: u32,
    ) -> PyResult<Device> {
        let mut client = Client::new(link, ClientConfig { retries, ..config });
        let info = client.hello().map_err(|e| errors::device(e, &port))?;
        Ok(Device { client, port, info })
    }

    fn err(&self, e: quad_host::client::Error) -> PyErr {
        errors::device(e, &self.port)
    }

    /// A request answered by an ack (or an echoing `Configured`): its readback.
    fn ack<'py>(&mut self, py: Python<'py>, request: Request) -> PyResult<Bound<'py, PyDict>> {
        let rb = self.client.ack(request).map_err(|e| self.err(e))?;
        readback_dict(py, &rb)
    }

    /// A motion request answered by a `MotionAck`.
    fn motion<'py>(&mut self, py: Python<'py>, request: Request) -> PyResult<Bound<'py, PyDict>> {
        let name = quad_host::client::request_name(&request);
        match self.client.request(request).map_err(|e| self.err(e))? {
            DeviceToHost::MotionAck {
                status, readback, ..
            } => motion_dict(py, &status, &readback),
            other => Err(self.err(quad_host::client::Error::Unexpected {
                request: name,
                answer: Box::new(other),
            })),
        }
    }
}

fn preset_arg(robot: &str) -> PyResult<RobotPreset> {
    RobotPreset::from_name(robot).ok_or_else(|| {
        errors::value(format!(
            "robot {robot:?}: the simulated device runs a preset (shahriar2023 or fernando2025)"
        ))
    })
}

fn joint_arg(joint: &str) -> PyResult<Joint> {
    Joint::ALL
        .into_iter()
        .find(|j| j.name() == joint)
        .ok_or_else(|| {
            errors::value(format!(
                "joint {joint:?}: expected \"abduction\", \"hip\" or \"knee\""
            ))
        })
}

/// `obj` as a float array of exactly `shape` (numpy's conversion, any real dtype), flattened.
fn fixed(obj: &Bound<'_, PyAny>, shape: &[usize], what: &str) -> PyResult<Vec<f32>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj, "float64")).map_err(|e| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "{what}: expected a float array of shape {shape:?} ({e})"
        ))
    })?;
    let got: Vec<usize> = a.getattr("shape")?.extract()?;
    if got != shape {
        return Err(errors::value(format!(
            "{what}: expected an array of shape {shape:?}, got shape {got:?}"
        )));
    }
    let flat: Vec<f64> = a.call_method0("ravel")?.call_method0("tolist")?.extract()?;
    Ok(flat.into_iter().map(|v| v as f32).collect())
}

#[pymethods]
impl Device {
    /// The simulated controller of a preset robot behind a simulated UART (``quadctl
    /// --sim``): the device logic of the firmware on the host's maths. ``storage``: an EEPROM
    /// image file (read at power-on, written on every change).
    #[staticmethod]
    #[pyo3(signature = (robot = "shahriar2023", baud = 115_200, storage = None, retries = DEFAULT_RETRIES))]
    fn sim(robot: &str, baud: u32, storage: Option<PathBuf>, retries: u32) -> PyResult<Device> {
        let preset = preset_arg(robot)?;
        let config = SimConfig {
            baud,
            ..SimConfig::default()
        };
        let port = "sim".to_owned();
        let device_config = quad_device::Config::for_preset(preset)
            .ok_or_else(|| errors::link(&link::Error::NoSimulatedRobot, &port))?;
        let store = match &storage {
            Some(path) => EepromImage::with_file(path.clone()).map_err(|source| {
                errors::link(
                    &link::Error::Storage {
                        path: path.clone(),
                        source,
                    },
                    &port,
                )
            })?,
            None => EepromImage::erased(),
        };
        let sim = SimLink::new(config, device_config, store)
            .map_err(|e| errors::link(&link::Error::Device(e), &port))?;
        Device::open(
            ClientConfig::sim(config.compute),
            Box::new(sim),
            port,
            retries,
        )
    }

    /// The real firmware in simavr (``quadctl --emulator``), run by the ``quad-link-bridge``
    /// program (``cargo build --release -p quad-link-bridge``; simavr cannot be linked into
    /// this module): ``bridge`` its path (default: ``$QUADKIN_LINK_BRIDGE``, else
    /// ``quad-link-bridge`` on ``PATH``); ``elf`` the firmware ELF (default: built from
    /// ``firmware-avr/`` for the line rate); ``storage`` an EEPROM image file (read at
    /// power-on, written when the device is closed). Times are simulated.
    #[staticmethod]
    #[pyo3(signature = (elf = None, baud = 115_200, storage = None, retries = DEFAULT_RETRIES, bridge = None))]
    fn emulator(
        elf: Option<PathBuf>,
        baud: u32,
        storage: Option<PathBuf>,
        retries: u32,
        bridge: Option<PathBuf>,
    ) -> PyResult<Device> {
        let program = bridge
            .or_else(|| std::env::var_os("QUADKIN_LINK_BRIDGE").map(PathBuf::from))
            .unwrap_or_else(|| PathBuf::from("quad-link-bridge"));
        let mut args = vec![
            "--emulator".to_owned(),
            "--baud".to_owned(),
            baud.to_string(),
        ];
        for (flag, path) in [("--elf", &elf), ("--storage", &storage)] {
            if let Some(p) = path {
                args.push(flag.to_owned());
                args.push(p.to_string_lossy().into_owned());
            }
        }
        let port = "emulator".to_owned();
        let link = BridgeLink::spawn(&program, &args).map_err(|e| errors::link(&e, &port))?;
        Device::open(ClientConfig::emulator(), Box::new(link), port, retries)
    }

    /// A real device on serial port ``port`` (e.g. ``/dev/ttyACM0``).
    #[staticmethod]
    #[pyo3(signature = (port, baud = 115_200, retries = DEFAULT_RETRIES))]
    fn serial(port: &str, baud: u32, retries: u32) -> PyResult<Device> {
        let link = SerialLink::open(port, baud).map_err(|e| errors::link(&e, port))?;
        Device::open(
            ClientConfig::serial(),
            Box::new(link),
            port.to_owned(),
            retries,
        )
    }

    /// The link's name: ``"sim"``, ``"emulator"`` or the port.
    #[getter]
    fn port(&self) -> String {
        self.port.clone()
    }

    /// The handshake again: the device's info (``version``, ``firmware``, ``robot``,
    /// ``max_frame_len``, ``stance_height_m``, ``rotation_order``, ``policy``,
    /// ``link_timeout_ms``, ``link_loss_action``, ``robot_hash``: the hash of the robot the
    /// device holds, protocol 2.4, else ``None``).
    fn hello<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.info = self.client.hello().map_err(|e| self.err(e))?;
        info_dict(py, &self.info)
    }

    /// The device's info from the last handshake (as :meth:`hello`, without a request).
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        info_dict(py, &self.info)
    }

    /// The device's state: ``angles_rad`` (12,), ``pulses_half_us`` (12,), ``flags`` and its
    /// named bits, frame counters.
    fn state<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.ack(py, Request::GetState)
    }

    /// Switches the servo outputs on or off.
    fn set_outputs<'py>(&mut self, py: Python<'py>, enabled: bool) -> PyResult<Bound<'py, PyDict>> {
        self.ack(py, Request::SetOutputs { enabled })
    }

    /// A body pose ``[roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m]`` (world frame; the feet at
    /// the device's stance): the device solves the body IK. Returns the readback.
    fn set_body_pose<'py>(
        &mut self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let p = fixed(pose, &[6], "pose")?;
        let pose = Pose::from_array(core::array::from_fn(|k| p[k]));
        self.ack(py, Request::SetBodyPose(pose))
    }

    /// The four feet in the body frame, m, shape (4, 3) (FL, FR, RL, RR).
    fn set_feet<'py>(
        &mut self,
        py: Python<'py>,
        feet_in_body_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let f = fixed(feet_in_body_m, &[4, 3], "feet_in_body_m")?;
        let feet: [[f32; 3]; 4] = core::array::from_fn(|k| [f[3 * k], f[3 * k + 1], f[3 * k + 2]]);
        self.ack(
            py,
            Request::SetFeet {
                feet_in_body_m: feet,
            },
        )
    }

    /// Twelve joint angles, rad, shape (4, 3) (legs × abduction, hip, knee); bypasses the IK.
    fn set_joints<'py>(
        &mut self,
        py: Python<'py>,
        angles_rad: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let a = fixed(angles_rad, &[4, 3], "angles_rad")?;
        let angles: [f32; 12] = core::array::from_fn(|k| a[k]);
        self.ack(py, Request::SetJoints { angles_rad: angles })
    }

    /// The joint-speed limit of every output, rad/s.
    fn set_joint_speed_limit<'py>(
        &mut self,
        py: Python<'py>,
        joint_speed_limit_rad_s: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.ack(
            py,
            Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s,
            },
        )
    }

    /// One servo's calibration: ``zero_rad``, ``reversed``, ``us_per_rad``, ``center_us``,
    /// ``min_us``, ``max_us``.
    fn calibration<'py>(
        &mut self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        joint: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let servo = ServoId {
            leg: leg_arg(leg)?,
            joint: joint_arg(joint)?,
        };
        let c = self.client.calibration(servo).map_err(|e| self.err(e))?;
        calibration_dict(py, &c)
    }

    /// Replaces one servo's calibration in RAM (:meth:`save_calibration` persists it); the
    /// device refuses an invalid one (``NackError`` with ``reason="bad_calibration"`` and
    /// ``fault``). Returns the readback.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (leg, joint, *, zero_rad, reversed, us_per_rad, center_us, min_us, max_us))]
    fn set_calibration<'py>(
        &mut self,
        py: Python<'py>,
        leg: &Bound<'py, PyAny>,
        joint: &str,
        zero_rad: f32,
        reversed: bool,
        us_per_rad: f32,
        center_us: u16,
        min_us: u16,
        max_us: u16,
    ) -> PyResult<Bound<'py, PyDict>> {
        let servo = ServoId {
            leg: leg_arg(leg)?,
            joint: joint_arg(joint)?,
        };
        let calibration = Calibration {
            zero_rad,
            reversed,
            us_per_rad,
            center_us,
            min_us,
            max_us,
        };
        self.ack(py, Request::SetCalibration { servo, calibration })
    }

    /// Persists the twelve calibrations (EEPROM).
    fn save_calibration<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.ack(py, Request::SaveCalibration)
    }

    /// Outputs on at the rest pose, then a ramp to the stance. Returns the motion status.
    fn stand_up<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.motion(py, Request::StartMotion(MotionCommand::StandUp))
    }

    /// A ramp to the rest pose, held.
    fn sit<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.motion(py, Request::StartMotion(MotionCommand::Sit))
    }

    /// A ramp to the rest pose, then the outputs off.
    fn rest<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.motion(py, Request::StartMotion(MotionCommand::Rest))
    }

    /// Seed 001's sway about ``axis`` (``"roll"``, ``"pitch"``, ``"yaw"``): ``angle =
    /// amplitude_rad·sin(2πt/period_s)``, feet fixed; ``duration_s=None`` runs until
    /// :meth:`stop_motion`.
    #[pyo3(signature = (axis, amplitude_rad, period_s, duration_s = None))]
    fn start_sway<'py>(
        &mut self,
        py: Python<'py>,
        axis: &str,
        amplitude_rad: f32,
        period_s: f32,
        duration_s: Option<f32>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let axis = match axis {
            "roll" => Axis::Roll,
            "pitch" => Axis::Pitch,
            "yaw" => Axis::Yaw,
            other => {
                return Err(errors::value(format!(
                    "axis {other:?}: expected \"roll\", \"pitch\" or \"yaw\""
                )))
            }
        };
        self.motion(
            py,
            Request::StartMotion(MotionCommand::Sway {
                axis,
                amplitude_rad,
                period_s,
                duration_s,
            }),
        )
    }

    /// Seed 001's crossed-pair yaw turn about the body centre.
    #[pyo3(signature = (yaw_rate_rad_s, step_period_s, lift_height_m, duration_s = None))]
    fn start_yaw_turn<'py>(
        &mut self,
        py: Python<'py>,
        yaw_rate_rad_s: f32,
        step_period_s: f32,
        lift_height_m: f32,
        duration_s: Option<f32>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.motion(
            py,
            Request::StartMotion(MotionCommand::YawTurn {
                yaw_rate_rad_s,
                step_period_s,
                lift_height_m,
                duration_s,
            }),
        )
    }

    /// A seed 000 foot path (``path``: rectangle, semicircle, ellipse, cycloid, bezier) around
    /// the stance point of ``leg`` (``None``: all four legs, in phase), body held.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (path, stride_m, step_height_m, duty_factor, cycle_s, leg = None, duration_s = None))]
    fn start_foot_path<'py>(
        &mut self,
        py: Python<'py>,
        path: &str,
        stride_m: f32,
        step_height_m: f32,
        duty_factor: f32,
        cycle_s: f32,
        leg: Option<&Bound<'py, PyAny>>,
        duration_s: Option<f32>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let path = PathKind::parse(path).ok_or_else(|| {
            errors::value(format!(
                "path {path:?}: expected rectangle, semicircle, ellipse, cycloid or bezier"
            ))
        })?;
        let legs = match leg {
            None => LegSet::All,
            Some(l) => LegSet::One(leg_arg(l)?),
        };
        self.motion(
            py,
            Request::StartMotion(MotionCommand::FootPath {
                path,
                legs,
                stride_m,
                step_height_m,
                duty_factor,
                cycle_s,
                duration_s,
            }),
        )
    }

    /// Trot or walk (``gait``: ``"trot"``, ``"walk"``) from a velocity command
    /// (:meth:`set_velocity`, zero at the start), refreshed within ``velocity_timeout_ms``.
    #[pyo3(signature = (gait, body_height_m, step_height_m, cycle_s, velocity_timeout_ms = 500))]
    fn start_walk<'py>(
        &mut self,
        py: Python<'py>,
        gait: &str,
        body_height_m: f32,
        step_height_m: f32,
        cycle_s: f32,
        velocity_timeout_ms: u16,
    ) -> PyResult<Bound<'py, PyDict>> {
        let gait = match gait {
            "trot" => Pattern::Trot,
            "walk" => Pattern::Walk,
            other => {
                return Err(errors::value(format!(
                    "gait {other:?}: expected \"trot\" or \"walk\""
                )))
            }
        };
        self.motion(
            py,
            Request::StartMotion(MotionCommand::Walk {
                gait,
                body_height_m,
                step_height_m,
                cycle_s,
                velocity_timeout_ms,
            }),
        )
    }

    /// Stops the running motion cleanly (end of period or strides, then a ramp to the
    /// stance).
    fn stop_motion<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.motion(py, Request::StopMotion)
    }

    /// The motion engine's state: ``kind`` (None when idle), ``stage`` (``"idle"`` when idle),
    /// ``t_s`` and ``phase`` (0 when idle), ``fault``, and the readback.
    fn motion_status<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.motion(py, Request::GetMotion)
    }

    /// The running walk's velocity command, body frame: forward m/s, lateral (left) m/s, yaw
    /// rate rad/s (counter-clockwise positive).
    #[pyo3(signature = (forward_m_s, lateral_m_s = 0.0, yaw_rate_rad_s = 0.0))]
    fn set_velocity<'py>(
        &mut self,
        py: Python<'py>,
        forward_m_s: f32,
        lateral_m_s: f32,
        yaw_rate_rad_s: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.motion(
            py,
            Request::SetVelocity {
                forward_m_s,
                lateral_m_s,
                yaw_rate_rad_s,
            },
        )
    }

    /// Lets ``duration_s`` of device time pass without a request (the simulated and emulated
    /// devices run meanwhile; on a serial port it waits).
    fn idle(&mut self, duration_s: f64) -> PyResult<()> {
        if !(duration_s.is_finite() && duration_s >= 0.0) {
            return Err(errors::value(format!(
                "duration_s {duration_s}: expected a finite time >= 0"
            )));
        }
        let until = self.client.link().now() + std::time::Duration::from_secs_f64(duration_s);
        self.client
            .idle_until(until)
            .map_err(|e| errors::link(&e, &self.port))
    }

    fn __repr__(&self) -> String {
        format!(
            "Device(port={:?}, robot={})",
            self.port,
            quad_host::names::robot_preset_name(self.info.robot)
        )
    }
}

fn info_dict<'py>(py: Python<'py>, i: &DeviceInfo) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("version", i.version)?;
    d.set_item(
        "firmware",
        format!(
            "{}.{}.{}",
            i.firmware.major, i.firmware.minor, i.firmware.patch
        ),
    )?;
    d.set_item("robot", quad_host::names::robot_preset_name(i.robot))?;
    d.set_item("max_frame_len", i.max_frame_len)?;
    d.set_item("stance_height_m", i.pose_config.stance_height_m)?;
    d.set_item("rotation_order", i.pose_config.order.name())?;
    d.set_item(
        "policy",
        quad_host::names::reach_policy_name(i.pose_config.policy),
    )?;
    d.set_item("link_timeout_ms", i.link_timeout.timeout_ms)?;
    d.set_item(
        "link_loss_action",
        format!("{:?}", i.link_timeout.action).to_lowercase(),
    )?;
    // The robot's hash (protocol 2.4; None from an older device).
    d.set_item("robot_hash", i.robot_hash)?;
    Ok(d)
}

fn readback_dict<'py>(py: Python<'py>, r: &Readback) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "angles_rad",
        PyArray1::from_slice(py, &r.angles_rad).reshape([4, 3])?,
    )?;
    d.set_item(
        "pulses_half_us",
        PyArray1::from_slice(py, &r.pulses_half_us).reshape([4, 3])?,
    )?;
    d.set_item("flags", r.flags.0)?;
    for (name, bit) in [
        ("clamped", Flags::CLAMPED),
        ("limited", Flags::LIMITED),
        ("outputs_enabled", Flags::OUTPUTS_ENABLED),
        ("failsafe_active", Flags::FAILSAFE_ACTIVE),
        ("calibration_unsaved", Flags::CALIBRATION_UNSAVED),
        ("calibration_default", Flags::CALIBRATION_DEFAULT),
        ("watchdog_reset", Flags::WATCHDOG_RESET),
    ] {
        d.set_item(name, r.flags.contains(bit))?;
    }
    d.set_item("frames_ok", r.frames_ok)?;
    d.set_item("frames_bad", r.frames_bad)?;
    Ok(d)
}

fn motion_dict<'py>(
    py: Python<'py>,
    s: &MotionStatus,
    r: &Readback,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "kind",
        s.kind.map(|k| crate::errors::snake(&format!("{k:?}"))),
    )?;
    d.set_item("stage", crate::errors::snake(&format!("{:?}", s.stage)))?;
    d.set_item("t_s", s.t_s)?;
    d.set_item("phase", s.phase)?;
    d.set_item("fault", s.fault.map(|f| f.to_string()))?;
    d.set_item("readback", readback_dict(py, r)?)?;
    Ok(d)
}

fn calibration_dict<'py>(py: Python<'py>, c: &Calibration) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("zero_rad", c.zero_rad)?;
    d.set_item("reversed", c.reversed)?;
    d.set_item("us_per_rad", c.us_per_rad)?;
    d.set_item("center_us", c.center_us)?;
    d.set_item("min_us", c.min_us)?;
    d.set_item("max_us", c.max_us)?;
    Ok(d)
}
