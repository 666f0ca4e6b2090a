//! The device's servo calibration: its TOML file (read and written) and the operation behind
//! `quadctl calibrate` (read, edit, save), and the guided calibration ([`guide`]).

pub mod guide;

use crate::client::{self, Client, ClientConfig};
use crate::csv::Num;
use crate::link::{self, Target};
use quad_protocol::servo::Calibration;
use quad_protocol::{Request as DeviceRequest, ServoId};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why a calibration could not be read, sent or saved.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not valid TOML, or a key is missing, unknown or of the wrong type.
    #[error("{}: {source}", path.display())]
    Toml {
        /// The file.
        path: PathBuf,
        /// The TOML error.
        source: toml::de::Error,
    },
    /// A file without any servo table: nothing would be sent.
    #[error(
        "{}: no servo calibration in the file (expected tables such as FL_knee = {{ zero_rad = ... }}; `quadctl calibrate get` prints all twelve)",
        path.display()
    )]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A table name that is not a servo.
    #[error("{}: `{name}` is not a servo (FL_abduction, FL_hip, FL_knee, ..., RR_knee)", path.display())]
    Servo {
        /// The file.
        path: PathBuf,
        /// The name found.
        name: String,
    },
    /// A calibration the protocol refuses.
    #[error("{}: {}: {source}", path.display(), servo_name(*servo))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The servo.
        servo: ServoId,
        /// Why.
        source: quad_protocol::servo::Error,
    },
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// A request failed.
    #[error(transparent)]
    Client(#[from] client::Error),
    /// The device refused or failed one servo's calibration.
    #[error("{}: {source}", servo_name(*servo))]
    Send {
        /// The servo.
        servo: ServoId,
        /// What the device said.
        source: client::Error,
    },
    /// The device holds another calibration than the one sent.
    #[error("{}: the device holds another calibration than the one sent ({})", servo_name(*servo), one_line(held))]
    NotHeld {
        /// The servo.
        servo: ServoId,
        /// What the device holds.
        held: Calibration,
    },
}

/// A calibration on one line, in the file's terms.
fn one_line(c: &Calibration) -> String {
    format!(
        "zero_rad = {}, reversed = {}, us_per_rad = {}, center_us = {}, min_us = {}, max_us = {}",
        toml_f32(c.zero_rad),
        c.reversed,
        toml_f32(c.us_per_rad),
        c.center_us,
        c.min_us,
        c.max_us
    )
}

/// One servo in the TOML file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    zero_rad: f32,
    reversed: bool,
    us_per_rad: f32,
    center_us: u16,
    min_us: u16,
    max_us: u16,
}

impl From<Entry> for Calibration {
    fn from(e: Entry) -> Calibration {
        Calibration {
            zero_rad: e.zero_rad,
            reversed: e.reversed,
            us_per_rad: e.us_per_rad,
            center_us: e.center_us,
            min_us: e.min_us,
            max_us: e.max_us,
        }
    }
}

/// TOML name of a servo: `FL_abduction`.
pub fn servo_name(s: ServoId) -> String {
    format!("{}_{}", s.leg, s.joint)
}

/// A float TOML reads back as the same f32 (always with a decimal point or exponent).
fn toml_f32(v: f32) -> String {
    let s = Num(v).to_string();
    if s.contains(['.', 'e', 'E']) || !v.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

/// The twelve calibrations as TOML, one inline table per servo.
pub fn to_toml(table: &[Calibration; 12]) -> String {
    let mut s = String::from(
        "# Servo calibration: pulse_us = center_us + s*us_per_rad*(angle_rad - zero_rad),\n\
         # s = -1 if reversed; valid within [min_us, max_us]. Angles rad, pulses us.\n",
    );
    for id in ServoId::ALL {
        let c = &table[id.index()];
        let _ = writeln!(
            s,
            "{} = {{ zero_rad = {}, reversed = {}, us_per_rad = {}, center_us = {}, min_us = {}, max_us = {} }}",
            servo_name(id),
            toml_f32(c.zero_rad),
            c.reversed,
            toml_f32(c.us_per_rad),
            c.center_us,
            c.min_us,
            c.max_us
        );
    }
    s
}

/// Reads a calibration file: the servos it lists, each validated.
///
/// # Errors
/// [`Error::Toml`], [`Error::Servo`], [`Error::Invalid`], naming the file.
pub fn parse_toml(text: &str, path: &Path) -> Result<Vec<(ServoId, Calibration)>, Error> {
    let map: BTreeMap<String, Entry> = toml::from_str(text).map_err(|source| Error::Toml {
        path: path.to_owned(),
        source,
    })?;
    let mut out = Vec::new();
    for (name, entry) in map {
        let id = ServoId::ALL
            .into_iter()
            .find(|s| servo_name(*s).eq_ignore_ascii_case(&name))
            .ok_or_else(|| Error::Servo {
                path: path.to_owned(),
                name: name.clone(),
            })?;
        let c = Calibration::from(entry);
        c.validate().map_err(|source| Error::Invalid {
            path: path.to_owned(),
            servo: id,
            source,
        })?;
        out.push((id, c));
    }
    Ok(out)
}

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// Read the 12 calibrations.
    Get,
    /// Send the calibrations of a TOML file to the device's RAM, and persist them with `save`.
    Set {
        /// The file.
        file: PathBuf,
        /// Persist them too.
        save: bool,
    },
    /// Persist the calibration held in the device's RAM.
    Save,
}

