//! URDF out (for RViz, PyBullet, Gazebo users) and in: a URDF whose legs have the README's
//! chain is read back as a [`kin_core::Robot`]; any other shape is refused naming what
//! differs. Both directions go through the `urdf-rs` crate's types.
//!
//! The chain, per leg (`L` = `FL`, `FR`, `RL`, `RR`; `s` = +1 left, −1 right):
//!
//! | joint | type | parent → child | origin (rpy 0) | axis |
//! |---|---|---|---|---|
//! | `L_abduction` | revolute | `body` → `L_abduction_link` | `(±length/2, ±width/2, 0)` | x |
//! | `L_hip` | revolute | `L_abduction_link` → `L_femur` | `(0, s·d_lat, −d_ax)` | y |
//! | `L_knee` | revolute | `L_femur` → `L_tibia` | `(0, 0, −femur)` | y |
//! | `L_foot` | fixed | `L_tibia` → `L_foot` | `(0, 0, −tibia)` | — |
//!
//! Reading identifies the legs by the quadrant of their mounts (front/rear by the sign of x,
//! left/right by the sign of y), not by name. The knee bend is not a URDF notion: it is read as
//! [`KneeBend::Forward`] when the knee's lower limit is ≥ 0, else [`KneeBend::Backward`] (the
//! limits of this project are expressed for the robot's knee bend).

use crate::mjcf::joint_name;
use crate::physical::{Error, Model};
use core::fmt;
use kin_core::robot::RobotError;
use kin_core::{Joint, JointLimits, KneeBend, LegGeometry, LegId, Robot};
use urdf_rs as u;

fn f(v: f32) -> f64 {
    f64::from(v)
}

fn pose(xyz: [f64; 3]) -> u::Pose {
    u::Pose {
        xyz: u::Vec3(xyz),
        rpy: u::Vec3([0.0; 3]),
    }
}

fn inertial(i: &crate::inertia::Inertial) -> u::Inertial {
    u::Inertial {
        origin: pose(i.com_m),
        mass: u::Mass { value: i.mass_kg },
        inertia: u::Inertia {
            ixx: i.diag_kg_m2[0],
            ixy: 0.0,
            ixz: 0.0,
            iyy: i.diag_kg_m2[1],
            iyz: 0.0,
            izz: i.diag_kg_m2[2],
        },
    }
}

fn shape(name: &str, origin: [f64; 3], geometry: u::Geometry, rgba: [f64; 4]) -> u::Visual {
    u::Visual {
        name: Some(name.to_owned()),
        origin: pose(origin),
        geometry,
        material: Some(u::Material {
            name: format!("{name}_colour"),
            color: Some(u::Color {
                rgba: u::Vec4(rgba),
            }),
            texture: None,
        }),
    }
}

fn link(name: &str, inertial: u::Inertial, visual: Vec<u::Visual>, collide: bool) -> u::Link {
    let collision = if collide {
        visual
            .iter()
            .map(|v| u::Collision {
                name: v.name.clone(),
                origin: v.origin.clone(),
                geometry: v.geometry.clone(),
            })
            .collect()
    } else {
        Vec::new()
    };
    u::Link {
        name: name.to_owned(),
        inertial,
        visual,
        collision,
    }
}

