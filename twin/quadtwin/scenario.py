"""The world around the robot during a run: the floor (level, a slope, or tilting during the
run) and a sideways push on the body.

The start message's ``scenario`` (none: a level floor and no push)::

    {"floor": {"axis": "roll" | "pitch", "slope_rad": 0.1745,
               "tilt": null | {"start_s": 2.5, "duration_s": 1.0, "by_rad": 0.1745}},
     "push": null | {"impulse_n_s": 5.0, "at_s": 2.5, "duration_s": 0.1}}

The floor is the model's mocap body ``floor`` (a plane through the world's origin), turned
about the world's x axis (``roll``: positive raises the floor on the robot's left, so the
body placed on it rolls by +slope) or y axis (``pitch``: positive lowers the floor ahead, the
body pitches by +slope, nose down). A tilt turns it further by ``by_rad`` at a constant rate
over ``duration_s`` from ``start_s`` (motion time). The push is a constant force of
``impulse_n_s / duration_s`` newtons along the world's +y axis (the robot's left at the start;
a negative impulse pushes to the right), applied at the body's centre of mass through
``xfrc_applied`` from ``at_s`` for ``duration_s``.
"""

import math

import mujoco
import numpy as np

#: World axis of each slope axis.
AXES = {"roll": np.array([1.0, 0.0, 0.0]), "pitch": np.array([0.0, 1.0, 0.0])}
#: Direction of the push in the world.
PUSH_DIRECTION = np.array([0.0, 1.0, 0.0])
#: How long the push's arrow stays in the pictures after the push starts, s (at least the
#: push itself; long enough for one picture of the GIF to show it).
PUSH_SHOWN_S = 0.3


class Scenario:
    def __init__(self, spec, twin):
        spec = spec or {}
        floor = spec.get("floor") or {}
        self.axis_name = floor.get("axis", "roll")
        self.axis = AXES[self.axis_name]
        self.slope_rad = float(floor.get("slope_rad", 0.0))
        self.tilt = floor.get("tilt")
        self.push = spec.get("push")
        self.floor_mocap = int(twin.model.body_mocapid[twin.model.body("floor").id])
        self.body = twin.body
        self.active = bool(spec)

    def floor_angle_rad(self, t):
        """The floor's angle about its axis at motion time ``t``."""
        angle = self.slope_rad
        if self.tilt:
            u = (t - self.tilt["start_s"]) / self.tilt["duration_s"]
            angle += self.tilt["by_rad"] * min(1.0, max(0.0, u))
        return angle

    def floor_quat(self, t):
        q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(q, self.axis, self.floor_angle_rad(t))
        return q

    def floor_normal(self, t):
        """The floor's upward normal in the world at motion time ``t``."""
        m = np.zeros(9)
        mujoco.mju_quat2Mat(m, self.floor_quat(t))
        return m.reshape(3, 3)[:, 2]

    def push_force_n(self, t):
        """The push's force at motion time ``t`` (zero outside the pulse), N."""
        p = self.push
        if p and p["at_s"] <= t < p["at_s"] + p["duration_s"]:
            return p["impulse_n_s"] / p["duration_s"]
        return 0.0

    def push_shown(self, t):
        """The push's impulse when a picture at motion time ``t`` shows its arrow, else 0."""
        p = self.push
        if p and p["at_s"] <= t < p["at_s"] + max(p["duration_s"], PUSH_SHOWN_S):
            return p["impulse_n_s"]
        return 0.0

    def apply(self, d, t):
        """Sets the floor and the push for the physics step starting at motion time ``t``."""
        if not self.active:
            return
        d.mocap_quat[self.floor_mocap] = self.floor_quat(t)
        d.xfrc_applied[self.body, 0:3] = self.push_force_n(t) * PUSH_DIRECTION

    def disturbance_s(self):
        """When the run's disturbance starts and ends (motion time, s): the tilt, the push, or
        the whole run on a fixed slope (from 0)."""
        spans = []
        if self.tilt:
            spans.append((self.tilt["start_s"], self.tilt["start_s"] + self.tilt["duration_s"]))
        if self.push:
            spans.append((self.push["at_s"], self.push["at_s"] + self.push["duration_s"]))
        if not spans:
            return (0.0, 0.0)
        return (min(s for s, _ in spans), max(e for _, e in spans))

    def describe(self):
        """The scenario for the summary (none for a level floor and no push)."""
        if not self.active:
            return None
        return {
            "axis": self.axis_name,
            "slope_rad": self.slope_rad,
            "tilt_by_rad": self.tilt["by_rad"] if self.tilt else None,
            "push_n_s": self.push["impulse_n_s"] if self.push else None,
        }

    def label(self):
        """A short caption for the pictures."""
        parts = []
        if self.slope_rad:
            parts.append(f"slope {math.degrees(self.slope_rad):.0f}° {self.axis_name}")
        if self.tilt:
            parts.append(f"floor tilting {math.degrees(self.tilt['by_rad']):+.0f}° {self.axis_name}")
        if self.push:
            parts.append(f"push {self.push['impulse_n_s']:.1f} N s")
        return ", ".join(parts)
