"""From Python, 10^6 leg IKs: quadkin's batch call against a numpy-vectorised implementation of
the same equations (written here for the comparison: kin-core's leg IK, seed 000 eq. 4.1–4.21,
reject policy, backward knee) and against a Python loop over single solves; and the overhead of
one single-leg call. Medians of repeated runs after at least 0.5 s of warm-up runs, same run,
ratios.

    .venv-py/bin/python crates/kin-py/bench/leg_ik.py [--n 1000000] [--repeat 15] [--form F]

Prints a Markdown table (the "Python" table of BENCHMARKS.md).
"""

import argparse
import os
import statistics
import time
import timeit

import numpy as np

import quadkin


def numpy_leg_ik(robot: quadkin.Robot, left: bool, feet_m: np.ndarray):
    """kin-core's leg IK (reject policy, backward knee) on float32 arrays: the same equations,
    vectorised with numpy. Returns (angles_rad (N, 3), code (N,))."""
    f32 = np.float32
    d_lat, d_ax = f32(robot.d_lat_m), f32(robot.d_ax_m)
    l1, l2 = f32(robot.femur_m), f32(robot.tibia_m)
    d_lat_sq, far_sq, near_sq = d_lat * d_lat, (l1 + l2) ** 2, (l1 - l2) ** 2
    sum_sq, diff_sq = l1 * l1 + l2 * l2, l1 * l1 - l2 * l2
    sd = d_lat if left else -d_lat
    x, y, z = (feet_m[:, k].astype(f32) for k in range(3))
    with np.errstate(invalid="ignore", over="ignore"):
        r_sq = y * y + z * z
        w = -np.sqrt(np.maximum(r_sq - d_lat_sq, f32(0)))
        v = w + d_ax
        dist2 = x * x + v * v
        s = -np.sqrt(np.maximum((dist2 - near_sq) * (far_sq - dist2), f32(0)))
        abduction = np.arctan2(sd * z - w * y, sd * y + w * z)
        knee = np.arctan2(s, dist2 - sum_sq)
        bx = dist2 + diff_sq
        hip = np.arctan2(bx * -x - s * -v, bx * -v + s * -x)
        angles = np.stack([abduction, hip, knee], axis=1)
        lo, hi = robot.joint_min_rad, robot.joint_max_rad
        within = np.all((angles >= lo) & (angles <= hi), axis=1)
    code = np.full(len(x), quadkin.JOINT_LIMIT, dtype=np.int8)
    code[within] = quadkin.OK
    code[dist2 < near_sq] = quadkin.TOO_CLOSE
    code[dist2 > far_sq] = quadkin.TOO_FAR
    code[r_sq < d_lat_sq] = quadkin.INSIDE_OFFSET
    code[~(np.isfinite(x) & np.isfinite(y) & np.isfinite(z))] = quadkin.NON_FINITE
    angles[code != quadkin.OK] = 0
    return angles, code


def median_s(f, repeat: int, warmup: int = 3, warmup_s: float = 0.5) -> float:
    """The median time of `repeat` calls of `f`, after at least `warmup` calls and `warmup_s`
    seconds of calls (as criterion warms up for a time): rayon's threads start, the allocator
    settles on its large blocks and an idle core wakes, for every contender alike."""
    t_end = time.perf_counter() + warmup_s
    done = 0
    while done < warmup or time.perf_counter() < t_end:
        f()
        done += 1
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--loop-n", type=int, default=200_000)
    parser.add_argument("--form", choices=["avx512", "avx2", "portable"],
                        help="the batch solves' form (default: the widest this CPU runs)")
    args = parser.parse_args()
    if args.form:
        quadkin.set_batch_form(args.form)
    robot = quadkin.Robot("shahriar2023")
    rng = np.random.default_rng(0)
    # Targets around the leg's workspace (most reachable, some not).
    feet_m = np.column_stack(
        [
            rng.uniform(-0.35, 0.35, args.n),
            rng.uniform(-0.2, 0.25, args.n),
            rng.uniform(-0.5, -0.1, args.n),
        ]
    ).astype(np.float32)

    # The numpy implementation agrees with quadkin (same verdicts, angles within f32 noise).
    a_q, c_q = robot.leg_ik("FL", feet_m)
    a_n, c_n = numpy_leg_ik(robot, True, feet_m)
    agree = np.mean(c_q == c_n)
    both = (c_q == quadkin.OK) & (c_n == quadkin.OK)
    max_diff = float(np.abs(a_q[both] - a_n[both]).max())
    assert agree > 0.9999 and max_diff < 1e-4, (agree, max_diff)

    t_batch = median_s(lambda: robot.leg_ik("FL", feet_m), args.repeat)
    t_numpy = median_s(lambda: numpy_leg_ik(robot, True, feet_m), args.repeat)
    loop_feet = feet_m[: args.loop_n].tolist()

    def loop() -> None:
        solve = robot.leg_ik_one
        for x, y, z in loop_feet:
            try:
                solve("FL", x, y, z)
            except quadkin.UnreachableError:
                pass

    t_loop = median_s(loop, 3, warmup=1, warmup_s=0.0) * args.n / args.loop_n
    one = timeit.Timer(lambda: robot.leg_ik_one("FL", 0.0, 0.044, -0.4))
    n_one, _ = one.autorange()
    t_one = statistics.median(r / n_one for r in one.repeat(5, n_one))
    single = feet_m[:1]
    batch1 = timeit.Timer(lambda: robot.leg_ik("FL", single))
    n_b1, _ = batch1.autorange()
    t_b1 = statistics.median(r / n_b1 for r in batch1.repeat(5, n_b1))

    ns = 1e9 / args.n
    print(f"N = {args.n:.0e} leg IKs (shahriar2023, FL, float32), {os.cpu_count()} cores, "
          f"batch form {quadkin.batch_form()}, load {os.getloadavg()[0]:.1f}, "
          f"{100 * np.mean(c_q == quadkin.OK):.1f} % reachable; numpy agrees on "
          f"{100 * agree:.4f} % of codes, max |Δangle| {max_diff:.1e} rad")
    print()
    print("| what | median | per leg | quadkin batch is |")
    print("|---|---|---|---|")
    print(f"| quadkin `Robot.leg_ik` batch (GIL released, rayon) | {1e3 * t_batch:.1f} ms "
          f"| {t_batch * ns:.1f} ns | 1× |")
    print(f"| numpy, the same equations vectorised | {1e3 * t_numpy:.1f} ms "
          f"| {t_numpy * ns:.1f} ns | {t_numpy / t_batch:.1f}× faster |")
    print(f"| Python loop over `Robot.leg_ik_one` (timed on {args.loop_n:.0e}, scaled) "
          f"| {t_loop:.2f} s | {t_loop * ns:.0f} ns | {t_loop / t_batch:.0f}× faster |")
    print(f"| one `Robot.leg_ik_one` call | {1e6 * t_one:.2f} µs | | |")
    print(f"| one `Robot.leg_ik` call with N = 1 | {1e6 * t_b1:.2f} µs | | |")


if __name__ == "__main__":
    main()
