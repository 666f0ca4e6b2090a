//! The physical side of a robot that kinematics does not need: masses, sizes of the solid
//! parts, feet, and the servo. Neither paper gives these; every preset value is an assumption
//! whose reasoning is in `docs/twin.md`.

use crate::inertia::Inertial;
use crate::servo::{ServoModel, UnknownServo};
use core::fmt;
use kin_core::robot::RobotError;
use kin_core::Robot;

/// Masses, solid sizes, feet and the servo of a robot (SI units). Together with a
/// [`kin_core::Robot`] this is a [`crate::Model`].
///
/// Where the mass sits, per leg: the abduction servo in the body; the hip servo and its
/// bracket on the abduction link, centred on the hip joint; the knee servo on the femur,
/// `knee_servo_offset_m` below the hip joint (driving the knee through a linkage, as most
/// hobby-servo legs do); the femur and tibia structures as uniform rods along their links.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Physical {
    /// Body mass with everything it carries (frame, battery, electronics, the four abduction
    /// servos), kg. The body is a uniform box `body_length_m × body_width_m × body_height_m`.
    pub body_mass_kg: f32,
    /// Height (thickness) of the body box, m.
    pub body_height_m: f32,
    /// Mass turning with the abduction joint (the hip servo and its bracket), kg.
    pub abduction_link_mass_kg: f32,
    /// Femur structure (without the knee servo), kg.
    pub femur_mass_kg: f32,
    /// Tibia structure with the foot, kg.
    pub tibia_mass_kg: f32,
    /// Distance of the knee servo's centre below the hip joint along the femur, m (≤ femur).
    pub knee_servo_offset_m: f32,
    /// Radius of the spherical foot, m. The foot point of the kinematics is the sphere's
    /// centre, so the body stands `foot_radius_m` higher above the floor than the stance
    /// height.
    pub foot_radius_m: f32,
    /// Sliding friction coefficient of foot on floor.
    pub foot_friction: f32,
    /// Radius of the femur and tibia rods (drawing and rod inertia), m.
    pub link_radius_m: f32,
    /// The servo on every joint (its mass is the servo mass of the layout above).
    pub servo: ServoModel,
}

impl Physical {
    /// Seed 000's robot (0.6 × 0.28 m body, 0.28 / 0.277 m legs) with 35 kgf·cm-class hobby
    /// servos ([`ServoModel::DS3235`]; the twin shows MG996R-class servos cannot hold its
    /// stance): 1.8 kg body (frame 0.9, 2S LiPo 0.35, electronics and wiring 0.33, four
    /// abduction servos 0.22), 3D-printed or aluminium links; 2.84 kg in all.
    pub const fn shahriar2023() -> Physical {
        Physical {
            body_mass_kg: 1.8,
            body_height_m: 0.06,
            abduction_link_mass_kg: 0.085,
            femur_mass_kg: 0.06,
            tibia_mass_kg: 0.05,
            knee_servo_offset_m: 0.04,
            foot_radius_m: 0.015,
            foot_friction: 0.8,
            link_radius_m: 0.012,
            servo: ServoModel::DS3235,
        }
    }

    /// Seed 001's robot (1.0 × 0.5 m body, 0.15 / 0.45 / 0.45 m legs), which no hobby servo
    /// can hold: Unitree A1-class actuators ([`ServoModel::QDD33`]; the Mini Cheetah class
    /// seed 001 cites, [`ServoModel::QDD17`], holds the stance but not a trot on two legs), a
    /// 12 kg body (aluminium-profile frame 6, 24 V battery 2.5, electronics 1.5, four
    /// abduction actuators 2), aluminium-tube links; 22 kg in all.
    pub const fn fernando2025() -> Physical {
        Physical {
            body_mass_kg: 12.0,
            body_height_m: 0.15,
            abduction_link_mass_kg: 1.0,
            femur_mass_kg: 0.6,
            tibia_mass_kg: 0.3,
            knee_servo_offset_m: 0.05,
            foot_radius_m: 0.03,
            foot_friction: 0.8,
            link_radius_m: 0.025,
            servo: ServoModel::QDD33,
        }
    }

