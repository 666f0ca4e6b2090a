"""The body's roll and pitch of runs side by side (e.g. a slope with balance off and on).

    python -m quadtwin.compare OUT.png LABEL=RUN_DIR [LABEL=RUN_DIR ...]

Each RUN_DIR is a run's `--out-dir` (its trace.npz); OUT.png gets one panel for roll and one
for pitch, degrees over the motion's time, a line per run.
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) < 2 or any("=" not in a for a in argv[1:]):
        print(__doc__, file=sys.stderr)
        return 2
    out, runs = argv[0], [a.split("=", 1) for a in argv[1:]]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.2), sharex=True)
    for label, run_dir in runs:
        trace = np.load(f"{run_dir}/trace.npz")
        rpy = np.degrees(trace["rpy_rad"])
        for i, ax in enumerate(axes):
            ax.plot(trace["t_s"], rpy[:, i], label=label)
    for ax, name in zip(axes, ["roll", "pitch"]):
        ax.set_title(f"body {name}")
        ax.set_xlabel("time, s")
        ax.set_ylabel("degrees")
        ax.axhspan(-1.5, 1.5, color="0.9", zorder=0)
        ax.grid(True, alpha=0.3)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
