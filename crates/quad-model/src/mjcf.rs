//! MuJoCo MJCF: the robot as a free-floating body over a floor, its legs in the README's chain,
//! its servos as actuators (see [`crate::servo`]), an IMU site with its sensors.
//!
//! The XML is written with `format!`: the document's structure is fixed, every name in it is
//! generated here (leg and joint names, never user text), so there is nothing to escape, and
//! MuJoCo itself is the schema check (the twin's tests load every preset's file in MuJoCo).
//!
//! Names the twin relies on: body `body` (free joint `root`, site `imu`), joints and actuators
//! `{leg}_{joint}` (`FL_abduction`, `FL_hip`, `FL_knee`, …, canonical order), foot geoms and
//! sites `{leg}_foot`, the floor `floor` (a plane geom on a mocap body of the same name, so
//! that the twin can incline it or tilt it during a run), sensors `accel`, `gyro` (the IMU)
//! and `body_quat` (the true attitude), numeric custom fields `servo_*` (the servo model) and
//! `foot_radius_m`, text field `servo_name`.
//!
//! The IMU: site `imu` where the controller board carries its MPU-6050, on the body's top face
//! above the body frame's origin ([`imu_site_m`]), its axes the body frame's (x forward, y
//! left, z up, as kin-core's). MuJoCo's `accelerometer` there reads the specific force (level
//! and still: `(0, 0, +g)`), its `gyro` the body's angular rate about those axes; both are
//! what the driver hands the controller (`quad_device::ImuSample`) once the chip's mounting is
//! applied.

use crate::physical::{Error, Model};
use core::fmt::Write as _;
use kin_core::{Joint, LegId};

/// The physics time step written into the model, s (1 kHz: twenty steps per 20 ms servo
/// frame).
pub const PHYSICS_TIMESTEP_S: f64 = 0.001;

/// The name of a joint (and of its actuator) in the MJCF and URDF: `FL_abduction`, `FR_knee`.
pub fn joint_name(leg: LegId, joint: Joint) -> String {
    format!("{}_{}", leg.name(), joint.name())
}

/// A number as MJCF/URDF text: the shortest decimal that reads back as the same f64 (an f32
/// input therefore reads back bit for bit).
pub(crate) fn num(v: f64) -> String {
    if v == 0.0 {
        // Also turns −0 into 0.
        "0".to_owned()
    } else {
        format!("{v}")
    }
}

/// Where the IMU site sits in the body frame, m: the controller board on the body's top face,
/// above the body frame's origin (the board's MPU-6050; an offset from the centre of rotation
/// adds the rotation's own accelerations to the accelerometer's reading, as on the robot).
pub fn imu_site_m(model: &Model) -> [f64; 3] {
    [0.0, 0.0, 0.5 * f(model.physical().body_height_m)]
}

fn vec3(v: [f64; 3]) -> String {
    format!("{} {} {}", num(v[0]), num(v[1]), num(v[2]))
}

fn f(v: f32) -> f64 {
    f64::from(v)
}

