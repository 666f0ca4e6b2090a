"""Foot sites at given joint angles, for the forward-kinematics agreement test.

stdin: JSON ``{"model": PATH, "angles_rad": [[12 angles], ...]}``; stdout: JSON
``{"feet_m": [[[x, y, z] × 4], ...], "nq": …, "nu": …}`` with the body at the world origin in
its nominal orientation (so world = body frame)."""

import json
import sys

import mujoco

from .model import Model


def main():
    request = json.load(sys.stdin)
    twin = Model(request["model"])
    data = twin.new_data()
    feet = []
    for angles in request["angles_rad"]:
        twin.set_pose(data, angles)
        mujoco.mj_kinematics(twin.model, data)
        feet.append([data.site_xpos[s].tolist() for s in twin.foot_site])
    json.dump(
        {
            "feet_m": feet,
            "nq": int(twin.model.nq),
            "nu": int(twin.model.nu),
            "servo_name": twin.servo_name,
            "total_mass_kg": twin.total_mass_kg,
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main()
