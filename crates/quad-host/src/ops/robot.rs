//! The robot the device holds (protocol 2.4): the operation behind `quadctl robot` (show it,
//! send a robot file or preset, store it) and the robot as a robot file.
//!
//! The robot sent is resolved as every device command's `--robot` is
//! ([`robot_file::device_description`]) and checked on the host first
//! ([`quad_protocol::check_robot`], the device's own check): a robot the device cannot hold is
//! refused naming the field, and nothing is sent.

use crate::client::{self, Client, ClientConfig};
use crate::link::{self, Target};
use crate::{names, robot_file};
use quad_protocol::RobotDescription;
use std::fmt::Write as _;

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// Read the robot the device holds.
    Show,
    /// Send a robot (a preset, a TOML or a URDF file) to the device's RAM, and store it with
    /// `save`.
    Send {
        /// The preset or file.
        robot: String,
        /// Store it too.
        save: bool,
    },
    /// Store the robot held in the device's RAM.
    Save,
}

/// Why the robot could not be read, sent or stored.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The robot to send was refused on the host (not sent).
    #[error(transparent)]
    Robot(#[from] robot_file::DeviceError),
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// A request failed or the device refused it.
    #[error(transparent)]
    Client(#[from] client::Error),
}

/// Carries out `action` on the device at `target` and returns the robot it then holds.
///
/// # Errors
/// See [`Error`]; [`client::Error::NoRobotRequests`] for a device older than 2.4.
pub fn run(target: &Target, retries: u32, action: &Action) -> Result<RobotDescription, Error> {
    let sent = match action {
        Action::Send { robot, .. } => Some(robot_file::device_description(robot)?),
        _ => None,
    };
    let link = link::open(target)?;
    let mut client = Client::new(link, ClientConfig::for_target(target, retries));
    let info = client.hello()?;
    if quad_protocol::version_minor(info.version) < 4 {
        return Err(client::Error::NoRobotRequests {
            device: info.version,
        }
        .into());
    }
    if let Some(robot) = &sent {
        client.set_robot(robot)?;
    }
    if matches!(action, Action::Save | Action::Send { save: true, .. }) {
        client.save_robot()?;
    }
    Ok(client.get_robot()?)
}

/// `robot` as a robot file (the keys of [`robot_file`], its `[device]` table included), headed
/// by its hash: what `quadctl robot send` reads back.
pub fn to_toml(robot: &RobotDescription) -> String {
    let r = &robot.robot;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# the robot the device holds; hash {:08x}",
        robot.hash()
    );
    for (key, v) in [
        ("d_lat_m", r.leg.d_lat_m),
        ("d_ax_m", r.leg.d_ax_m),
        ("femur_m", r.leg.femur_m),
        ("tibia_m", r.leg.tibia_m),
        ("body_length_m", r.body_length_m),
        ("body_width_m", r.body_width_m),
    ] {
        let _ = writeln!(out, "{key} = {}", toml_f32(v));
    }
    let _ = writeln!(
        out,
        "knee_bend = \"{}\"\n\n[limits]",
        names::knee_bend_name(r.knee_bend)
    );
    for (j, key) in ["abduction_rad", "hip_rad", "knee_rad"].iter().enumerate() {
        let _ = writeln!(
            out,
            "{key} = [{}, {}]",
            toml_f32(r.limits.min_rad[j]),
            toml_f32(r.limits.max_rad[j])
        );
    }
    let _ = writeln!(
        out,
        "\n[device]\nname = \"{}\"\nstance_height_m = {}\nrotation_order = \"{}\"\n\
         joint_speed_limit_rad_s = {}",
        robot.name_str().unwrap_or(""),
        toml_f32(robot.stance_height_m),
        robot.order.name(),
        toml_f32(robot.joint_speed_limit_rad_s)
    );
    out
}

/// An f32 as a TOML float that reads back to the same bits (always with a decimal point).
fn toml_f32(v: f32) -> String {
    let s = format!("{v:?}");
    if s.contains(['.', 'e', 'E']) || !v.is_finite() {
        s
    } else {
        s + ".0"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::sim::SimConfig;
    use quad_protocol::RobotPreset;

    #[test]
    fn the_toml_of_a_robot_reads_back_to_the_same_robot() {
        let robot = quad_device::Config::fernando2025().description();
        let dir = std::env::temp_dir().join(format!("quad-robot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("back.toml");
        std::fs::write(&path, to_toml(&robot)).unwrap();
        let back = robot_file::device_description(path.to_str().unwrap()).unwrap();
        assert_eq!(back, robot);
        assert_eq!(back.hash(), robot.hash());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn send_save_and_show_on_the_simulated_device() {
        let target = Target::Sim {
            preset: RobotPreset::Fernando2025,
            config: SimConfig::default(),
            storage: None,
        };
        let shown = run(&target, 3, &Action::Show).unwrap();
        assert_eq!(shown, quad_device::Config::fernando2025().description());
        let sent = run(
            &target,
            3,
            &Action::Send {
                robot: "shahriar2023".into(),
                save: true,
            },
        )
        .unwrap();
        assert_eq!(sent, quad_device::Config::shahriar2023().description());
        // A robot the device cannot hold: refused on the host, naming the field.
        let dir = std::env::temp_dir().join(format!("quad-robot-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("long.toml");
        std::fs::write(
            &path,
            "d_lat_m = 0.0\nd_ax_m = 0.0\nfemur_m = 3.0\ntibia_m = 0.2\nbody_length_m = 0.4\n\
             body_width_m = 0.2\n",
        )
        .unwrap();
        let err = run(
            &target,
            3,
            &Action::Send {
                robot: path.to_str().unwrap().into(),
                save: false,
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("femur_m"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
