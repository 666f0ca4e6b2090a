"""Reachable-workspace map of one leg, with quadkin and matplotlib: a grid of foot targets in
the leg plane (x forward, z up; y = s·d_lat) solved in one batch call, coloured by reach code,
with the singularity measure (inverse condition number of the Jacobian) over the reachable part.

    .venv-py/bin/python examples/python/workspace_map.py [--robot NAME|FILE] [--out FILE.png]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

import quadkin  # noqa: E402

GRID_POINTS = 401


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="shahriar2023")
    parser.add_argument("--leg", default="FL")
    parser.add_argument("--out", default="workspace_map.png")
    args = parser.parse_args()
    robot = quadkin.Robot(args.robot)
    reach_m = robot.d_ax_m + robot.femur_m + robot.tibia_m
    side = 1.0 if args.leg in ("FL", "RL") else -1.0
    x_m = np.linspace(-1.1 * reach_m, 1.1 * reach_m, GRID_POINTS)
    z_m = np.linspace(-1.1 * reach_m, 1.1 * reach_m, GRID_POINTS)
    xx, zz = np.meshgrid(x_m, z_m)
    targets_m = np.column_stack(
        [xx.ravel(), np.full(xx.size, side * robot.d_lat_m), zz.ravel()]
    )
    angles_rad, code = robot.leg_ik(args.leg, targets_m)
    inverse_condition, _ = robot.singularity(args.leg, angles_rad)
    code = code.reshape(xx.shape)
    measure = np.where(code == quadkin.OK, inverse_condition.reshape(xx.shape), np.nan)

    fig, (ax_code, ax_sing) = plt.subplots(1, 2, figsize=(12, 5.5), constrained_layout=True)
    colours = ["#2e7d32", "#eeeeee", "#90caf9", "#ce93d8", "#ffb74d", "#000000"]
    ax_code.pcolormesh(
        x_m, z_m, code, cmap=ListedColormap(colours), vmin=-0.5, vmax=5.5, shading="auto"
    )
    handles = [
        plt.Rectangle((0, 0), 1, 1, color=c) for c in colours[: len(quadkin.CODE_NAMES) - 1]
    ]
    ax_code.legend(handles, quadkin.CODE_NAMES[:-1], loc="upper right", fontsize=8)
    ax_code.set_title(f"{args.robot} {args.leg}: reach code (y = {side * robot.d_lat_m:+.3f} m)")
    mesh = ax_sing.pcolormesh(x_m, z_m, measure, cmap="viridis", vmin=0, shading="auto")
    ax_sing.contour(
        x_m, z_m, np.nan_to_num(measure, nan=1.0), levels=[quadkin.SINGULARITY_THRESHOLD],
        colors="red", linewidths=0.8,
    )
    fig.colorbar(mesh, ax=ax_sing, label="inverse condition number σmin/σmax")
    ax_sing.set_title("singularity measure (red: threshold)")
    for ax in (ax_code, ax_sing):
        ax.set_xlabel("x_m (forward)")
        ax.set_ylabel("z_m (up)")
        ax.set_aspect("equal")
        ax.plot(0, 0, "k+")
    fig.savefig(args.out, dpi=110)
    reachable = (code == quadkin.OK).mean()
    print(f"{args.out}: {xx.size} targets, {100 * reachable:.1f} % reachable")


if __name__ == "__main__":
    main()