    /// Names of the presets accepted by [`Physical::preset`] (the robot presets' names).
    pub const PRESETS: [&'static str; 2] = ["shahriar2023", "fernando2025"];

    /// The physical preset of a robot preset name.
    ///
    /// # Errors
    /// [`Error::UnknownPreset`] naming the preset asked for.
    pub fn preset(name: &str) -> Result<Physical, Error> {
        match name {
            "shahriar2023" => Ok(Physical::shahriar2023()),
            "fernando2025" => Ok(Physical::fernando2025()),
            _ => Err(Error::UnknownPreset {
                name: name.to_owned(),
            }),
        }
    }

    /// The same with the servo preset `name`.
    ///
    /// # Errors
    /// [`Error::UnknownServo`] naming the servo asked for.
    pub fn with_servo(mut self, name: &str) -> Result<Physical, Error> {
        self.servo = ServoModel::preset(name).map_err(Error::UnknownServo)?;
        Ok(self)
    }

    /// Where the mass sits, for kin-core's centre of mass and static stability margin: the
    /// abduction link at the hip joint, the femur and tibia at their middles, the knee servo
    /// (the servo preset's mass) `knee_servo_offset_m` down the femur.
    pub const fn mass_model(&self) -> kin_core::stability::MassModel {
        kin_core::stability::MassModel {
            body_kg: self.body_mass_kg,
            abduction_link_kg: self.abduction_link_mass_kg,
            femur_kg: self.femur_mass_kg,
            knee_servo_kg: self.servo.mass_kg,
            knee_servo_offset_m: self.knee_servo_offset_m,
            tibia_kg: self.tibia_mass_kg,
        }
    }

    /// Total mass of the robot, kg.
    pub fn total_mass_kg(&self) -> f32 {
        self.body_mass_kg
            + 4.0
                * (self.abduction_link_mass_kg
                    + self.femur_mass_kg
                    + self.servo.mass_kg
                    + self.tibia_mass_kg)
    }
}

/// Why a model could not be built or written.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// A mass, length or servo parameter that must be finite and > 0 is not; the field's name.
    NonPositive {
        /// The field, as named in the robot description (`femur_m`, `body_mass_kg`,
        /// `servo.stall_torque_nm`, …).
        field: &'static str,
    },
    /// A parameter that must be finite and ≥ 0 is negative or not finite.
    Negative {
        /// The field.
        field: &'static str,
    },
    /// The knee servo sits beyond the femur (`knee_servo_offset_m` > `femur_m`).
    KneeServoBeyondFemur,
    /// The kinematic description is invalid.
    Robot(RobotError),
    /// Not a physical preset name.
    UnknownPreset {
        /// The name asked for.
        name: String,
    },
    /// Not a servo preset name.
    UnknownServo(UnknownServo),
    /// The output file could not be written (nothing is left at its path).
    Write {
        /// The path.
        path: std::path::PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The URDF serializer failed.
    Urdf(urdf_rs::UrdfError),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonPositive { field } => {
                write!(f, "`{field}` must be a finite number greater than zero")
            }
            Error::Negative { field } => write!(f, "`{field}` must be finite and not negative"),
            Error::KneeServoBeyondFemur => {
                f.write_str("`knee_servo_offset_m` must not exceed `femur_m`")
            }
            Error::Robot(e) => write!(f, "robot: {e}"),
            Error::UnknownPreset { name } => write!(
                f,
                "unknown physical preset `{name}` (known: {})",
                Physical::PRESETS.join(", ")
            ),
            Error::UnknownServo(e) => write!(f, "{e}"),
            Error::Write { path, source } => {
                write!(f, "cannot write `{}`: {source}", path.display())
            }
            Error::Urdf(e) => write!(f, "URDF serialization: {e}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Robot(e) => Some(e),
            Error::UnknownServo(e) => Some(e),
            Error::Write { source, .. } => Some(source),
            Error::Urdf(e) => Some(e),
            _ => None,
        }
    }
}