/// The URDF of `model` as urdf-rs's description.
pub fn to_urdf(model: &Model) -> u::Robot {
    let robot = model.robot();
    let p = model.physical();
    let g = &robot.leg;
    let servo = &p.servo;
    let mut links = vec![link(
        "body",
        inertial(&model.body_inertial()),
        vec![shape(
            "body",
            [0.0; 3],
            u::Geometry::Box {
                size: u::Vec3([
                    f(robot.body_length_m),
                    f(robot.body_width_m),
                    f(p.body_height_m),
                ]),
            },
            [0.25, 0.35, 0.55, 1.0],
        )],
        true,
    )];
    let mut joints = Vec::new();
    let r = f(p.link_radius_m);
    for leg in LegId::ALL {
        let l = leg.name();
        let s = leg.side();
        let hip = robot.hip_in_body(leg);
        let parts = model.leg_inertials(s);
        let limit = |j: Joint| u::JointLimit {
            lower: f(robot.limits.min_rad[j as usize]),
            upper: f(robot.limits.max_rad[j as usize]),
            effort: f(servo.stall_torque_nm),
            velocity: f(servo.no_load_speed_rad_s),
        };
        let revolute =
            |j: Joint, parent: &str, child: &str, xyz: [f64; 3], axis: [f64; 3]| u::Joint {
                name: joint_name(leg, j),
                joint_type: u::JointType::Revolute,
                origin: pose(xyz),
                parent: u::LinkName {
                    link: parent.to_owned(),
                },
                child: u::LinkName {
                    link: child.to_owned(),
                },
                axis: u::Axis { xyz: u::Vec3(axis) },
                limit: limit(j),
                calibration: None,
                dynamics: Some(u::Dynamics {
                    damping: 0.0,
                    friction: f(servo.friction_loss_nm),
                }),
                mimic: None,
                safety_controller: None,
            };
        let (abd, femur, tibia, foot) = (
            format!("{l}_abduction_link"),
            format!("{l}_femur"),
            format!("{l}_tibia"),
            format!("{l}_foot"),
        );
        let hip_joint = [0.0, f(s * g.d_lat_m), -f(g.d_ax_m)];
        let (lf, lt) = (f(g.femur_m), f(g.tibia_m));
        links.push(link(
            &abd,
            inertial(&parts.abduction),
            vec![shape(
                &abd,
                hip_joint,
                u::Geometry::Sphere { radius: 1.6 * r },
                [0.2, 0.2, 0.2, 1.0],
            )],
            false,
        ));
        links.push(link(
            &femur,
            inertial(&parts.femur),
            vec![shape(
                &femur,
                [0.0, 0.0, -0.5 * lf],
                u::Geometry::Cylinder {
                    radius: r,
                    length: lf,
                },
                [0.85, 0.55, 0.2, 1.0],
            )],
            false,
        ));
        links.push(link(
            &tibia,
            inertial(&parts.tibia),
            vec![shape(
                &tibia,
                [0.0, 0.0, -0.5 * lt],
                u::Geometry::Cylinder {
                    radius: 0.8 * r,
                    length: lt,
                },
                [0.9, 0.7, 0.3, 1.0],
            )],
            false,
        ));
        links.push(link(
            &foot,
            u::Inertial::default(),
            vec![shape(
                &foot,
                [0.0; 3],
                u::Geometry::Sphere {
                    radius: f(p.foot_radius_m),
                },
                [0.1, 0.1, 0.1, 1.0],
            )],
            true,
        ));
        joints.push(revolute(
            Joint::Abduction,
            "body",
            &abd,
            [f(hip.x), f(hip.y), f(hip.z)],
            [1.0, 0.0, 0.0],
        ));
        joints.push(revolute(
            Joint::Hip,
            &abd,
            &femur,
            hip_joint,
            [0.0, 1.0, 0.0],
        ));
        joints.push(revolute(
            Joint::Knee,
            &femur,
            &tibia,
            [0.0, 0.0, -lf],
            [0.0, 1.0, 0.0],
        ));
        joints.push(u::Joint {
            name: format!("{l}_foot"),
            joint_type: u::JointType::Fixed,
            origin: pose([0.0, 0.0, -lt]),
            parent: u::LinkName { link: tibia },
            child: u::LinkName { link: foot },
            axis: u::Axis::default(),
            limit: u::JointLimit::default(),
            calibration: None,
            dynamics: None,
            mimic: None,
            safety_controller: None,
        });
    }
    u::Robot {
        name: crate::mjcf::robot_name(model).to_owned(),
        links,
        joints,
        materials: Vec::new(),
    }
}

/// The URDF document of `model`.
///
/// # Errors
/// [`Error::Urdf`] when urdf-rs's serializer fails.
pub fn to_string(model: &Model) -> Result<String, Error> {
    let text = u::write_to_string(&to_urdf(model)).map_err(Error::Urdf)?;
    Ok(format!("<?xml version=\"1.0\"?>\n{text}\n"))
}

/// Writes the URDF of `model` to `path` (atomically, as [`crate::mjcf::write`]).
///
/// # Errors
/// [`Error::Urdf`], [`Error::Write`].
pub fn write(model: &Model, path: &std::path::Path) -> Result<(), Error> {
    crate::write_atomic(path, to_string(model)?.as_bytes())
}

