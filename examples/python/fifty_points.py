"""Seed 000's random 50-point test (§3.1/§5), with quadkin: per leg, 50 random reachable foot
targets drawn in the box |x|, |y|, |z| <= La + Lb of the paper's Table 4 (shahriar2023), solved
in one batch call, and each answer checked through forward kinematics.

    .venv-py/bin/python examples/python/fifty_points.py [--seed N]

Prints per leg the targets drawn, the worst FK error (m) and the mean |angle| per joint (rad);
exits with status 1 if any reachable target fails to solve or misses by more than 1 µm.
"""

import argparse
import sys

import numpy as np

import quadkin

POINTS_PER_LEG = 50
# FK∘IK bound, m: seed 000's claim is exact solutions; f32 leaves well under a micrometre.
FOOT_TOLERANCE_M = 1e-6


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=50)
    args = parser.parse_args()
    robot = quadkin.Robot("shahriar2023")
    bound_m = robot.d_lat_m + robot.femur_m
    rng = np.random.default_rng(args.seed)
    failed = False
    print(f"{'leg':<4} {'drawn':>6} {'solved':>6} {'max FK error (m)':>17}  mean |angle| (rad)")
    for leg in quadkin.LEGS:
        # Draw a generous batch; keep the first 50 reachable ones (the box holds many points
        # beyond reach, and the batch call answers every one with its reach code).
        targets_m = rng.uniform(-bound_m, bound_m, size=(4000, 3))
        angles_rad, code = robot.leg_ik(leg, targets_m)
        reachable = np.flatnonzero(code == quadkin.OK)[:POINTS_PER_LEG]
        if len(reachable) < POINTS_PER_LEG:
            print(f"{leg}: only {len(reachable)} reachable targets drawn", file=sys.stderr)
            return 1
        drawn = reachable[-1] + 1
        feet_m, _ = robot.leg_fk(leg, angles_rad[reachable])
        error_m = np.linalg.norm(feet_m - targets_m[reachable].astype(np.float32), axis=1)
        mean_abs = np.abs(angles_rad[reachable]).mean(axis=0)
        print(
            f"{leg:<4} {drawn:>6} {len(reachable):>6} {error_m.max():>17.3e}  "
            + " ".join(f"{a:.3f}" for a in mean_abs)
        )
        failed |= bool(error_m.max() > FOOT_TOLERANCE_M)
    print("all 200 targets solved within 1 µm" if not failed else "FAILED", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
