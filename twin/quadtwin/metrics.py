"""Figures of a run: fall, yaw, travel, slip, torque, tracking, the response to a slope, a
tilting floor or a push, and the IMU's samples with the true attitude.

Thresholds are named constants here; docs/twin.md says why each has its value."""

import math

import mujoco
import numpy as np

from .model import JOINT_NAMES

#: The body fell when its centre sinks below this fraction of its commanded height.
FALL_HEIGHT_FRACTION = 0.5
#: ... or when |roll| or |pitch| exceeds this, rad (46°: beyond every commanded sway).
FALL_TILT_RAD = 0.8
#: A motion "turns" when its commanded yaw changes by more than this over the run, rad.
TURN_MIN_RAD = 0.05
#: A motion "travels" when its commanded displacement exceeds this, m.
TRAVEL_MIN_M = 0.05
#: A motion "sways" on the axis whose commanded peak-to-peak exceeds this, rad.
SWAY_MIN_RAD = 0.05
#: Stance frames skipped after a touchdown before the slip is measured (landing transient).
SLIP_SKIP_FRAMES = 1
#: The body's settled roll and pitch: their means over the run's last this many seconds.
SETTLED_WINDOW_S = 0.5
#: Settled: roll and pitch stay within this of their settled values, rad (0.5°).
SETTLE_BAND_RAD = math.radians(0.5)


def feet_contact(twin, d):
    """Which feet touch the floor."""
    touching = [False] * 4
    for c in d.contact[: d.ncon]:
        pair = (int(c.geom1), int(c.geom2))
        if twin.floor_geom in pair:
            other = pair[0] if pair[1] == twin.floor_geom else pair[1]
            for i, g in enumerate(twin.foot_geom):
                if other == g:
                    touching[i] = True
    return touching


def body_on_floor(twin, d):
    for c in d.contact[: d.ncon]:
        pair = (int(c.geom1), int(c.geom2))
        if twin.floor_geom in pair and twin.body_geom in pair:
            return True
    return False


