//! The inertial sensor's readings, the balance functions and the safe state.

use super::*;

impl<O, C, S, M> Device<O, C, S, M>
where
    O: ServoOutputs,
    C: Clock,
    S: Storage,
    M: Math,
{
    /// Takes one reading of the inertial sensor (or the fault that kept the driver from reading
    /// one), pushed by the target's driver at its rate (the device clock times it); see
    /// [`crate::imu`] and [`crate::balance`]. A fall detected here stops the motion and puts
    /// the outputs in their safe state at once.
    pub fn on_imu(&mut self, reading: ImuReading) {
        self.imu.push(reading);
        let now = self.clock.now_ms();
        match self.balance.push(reading, now, self.outputs_enabled) {
            Event::None => {}
            Event::Fall(_) => self.enter_safe_state(),
            Event::Fault => {
                if self.balance.config().on_fault == FaultAction::Stop {
                    self.engine.stop();
                }
            }
        }
    }

    /// The balance functions' report (what `GetImu` answers).
    pub fn imu_report(&self) -> ImuReport {
        self.balance.report()
    }

    /// Configures the balance functions (`SetBalance`).
    ///
    /// # Errors
    /// [`NackReason::ImuAbsent`] or [`NackReason::ImuFault`] for leveling without a working
    /// sensor.
    pub fn set_balance(&mut self, config: BalanceConfig) -> Result<(), NackReason> {
        self.balance.configure(config)
    }

    /// A fall: the motion ends and the outputs go to the safe state.
    pub(super) fn enter_safe_state(&mut self) {
        self.engine.cancel();
        self.base_pose = None;
        if self.balance.config().safe_state == SafeState::Rest {
            let rest = engine::rest_angles(&self.config.robot);
            if let Ok(()) = rest.and_then(|r| self.hold_motion_target(r)) {
                return;
            }
        }
        self.stop_outputs();
    }

    /// Holds `pose` with the leveling correction `c` (roll, pitch) added, or the largest of
    /// [`LEVEL_SHARES`] of it within reach: the set point, the correction applied and whether
    /// it was limited; `None` when not even the pose itself maps.
    // Out of line: the body solve's locals stay out of the frame tick's stack frame.
    #[inline(never)]
    pub(super) fn level_pose(
        &mut self,
        pose: &Pose,
        c: [f32; 2],
    ) -> Option<([f32; 2], [f32; 2], bool)> {
        let pc = self.config.pose_config;
        let intended = [pose.roll_rad, pose.pitch_rad];
        for share in LEVEL_SHARES {
            let applied = [c[0] * share, c[1] * share];
            let leveled = Pose {
                roll_rad: pose.roll_rad + applied[0],
                pitch_rad: pose.pitch_rad + applied[1],
                ..*pose
            };
            let mut solution = BodySolution::default();
            let solved = self.solver.inverse_at_stance_into(
                &leveled,
                &BodyConfig::about_centre(pc.order),
                pc.stance_height_m,
                ReachPolicy::Reject,
                &mut solution,
            );
            if solved.is_ok() && self.hold_angles(&solution.angles_rad).is_ok() {
                let limited = share < 1.0 && (c[0] != 0.0 || c[1] != 0.0);
                return Some((intended, applied, limited));
            }
        }
        None
    }

    /// Makes `angles_rad` the held target when all twelve map through the calibration, the
    /// flags and the engine untouched (the leveling's re-solve of the held pose).
    pub(super) fn hold_angles(&mut self, angles_rad: &[f32; 12]) -> Result<(), ()> {
        let mut pulses_half_us = [0u16; 12];
        for (i, p) in pulses_half_us.iter_mut().enumerate() {
            *p = self.pulse_maps[i]
                .pulse_half_us(angles_rad[i])
                .map_err(|_| ())?;
        }
        self.held = Some(Held {
            angles_rad: *angles_rad,
            pulses_half_us,
        });
        Ok(())
    }

    /// What the controller knows of its inertial sensor.
    pub fn imu(&self) -> &ImuState {
        &self.imu
    }
}