/// Why a URDF is not a robot of this project's shape.
#[derive(Debug)]
#[non_exhaustive]
pub enum ReadError {
    /// Not readable as URDF.
    Parse(u::UrdfError),
    /// The URDF must have exactly one root link (the body); the number found.
    Roots {
        /// Root links found.
        found: usize,
    },
    /// The body must carry exactly four legs (revolute joints); the number found.
    LegCount {
        /// Movable joints on the body.
        found: usize,
    },
    /// Two leg mounts lie in the same quadrant, or a mount lies on the x or y axis.
    Quadrant {
        /// The abduction joint whose mount is not in a quadrant of its own.
        joint: String,
    },
    /// A joint of the chain has the wrong type.
    JointType {
        /// The joint.
        joint: String,
        /// What the chain needs there.
        expected: &'static str,
    },
    /// A joint's axis differs from the chain's.
    Axis {
        /// The joint.
        joint: String,
        /// The axis the chain needs.
        expected: [f64; 3],
        /// The axis found.
        found: [f64; 3],
    },
    /// A joint's origin is rotated (non-zero rpy) or offset where the chain has no offset.
    Origin {
        /// The joint.
        joint: String,
        /// What the chain needs there.
        expected: &'static str,
        /// The origin found.
        found: [f64; 3],
    },
    /// A link of the chain has other than one child joint.
    Branch {
        /// The link.
        link: String,
        /// The number of child joints.
        found: usize,
    },
    /// The legs do not share one geometry or one set of limits.
    LegsDiffer {
        /// What differs (`d_lat_m`, `femur_m`, `body_length_m`, `limits`, …).
        what: &'static str,
        /// The first leg that differs from FL.
        leg: LegId,
    },
    /// The values read are not a valid robot.
    Invalid(RobotError),
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const CHAIN: &str = "body → abduction (x) → hip (y) → knee (y) → fixed foot";
        match self {
            ReadError::Parse(e) => write!(f, "not a readable URDF: {e}"),
            ReadError::Roots { found } => {
                write!(f, "expected one root link (the body), found {found}")
            }
            ReadError::LegCount { found } => write!(
                f,
                "expected four legs (revolute joints on the body), found {found}; the chain is {CHAIN}"
            ),
            ReadError::Quadrant { joint } => write!(
                f,
                "joint `{joint}`: each leg must be mounted in its own quadrant (front/rear by x, left/right by y)"
            ),
            ReadError::JointType { joint, expected } => {
                write!(f, "joint `{joint}` must be {expected}; the chain is {CHAIN}")
            }
            ReadError::Axis {
                joint,
                expected,
                found,
            } => write!(
                f,
                "joint `{joint}` turns about {found:?}, the chain needs {expected:?}; the chain is {CHAIN}"
            ),
            ReadError::Origin {
                joint,
                expected,
                found,
            } => write!(
                f,
                "joint `{joint}` has origin {found:?}, the chain needs {expected} with rpy 0"
            ),
            ReadError::Branch { link, found } => write!(
                f,
                "link `{link}` has {found} child joints, the chain needs exactly one; the chain is {CHAIN}"
            ),
            ReadError::LegsDiffer { what, leg } => {
                write!(f, "leg {leg} differs from FL in `{what}`; all four legs must be alike")
            }
            ReadError::Invalid(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ReadError::Parse(e) => Some(e),
            ReadError::Invalid(e) => Some(e),
            _ => None,
        }
    }
}

/// Components smaller than this are taken as zero when checking axes and origins (URDF files
/// written by other tools round their numbers), m or unit-vector components.
const TOLERANCE: f64 = 1e-9;

/// What one leg's chain gave.
#[derive(Debug, Clone, Copy)]
struct LegRead {
    mount: [f64; 3],
    d_lat: f64,
    d_ax: f64,
    femur: f64,
    tibia: f64,
    limits: [[f64; 2]; 3],
}

