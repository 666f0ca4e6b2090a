"""The servo's controller board: the duty cycle from the position error.

The motor law itself (torque = stall * duty - stall / no_load_speed * velocity) is the MJCF
actuator written by quad-model; see crates/quad-model/src/servo.rs for the model and
docs/twin.md for its parameters."""

import numpy as np


class ServoBoard:
    """Twelve servo controllers with the parameters the model carries."""

    def __init__(self, twin):
        s = twin.servo
        self.full_duty_error_rad = s["full_duty_error_rad"]
        self.deadband_rad = s["deadband_rad"]
        self.derivative_s = s["derivative_s"]
        self.stall_torque_nm = s["stall_torque_nm"]

    def duty(self, target_rad, q_rad, qd_rad_s):
        """Duty cycle in [-1, 1] per servo; 0 inside the deadband."""
        err = target_rad - q_rad
        u = np.clip((err - self.derivative_s * qd_rad_s) / self.full_duty_error_rad, -1.0, 1.0)
        u[np.abs(err) < self.deadband_rad] = 0.0
        return u