class Recorder:
    """Samples of a run: torques every physics step, the body every frame."""

    def __init__(self, twin, start, scenario):
        self.twin = twin
        self.start = start
        self.scenario = scenario
        self.height = []
        self.imu = []
        self.estimate = []
        self.torque = []
        self.saturated = []
        self.t = []
        self.pos = []
        self.rpy = []
        self.cmd = []
        self.stance = []
        self.feet = []
        self.body_touch = []
        self.q = []
        self.q_target = []
        self.contact = []
        self.frame_peak = []
        self._frame_peak = np.zeros(12)
        self.frame_mean = []
        self._frame_sum = np.zeros(12)
        self._frame_n = 0
        self.feet_in_body = []
        self.feet_in_body_cmd = []
        self._scratch = twin.new_data()
        self.t0 = 0.0

    def begin(self, d):
        self.t0 = float(d.time)

    def step(self, d, u):
        tau = d.actuator_force[self.twin.actuator].copy()
        self.torque.append(tau)
        self._frame_peak = np.maximum(self._frame_peak, np.abs(tau))
        self._frame_sum += tau
        self._frame_n += 1
        self.saturated.append(bool(np.any(np.abs(u) >= 1.0)))

    def frame(self, d, msg, state):
        t = float(d.time) - self.t0
        self.t.append(t)
        self.pos.append(state["pos_m"])
        # Height of the body centre over the (possibly inclined) floor plane through the origin.
        self.height.append(float(self.scenario.floor_normal(t) @ np.array(state["pos_m"])))
        for s in state["imu"]:
            self.imu.append(
                [s["t_s"] - self.t0, *s["accel_m_s2"], *s["gyro_rad_s"], *s["rpy_rad"]]
            )
        # The device's attitude estimate at the frame's start, when it reports one.
        est = msg.get("estimated_rpy_rad")
        if est is not None:
            self.estimate.append([msg["t_s"], *est])
        self.rpy.append(state["rpy_rad"])
        self.cmd.append(msg["commanded_pose"])
        self.stance.append(msg["stance"])
        self.feet.append([d.site_xpos[s].copy() for s in self.twin.foot_site])
        self.body_touch.append(body_on_floor(self.twin, d))
        self.q.append(d.qpos[self.twin.qpos_adr].copy())
        self.q_target.append(np.array(msg["angles_rad"], dtype=float))
        self.contact.append(state["feet_contact"])
        self.feet_in_body.append(self.in_body(d))
        # The commanded feet: the same kinematics at the frame's joint targets.
        s = self._scratch
        self.twin.set_pose(s, msg["angles_rad"])
        mujoco.mj_kinematics(self.twin.model, s)
        self.feet_in_body_cmd.append(self.in_body(s))
        self.frame_peak.append(self._frame_peak)
        self._frame_peak = np.zeros(12)
        self.frame_mean.append(self._frame_sum / max(1, self._frame_n))
        self._frame_sum = np.zeros(12)
        self._frame_n = 0

    def in_body(self, d):
        """The four foot centres in the body frame, m."""
        b = self.twin.body
        r = d.xmat[b].reshape(3, 3)
        return np.array([r.T @ (d.site_xpos[s] - d.xpos[b]) for s in self.twin.foot_site])

    def duration_s(self):
        return self.t[-1] if self.t else 0.0

    def arrays(self):
        return (
            np.array(self.t),
            np.array(self.pos),
            np.array(self.rpy),
            np.array(self.cmd),
            np.array(self.stance, dtype=bool),
            np.array(self.feet),
        )

    def save_trace(self, path):
        """Every frame's samples (body, commanded pose, joint targets and angles, feet,
        contacts) as a NumPy archive, for studies beyond the summary."""
        t, pos, rpy, cmd, stance, feet = self.arrays()
        np.savez_compressed(
            path,
            t_s=t,
            pos_m=pos,
            rpy_rad=rpy,
            commanded_pose=cmd,
            stance=stance,
            feet_m=feet,
            q_rad=np.array(self.q),
            q_target_rad=np.array(self.q_target),
            contact=np.array(self.contact, dtype=bool),
            torque_peak_nm=np.array(self.frame_peak),
            torque_frame_mean_nm=np.array(self.frame_mean),
            stance_height_m=self.start["stance_height_m"],
            height_over_floor_m=np.array(self.height),
            # The IMU's samples: time (motion clock), accelerometer, gyroscope, true roll,
            # pitch, yaw (body frame, SI).
            imu_t_s=self.imu_array()[:, 0],
            imu_accel_m_s2=self.imu_array()[:, 1:4],
            imu_gyro_rad_s=self.imu_array()[:, 4:7],
            imu_true_rpy_rad=self.imu_array()[:, 7:10],
            estimate_rpy_rad=np.array(self.estimate).reshape(-1, 4),
        )

    def imu_array(self):
        return np.array(self.imu, dtype=float).reshape(-1, 10)

    def commanded_height_m(self, cmd):
        return self.start["stance_height_m"] + cmd[:, 5] + self.twin.foot_radius_m

    def summary(self):
        t, pos, rpy, cmd, stance, feet = self.arrays()
        out = {
            "robot": self.start["robot"],
            "motion": self.start["motion"],
            "servo": self.twin.servo_name,
            "duration_s": self.duration_s(),
        }
        out.update(self.fall(t, pos, rpy, cmd))
        out["yaw"] = self.yaw(rpy, cmd)
        out["travel"] = self.travel(pos, cmd)
        out["slip"] = self.slip(stance, feet)
        out["torque"] = self.torques()
        out["tracking"] = self.tracking(rpy, cmd)
        out["stepping"] = self.stepping(stance)
        out["scenario"] = self.disturbance(t, rpy)
        out["attitude"] = self.attitude()
        return out

    def disturbance(self, t, rpy):
        """How the body answered the run's slope, tilting floor or push: its largest |roll| and
        |pitch| from the disturbance's start, their settled values (means over the last
        SETTLED_WINDOW_S), and the settling time: from the disturbance's end until roll and
        pitch stay within SETTLE_BAND_RAD of their settled values (none when they never do)."""
        described = self.scenario.describe()
        if described is None or len(t) == 0:
            return None
        start, end = self.scenario.disturbance_s()
        after = t >= start
        last = t >= t[-1] - SETTLED_WINDOW_S
        settled = rpy[last, 0:2].mean(axis=0)
        outside = np.any(np.abs(rpy[:, 0:2] - settled) > SETTLE_BAND_RAD, axis=1) & (t >= end)
        settling = None
        if not outside[-1]:
            late = np.nonzero(outside)[0]
            settling = float(t[late[-1] + 1] - end) if len(late) else 0.0
        described.update(
            {
                "disturbance_start_s": start,
                "disturbance_end_s": end,
                "max_abs_roll_rad": float(np.max(np.abs(rpy[after, 0]))),
                "max_abs_pitch_rad": float(np.max(np.abs(rpy[after, 1]))),
                "settled_roll_rad": float(settled[0]),
                "settled_pitch_rad": float(settled[1]),
                "settling_time_s": settling,
            }
        )
        return described

    def attitude(self):
        """The IMU's sample count and rate, and, when the device reported an attitude
        estimate, its error against the true attitude at the same time (RMS and largest, roll
        and pitch)."""
        imu = self.imu_array()
        if len(imu) == 0:
            return None
        out = {
            "imu_samples": len(imu),
            "imu_rate_hz": float((len(imu) - 1) / (imu[-1, 0] - imu[0, 0])) if len(imu) > 1 else None,
            "estimate": None,
        }
        if self.estimate:
            est = np.array(self.estimate)
            true = np.column_stack([np.interp(est[:, 0], imu[:, 0], imu[:, 7 + i]) for i in range(2)])
            err = est[:, 1:3] - true
            out["estimate"] = {
                "roll_rms_error_rad": float(np.sqrt(np.mean(err[:, 0] ** 2))),
                "pitch_rms_error_rad": float(np.sqrt(np.mean(err[:, 1] ** 2))),
                "max_error_rad": float(np.max(np.abs(err))),
            }
        return out

    def stepping(self, stance):
        """Why a gait covers less ground than commanded: per leg, how far the foot swept back
        under the body (along the commanded sweep) during each whole commanded stance against
        the commanded sweep, the
        share of the commanded stance and swing frames with the foot on the floor, and the
        mean knee position error (reached − target) in stance."""
        if stance.all():
            return None
        contact = np.array(self.contact, dtype=bool)
        fb = np.array(self.feet_in_body)
        fc = np.array(self.feet_in_body_cmd)
        err = np.array(self.q) - np.array(self.q_target)
        legs = []
        for leg in range(4):
            st = stance[:, leg]
            swept, commanded = [], []
            i, n = 0, len(st)
            while i < n:
                if st[i]:
                    j = i
                    while j < n and st[j]:
                        j += 1
                    if i > 0 and j < n:  # whole stances only
                        c = fc[i, leg, 0:2] - fc[j - 1, leg, 0:2]
                        length = float(np.linalg.norm(c))
                        if length > 0.0:
                            # The reached sweep along the commanded one.
                            swept.append(float(np.dot(fb[i, leg, 0:2] - fb[j - 1, leg, 0:2], c)) / length)
                            commanded.append(length)
                    i = j
                else:
                    i += 1
            legs.append(
                {
                    "stance_sweep_ratio": float(np.sum(swept) / np.sum(commanded)) if commanded else None,
                    "contact_in_stance": float(np.mean(contact[st, leg])) if st.any() else None,
                    "contact_in_swing": float(np.mean(contact[~st, leg])) if (~st).any() else None,
                    "knee_error_in_stance_rad": float(np.mean(err[st, 3 * leg + 2])) if st.any() else None,
                }
            )
        return {"legs": legs}

    def fall(self, t, pos, rpy, cmd):
        h_cmd = self.commanded_height_m(cmd)
        height = np.array(self.height)
        low = height < FALL_HEIGHT_FRACTION * h_cmd
        tilt = np.max(np.abs(rpy[:, :2]), axis=1)
        tilted = tilt > FALL_TILT_RAD
        touch = np.array(self.body_touch, dtype=bool)
        reason = None
        for i in range(len(t)):
            if low[i]:
                reason = f"body height {height[i]:.3f} m < {FALL_HEIGHT_FRACTION} x commanded {h_cmd[i]:.3f} m at t = {t[i]:.2f} s"
            elif tilted[i]:
                reason = f"tilt {tilt[i]:.2f} rad > {FALL_TILT_RAD} rad at t = {t[i]:.2f} s"
            elif touch[i]:
                reason = f"body touched the floor at t = {t[i]:.2f} s"
            if reason:
                break
        return {
            "fell": reason is not None,
            "fall_reason": reason,
            "min_height_m": float(np.min(height)),
            "max_tilt_rad": float(np.max(tilt)),
        }

    def yaw(self, rpy, cmd):
        cy = np.unwrap(cmd[:, 2])
        commanded = float(cy[-1] - cy[0])
        if abs(commanded) < TURN_MIN_RAD:
            return None
        y = np.unwrap(rpy[:, 2])
        achieved = float(y[-1] - y[0])
        return {"commanded_rad": commanded, "achieved_rad": achieved, "ratio": achieved / commanded}

    def travel(self, pos, cmd):
        dc = cmd[-1, 3:5] - cmd[0, 3:5]
        commanded = float(np.linalg.norm(dc))
        if commanded < TRAVEL_MIN_M:
            return None
        d = pos[-1, 0:2] - pos[0, 0:2]
        unit = dc / commanded
        along = float(np.dot(d, unit))
        heading = math.atan2(float(unit[0] * d[1] - unit[1] * d[0]), float(np.dot(d, unit)))
        return {
            "commanded_m": commanded,
            "achieved_m": float(np.linalg.norm(d)),
            "ratio": along / commanded,
            "heading_error_rad": heading,
        }

    def slip(self, stance, feet):
        per_leg = [0.0] * 4
        for leg in range(4):
            run_start = None
            for i in range(len(stance)):
                if stance[i, leg]:
                    if run_start is None:
                        run_start = i
                    if i - run_start >= SLIP_SKIP_FRAMES:
                        ref = feet[run_start + SLIP_SKIP_FRAMES, leg, 0:2]
                        per_leg[leg] = max(per_leg[leg], float(np.linalg.norm(feet[i, leg, 0:2] - ref)))
                else:
                    run_start = None
        return {"max_stance_slip_m": max(per_leg), "per_leg_max_m": per_leg}

    def torques(self):
        tau = np.array(self.torque)
        peak = np.max(np.abs(tau), axis=0)
        rms = np.sqrt(np.mean(tau * tau, axis=0))
        joints = [
            {"name": n, "peak_nm": float(p), "rms_nm": float(r)} for n, p, r in zip(JOINT_NAMES, peak, rms)
        ]
        worst = int(np.argmax(peak))
        return {
            "stall_nm": self.twin.servo["stall_torque_nm"],
            "joints": joints,
            "peak_nm": float(peak[worst]),
            "peak_joint": JOINT_NAMES[worst],
            "saturated_fraction": float(np.mean(self.saturated)),
        }

    def tracking(self, rpy, cmd):
        err = rpy[:, 0:2] - cmd[:, 0:2]
        out = {
            "roll_rms_error_rad": float(np.sqrt(np.mean(err[:, 0] ** 2))),
            "pitch_rms_error_rad": float(np.sqrt(np.mean(err[:, 1] ** 2))),
            "amplitude_ratio": None,
        }
        cmd_angles = np.column_stack([cmd[:, 0], cmd[:, 1], np.unwrap(cmd[:, 2])])
        got = np.column_stack([rpy[:, 0], rpy[:, 1], np.unwrap(rpy[:, 2])])
        p2p = np.ptp(cmd_angles, axis=0)
        axis = int(np.argmax(p2p))
        turning = abs(cmd_angles[-1, 2] - cmd_angles[0, 2]) >= TURN_MIN_RAD
        if p2p[axis] >= SWAY_MIN_RAD and not (axis == 2 and turning):
            out["amplitude_ratio"] = float(np.ptp(got[:, axis]) / p2p[axis])
        return out
