//! Servo models: what a joint's actuator can do, as the physics twin simulates it.
//!
//! A hobby servo is a DC motor behind a gear train, driven by an H-bridge whose duty cycle a
//! proportional controller sets from the position error. With the motor's electrical time
//! constant neglected (well under a millisecond against a 20 ms servo frame), the torque at the
//! output shaft is
//!
//! ```text
//! u = clamp((target − q − T_d·q̇) / e_full, −1, 1),   u = 0 when |target − q| < deadband
//! τ = τ_stall · u − (τ_stall / ω_0) · q̇
//! ```
//!
//! `τ_stall` is the stall torque, `ω_0` the no-load speed, `e_full` the position error at which
//! the duty cycle saturates (the proportional gain is `τ_stall / e_full`), `T_d` an optional
//! derivative time. The second term is the motor's back-EMF: at full duty the torque falls
//! linearly from `τ_stall` at rest to zero at `ω_0`, which is the servo's speed limit — no
//! separate clamp is needed, and a loaded servo is slower than the no-load figure, as a real
//! one is. The MJCF writer emits exactly this as a MuJoCo `general` actuator (gain `τ_stall`,
//! affine bias `−τ_stall/ω_0 · q̇`, control `u ∈ [−1, 1]`); the twin computes `u` from the
//! target every physics step.

use core::f32::consts::PI;
use core::fmt;

/// A servo's parameters (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoModel {
    /// Preset name (`mg996r`, `qdd17`, …).
    pub name: &'static str,
    /// Torque at zero speed and full duty, N·m.
    pub stall_torque_nm: f32,
    /// Speed at full duty and zero load, rad/s.
    pub no_load_speed_rad_s: f32,
    /// Position error at which the duty cycle reaches 100 %, rad (proportional gain =
    /// `stall_torque_nm / full_duty_error_rad`).
    pub full_duty_error_rad: f32,
    /// Errors smaller than this leave the motor undriven, rad.
    pub deadband_rad: f32,
    /// Derivative time of the position controller, s (0 for a P-only hobby servo).
    pub derivative_s: f32,
    /// Rotor inertia reflected through the gear train (`J_rotor · N²`), kg·m².
    pub armature_kg_m2: f32,
    /// Dry friction of the gear train, N·m.
    pub friction_loss_nm: f32,
    /// Mass of one servo, kg (used by the physical presets that place servos on links).
    pub mass_kg: f32,
}

/// The pulse gain this project's default calibration assumes, µs per rad (1000 µs per 90°);
/// the same value as `quad_protocol::servo::STANDARD_US_PER_RAD`, restated here as a plain
/// number because a deadband given in µs by a datasheet needs a gain to become an angle.
const DATASHEET_US_PER_RAD: f32 = 2000.0 / PI;

impl ServoModel {
    /// TowerPro MG996R-class hobby servo at 6 V. Datasheet: stall torque 11 kgf·cm at 6 V
    /// (1.08 N·m), speed 0.17 s/60° at 4.8 V (6.16 rad/s; 0.14 s/60° at 6 V — the slower
    /// figure is kept), deadband 5 µs (7.9 mrad at 1000 µs per 90°), 55 g. Assumed (no
    /// datasheet value): full duty at 0.1 rad of error, P-only, reflected rotor inertia
    /// 2·10⁻³ kg·m², gear friction 0.01 N·m. Reasons in `docs/twin.md`.
    pub const MG996R: ServoModel = ServoModel {
        name: "mg996r",
        stall_torque_nm: 1.08,
        no_load_speed_rad_s: (PI / 3.0) / 0.17,
        full_duty_error_rad: 0.1,
        deadband_rad: 5.0 / DATASHEET_US_PER_RAD,
        derivative_s: 0.0,
        armature_kg_m2: 2.0e-3,
        friction_loss_nm: 0.01,
        mass_kg: 0.055,
    };

    /// A quasi-direct-drive actuator of the MIT Mini Cheetah class (the robot seed 001 cites):
    /// 17 N·m peak torque, 40 rad/s top speed, 6:1 gearing, 0.48 kg (Katz et al., ICRA 2019).
    /// Assumed: full duty at 0.1 rad of error, derivative time 0.02 s, reflected rotor inertia
    /// 2.2·10⁻³ kg·m², friction 0.05 N·m, deadband 1 mrad (encoder resolution class).
    pub const QDD17: ServoModel = ServoModel {
        name: "qdd17",
        stall_torque_nm: 17.0,
        no_load_speed_rad_s: 40.0,
        full_duty_error_rad: 0.1,
        deadband_rad: 1.0e-3,
        derivative_s: 0.02,
        armature_kg_m2: 2.2e-3,
        friction_loss_nm: 0.05,
        mass_kg: 0.48,
    };

