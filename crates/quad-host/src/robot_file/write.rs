//! A robot file written: the TOML that [`super::parse_description`] reads back as the same
//! robot and body.

use super::{names, Description, Error};

/// An `f32` as the `f64` of its shortest decimal form, so that the TOML writer prints `0.28`
/// (not `0.2800000011920929`) and reading the file back gives the same `f32`.
fn shortest(x: f32) -> f64 {
    // The shortest form of a finite f32 always parses as an f64; a non-finite value never
    // reaches here (a validated robot and physical preset hold finite values only).
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// The file layout [`to_toml`] writes: the keys [`parse_description`] reads, in its order.
#[derive(serde::Serialize)]
struct RobotFileOut {
    d_lat_m: f64,
    d_ax_m: f64,
    femur_m: f64,
    tibia_m: f64,
    body_length_m: f64,
    body_width_m: f64,
    knee_bend: &'static str,
    limits: LimitsOut,
    physical: PhysicalOut,
}

/// `[limits]` as written: every joint explicit.
#[derive(serde::Serialize)]
struct LimitsOut {
    abduction_rad: [f64; 2],
    hip_rad: [f64; 2],
    knee_rad: [f64; 2],
}

/// `[physical]` as written: every key explicit, the servo by its preset name.
#[derive(serde::Serialize)]
struct PhysicalOut {
    servo: &'static str,
    body_mass_kg: f64,
    body_height_m: f64,
    abduction_link_mass_kg: f64,
    femur_mass_kg: f64,
    tibia_mass_kg: f64,
    knee_servo_offset_m: f64,
    foot_radius_m: f64,
    foot_friction: f64,
    link_radius_m: f64,
}

/// The robot file of `description`: every key explicit (the limits of all three joints and the
/// whole `[physical]` table), so that [`super::parse_description`] of the text gives `description`
/// back exactly, whatever the presets' defaults become. `quadctl export --format toml` writes it.
///
/// # Errors
/// [`Error::Write`] when the description cannot be written as TOML (a non-finite value).
pub fn to_toml(description: &Description) -> Result<String, Error> {
    let Description { robot, physical } = description;
    let limit = |j: usize| {
        [
            shortest(robot.limits.min_rad[j]),
            shortest(robot.limits.max_rad[j]),
        ]
    };
    let out = RobotFileOut {
        d_lat_m: shortest(robot.leg.d_lat_m),
        d_ax_m: shortest(robot.leg.d_ax_m),
        femur_m: shortest(robot.leg.femur_m),
        tibia_m: shortest(robot.leg.tibia_m),
        body_length_m: shortest(robot.body_length_m),
        body_width_m: shortest(robot.body_width_m),
        knee_bend: names::knee_bend_name(robot.knee_bend),
        limits: LimitsOut {
            abduction_rad: limit(0),
            hip_rad: limit(1),
            knee_rad: limit(2),
        },
        physical: PhysicalOut {
            servo: physical.servo.name,
            body_mass_kg: shortest(physical.body_mass_kg),
            body_height_m: shortest(physical.body_height_m),
            abduction_link_mass_kg: shortest(physical.abduction_link_mass_kg),
            femur_mass_kg: shortest(physical.femur_mass_kg),
            tibia_mass_kg: shortest(physical.tibia_mass_kg),
            knee_servo_offset_m: shortest(physical.knee_servo_offset_m),
            foot_radius_m: shortest(physical.foot_radius_m),
            foot_friction: shortest(physical.foot_friction),
            link_radius_m: shortest(physical.link_radius_m),
        },
    };
    let body = toml::to_string(&out).map_err(|e| Error::Write(e.to_string()))?;
    Ok(format!(
        "# A robot file (docs/robots.md): lengths in m, limits in rad, masses in kg.\n{body}"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot_file::{parse_description, resolve_description};
    use kin_core::Robot;

    const MINIMAL: &str = "d_lat_m = 0.044\nd_ax_m = 0.0\nfemur_m = 0.28\ntibia_m = 0.277\n\
                           body_length_m = 0.6\nbody_width_m = 0.28\n";

    #[test]
    fn the_written_file_reads_back_as_the_same_description() {
        let custom = parse_description(&format!(
            "{MINIMAL}knee_bend = \"forward\"\n[limits]\nknee_rad = [0.05, 2.7]\n[physical]\nservo = \"qdd17\"\nbody_mass_kg = 2.345\n"
        ))
        .unwrap();
        let presets = Robot::PRESETS.map(|name| resolve_description(name).unwrap());
        for description in presets.iter().chain([&custom]) {
            let text = to_toml(description).unwrap();
            let back = parse_description(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(back.robot, description.robot, "{text}");
            assert_eq!(back.physical, description.physical, "{text}");
            // Bit for bit, not only within the tolerance `Robot::eq` may allow.
            assert_eq!(
                back.robot.leg.femur_m.to_bits(),
                description.robot.leg.femur_m.to_bits()
            );
            assert!(!text.contains("00000"), "shortest decimals only:\n{text}");
        }
    }
}
