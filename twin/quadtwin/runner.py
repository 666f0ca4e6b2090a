"""The twin's frame loop: JSON lines in (servo frames), JSON lines out (body states).

See crates/quad-twin/src/link.rs for the protocol. Each frame's servo targets are held for
the frame; the physics steps at the model's time step; the servo boards update their duty
cycle every physics step. Every ``imu_period_s`` of the frame the IMU's accelerometer and
gyroscope are sampled, with the body's true attitude, and the frame's samples go back with
its state (``scenario`` for the floor and the push the run has)."""

import json
import math
import sys
import time

import mujoco
import numpy as np

from . import metrics
from .model import Model
from .scenario import Scenario
from .servo import ServoBoard

#: Pictures per simulated second in the GIF.
RENDER_FPS = 10
#: The IMU's sample period when the start message gives none, s (200 Hz: four samples a frame).
IMU_PERIOD_S = 0.005


def rpy_zyx(quat):
    """Roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) of a quaternion [w, x, y, z]."""
    w, x, y, z = quat
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return [roll, pitch, yaw]


def quat_zyx(roll, pitch, yaw):
    """The quaternion [w, x, y, z] of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.array([roll, pitch, yaw]), "XYZ")
    return q


class Run:
    def __init__(self, start):
        self.start = start
        self.twin = Model(start["model"])
        self.m = self.twin.model
        self.d = self.twin.new_data()
        self.board = ServoBoard(self.twin)
        self.timestep_s = float(self.m.opt.timestep)
        self.steps_per_frame = max(1, round(start["frame_s"] / self.timestep_s))
        self.scenario = Scenario(start.get("scenario"), self.twin)
        self.rec = metrics.Recorder(self.twin, start, self.scenario)
        imu_period_s = float(start.get("imu_period_s") or IMU_PERIOD_S)
        self.imu_every = max(1, round(imu_period_s / self.timestep_s))
        self.imu_samples = []
        #: Physics time at the motion's start (after the settling), s.
        self.t0 = None
        self.step_wall_s = 0.0
        self.started = False
        self.snapshots = []
        self.frames_per_snapshot = max(1, round(1.0 / (RENDER_FPS * start["frame_s"])))

    def place(self, frame):
        """Puts the robot in the first frame's pose, turned with the floor (a slope), with its
        lowest foot on the floor."""
        roll, pitch, yaw, x, y, _ = frame["commanded_pose"]
        floor_quat = self.scenario.floor_quat(0.0)
        self.scenario.apply(self.d, 0.0)
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, floor_quat, quat_zyx(roll, pitch, yaw))
        self.twin.set_pose(self.d, frame["angles_rad"], (x, y, 0.0), quat)
        mujoco.mj_kinematics(self.m, self.d)
        normal = self.scenario.floor_normal(0.0)
        lowest = min(float(normal @ self.d.site_xpos[s]) for s in self.twin.foot_site)
        self.d.qpos[0:3] += (self.twin.foot_radius_m - lowest) * normal
        mujoco.mj_forward(self.m, self.d)

    def hold(self, target, enabled, n_steps, record):
        qpos, dofs = self.twin.qpos_adr, self.twin.dof_adr
        m, d = self.m, self.d
        act = self.twin.actuator
        t0 = time.perf_counter()
        for i in range(n_steps):
            if enabled:
                u = self.board.duty(target, d.qpos[qpos], d.qvel[dofs])
            else:
                u = np.zeros(12)
            d.ctrl[act] = u
            if self.t0 is not None:
                self.scenario.apply(d, float(d.time) - self.t0)
            mujoco.mj_step(m, d)
            if record:
                self.rec.step(d, u)
                if (i + 1) % self.imu_every == 0:
                    self.imu_samples.append(self.imu_sample())
        self.step_wall_s += time.perf_counter() - t0

    def imu_sample(self):
        """The IMU's reading after a step: MuJoCo computes the sensors from the state the step
        started from, so the sample's time is one time step before ``d.time``."""
        d = self.d
        quat = d.sensor("body_quat").data.tolist()
        return {
            "t_s": float(d.time) - self.timestep_s,
            "accel_m_s2": d.sensor("accel").data.tolist(),
            "gyro_rad_s": d.sensor("gyro").data.tolist(),
            "rpy_rad": rpy_zyx(quat),
        }

    def frame(self, msg):
        target = np.array(msg["angles_rad"], dtype=float)
        if not self.started:
            self.place(msg)
            settle_steps = round(self.start["settle_s"] / self.timestep_s)
            self.hold(target, msg["enabled"], settle_steps, record=False)
            self.rec.begin(self.d)
            self.t0 = float(self.d.time)
            self.started = True
        self.imu_samples = []
        self.hold(target, msg["enabled"], self.steps_per_frame, record=True)
        state = self.state()
        state["imu"] = self.imu_samples
        self.rec.frame(self.d, msg, state)
        if self.start.get("render") and msg["k"] % self.frames_per_snapshot == 0:
            t = float(self.d.time) - self.t0
            self.snapshots.append(
                (msg["t_s"], self.d.qpos.copy(), self.d.mocap_quat.copy(), self.scenario.push_shown(t))
            )
        return state

    def state(self):
        d = self.d
        quat = d.qpos[3:7].tolist()
        return {
            "type": "state",
            "t_s": float(d.time),
            "pos_m": d.qpos[0:3].tolist(),
            "quat": quat,
            "rpy_rad": rpy_zyx(quat),
            "gyro_rad_s": d.sensor("gyro").data.tolist(),
            "accel_m_s2": d.sensor("accel").data.tolist(),
            "feet_contact": metrics.feet_contact(self.twin, d),
        }

    def end(self):
        simulated = self.start["settle_s"] + self.rec.duration_s()
        summary = self.rec.summary()
        summary["physics_hz"] = 1.0 / self.timestep_s
        summary["sim_per_wall"] = simulated / self.step_wall_s if self.step_wall_s > 0 else 0.0
        out_dir = self.start.get("out_dir")
        files = []
        if out_dir:
            from . import render

            files += render.plots(self.rec, summary, out_dir)
            trace = f"{out_dir}/trace.npz"
            self.rec.save_trace(trace)
            files.append(trace)
            if self.start.get("render") and self.snapshots:
                files += render.pictures(self.twin, self.snapshots, out_dir, self.scenario)
            summary["files"] = files
            path = f"{out_dir}/summary.json"
            with open(path, "w") as f:
                json.dump(summary, f, indent=2)
            files.append(path)
        summary["files"] = files
        summary["type"] = "summary"
        return summary


def main():
    out = sys.stdout
    # Anything printed by a library goes to stderr, never into the protocol.
    sys.stdout = sys.stderr
    run = None

    def send(msg):
        out.write(json.dumps(msg) + "\n")
        out.flush()

    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            msg = json.loads(line)
            kind = msg.get("type")
            if kind == "start":
                run = Run(msg)
                send({"type": "ready", "timestep_s": run.timestep_s})
            elif kind == "frame" and run is not None:
                send(run.frame(msg))
            elif kind == "end" and run is not None:
                send(run.end())
                return 0
            else:
                send({"type": "error", "message": f"unexpected message `{kind}`"})
                return 2
        except Exception as e:  # reported to the device side, then exit non-zero
            send({"type": "error", "message": f"{type(e).__name__}: {e}"})
            raise
    return 0


if __name__ == "__main__":
    sys.exit(main())
