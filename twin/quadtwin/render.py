"""Pictures of a run: the metric plots (matplotlib) and offscreen renders (GIF + PNG strip)."""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image, ImageDraw  # noqa: E402

from .model import JOINT_NAMES  # noqa: E402

#: Size of a rendered picture, pixels.
WIDTH, HEIGHT = 480, 360
#: Pictures in the strip.
STRIP_FRAMES = 6


def plots(rec, summary, out_dir):
    t, pos, rpy, cmd, stance, feet = rec.arrays()
    stepping = summary.get("stepping") is not None
    fig, ax = plt.subplots(2, 3 if stepping else 2, figsize=(16 if stepping else 11, 7))
    label = rec.scenario.label()
    title = (
        f"{summary['robot']} / {summary['motion']} / {summary['servo']}"
        + (f" / {label}" if label else "")
        + ("  — FELL" if summary["fell"] else "")
    )
    fig.suptitle(title)
    a = ax[0, 0]
    a.plot(t, np.array(rec.height), label="body height over the floor")
    a.plot(t, rec.commanded_height_m(cmd), "--", label="commanded")
    a.set_xlabel("t (s)")
    a.set_ylabel("m")
    a.legend()
    a = ax[0, 1]
    for i, name in enumerate(("roll", "pitch")):
        a.plot(t, np.degrees(rpy[:, i]), label=name)
        a.plot(t, np.degrees(cmd[:, i]), "--", label=f"{name} commanded")
    if summary.get("scenario") is not None:
        start, end = rec.scenario.disturbance_s()
        if end > start:
            a.axvspan(start, end, color="tab:red", alpha=0.15, label="disturbance")
    a.set_xlabel("t (s)")
    a.set_ylabel("deg")
    a.legend(fontsize=8)
    a = ax[1, 0]
    if summary["travel"] is not None:
        a.plot(pos[:, 0], pos[:, 1], label="body")
        a.plot(cmd[:, 3], cmd[:, 4], "--", label="commanded")
        a.set_xlabel("x (m)")
        a.set_ylabel("y (m)")
        a.axis("equal")
    else:
        a.plot(t, np.degrees(np.unwrap(rpy[:, 2])), label="yaw")
        a.plot(t, np.degrees(np.unwrap(cmd[:, 2])), "--", label="yaw commanded")
        a.set_xlabel("t (s)")
        a.set_ylabel("deg")
    a.legend()
    a = ax[1, 1]
    tq = summary["torque"]
    x = np.arange(12)
    a.bar(x - 0.2, [j["peak_nm"] for j in tq["joints"]], 0.4, label="peak")
    a.bar(x + 0.2, [j["rms_nm"] for j in tq["joints"]], 0.4, label="RMS")
    a.axhline(tq["stall_nm"], color="r", ls="--", label=f"stall {tq['stall_nm']:.2f} N·m")
    a.set_xticks(x, JOINT_NAMES, rotation=60, fontsize=7)
    a.set_ylabel("N·m")
    a.legend(fontsize=8)
    if stepping:
        step_panels(ax[0, 2], ax[1, 2], rec, t, stance)
    fig.tight_layout()
    path = os.path.join(out_dir, "plots.png")
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return [path]


#: The leg and the time span the stepping panels show.
STEP_LEG, STEP_WINDOW_S = 2, (4.0, 7.0)


def step_panels(a, b, rec, t, stance):
    """One leg's foot under the body (along x) and knee error over a few cycles: where the
    stance sweep is lost."""
    leg = STEP_LEG
    w = (t >= STEP_WINDOW_S[0]) & (t <= STEP_WINDOW_S[1])
    if not w.any():
        w = np.ones_like(t, dtype=bool)
    fb = np.array(rec.feet_in_body)[:, leg]
    fc = np.array(rec.feet_in_body_cmd)[:, leg]
    contact = np.array(rec.contact, dtype=bool)[:, leg]
    a.plot(t[w], fc[w, 0], "--", label="commanded")
    a.plot(t[w], fb[w, 0], label="reached")
    lo, hi = a.get_ylim()
    a.fill_between(t[w], lo, hi, where=stance[w, leg], color="0.9", label="commanded stance")
    a.fill_between(t[w], lo, lo + 0.08 * (hi - lo), where=contact[w], color="tab:green", alpha=0.5, label="on the floor")
    a.set_ylim(lo, hi)
    a.set_xlabel("t (s)")
    a.set_ylabel(f"{JOINT_NAMES[3 * leg][:2]} foot x in the body (m)")
    a.legend(fontsize=7)
    err = np.array(rec.q)[:, 3 * leg + 2] - np.array(rec.q_target)[:, 3 * leg + 2]
    b.plot(t[w], np.degrees(err[w]), label=f"{JOINT_NAMES[3 * leg + 2]} reached − target")
    b.axhline(-np.degrees(rec.twin.servo["full_duty_error_rad"]), color="r", ls="--", label="full duty")
    b.set_xlabel("t (s)")
    b.set_ylabel("deg")
    b.legend(fontsize=7)


