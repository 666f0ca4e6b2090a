"""A model written by quad-model's MJCF writer, and the names it relies on."""

import mujoco
import numpy as np

LEGS = ("FL", "FR", "RL", "RR")
JOINTS = ("abduction", "hip", "knee")
#: Joint (and actuator) names in the canonical order of every 12-value array.
JOINT_NAMES = tuple(f"{leg}_{joint}" for leg in LEGS for joint in JOINTS)


class Model:
    """A loaded model with the indices the twin uses."""

    def __init__(self, path):
        self.model = mujoco.MjModel.from_xml_path(str(path))
        m = self.model
        self.qpos_adr = np.array(
            [m.jnt_qposadr[m.joint(n).id] for n in JOINT_NAMES], dtype=int
        )
        self.dof_adr = np.array(
            [m.jnt_dofadr[m.joint(n).id] for n in JOINT_NAMES], dtype=int
        )
        self.actuator = np.array([m.actuator(n).id for n in JOINT_NAMES], dtype=int)
        self.foot_site = np.array([m.site(f"{leg}_foot").id for leg in LEGS], dtype=int)
        self.foot_geom = np.array([m.geom(f"{leg}_foot").id for leg in LEGS], dtype=int)
        self.floor_geom = m.geom("floor").id
        self.body_geom = m.geom("body").id
        self.body = m.body("body").id
        self.servo = {
            key: self.numeric(f"servo_{key}")
            for key in (
                "stall_torque_nm",
                "no_load_speed_rad_s",
                "full_duty_error_rad",
                "deadband_rad",
                "derivative_s",
            )
        }
        self.servo_name = self.text("servo_name")
        self.foot_radius_m = self.numeric("foot_radius_m")
        self.total_mass_kg = self.numeric("total_mass_kg")

    def numeric(self, name):
        return float(self.model.numeric(name).data[0])

    def text(self, name):
        m = self.model
        i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXT, name)
        if i < 0:
            raise KeyError(f"custom text `{name}` missing from the model")
        adr, size = m.text_adr[i], m.text_size[i]
        return bytes(m.text_data[adr : adr + size - 1]).decode()

    def new_data(self):
        return mujoco.MjData(self.model)

    def set_pose(self, data, angles_rad, body_pos_m=(0.0, 0.0, 0.0), body_quat=(1, 0, 0, 0)):
        """Places the free body and sets the twelve joint angles (no velocities)."""
        data.qpos[0:3] = body_pos_m
        data.qpos[3:7] = body_quat
        data.qpos[self.qpos_adr] = angles_rad
        data.qvel[:] = 0.0
