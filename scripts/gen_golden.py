#!/usr/bin/env python3
"""Golden vectors for kin-core's leg kinematics, from an independent f64 reference.

Writes crates/kin-core/tests/data/golden_ik.csv (foot target -> expected angles or status) and
golden_fk.csv (angles -> expected foot) for the two papers' robots:

- shahriar2023 (seed 000, Table 4): La = 0.044 m lateral offset, Lb = 0.28 m, Lc = 0.277 m;
- fernando2025 (seed 001): l0 = 0.15 m along the leg plane, l1 = l2 = 0.45 m.

Canonical chain (hip frame: x forward, y left, z up; s = +1 left legs, -1 right legs):
    foot = Rx(a) * ([0, s*d_lat, -d_ax] + Ry(h)*[0,0,-L1] + Ry(h+k)*[0,0,-L2])
IK branches: knee <= 0 ("backward") or >= 0 ("forward"), and the abduction whose un-abducted foot
lies below the hip (w <= 0). Checks in the crate's order: inside_offset, too_far / too_close, then
joint limits in order abduction, hip, knee.

Inputs are rounded to f32 before anything is computed from them, so the Rust test reads exactly
the values used here. Rows are kept only when they are well away from every decision boundary
and singularity, so that f32 rounding cannot change the expected answer.

Plain Python 3 (math, random, struct); deterministic. Run from the repository root:
    python3 scripts/gen_golden.py
The test (crates/kin-core/tests/golden.rs) reads the checked-in CSV files; it does not run this.
"""

import math
import os
import random
import struct

SEED = 20240613
OUT = os.path.join("crates", "kin-core", "tests", "data")
LEGS = ["FL", "FR", "RL", "RR"]
SIDE = {"FL": 1.0, "FR": -1.0, "RL": 1.0, "RR": -1.0}
# Margins (m or rad) a kept row must have from every boundary / singularity.
BOUNDARY_MARGIN = 1e-3
# The inside-offset test compares y^2 + z^2 with d_lat^2, whose f32 rounding moves the boundary by
# ~1e-9 m: a smaller margin suffices there (shahriar2023's too_close targets, within 3 mm of
# the hip joint, all lie within w^2/(2 d_lat) < 1e-4 m of that circle).
INSIDE_OFFSET_MARGIN_M = 1e-5
W_MARGIN_M = 0.01
SIN_KNEE_MARGIN = 0.1