/// A robot as a physical body: its kinematics and its [`Physical`] properties, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    robot: Robot,
    physical: Physical,
}

/// The inertial properties of one leg's three moving parts, in each part's own frame (the
/// frame of its joint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegInertials {
    /// The abduction link (hip servo and bracket), about the abduction joint's frame.
    pub abduction: Inertial,
    /// The femur with the knee servo, about the hip joint's frame.
    pub femur: Inertial,
    /// The tibia with the foot, about the knee joint's frame.
    pub tibia: Inertial,
}

impl Model {
    /// Validates and pairs a robot with its physical properties.
    ///
    /// # Errors
    /// [`Error::NonPositive`] / [`Error::Negative`] naming the first bad field (lengths of the
    /// robot, including the body size, which a physical body needs > 0), [`Error::Robot`] for
    /// bad joint limits, [`Error::KneeServoBeyondFemur`].
    pub fn new(robot: Robot, physical: Physical) -> Result<Model, Error> {
        let positive = |field, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::NonPositive { field })
            }
        };
        let non_negative = |field, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(Error::Negative { field })
            }
        };
        positive("femur_m", robot.leg.femur_m)?;
        positive("tibia_m", robot.leg.tibia_m)?;
        non_negative("d_lat_m", robot.leg.d_lat_m)?;
        non_negative("d_ax_m", robot.leg.d_ax_m)?;
        positive("body_length_m", robot.body_length_m)?;
        positive("body_width_m", robot.body_width_m)?;
        robot.validate().map_err(Error::Robot)?;
        let p = &physical;
        for (field, v) in [
            ("body_mass_kg", p.body_mass_kg),
            ("body_height_m", p.body_height_m),
            ("abduction_link_mass_kg", p.abduction_link_mass_kg),
            ("femur_mass_kg", p.femur_mass_kg),
            ("tibia_mass_kg", p.tibia_mass_kg),
            ("foot_radius_m", p.foot_radius_m),
            ("foot_friction", p.foot_friction),
            ("link_radius_m", p.link_radius_m),
        ]
        .into_iter()
        .chain(p.servo.positive_fields())
        {
            positive(field, v)?;
        }
        non_negative("knee_servo_offset_m", p.knee_servo_offset_m)?;
        for (field, v) in p.servo.non_negative_fields() {
            non_negative(field, v)?;
        }
        if p.knee_servo_offset_m > robot.leg.femur_m {
            return Err(Error::KneeServoBeyondFemur);
        }
        Ok(Model { robot, physical })
    }

    /// A robot preset with its physical preset (`shahriar2023`, `fernando2025`).
    ///
    /// # Errors
    /// [`Error::UnknownPreset`].
    pub fn preset(name: &str) -> Result<Model, Error> {
        let robot = Robot::preset(name).ok_or_else(|| Error::UnknownPreset {
            name: name.to_owned(),
        })?;
        Model::new(robot, Physical::preset(name)?)
    }

    /// The kinematic description.
    pub const fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The physical properties.
    pub const fn physical(&self) -> &Physical {
        &self.physical
    }

    /// The body's inertial properties about its centre.
    pub fn body_inertial(&self) -> Inertial {
        Inertial::solid_box(
            self.physical.body_mass_kg,
            [
                self.robot.body_length_m,
                self.robot.body_width_m,
                self.physical.body_height_m,
            ],
            [0.0; 3],
        )
    }

    /// Inertial properties of the moving parts of a leg on side `side` (+1 left, −1 right).
    pub fn leg_inertials(&self, side: f32) -> LegInertials {
        let p = &self.physical;
        let g = &self.robot.leg;
        let servo = &p.servo;
        // The hip servo, as a solid cube of the servo's mass about the hip joint (MG996R:
        // 40 × 20 × 43 mm; a cube of the same volume is close enough for its inertia).
        let servo_side_m = servo_cube_side_m(servo.mass_kg);
        let abduction = Inertial::solid_box(
            p.abduction_link_mass_kg,
            [servo_side_m; 3],
            [0.0, side * g.d_lat_m, -g.d_ax_m],
        );
        let femur = Inertial::rod_z(p.femur_mass_kg, g.femur_m, p.link_radius_m).combine(
            &Inertial::solid_box(
                servo.mass_kg,
                [servo_side_m; 3],
                [0.0, 0.0, -p.knee_servo_offset_m],
            ),
        );
        let tibia = Inertial::rod_z(p.tibia_mass_kg, g.tibia_m, p.link_radius_m);
        LegInertials {
            abduction,
            femur,
            tibia,
        }
    }
}