    /// A 35 kgf·cm-class digital hobby servo (DS3235 class): 3.4 N·m stall at 7.4 V,
    /// 0.13 s/60°, deadband 3 µs, 65 g. Class values, not one datasheet; the other parameters
    /// as [`ServoModel::MG996R`].
    pub const DS3235: ServoModel = ServoModel {
        name: "ds3235",
        stall_torque_nm: 3.4,
        no_load_speed_rad_s: (PI / 3.0) / 0.13,
        full_duty_error_rad: 0.1,
        deadband_rad: 3.0 / DATASHEET_US_PER_RAD,
        derivative_s: 0.0,
        armature_kg_m2: 2.0e-3,
        friction_loss_nm: 0.01,
        mass_kg: 0.065,
    };

    /// A quasi-direct-drive actuator of the Unitree A1 class: 33.5 N·m peak torque, 21 rad/s,
    /// 0.605 kg. Assumed as [`ServoModel::QDD17`]: full duty at 0.1 rad, derivative time
    /// 0.02 s, friction 0.05 N·m, deadband 1 mrad; reflected inertia 4·10⁻³ kg·m² (9:1 gearing).
    pub const QDD33: ServoModel = ServoModel {
        name: "qdd33",
        stall_torque_nm: 33.5,
        no_load_speed_rad_s: 21.0,
        full_duty_error_rad: 0.1,
        deadband_rad: 1.0e-3,
        derivative_s: 0.02,
        armature_kg_m2: 4.0e-3,
        friction_loss_nm: 0.05,
        mass_kg: 0.605,
    };

    /// Names of the presets accepted by [`ServoModel::preset`].
    pub const PRESETS: [&'static str; 4] = ["mg996r", "ds3235", "qdd17", "qdd33"];

    /// A preset by name.
    ///
    /// # Errors
    /// [`UnknownServo`] naming the preset asked for.
    pub fn preset(name: &str) -> Result<ServoModel, UnknownServo> {
        match name {
            "mg996r" => Ok(ServoModel::MG996R),
            "ds3235" => Ok(ServoModel::DS3235),
            "qdd17" => Ok(ServoModel::QDD17),
            "qdd33" => Ok(ServoModel::QDD33),
            _ => Err(UnknownServo {
                name: name.to_owned(),
            }),
        }
    }

    /// Proportional gain of the position loop at full supply, N·m/rad.
    pub fn kp_nm_per_rad(&self) -> f32 {
        self.stall_torque_nm / self.full_duty_error_rad
    }

    /// Back-EMF damping `τ_stall / ω_0`, N·m·s/rad.
    pub fn back_emf_nm_s_per_rad(&self) -> f32 {
        self.stall_torque_nm / self.no_load_speed_rad_s
    }

    /// The fields that must be finite and > 0, by name, with their values (the others must be
    /// finite and ≥ 0; see [`ServoModel::non_negative_fields`]).
    pub(crate) fn positive_fields(&self) -> [(&'static str, f32); 5] {
        [
            ("servo.stall_torque_nm", self.stall_torque_nm),
            ("servo.no_load_speed_rad_s", self.no_load_speed_rad_s),
            ("servo.full_duty_error_rad", self.full_duty_error_rad),
            ("servo.armature_kg_m2", self.armature_kg_m2),
            ("servo.mass_kg", self.mass_kg),
        ]
    }

    /// The fields that must be finite and ≥ 0.
    pub(crate) fn non_negative_fields(&self) -> [(&'static str, f32); 3] {
        [
            ("servo.deadband_rad", self.deadband_rad),
            ("servo.derivative_s", self.derivative_s),
            ("servo.friction_loss_nm", self.friction_loss_nm),
        ]
    }
}

/// A servo preset name that is not one of [`ServoModel::PRESETS`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownServo {
    /// The name asked for.
    pub name: String,
}

impl fmt::Display for UnknownServo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown servo preset `{}` (known: {})",
            self.name,
            ServoModel::PRESETS.join(", ")
        )
    }
}

impl std::error::Error for UnknownServo {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_resolve_and_unknown_is_named() {
        for name in ServoModel::PRESETS {
            assert_eq!(ServoModel::preset(name).map(|s| s.name), Ok(name));
        }
        let err = ServoModel::preset("sg90").unwrap_err();
        assert_eq!(err.name, "sg90");
        assert!(err.to_string().contains("`sg90`"), "{err}");
        assert!(err.to_string().contains("mg996r"), "{err}");
    }

    #[test]
    fn mg996r_matches_its_datasheet() {
        let s = ServoModel::MG996R;
        // 0.17 s per 60 degrees.
        assert!(((PI / 3.0) / s.no_load_speed_rad_s - 0.17).abs() < 1e-6);
        // 5 us of deadband at 1000 us per 90 degrees.
        assert!((s.deadband_rad * 1000.0 / (PI / 2.0) - 5.0).abs() < 1e-4);
        assert!((s.kp_nm_per_rad() - 10.8).abs() < 1e-4);
    }
}
