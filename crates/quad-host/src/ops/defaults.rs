//! The device's defaults as the host's commands plan with them, read from the device's own
//! configuration ([`quad_device::Config`]'s presets, which the firmware and the simulated
//! device run): one place, so that `check`, `motion` and `play` judge a motion by the numbers
//! the device applies to it.

use quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S;
use quad_device::Config;
use quad_protocol::RobotPreset;

/// The device's configuration of the robot `robot` (a preset name; `None` for a robot file).
fn config(robot: &str) -> Option<Config> {
    RobotPreset::from_name(robot.trim()).and_then(Config::for_preset)
}

/// The joint-speed limit every output of the device of `robot` passes at power-on, rad/s: its
/// configuration's for a preset, the limiter's default (3 rad/s) otherwise.
pub fn joint_speed_limit_rad_s(robot: &str) -> f32 {
    config(robot).map_or(DEFAULT_JOINT_SPEED_LIMIT_RAD_S, |c| {
        c.joint_speed_limit_rad_s
    })
}

/// The device's stance height for a preset robot, m (shahriar2023 0.40, fernando2025 0.9294):
/// where its motions stand and where it holds body poses. `None` for a robot file.
pub fn stance_height_m(robot: &str) -> Option<f32> {
    config(robot).map(|c| c.pose_config.stance_height_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_the_device_configurations() {
        assert_eq!(joint_speed_limit_rad_s("shahriar2023"), 3.0);
        assert_eq!(joint_speed_limit_rad_s("robot.toml"), 3.0);
        assert_eq!(
            stance_height_m("shahriar2023"),
            Some(Config::shahriar2023().pose_config.stance_height_m)
        );
        assert_eq!(stance_height_m("shahriar2023"), Some(0.40));
        assert_eq!(stance_height_m("fernando2025"), Some(0.9294));
        assert_eq!(stance_height_m("examples/robots/custom.toml"), None);
    }
}