/// Side of a cube of servo-like density (MG996R: 55 g in 40 × 20 × 43 mm, 1.6 g/cm³) and
/// mass `mass_kg`, m.
fn servo_cube_side_m(mass_kg: f32) -> f32 {
    const DENSITY_KG_M3: f32 = 1600.0;
    (mass_kg / DENSITY_KG_M3).cbrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_weigh_what_the_docs_say() {
        let s = Model::preset("shahriar2023").unwrap();
        assert!((s.physical().total_mass_kg() - 2.84).abs() < 1e-4);
        let f = Model::preset("fernando2025").unwrap();
        assert!((f.physical().total_mass_kg() - 22.02).abs() < 1e-3);
    }

    #[test]
    fn kin_cores_mass_presets_are_the_twins() {
        use kin_core::stability::MassModel;
        assert_eq!(
            Physical::shahriar2023().mass_model(),
            MassModel::shahriar2023()
        );
        assert_eq!(
            Physical::fernando2025().mass_model(),
            MassModel::fernando2025()
        );
        for name in Physical::PRESETS {
            let p = Physical::preset(name).unwrap();
            assert!((p.mass_model().total_kg() - p.total_mass_kg()).abs() < 1e-4);
        }
    }

    #[test]
    fn bad_fields_are_named() {
        let mut r = Robot::shahriar2023();
        r.leg.femur_m = 0.0;
        let err = Model::new(r, Physical::shahriar2023()).unwrap_err();
        assert!(matches!(err, Error::NonPositive { field: "femur_m" }));
        assert!(err.to_string().contains("`femur_m`"), "{err}");

        let mut p = Physical::shahriar2023();
        p.body_mass_kg = -1.0;
        let err = Model::new(Robot::shahriar2023(), p).unwrap_err();
        assert!(matches!(
            err,
            Error::NonPositive {
                field: "body_mass_kg"
            }
        ));

        let mut p = Physical::shahriar2023();
        p.servo.stall_torque_nm = f32::NAN;
        let err = Model::new(Robot::shahriar2023(), p).unwrap_err();
        assert!(err.to_string().contains("servo.stall_torque_nm"), "{err}");

        let mut r = Robot::shahriar2023();
        r.body_width_m = 0.0;
        let err = Model::new(r, Physical::shahriar2023()).unwrap_err();
        assert!(matches!(
            err,
            Error::NonPositive {
                field: "body_width_m"
            }
        ));
    }

    #[test]
    fn unknown_presets_are_named() {
        let err = Model::preset("spot").unwrap_err();
        assert!(err.to_string().contains("`spot`"), "{err}");
        let err = Physical::shahriar2023().with_servo("sg90").unwrap_err();
        assert!(matches!(err, Error::UnknownServo(_)));
        assert!(err.to_string().contains("`sg90`"), "{err}");
    }
}