/// The MJCF document of `model`.
pub fn to_string(model: &Model) -> String {
    let robot = model.robot();
    let p = model.physical();
    let g = &robot.leg;
    let servo = &p.servo;
    let leg_len = f(g.d_ax_m) + f(g.femur_m) + f(g.tibia_m);
    let body = model.body_inertial();
    let mut x = String::new();
    // `write!` into a String cannot fail.
    let _ = writeln!(
        x,
        "<mujoco model=\"{name}\">\n\
         \x20 <compiler angle=\"radian\" autolimits=\"true\"/>\n\
         \x20 <option timestep=\"{dt}\" integrator=\"implicitfast\" cone=\"elliptic\"/>\n\
         \x20 <size memory=\"8M\"/>\n\
         \x20 <visual><global offwidth=\"1280\" offheight=\"960\"/><quality shadowsize=\"2048\"/></visual>\n\
         \x20 <custom>\n\
         \x20   <text name=\"servo_name\" data=\"{servo_name}\"/>\n\
         \x20   <numeric name=\"servo_stall_torque_nm\" data=\"{stall}\"/>\n\
         \x20   <numeric name=\"servo_no_load_speed_rad_s\" data=\"{speed}\"/>\n\
         \x20   <numeric name=\"servo_full_duty_error_rad\" data=\"{efull}\"/>\n\
         \x20   <numeric name=\"servo_deadband_rad\" data=\"{deadband}\"/>\n\
         \x20   <numeric name=\"servo_derivative_s\" data=\"{td}\"/>\n\
         \x20   <numeric name=\"foot_radius_m\" data=\"{foot_r}\"/>\n\
         \x20   <numeric name=\"total_mass_kg\" data=\"{mass}\"/>\n\
         \x20 </custom>\n\
         \x20 <asset>\n\
         \x20   <texture name=\"grid\" type=\"2d\" builtin=\"checker\" rgb1=\".82 .84 .86\" rgb2=\".62 .66 .70\" width=\"512\" height=\"512\"/>\n\
         \x20   <material name=\"grid\" texture=\"grid\" texrepeat=\"{rep} {rep}\" texuniform=\"true\"/>\n\
         \x20   <texture name=\"sky\" type=\"skybox\" builtin=\"gradient\" rgb1=\".92 .94 .97\" rgb2=\".55 .65 .78\" width=\"256\" height=\"256\"/>\n\
         \x20 </asset>\n\
         \x20 <default>\n\
         \x20   <joint armature=\"{armature}\" frictionloss=\"{friction}\" damping=\"0\"/>\n\
         \x20   <geom contype=\"0\" conaffinity=\"0\" density=\"0\"/>\n\
         \x20   <default class=\"contact\"><geom contype=\"2\" conaffinity=\"1\" condim=\"3\" friction=\"{mu} 0.005 0.0001\"/></default>\n\
         \x20 </default>\n\
         \x20 <worldbody>\n\
         \x20   <light name=\"sun\" directional=\"true\" pos=\"0 0 5\" dir=\"-0.3 0.2 -1\" castshadow=\"true\"/>\n\
         \x20   <body name=\"floor\" mocap=\"true\">\n\
         \x20     <geom name=\"floor\" type=\"plane\" size=\"0 0 0.05\" material=\"grid\" contype=\"1\" conaffinity=\"1\" condim=\"3\" friction=\"{mu} 0.005 0.0001\"/>\n\
         \x20   </body>\n\
         \x20   <body name=\"body\" pos=\"0 0 {z0}\">\n\
         \x20     <freejoint name=\"root\"/>\n\
         \x20     <inertial pos=\"{bcom}\" mass=\"{bm}\" diaginertia=\"{bdiag}\"/>\n\
         \x20     <geom name=\"body\" class=\"contact\" type=\"box\" size=\"{bsize}\" rgba=\".25 .35 .55 1\"/>\n\
         \x20     <site name=\"imu\" pos=\"{imu}\" size=\"0.01\"/>",
        name = robot_name(model),
        dt = num(PHYSICS_TIMESTEP_S),
        servo_name = servo.name,
        stall = num(f(servo.stall_torque_nm)),
        speed = num(f(servo.no_load_speed_rad_s)),
        efull = num(f(servo.full_duty_error_rad)),
        deadband = num(f(servo.deadband_rad)),
        td = num(f(servo.derivative_s)),
        foot_r = num(f(p.foot_radius_m)),
        mass = num(f(p.total_mass_kg())),
        rep = num(leg_len.recip().max(0.5)),
        armature = num(f(servo.armature_kg_m2)),
        friction = num(f(servo.friction_loss_nm)),
        mu = num(f(p.foot_friction)),
        z0 = num(leg_len + f(p.foot_radius_m)),
        bcom = vec3(body.com_m),
        bm = num(body.mass_kg),
        bdiag = vec3(body.diag_kg_m2),
        imu = vec3(imu_site_m(model)),
        bsize = vec3([
            0.5 * f(robot.body_length_m),
            0.5 * f(robot.body_width_m),
            0.5 * f(p.body_height_m),
        ]),
    );
    for leg in LegId::ALL {
        write_leg(&mut x, model, leg);
    }
    x.push_str("    </body>\n  </worldbody>\n  <actuator>\n");
    let gain = f(servo.stall_torque_nm);
    let back_emf = f(servo.back_emf_nm_s_per_rad());
    for leg in LegId::ALL {
        for joint in Joint::ALL {
            let n = joint_name(leg, joint);
            let _ = writeln!(
                x,
                "    <general name=\"{n}\" joint=\"{n}\" ctrlrange=\"-1 1\" gaintype=\"fixed\" \
                 gainprm=\"{}\" biastype=\"affine\" biasprm=\"0 0 {}\"/>",
                num(gain),
                num(-back_emf)
            );
        }
    }
    x.push_str(
        "  </actuator>\n  <sensor>\n\
         \x20   <framequat name=\"body_quat\" objtype=\"site\" objname=\"imu\"/>\n\
         \x20   <gyro name=\"gyro\" site=\"imu\"/>\n\
         \x20   <accelerometer name=\"accel\" site=\"imu\"/>\n\
         \x20 </sensor>\n</mujoco>\n",
    );
    x
}

