//! `quadctl calibrate`: read, edit (from a TOML file) and save the device's servo calibration.

use super::stream::TargetArgs;
use super::{EXIT_FATAL, EXIT_OK};
use crate::client::{Client, ClientError};
use crate::csv_io::Num;
use quad_protocol::servo::Calibration;
use quad_protocol::{Request, RobotPreset, ServoId};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Reads, edits and saves the servo calibration of the device (--sim or --port).

One calibration per servo, named <LEG>_<joint> (FL_abduction, FL_hip, FL_knee, FR_..., RL_...,
RR_...). The pulse for a joint angle is

  pulse_us = center_us + s * us_per_rad * (angle_rad - zero_rad),  s = -1 if reversed, else +1

valid only within [min_us, max_us] (a target outside is refused, never clamped). Angles in
RADIANS, pulses in MICROSECONDS.

  get            print the 12 calibrations as TOML (the format `set` reads)
  set FILE.toml  send the servos listed in FILE (any subset) to the device's RAM; --save also
                 persists them
  save           persist the calibration in the device's RAM (EEPROM, two banks with a CRC)

TOML: one inline table per servo, every field required, e.g.
  FL_knee = { zero_rad = -1.0472, reversed = false, us_per_rad = 636.62, center_us = 1500, min_us = 500, max_us = 2500 }

The device refuses a calibration whose travel excludes the joint's current angle (move the robot
first). With --sim the simulated device powers on at every run: keep its EEPROM in a file with
--sim-storage FILE to see a save in a later run.";

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq, clap::Subcommand)]
pub enum Action {
    /// Print the device's 12 calibrations as TOML.
    Get,
    /// Send the calibrations of FILE.toml to the device's RAM.
    Set {
        /// TOML file with one table per servo to change.
        file: PathBuf,
        /// Persist them too (as `save`).
        #[arg(long)]
        save: bool,
    },
    /// Persist the calibration held in the device's RAM.
    Save,
}

/// Arguments of `quadctl calibrate`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Read, edit (TOML) and save the device's servo calibration (--sim or --port)",
    long_about = LONG_ABOUT
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Robot of the simulated device.
    #[arg(long, value_name = "PRESET", default_value = "fernando2025")]
    pub robot: String,
    #[command(subcommand)]
    #[allow(missing_docs)]
    pub action: Action,
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
/// A message naming the file and what is wrong.
pub fn parse_toml(text: &str, path: &Path) -> Result<Vec<(ServoId, Calibration)>, String> {
    let map: BTreeMap<String, Entry> =
        toml::from_str(text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    for (name, entry) in map {
        let id = ServoId::ALL
            .into_iter()
            .find(|s| servo_name(*s).eq_ignore_ascii_case(&name))
            .ok_or_else(|| {
                format!(
                    "{}: `{name}` is not a servo (FL_abduction, FL_hip, FL_knee, ..., RR_knee)",
                    path.display()
                )
            })?;
        let c = Calibration::from(entry);
        c.validate()
            .map_err(|e| format!("{}: {name}: {e}", path.display()))?;
        out.push((id, c));
    }
    Ok(out)
}

/// Runs `quadctl calibrate` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let stdout = io::stdout();
    let mut out = stdout.lock();
    match run(args, &mut out) {
        Ok(()) => ExitCode::from(EXIT_OK),
        Err(message) => {
            let _ = writeln!(io::stderr(), "quadctl: error: {message}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}

/// Runs the action, printing the resulting calibration (get, set) or a confirmation (save).
///
/// # Errors
/// A message for the user.
pub fn run(args: &Args, out: &mut dyn Write) -> Result<(), String> {
    let preset = RobotPreset::from_name(args.robot.trim()).ok_or_else(|| {
        format!(
            "--robot {}: not a preset (shahriar2023, fernando2025)",
            args.robot
        )
    })?;
    let edits = match &args.action {
        Action::Set { file, .. } => {
            let text = std::fs::read_to_string(file)
                .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
            Some(parse_toml(&text, file)?)
        }
        _ => None,
    };
    let (link, config) = args.target.open(preset)?;
    let mut client = Client::new(link, config);
    let fail = |e: ClientError| e.to_string();
    client.hello().map_err(fail)?;
    for (id, calibration) in edits.iter().flatten() {
        client
            .ack(Request::SetCalibration {
                servo: *id,
                calibration: *calibration,
            })
            .map_err(|e| format!("{}: {e}", servo_name(*id)))?;
    }
    let save = matches!(args.action, Action::Save | Action::Set { save: true, .. });
    if save {
        client.ack(Request::SaveCalibration).map_err(fail)?;
    }
    let table = client.calibrations().map_err(fail)?;
    for (id, want) in edits.iter().flatten() {
        if table[id.index()] != *want {
            return Err(format!(
                "{}: the device holds {:?}, not the calibration sent",
                servo_name(*id),
                table[id.index()]
            ));
        }
    }
    let text = match args.action {
        Action::Save => "# saved\n".to_owned() + &to_toml(&table),
        _ => to_toml(&table),
    };
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| e.to_string())
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
        let e = parse_toml(&format!("FL_knee = {{ {bad} }}"), p).unwrap_err();
        assert!(e.contains("FL_knee"), "{e}");
    }
}
