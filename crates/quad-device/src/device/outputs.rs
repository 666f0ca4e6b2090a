//! Direct setpoints (body pose, feet, joints) solved and mapped through the calibration to the
//! outputs, and the outputs switched on and off.

use super::*;

impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// `SetBodyPose`: the pose at the stance of the pose configuration's height, about the body
    /// centre in its rotation order.
    // Out of line: the body solve's locals stay out of the dispatcher's stack frame.
    #[inline(never)]
    pub(super) fn set_body_pose(&mut self, pose: &Pose) -> Result<(), NackReason> {
        let c = &self.config.pose_config;
        // Solved into this frame's solution and read there (no solution returned through
        // memory, no flattened copy of its angles).
        let mut solution = BodySolution::default();
        self.solver.inverse_at_stance_into(
            pose,
            &BodyConfig::about_centre(c.order),
            c.stance_height_m,
            c.policy,
            &mut solution,
        )?;
        self.apply_solution(&solution)?;
        self.base_pose = Some(*pose);
        Ok(())
    }

    /// `SetFeet`: the feet in the body frame at the zero pose.
    // Out of line: the body solve's locals stay out of the dispatcher's stack frame.
    #[inline(never)]
    pub(super) fn set_feet(&mut self, feet: &[[f32; 3]; 4]) -> Result<(), NackReason> {
        let feet = feet.map(|[x, y, z]| Vec3::new(x, y, z));
        // Through the general solve at the zero pose (the body frame is the world frame):
        // its one out-of-line copy, not a second for the feet in the body frame.
        let pc = &self.config.pose_config;
        let mut solution = BodySolution::default();
        self.solver.inverse_into(
            &Pose::default(),
            &BodyConfig::about_centre(pc.order),
            &feet,
            pc.policy,
            &mut solution,
        )?;
        self.apply_solution(&solution)?;
        self.base_pose = None;
        Ok(())
    }

    /// Applies a body solve's angles, read where the solve left them (no copy).
    pub(super) fn apply_solution(&mut self, solution: &BodySolution) -> Result<(), NackReason> {
        let angles = &solution.angles_rad;
        let clamped = solution.any_clamped();
        // A clamp to the joint limits puts the angle exactly on a bound.
        let limits = &self.config.robot.limits;
        let limited = clamped
            && ServoId::ALL.iter().zip(angles).any(|(s, &a)| {
                let j = s.joint as usize;
                a == limits.min_rad[j] || a == limits.max_rad[j]
            });
        self.apply(angles, clamped, limited)
    }

    /// `SetJoints`, on angles the range check has found finite (`check_request`).
    pub(super) fn set_joints(&mut self, angles: &[f32; 12]) -> Result<(), NackReason> {
        for (s, &a) in ServoId::ALL.iter().zip(angles) {
            if !self.config.robot.limits.admits(s.joint, a) {
                return Err(NackReason::JointLimit {
                    leg: s.leg,
                    joint: s.joint,
                });
            }
        }
        self.apply(angles, false, false)?;
        self.base_pose = None;
        Ok(())
    }

    /// Maps all twelve angles through the calibration; commits and drives only when all map.
    pub(super) fn apply(
        &mut self,
        angles_rad: &[f32; 12],
        clamped: bool,
        limited: bool,
    ) -> Result<(), NackReason> {
        let mut pulses_half_us = [0u16; 12];
        // By reference: `into_iter` would copy the servo table into this frame first.
        for (i, s) in ServoId::ALL.iter().enumerate() {
            let a = angles_rad[i];
            if !a.is_finite() {
                return Err(NackReason::NonFinite);
            }
            pulses_half_us[i] =
                self.pulse_maps[i]
                    .pulse_half_us(a)
                    .map_err(|fault| NackReason::ServoRange {
                        leg: s.leg,
                        joint: s.joint,
                        fault,
                    })?;
        }
        // In place: each array is copied once, into the held target (built on the stack and
        // then moved into place, it was copied twice).
        match &mut self.held {
            Some(held) => {
                held.angles_rad = *angles_rad;
                held.pulses_half_us = pulses_half_us;
            }
            None => {
                self.held = Some(Held {
                    angles_rad: *angles_rad,
                    pulses_half_us,
                })
            }
        }
        self.clamped = clamped;
        self.limited = limited;
        // A direct setpoint takes over from a running motion (and is an explicit request after
        // a fall).
        self.engine.cancel();
        self.balance.clear_fall();
        if self.outputs_enabled && self.in_enabling_frame() {
            self.out_rad = *angles_rad;
            self.write_out();
        }
        Ok(())
    }

    /// True while no frame boundary has passed since the outputs were enabled: the enabling
    /// frame, whose target is written at once. Ended here as well as by the frame that follows
    /// it: that frame may not run before the next target comes (it waits while a write is
    /// pending, and a host that sends a target early in every period keeps one pending at each
    /// poll), and every target would then be written at once.
    pub(super) fn in_enabling_frame(&mut self) -> bool {
        if self.enabling_frame {
            let boundary_passed = match self.outputs.periods_begun() {
                Some(period) => period != self.next_frame,
                None => self.clock.now_ms().wrapping_sub(self.next_frame) <= i32::MAX as u32,
            };
            if boundary_passed {
                self.enabling_frame = false;
            }
        }
        self.enabling_frame
    }

    /// Writes the output angles through the calibration; stops the outputs instead if one maps
    /// outside its travel (unreachable by construction: the outputs lie between admitted
    /// targets).
    pub(super) fn write_out(&mut self) -> bool {
        let mut pulses = [0u16; 12];
        for (p, (c, &a)) in pulses
            .iter_mut()
            .zip(self.pulse_maps.iter().zip(&self.out_rad))
        {
            match c.pulse_half_us(a) {
                Ok(v) => *p = v,
                Err(_) => {
                    self.stop_outputs();
                    return false;
                }
            }
        }
        self.outputs.set_pulses(&pulses);
        true
    }

    pub(super) fn stop_outputs(&mut self) {
        self.outputs.set_enabled(false);
        self.outputs_enabled = false;
        self.engine.cancel();
    }

    pub(super) fn set_outputs(&mut self, enabled: bool) -> Result<(), NackReason> {
        if !enabled {
            self.stop_outputs();
            return Ok(());
        }
        if !self.outputs_enabled {
            // The enabling frame: the held target is written as it is (module docs).
            let Some(held) = &self.held else {
                self.stop_outputs();
                return Err(NackReason::InvalidArgument);
            };
            self.out_rad = held.angles_rad;
            self.enabling_frame = true;
            self.next_frame = match self.outputs.periods_begun() {
                Some(period) => period,
                None => self.clock.now_ms().wrapping_add(FRAME_MS),
            };
        }
        if !self.write_out() {
            return Err(NackReason::InvalidArgument);
        }
        if !self.outputs_enabled {
            self.outputs.set_enabled(true);
            self.outputs_enabled = true;
        }
        self.balance.clear_fall();
        Ok(())
    }

    pub(super) fn set_pose_config(&mut self, p: PoseConfig) -> Result<(), NackReason> {
        validate_pose_config(&p).map_err(|_| NackReason::InvalidArgument)?;
        self.config.pose_config = p;
        Ok(())
    }
}