/// Reads a URDF document as a robot description.
///
/// # Errors
/// [`ReadError`] naming what differs from the chain.
pub fn from_str(text: &str) -> Result<Robot, ReadError> {
    let urdf = u::read_from_string(text).map_err(ReadError::Parse)?;
    from_urdf(&urdf)
}

/// Reads urdf-rs's description as a robot description.
///
/// # Errors
/// [`ReadError`] naming what differs from the chain.
pub fn from_urdf(urdf: &u::Robot) -> Result<Robot, ReadError> {
    let roots: Vec<&u::Link> = urdf
        .links
        .iter()
        .filter(|l| !urdf.joints.iter().any(|j| j.child.link == l.name))
        .collect();
    let [root] = roots.as_slice() else {
        return Err(ReadError::Roots { found: roots.len() });
    };
    let children = |link: &str| -> Vec<&u::Joint> {
        urdf.joints
            .iter()
            .filter(|j| j.parent.link == link)
            .collect()
    };
    let legs: Vec<&u::Joint> = children(&root.name)
        .into_iter()
        .filter(|j| j.joint_type != u::JointType::Fixed)
        .collect();
    if legs.len() != 4 {
        return Err(ReadError::LegCount { found: legs.len() });
    }
    let mut read: [Option<LegRead>; 4] = [None; 4];
    for abduction in legs {
        let [x, y, _] = abduction.origin.xyz.0;
        let leg = match (x > TOLERANCE, x < -TOLERANCE, y > TOLERANCE, y < -TOLERANCE) {
            (true, _, true, _) => Some(LegId::FL),
            (true, _, _, true) => Some(LegId::FR),
            (_, true, true, _) => Some(LegId::RL),
            (_, true, _, true) => Some(LegId::RR),
            _ => None,
        };
        let quadrant = || ReadError::Quadrant {
            joint: abduction.name.clone(),
        };
        let leg = leg.ok_or_else(quadrant)?;
        if read[leg.index()].is_some() {
            return Err(quadrant());
        }
        read[leg.index()] = Some(read_leg(abduction, leg, &children)?);
    }
    let legs = read.map(|r| r.expect("four legs in four distinct quadrants"));
    assemble(&legs)
}

fn revolute(j: &u::Joint, axis: [f64; 3]) -> Result<[[f64; 2]; 1], ReadError> {
    let limits = match j.joint_type {
        u::JointType::Revolute => [j.limit.lower, j.limit.upper],
        u::JointType::Continuous => [-core::f64::consts::PI, core::f64::consts::PI],
        _ => {
            return Err(ReadError::JointType {
                joint: j.name.clone(),
                expected: "revolute (or continuous)",
            })
        }
    };
    let found = j.axis.xyz.0;
    if (0..3).any(|i| (found[i] - axis[i]).abs() > TOLERANCE) {
        return Err(ReadError::Axis {
            joint: j.name.clone(),
            expected: axis,
            found,
        });
    }
    check_unrotated(j)?;
    Ok([limits])
}

fn check_unrotated(j: &u::Joint) -> Result<(), ReadError> {
    if j.origin.rpy.0.iter().any(|a| a.abs() > TOLERANCE) {
        return Err(ReadError::Origin {
            joint: j.name.clone(),
            expected: "no rotation",
            found: j.origin.xyz.0,
        });
    }
    Ok(())
}

fn only_child<'a>(
    link: &str,
    children: &impl Fn(&str) -> Vec<&'a u::Joint>,
) -> Result<&'a u::Joint, ReadError> {
    let c = children(link);
    match c.as_slice() {
        [one] => Ok(one),
        _ => Err(ReadError::Branch {
            link: link.to_owned(),
            found: c.len(),
        }),
    }
}

