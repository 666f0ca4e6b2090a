"""A servo's step response in the model, for the servo-law test.

stdin: JSON ``{"model": PATH, "joint": NAME, "from_rad": a, "to_rad": b, "duration_s": T}``;
stdout: JSON ``{"max_speed_rad_s", "final_error_rad", "max_torque_nm", "no_load_speed_rad_s",
"stall_torque_nm"}``. Gravity is off and the body floats clear of the floor, so the servo moves
only its own link: its top speed is the no-load speed."""

import json
import sys

import mujoco
import numpy as np

from .model import JOINT_NAMES, Model
from .servo import ServoBoard


def main():
    req = json.load(sys.stdin)
    twin = Model(req["model"])
    m = twin.model
    m.opt.gravity[:] = 0.0
    d = twin.new_data()
    # Legs bent within every preset's limits; the body well above the floor.
    start = np.array([0.0, 0.5, -1.0] * 4)
    i = JOINT_NAMES.index(req["joint"])
    start[i] = req["from_rad"]
    twin.set_pose(d, start, (0.0, 0.0, 10.0))
    target = start.copy()
    target[i] = req["to_rad"]
    board = ServoBoard(twin)
    max_speed = 0.0
    max_torque = 0.0
    for _ in range(round(req["duration_s"] / m.opt.timestep)):
        q = d.qpos[twin.qpos_adr]
        qd = d.qvel[twin.dof_adr]
        d.ctrl[twin.actuator] = board.duty(target, q, qd)
        mujoco.mj_step(m, d)
        max_speed = max(max_speed, abs(float(d.qvel[twin.dof_adr[i]])))
        max_torque = max(max_torque, abs(float(d.actuator_force[twin.actuator[i]])))
    json.dump(
        {
            "max_speed_rad_s": max_speed,
            "final_error_rad": float(target[i] - d.qpos[twin.qpos_adr[i]]),
            "max_torque_nm": max_torque,
            "no_load_speed_rad_s": twin.servo["no_load_speed_rad_s"],
            "stall_torque_nm": twin.servo["stall_torque_nm"],
            "deadband_rad": twin.servo["deadband_rad"],
            "full_duty_error_rad": twin.servo["full_duty_error_rad"],
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main()