def f32(x):
    """Round a Python float to the nearest IEEE-754 single."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


PI32 = f32(math.pi)

ROBOTS = {
    "shahriar2023": dict(
        d_lat=f32(0.044), d_ax=0.0, l1=f32(0.28), l2=f32(0.277),
        lo=[-PI32, -PI32, f32(-2.8)], hi=[PI32, PI32, f32(-0.05)],
    ),
    "fernando2025": dict(
        d_lat=0.0, d_ax=f32(0.15), l1=f32(0.45), l2=f32(0.45),
        lo=[f32(-0.8), f32(-1.6), f32(-2.8)], hi=[f32(0.8), f32(1.6), f32(-0.05)],
    ),
}


def with_bend(robot, bend):
    """Limits for the knee bend: forward mirrors the knee interval."""
    r = dict(robot)
    if bend == "forward":
        r["lo"] = [robot["lo"][0], robot["lo"][1], -robot["hi"][2]]
        r["hi"] = [robot["hi"][0], robot["hi"][1], -robot["lo"][2]]
    return r


def wrap_pi(a):
    """Wrap into (-pi, pi]."""
    a = math.fmod(a, 2.0 * math.pi)
    if a <= -math.pi:
        a += 2.0 * math.pi
    elif a > math.pi:
        a -= 2.0 * math.pi
    return a


def fk(robot, leg, q):
    """Forward kinematics, f64, written out component by component."""
    a, h, k = q
    s = SIDE[leg]
    u = -robot["l1"] * math.sin(h) - robot["l2"] * math.sin(h + k)
    w = -robot["d_ax"] - robot["l1"] * math.cos(h) - robot["l2"] * math.cos(h + k)
    y0 = s * robot["d_lat"]
    return (u, math.cos(a) * y0 - math.sin(a) * w, math.sin(a) * y0 + math.cos(a) * w)


def ik(robot, leg, bend, p):
    """Analytic IK, f64. Returns (status, angles or None, margin, w, knee)."""
    x, y, z = p
    d, dax, l1, l2 = robot["d_lat"], robot["d_ax"], robot["l1"], robot["l2"]
    s = SIDE[leg]
    r = math.hypot(y, z)
    margin = abs(r - d) * BOUNDARY_MARGIN / INSIDE_OFFSET_MARGIN_M
    if r < d:
        return "inside_offset", None, margin, None, None
    w = -math.sqrt(max(r * r - d * d, 0.0))
    # Rx(a) maps (s*d, w) onto (y, z): a = angle(y, z) - angle(s*d, w).
    a = wrap_pi(math.atan2(z, y) - math.atan2(w, s * d))
    u, v = x, w + dax
    dist = math.hypot(u, v)
    margin = min(margin, abs(dist - (l1 + l2)), abs(dist - abs(l1 - l2)))
    if dist > l1 + l2:
        return "too_far", None, margin, w, None
    if dist < abs(l1 - l2):
        return "too_close", None, margin, w, None
    cos_k = max(-1.0, min(1.0, (dist * dist - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)))
    k = math.acos(cos_k) * (1.0 if bend == "forward" else -1.0)
    # (-v, -u) = rotation by h of (L1 + L2 cos k, L2 sin k).
    h = wrap_pi(math.atan2(-u, -v) - math.atan2(l2 * math.sin(k), l1 + l2 * math.cos(k)))
    q = (a, h, k)
    for j in range(3):
        margin = min(margin, abs(q[j] - robot["lo"][j]), abs(q[j] - robot["hi"][j]))
    for j, name in enumerate(["abduction", "hip", "knee"]):
        if not (robot["lo"][j] <= q[j] <= robot["hi"][j]):
            return "joint_limit:" + name, None, margin, w, k
    return "ok", q, margin, w, k


def well_posed(status, margin, w, k):
    if margin < BOUNDARY_MARGIN:
        return False
    if status == "ok":
        return abs(w) > W_MARGIN_M and abs(math.sin(k)) > SIN_KNEE_MARGIN
    return True


def fmt(v):
    return repr(float(v))


def ik_rows(rng):
    rows = []
    for name, base in ROBOTS.items():
        for bend in ["backward", "forward"]:
            robot = with_bend(base, bend)
            for leg in LEGS:
                # Reachable: angles drawn within the limits -> FK -> f32 foot.
                kept = 0
                while kept < 10:
                    q = [rng.uniform(robot["lo"][j], robot["hi"][j]) for j in range(3)]
                    p = tuple(f32(c) for c in fk(robot, leg, q))
                    status, ang, margin, w, k = ik(robot, leg, bend, p)
                    if status != "ok" or not well_posed(status, margin, w, k):
                        continue
                    # Self-check: the answer reproduces the foot.
                    back = fk(robot, leg, ang)
                    assert max(abs(b - c) for b, c in zip(back, p)) < 1e-12
                    rows.append((name, bend, leg, p, status, ang))
                    kept += 1
                # Unreachable (and a few more reachable) targets drawn in a box.
                reach = robot["d_lat"] + robot["d_ax"] + robot["l1"] + robot["l2"]
                kinds = {}
                tries = 0
                while len(kinds) < 4 and tries < 20000:
                    tries += 1
                    p = tuple(f32(rng.uniform(-1.2 * reach, 1.2 * reach)) for _ in range(3))
                    status, ang, margin, w, k = ik(robot, leg, bend, p)
                    key = status.split(":")[0]
                    if key in kinds or not well_posed(status, margin, w, k):
                        continue
                    kinds[key] = (name, bend, leg, p, status, ang)
                rows.extend(kinds.values())
        # Targets made for the kinds a box rarely hits: too far straight down, inside the
        # offset circle, within |L1 - L2| of the hip joint, and each joint past its limits.
        for leg in LEGS:
            s = SIDE[leg]
            crafted = [
                ("backward", (0.0, s * base["d_lat"], -(base["d_ax"] + base["l1"] + base["l2"] + 0.05))),
                ("backward", (0.3, 0.0, 0.0)),
                ("backward", (0.001, s * base["d_lat"], -0.0015 - base["d_ax"])),
            ]
            for bend, q in [("backward", (1.2, 0.3, -1.0)), ("backward", (0.0, 1.8, -1.0)),
                            ("forward", (0.0, -1.75, 1.0)), ("backward", (0.1, 0.2, -2.95))]:
                crafted.append((bend, fk(with_bend(base, bend), leg, q)))
            for bend, p in crafted:
                robot = with_bend(base, bend)
                p = tuple(f32(c) for c in p)
                status, ang, margin, w, k = ik(robot, leg, bend, p)
                if well_posed(status, margin, w, k):
                    rows.append((name, bend, leg, p, status, ang))
    return rows


def fk_rows(rng):
    rows = []
    for name, robot in ROBOTS.items():
        for i in range(64):
            leg = LEGS[i % 4]
            q = [f32(rng.uniform(-math.pi, math.pi)) for _ in range(3)]
            rows.append((name, leg, q, fk(robot, leg, q)))
    return rows


def main():
    rng = random.Random(SEED)
    os.makedirs(OUT, exist_ok=True)
    rows = ik_rows(rng)
    with open(os.path.join(OUT, "golden_ik.csv"), "w", newline="\n") as f:
        f.write("robot,knee_bend,leg,x_m,y_m,z_m,status,abduction_rad,hip_rad,knee_rad\n")
        for name, bend, leg, p, status, ang in rows:
            cells = [name, bend, leg] + [fmt(c) for c in p] + [status]
            cells += [fmt(a) for a in ang] if ang else ["", "", ""]
            f.write(",".join(cells) + "\n")
    frows = fk_rows(rng)
    with open(os.path.join(OUT, "golden_fk.csv"), "w", newline="\n") as f:
        f.write("robot,leg,abduction_rad,hip_rad,knee_rad,x_m,y_m,z_m\n")
        for name, leg, q, p in frows:
            f.write(",".join([name, leg] + [fmt(a) for a in q] + [fmt(c) for c in p]) + "\n")
    counts = {}
    for r in rows:
        counts[(r[0], r[4].split(":")[0])] = counts.get((r[0], r[4].split(":")[0]), 0) + 1
    for key in sorted(counts):
        print(f"ik {key[0]:>13} {key[1]:>13}: {counts[key]}")
    print(f"fk rows: {len(frows)}")


if __name__ == "__main__":
    main()
