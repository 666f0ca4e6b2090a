//! The servo frame: the link-loss failsafe, the onboard motions and the joint-speed limiter.

use super::*;

impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// Runs the link-loss failsafe and, at each servo frame boundary, the motion engine and the
    /// joint-speed limiter; call it from the main loop (at least every 20 ms).
    pub fn poll(&mut self) {
        self.failsafe_check();
        self.frame_tick();
    }

    pub(super) fn failsafe_check(&mut self) {
        let LinkTimeout { timeout_ms, action } = self.config.link_timeout;
        if timeout_ms == 0 || !self.failsafe_armed {
            return;
        }
        let silent_ms = self.clock.now_ms().wrapping_sub(self.last_valid_ms);
        if silent_ms < u32::from(timeout_ms) {
            return;
        }
        self.failsafe = true;
        self.failsafe_armed = false;
        if action == LinkLossAction::Disable {
            self.stop_outputs();
        } else {
            // Holding a motion mid-stride would freeze it: it ends cleanly instead.
            self.engine.stop();
        }
    }

    /// One servo frame, when a frame boundary has passed: the engine's new target, then one
    /// limiter step of the outputs toward the held target. The boundaries are the outputs' PWM
    /// periods when they count them ([`ServoOutputs::periods_begun`]), else the clock's 20 ms.
    pub(super) fn frame_tick(&mut self) {
        if !self.outputs_enabled {
            return;
        }
        let now = self.clock.now_ms();
        let frames = match self.outputs.periods_begun() {
            // Latched to the PWM periods: one frame per period at most, and none while the last
            // write waits for a period to show it.
            Some(period) => {
                let frames = period.wrapping_sub(self.next_frame);
                if frames == 0 || self.outputs.write_pending() {
                    return;
                }
                self.next_frame = period;
                frames
            }
            None => {
                let late_ms = now.wrapping_sub(self.next_frame);
                if late_ms > i32::MAX as u32 {
                    return; // Before the boundary.
                }
                let frames = 1 + late_ms / FRAME_MS;
                self.next_frame = self.next_frame.wrapping_add(frames * FRAME_MS);
                frames
            }
        };
        self.enabling_frame = false;
        let mut disable = false;
        // The leveling: its correction for this frame, taken by a sway or by the held pose.
        let had_correction = self.balance.correction_rad() != [0.0; 2];
        let correction = self.balance.level(frames as f32 * FRAME_S);
        let mut applied = None;
        if self.engine.is_active() {
            let kind = self.engine.status().kind;
            let levels = correction.filter(|_| self.engine.levels());
            let tick = self
                .engine
                .tick(frames, now, &self.out_rad, &self.solver, levels);
            if let Some(l) = tick.leveled {
                applied = Some((l.intended_rad, l.applied_rad, l.limited));
            }
            if let Some(q) = tick.target {
                if let Err(e) = self.hold_motion_target(q) {
                    self.engine.fail(e, &self.out_rad);
                }
            }
            disable = tick.disable_outputs;
            if !self.engine.is_active() {
                // Ended: at the stance, or at the rest pose after sit and rest.
                self.base_pose = match kind {
                    Some(MotionKind::Sit | MotionKind::Rest) => None,
                    _ => Some(Pose::default()),
                };
            }
        } else if let Some(pose) = self.base_pose {
            match correction {
                Some(c) => applied = self.level_pose(&pose, c),
                // Leveling just ended: the pose without its correction, once.
                None if had_correction => {
                    self.level_pose(&pose, [0.0; 2]);
                }
                None => {}
            }
        }
        self.balance
            .applied(applied, correction.unwrap_or([0.0; 2]));
        if let Some(held) = &self.held {
            if self
                .engine
                .limiter()
                .step(&mut self.out_rad, &held.angles_rad)
            {
                self.write_out();
            }
        }
        if disable {
            self.stop_outputs();
        }
    }

    /// Makes a motion setpoint the held target, after mapping it through the calibration.
    pub(super) fn hold_motion_target(
        &mut self,
        angles_rad: [f32; 12],
    ) -> Result<(), engine::Error> {
        let mut pulses_half_us = [0u16; 12];
        // `ServoId::ALL` is in index order: the position is the index, no bounds checks.
        for (i, s) in ServoId::ALL.into_iter().enumerate() {
            pulses_half_us[i] = self.pulse_maps[i]
                .pulse_half_us(angles_rad[i])
                .map_err(|fault| engine::Error::ServoRange { servo: s, fault })?;
        }
        self.held = Some(Held {
            angles_rad,
            pulses_half_us,
        });
        self.clamped = false;
        self.limited = false;
        Ok(())
    }

    /// Starts a motion of the engine (see [`engine`]): validated and start-checked first, refused
    /// with nothing changed. [`MotionCommand::StandUp`] with the outputs off holds the rest
    /// pose and enables the outputs at it.
    ///
    /// # Errors
    /// [`engine::Error`].
    pub fn start_motion(&mut self, request: &MotionCommand) -> Result<(), engine::Error> {
        self.balance.start_check(self.imu.last.as_ref())?;
        let setup = Setup {
            robot: &self.config.robot,
            solver: &self.solver,
            stance_height_m: self.config.pose_config.stance_height_m,
            order: self.config.pose_config.order,
            pulse_maps: &self.pulse_maps,
            outputs: if self.outputs_enabled {
                Some(&self.out_rad)
            } else {
                None
            },
            now_ms: self.clock.now_ms(),
        };
        let start = self.engine.start(request, &setup)?;
        if !self.outputs_enabled {
            let enabled = self.hold_motion_target(start).and_then(|()| {
                self.set_outputs(true)
                    .map_err(|_| engine::Error::OutputsOff)
            });
            if let Err(e) = enabled {
                self.engine.cancel();
                return Err(e);
            }
        }
        self.balance.clear_fall();
        Ok(())
    }

    /// Stops the running motion cleanly ([`Engine::stop`]).
    pub fn stop_motion(&mut self) {
        self.engine.stop();
    }

    /// Sets the running walk's velocity command (body frame; yaw counter-clockwise positive);
    /// it must be refreshed within the walk's timeout.
    ///
    /// # Errors
    /// [`engine::Error::NotWalking`], or the component beyond the gait's reach.
    pub fn set_velocity(&mut self, velocity: Velocity) -> Result<(), engine::Error> {
        let now = self.clock.now_ms();
        self.engine.set_velocity(velocity, now)
    }

    /// Sets the joint-speed limit of every output, rad/s (finite, > 0).
    ///
    /// # Errors
    /// [`engine::Error::Parameter`] naming `joint_speed_limit_rad_s`.
    pub fn set_joint_speed_limit(&mut self, rad_s: f32) -> Result<(), engine::Error> {
        self.engine.set_joint_speed_limit(rad_s)
    }

    /// The motion engine's status.
    pub fn motion_status(&self) -> engine::Status {
        self.engine.status()
    }

    /// The limiter in effect.
    pub fn limiter(&self) -> &Limiter {
        self.engine.limiter()
    }

    /// The angles on the outputs (`None` while they are stopped).
    pub fn output_angles(&self) -> Option<&[f32; 12]> {
        if self.outputs_enabled {
            Some(&self.out_rad)
        } else {
            None
        }
    }
}