fn read_leg<'a>(
    abduction: &'a u::Joint,
    leg: LegId,
    children: &impl Fn(&str) -> Vec<&'a u::Joint>,
) -> Result<LegRead, ReadError> {
    let [la] = revolute(abduction, [1.0, 0.0, 0.0])?;
    if abduction.origin.xyz.0[2].abs() > TOLERANCE {
        return Err(ReadError::Origin {
            joint: abduction.name.clone(),
            expected: "(±length/2, ±width/2, 0)",
            found: abduction.origin.xyz.0,
        });
    }
    let hip = only_child(&abduction.child.link, children)?;
    let [lh] = revolute(hip, [0.0, 1.0, 0.0])?;
    let [hx, hy, hz] = hip.origin.xyz.0;
    let side = f64::from(leg.side());
    if hx.abs() > TOLERANCE || hy * side < -TOLERANCE || hz > TOLERANCE {
        return Err(ReadError::Origin {
            joint: hip.name.clone(),
            expected: "(0, s·d_lat, −d_ax) with d_lat, d_ax ≥ 0 (s = +1 left, −1 right)",
            found: hip.origin.xyz.0,
        });
    }
    let knee = only_child(&hip.child.link, children)?;
    let [lk] = revolute(knee, [0.0, 1.0, 0.0])?;
    let femur = along_minus_z(knee, "(0, 0, −femur) with femur > 0")?;
    let foot = only_child(&knee.child.link, children)?;
    if foot.joint_type != u::JointType::Fixed {
        return Err(ReadError::JointType {
            joint: foot.name.clone(),
            expected: "fixed (the foot)",
        });
    }
    check_unrotated(foot)?;
    let tibia = along_minus_z(foot, "(0, 0, −tibia) with tibia > 0")?;
    Ok(LegRead {
        mount: abduction.origin.xyz.0,
        d_lat: hy * side,
        d_ax: -hz,
        femur,
        tibia,
        limits: [la, lh, lk],
    })
}

fn along_minus_z(j: &u::Joint, expected: &'static str) -> Result<f64, ReadError> {
    let [x, y, z] = j.origin.xyz.0;
    if x.abs() > TOLERANCE || y.abs() > TOLERANCE || !(z < 0.0) {
        return Err(ReadError::Origin {
            joint: j.name.clone(),
            expected,
            found: j.origin.xyz.0,
        });
    }
    Ok(-z)
}

fn assemble(legs: &[LegRead; 4]) -> Result<Robot, ReadError> {
    let first = &legs[LegId::FL.index()];
    let same = |a: f64, b: f64| (a - b).abs() <= TOLERANCE;
    for leg in LegId::ALL {
        let r = &legs[leg.index()];
        let checks: [(&'static str, bool); 7] = [
            ("d_lat_m", same(r.d_lat, first.d_lat)),
            ("d_ax_m", same(r.d_ax, first.d_ax)),
            ("femur_m", same(r.femur, first.femur)),
            ("tibia_m", same(r.tibia, first.tibia)),
            (
                "body_length_m",
                same(r.mount[0].abs(), first.mount[0].abs()),
            ),
            ("body_width_m", same(r.mount[1].abs(), first.mount[1].abs())),
            (
                "limits",
                (0..3).all(|j| {
                    same(r.limits[j][0], first.limits[j][0])
                        && same(r.limits[j][1], first.limits[j][1])
                }),
            ),
        ];
        if let Some((what, _)) = checks.iter().find(|(_, ok)| !ok) {
            return Err(ReadError::LegsDiffer { what, leg });
        }
    }
    // The f64 values of a file this crate wrote are f32 values widened: narrowing is exact.
    let limits = JointLimits {
        min_rad: core::array::from_fn(|j| first.limits[j][0] as f32),
        max_rad: core::array::from_fn(|j| first.limits[j][1] as f32),
    };
    let robot = Robot {
        leg: LegGeometry {
            d_lat_m: first.d_lat as f32,
            d_ax_m: first.d_ax as f32,
            femur_m: first.femur as f32,
            tibia_m: first.tibia as f32,
        },
        body_length_m: (2.0 * first.mount[0].abs()) as f32,
        body_width_m: (2.0 * first.mount[1].abs()) as f32,
        knee_bend: if limits.min_rad[Joint::Knee as usize] >= 0.0 {
            KneeBend::Forward
        } else {
            KneeBend::Backward
        },
        limits,
    };
    robot.validate().map_err(ReadError::Invalid)?;
    Ok(robot)
}

/// Reads a URDF file as a robot description.
///
/// # Errors
/// [`ReadError`].
pub fn read_file(path: &std::path::Path) -> Result<Robot, ReadError> {
    let urdf = u::read_file(path).map_err(ReadError::Parse)?;
    from_urdf(&urdf)
}