/// The leg's bodies, nested in the body: abduction about x at the hip mount, hip about y at
/// `(0, s·d_lat, −d_ax)`, knee about y at `(0, 0, −femur)`, the foot at `(0, 0, −tibia)`.
fn write_leg(x: &mut String, model: &Model, leg: LegId) {
    let robot = model.robot();
    let p = model.physical();
    let g = &robot.leg;
    let s = leg.side();
    let hip = robot.hip_in_body(leg);
    let inertials = model.leg_inertials(s);
    let range = |j: Joint| {
        format!(
            "{} {}",
            num(f(robot.limits.min_rad[j as usize])),
            num(f(robot.limits.max_rad[j as usize]))
        )
    };
    let inertial = |i: &crate::inertia::Inertial| {
        format!(
            "<inertial pos=\"{}\" mass=\"{}\" diaginertia=\"{}\"/>",
            vec3(i.com_m),
            num(i.mass_kg),
            vec3(i.diag_kg_m2)
        )
    };
    let l = leg.name();
    let r = f(p.link_radius_m);
    let (femur, tibia) = (f(g.femur_m), f(g.tibia_m));
    let hip_joint = [0.0, f(s * g.d_lat_m), -f(g.d_ax_m)];
    let _ = write!(
        x,
        "      <body name=\"{l}_abduction\" pos=\"{mount}\">\n\
         \x20       <joint name=\"{l}_abduction\" axis=\"1 0 0\" range=\"{ra}\"/>\n\
         \x20       {ia}\n\
         \x20       <geom type=\"sphere\" size=\"{hr}\" pos=\"{hj}\" rgba=\".2 .2 .2 1\"/>\n\
         \x20       <geom type=\"capsule\" fromto=\"0 0 0 {hj}\" size=\"{lr}\" rgba=\".2 .2 .2 1\"/>\n\
         \x20       <body name=\"{l}_femur\" pos=\"{hj}\">\n\
         \x20         <joint name=\"{l}_hip\" axis=\"0 1 0\" range=\"{rh}\"/>\n\
         \x20         {ifem}\n\
         \x20         <geom type=\"capsule\" fromto=\"0 0 0 0 0 {fz}\" size=\"{lr}\" rgba=\".85 .55 .2 1\"/>\n\
         \x20         <body name=\"{l}_tibia\" pos=\"0 0 {fz}\">\n\
         \x20           <joint name=\"{l}_knee\" axis=\"0 1 0\" range=\"{rk}\"/>\n\
         \x20           {itib}\n\
         \x20           <geom type=\"capsule\" fromto=\"0 0 0 0 0 {tz}\" size=\"{tr}\" rgba=\".9 .7 .3 1\"/>\n\
         \x20           <geom name=\"{l}_foot\" class=\"contact\" type=\"sphere\" pos=\"0 0 {tz}\" size=\"{fr}\" rgba=\".1 .1 .1 1\"/>\n\
         \x20           <site name=\"{l}_foot\" pos=\"0 0 {tz}\" size=\"{fr}\"/>\n\
         \x20         </body>\n\
         \x20       </body>\n\
         \x20     </body>\n",
        mount = vec3([f(hip.x), f(hip.y), f(hip.z)]),
        ra = range(Joint::Abduction),
        rh = range(Joint::Hip),
        rk = range(Joint::Knee),
        ia = inertial(&inertials.abduction),
        ifem = inertial(&inertials.femur),
        itib = inertial(&inertials.tibia),
        hr = num(1.6 * r),
        hj = vec3(hip_joint),
        lr = num(r),
        tr = num(0.8 * r),
        fz = num(-femur),
        tz = num(-tibia),
        fr = num(f(p.foot_radius_m)),
    );
}

/// The model's name: the preset's name when the geometry is a preset's, else `robot`.
pub fn robot_name(model: &Model) -> &'static str {
    kin_core::Robot::PRESETS
        .into_iter()
        .find(|n| kin_core::Robot::preset(n).as_ref() == Some(model.robot()))
        .unwrap_or("robot")
}

/// Writes the MJCF of `model` to `path`: to a temporary file in the same directory, renamed
/// over `path` once complete, so a failure never leaves a partial file.
///
/// # Errors
/// [`Error::Write`].
pub fn write(model: &Model, path: &std::path::Path) -> Result<(), Error> {
    crate::write_atomic(path, to_string(model).as_bytes())
}
