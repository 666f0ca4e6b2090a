//! What the device keeps in storage: the servo calibration and the robot it holds (two banks
//! each, written only by an explicit save).

use super::*;

impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// Loads the calibration from storage (true when a valid one was found).
    pub(super) fn load_calibration(&mut self) -> bool {
        self.store.load(&mut self.storage, &mut self.calibration)
    }

    /// Adopts the robot stored (since protocol 2.4) when the storage holds a valid one that
    /// passes [`quad_protocol::check_robot`]; else the configuration's robot stays.
    // Out of line: the image and the check's solver stay out of `boot`'s frame.
    #[inline(never)]
    pub(super) fn load_robot(&mut self) {
        let mut image = RobotImage([0; RobotDescription::WIRE_LEN]);
        if !self.robot_store.load(&mut self.storage, &mut image) {
            return;
        }
        let Some(robot) = image.robot() else {
            return;
        };
        if let Ok(solver) = quad_protocol::check_robot::<M>(&robot) {
            self.adopt_robot(&robot, solver);
        }
    }

    /// Makes `robot` (checked, with its body solver) the one held: the IK's geometry, the
    /// request ranges, the stance height and rotation order of body poses, the joint-speed
    /// limit, the preset and the hash the hello reports.
    pub(super) fn adopt_robot(&mut self, robot: &RobotDescription, solver: body::Solver<M>) {
        self.config.robot = robot.robot;
        self.config.pose_config.stance_height_m = robot.stance_height_m;
        self.config.pose_config.order = robot.order;
        self.config.joint_speed_limit_rad_s = robot.joint_speed_limit_rad_s;
        self.config.preset = preset_of(robot);
        self.ranges = Ranges::of(&robot.robot);
        self.solver = solver;
        // Within the range `check_robot` admits, which the limiter accepts.
        let _ = self
            .engine
            .set_joint_speed_limit(robot.joint_speed_limit_rad_s);
        self.robot = *robot;
        self.robot_hash = robot.hash();
    }

    /// `SetRobot` (since protocol 2.4): refused while the outputs are on (a geometry change
    /// must never move powered servos: with the outputs off no motion runs either), checked
    /// ([`quad_protocol::check_robot`]) before anything changes. Then the robot is adopted
    /// ([`Device::adopt_robot`]); a default calibration (none stored, none changed since) is
    /// recomputed for the new stance; the new stance is held when it maps within the
    /// calibration (else nothing is held, and enabling is refused until a setpoint maps).
    // Out of line: the check's solver stays out of the dispatcher's frame.
    #[inline(never)]
    pub(super) fn set_robot(&mut self, robot: &RobotDescription) -> Result<(), NackReason> {
        if self.outputs_enabled {
            return Err(NackReason::OutputsEnabled);
        }
        let solver = quad_protocol::check_robot::<M>(robot)?;
        self.adopt_robot(robot, solver);
        if self.calibration_default && !self.calibration_unsaved {
            write_default_calibration(
                &self.solver,
                &self.config.pose_config,
                &mut self.calibration,
            );
            self.refresh_pulse_maps();
        }
        self.held = None;
        self.base_pose = None;
        let _ = self.set_body_pose(&Pose::default());
        Ok(())
    }

    /// `SaveRobot` (since protocol 2.4): the robot held to the storage's inactive bank.
    pub(super) fn save_robot(&mut self) -> Result<(), NackReason> {
        self.robot_store
            .save(&mut self.storage, &RobotImage::of(&self.robot))
            .map_err(|_| NackReason::Storage)
    }

    /// The robot held (what `GetRobot` answers).
    pub fn robot(&self) -> &RobotDescription {
        &self.robot
    }

    pub(super) fn set_calibration(
        &mut self,
        servo: ServoId,
        c: Calibration,
    ) -> Result<(), NackReason> {
        let map = c.pulse_map().map_err(NackReason::BadCalibration)?;
        let i = servo.index();
        // Both checks before anything changes: a refusal leaves the held pulses as they were.
        let held_pulse = match &self.held {
            Some(held) => Some(map.pulse_half_us(held.angles_rad[i]).map_err(|fault| {
                NackReason::ServoRange {
                    leg: servo.leg,
                    joint: servo.joint,
                    fault,
                }
            })?),
            None => None,
        };
        if self.outputs_enabled {
            // The outputs may still be on their way to the held angle.
            map.pulse_half_us(self.out_rad[i])
                .map_err(|fault| NackReason::ServoRange {
                    leg: servo.leg,
                    joint: servo.joint,
                    fault,
                })?;
        }
        if let (Some(held), Some(pulse)) = (&mut self.held, held_pulse) {
            held.pulses_half_us[i] = pulse;
        }
        if self.calibration[i] != c {
            self.calibration[i] = c;
            self.pulse_maps[i] = map;
            self.calibration_unsaved = true;
        }
        if self.outputs_enabled {
            self.write_out();
        }
        Ok(())
    }

    pub(super) fn save_calibration(&mut self) -> Result<(), NackReason> {
        self.store
            .save(&mut self.storage, &self.calibration)
            .map_err(|_| NackReason::Storage)?;
        self.calibration_unsaved = false;
        self.calibration_default = false;
        Ok(())
    }

    /// The pulse maps of the calibration table. Each calibration was validated when it was
    /// loaded or set, and the defaults are valid: no map is left at `PulseMap::NONE`.
    pub(super) fn refresh_pulse_maps(&mut self) {
        for (m, c) in self.pulse_maps.iter_mut().zip(&self.calibration) {
            if let Ok(map) = c.pulse_map() {
                *m = map;
            }
        }
    }
}