/// Carries out `action` on the device at `target` (`retries` resends per streamed request) and
/// returns the calibration it then holds.
///
/// # Errors
/// See [`Error`].
pub fn run(target: &Target, retries: u32, action: &Action) -> Result<[Calibration; 12], Error> {
    let edits = match action {
        Action::Set { file, .. } => {
            let text = std::fs::read_to_string(file).map_err(|source| Error::Read {
                path: file.clone(),
                source,
            })?;
            Some(parse_toml(&text, file)?)
        }
        _ => None,
    };
    let link = link::open(target)?;
    // Refused once the device is known to be there (a missing port is the first thing to
    // report), before anything is sent.
    if let (Some(edits), Action::Set { file, .. }) = (&edits, action) {
        if edits.is_empty() {
            return Err(Error::Empty { path: file.clone() });
        }
    }
    let mut client = Client::new(link, ClientConfig::for_target(target, retries));
    client.hello()?;
    for (id, calibration) in edits.iter().flatten() {
        client
            .ack(DeviceRequest::SetCalibration {
                servo: *id,
                calibration: *calibration,
            })
            .map_err(|source| Error::Send { servo: *id, source })?;
    }
    if matches!(action, Action::Save | Action::Set { save: true, .. }) {
        client.ack(DeviceRequest::SaveCalibration)?;
    }
    let table = client.calibrations()?;
    for (id, want) in edits.iter().flatten() {
        if table[id.index()] != *want {
            return Err(Error::NotHeld {
                servo: *id,
                held: table[id.index()],
            });
        }
    }
    Ok(table)
}

/// Why the guided calibration could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GuideError {
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// The handshake or the calibration read failed.
    #[error(transparent)]
    Session(#[from] crate::ops::onboard::Error),
    /// The device's robot is not known.
    #[error(transparent)]
    Robot(#[from] crate::robot_file::DeviceRobotError),
    /// The robot has no calibration posture.
    #[error(transparent)]
    Posture(#[from] guide::PostureError),
}

/// Opens the device at `target` (`retries` resends per request), reads its calibration and
/// starts a [`guide::Guide`] on the device's own robot ([`crate::robot_file::device_robot`]: the
/// robot a device of protocol 2.4 holds; `robot_file` for an older device whose robot is no
/// preset, and a check against the device's robot otherwise).
///
/// # Errors
/// See [`GuideError`].
pub fn open_guide(
    target: &Target,
    retries: u32,
    robot_file: Option<&kin_core::Robot>,
) -> Result<
    (
        crate::ops::onboard::Session<Box<dyn link::Link>>,
        guide::Guide,
    ),
    GuideError,
> {
    let link = link::open(target)?;
    let mut client = Client::new(link, ClientConfig::for_target(target, retries));
    // A device of protocol 2.4 or later tells the robot it holds; an older one only its preset.
    let info = client.hello().map_err(crate::ops::onboard::Error::from)?;
    let session = if quad_protocol::version_minor(info.version) >= 4 {
        crate::ops::onboard::Session::connect_robot(client, None)?
    } else {
        crate::ops::onboard::Session::connect_to_device(client)?
    };
    let robot = crate::robot_file::device_robot(session.info(), session.robot(), robot_file)?;
    let guide = guide::Guide::new(&robot, *session.calibration())?;
    Ok((session, guide))
}

#[cfg(test)]
mod tests {
    use super::*;
    use quad_device::{default_calibration, Config};

    #[test]
    fn toml_round_trips_exactly() {
        let c = Config::fernando2025();
        let table = default_calibration::<kin_core::DefaultMath>(&c.robot, &c.pose_config);
        let text = to_toml(&table);
        let back = parse_toml(&text, Path::new("t.toml")).unwrap();
        assert_eq!(back.len(), 12);
        for (id, cal) in back {
            assert_eq!(cal, table[id.index()], "{}", servo_name(id));
        }
    }

    #[test]
    fn bad_files_are_refused() {
        let p = Path::new("t.toml");
        let ok = "zero_rad = 0.0, reversed = false, us_per_rad = 600.0, center_us = 1500, min_us = 1000, max_us = 2000";
        assert_eq!(
            parse_toml(&format!("fl_knee = {{ {ok} }}"), p)
                .unwrap()
                .len(),
            1
        );
        assert!(parse_toml(&format!("XX_knee = {{ {ok} }}"), p).is_err());
        assert!(parse_toml(&format!("FL_knee = {{ {ok}, sign = 1 }}"), p).is_err());
        assert!(parse_toml("FL_knee = { zero_rad = 0.0 }", p).is_err());
        let bad = ok.replace("min_us = 1000", "min_us = 1600");
        let e = parse_toml(&format!("FL_knee = {{ {bad} }}"), p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("FL_knee"), "{e}");
    }
}