#: The camera's azimuth and elevation, degrees: a three-quarter view from the front left; on
#: an inclined or tilting floor, nearly along the slope's axis and lower, so that the horizon
#: shows the floor's angle.
VIEW_DEG = (140.0, -18.0)
VIEW_ROLL_SLOPE_DEG = (165.0, -12.0)
VIEW_PITCH_SLOPE_DEG = (125.0, -12.0)


def view(scenario):
    if scenario.slope_rad or scenario.tilt:
        return VIEW_ROLL_SLOPE_DEG if scenario.axis_name == "roll" else VIEW_PITCH_SLOPE_DEG
    return VIEW_DEG


#: Length of the push's arrow per N·s of impulse, m, and its largest length as a share of the
#: body's length.
ARROW_M_PER_N_S, ARROW_MAX_BODY_LENGTHS = 0.1, 1.5


def push_arrow(scene, d, body, impulse_n_s, body_length_m, half_width_m, half_height_m):
    """Adds an arrow to ``scene`` pointing at the body along the push (world +y)."""
    if scene.ngeom >= scene.maxgeom:
        return
    length = min(abs(impulse_n_s) * ARROW_M_PER_N_S, ARROW_MAX_BODY_LENGTHS * body_length_m)
    length = max(length, 0.3 * body_length_m)
    sign = 1.0 if impulse_n_s >= 0 else -1.0
    # The tip at the body's side, the arrow along the push.
    # Level with the body's top face, clear of the legs.
    tip = d.xpos[body] + np.array([0.0, -sign * half_width_m * 1.1, half_height_m])
    tail = tip - sign * np.array([0.0, length, 0.0])
    g = scene.geoms[scene.ngeom]
    mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3), np.zeros(9),
                        np.array([0.85, 0.1, 0.1, 1.0], dtype=np.float32))
    mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_ARROW, 0.03 * body_length_m, tail, tip)
    scene.ngeom += 1


def pictures(twin, snapshots, out_dir, scenario):
    m = twin.model
    d = mujoco.MjData(m)
    renderer = mujoco.Renderer(m, HEIGHT, WIDTH)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    extent = float(m.stat.extent)
    cam.distance = 1.0 * extent
    cam.azimuth, cam.elevation = view(scenario)
    images = []
    body_length_m = 2.0 * float(m.geom_size[twin.body_geom][0])
    half_width_m = float(m.geom_size[twin.body_geom][1])
    half_height_m = float(m.geom_size[twin.body_geom][2])
    label = scenario.label()
    for t_s, qpos, mocap_quat, push_n_s in snapshots:
        d.qpos[:] = qpos
        d.mocap_quat[:] = mocap_quat
        mujoco.mj_forward(m, d)
        cam.lookat[:] = [d.qpos[0], d.qpos[1], 0.5 * d.qpos[2]]
        renderer.update_scene(d, cam)
        if push_n_s:
            push_arrow(renderer.scene, d, twin.body, push_n_s, body_length_m, half_width_m, half_height_m)
        img = Image.fromarray(renderer.render())
        draw = ImageDraw.Draw(img)
        draw.text((8, 8), f"t = {t_s:5.2f} s", fill=(0, 0, 0))
        if label:
            draw.text((8, 22), label, fill=(0, 0, 0))
        if push_n_s:
            draw.text((8, 36), f"push {push_n_s:.1f} N s", fill=(160, 0, 0))
        images.append(img)
    renderer.close()
    gif = os.path.join(out_dir, "motion.gif")
    images[0].save(gif, save_all=True, append_images=images[1:], duration=100, loop=0)
    picks = np.linspace(0, len(images) - 1, min(STRIP_FRAMES, len(images))).round().astype(int)
    # The push in the strip: its first picture in place of the nearest pick.
    pushed = [i for i, snap in enumerate(snapshots) if snap[3]]
    if pushed:
        nearest = int(np.argmin(np.abs(picks - pushed[0])))
        picks[nearest] = pushed[0]
        picks = np.unique(picks)
    strip = Image.new("RGB", (WIDTH * len(picks), HEIGHT), "white")
    for i, k in enumerate(picks):
        strip.paste(images[k], (i * WIDTH, 0))
    png = os.path.join(out_dir, "strip.png")
    strip.save(png)
    return [gif, png]
