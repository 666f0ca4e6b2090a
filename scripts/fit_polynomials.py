#!/usr/bin/env python3
"""Fits the polynomial coefficients of kin-core's math backends, and the cell table of
`math::poly::atan2_fixed`.

Lawson's iteratively re-weighted least squares converges to the minimax (equi-ripple) fit.
Prints each fit's coefficients (rounded to f32) and its maximum error in f64; the error of the
f32 evaluation is checked by kin-core's unit tests (`math::tests`). Needs numpy. Run: python3 scripts/fit_polynomials.py
"""
import math

import numpy as np


def lawson(f, powers, a, b, iters=300):
    t = np.cos(np.linspace(0, np.pi, 4000)) * (b - a) / 2 + (a + b) / 2
    A = np.stack([t**p for p in powers], 1)
    w = np.ones(len(t))
    for _ in range(iters):
        W = np.sqrt(w)
        c, *_ = np.linalg.lstsq(A * W[:, None], f(t) * W, rcond=None)
        e = np.abs(A @ c - f(t))
        w = w * e
        w /= w.sum()
    tt = np.linspace(a, b, 200001)
    err = np.max(np.abs(sum(ci * tt**p for ci, p in zip(c, powers)) - f(tt)))
    return c, err


def main():
    # atan(t), t in [0, 1], odd polynomials (fit on [-1, 1] for symmetry): degree 15 for the
    # hosts' `Fast` backend (math::poly::atan2_deg15), degree 9 for in-order targets such as
    # the ATmega2560 (math::poly::atan2_deg9).
    for degree in (15, 9):
        c, err = lawson(np.arctan, list(range(1, degree + 1, 2)), -1.0, 1.0)
        c = [float(np.float32(x)) for x in c]
        print(f"atan deg {degree:2}", c, "max err", err)
    atan_cells()
    q = np.pi / 4
    # sin/cos on the reduced range [-pi/4, pi/4]: degree 9/8 (math::poly::sin_cos_deg9) and
    # degree 5/6 (math::poly::sin_cos_deg5).
    for sin_powers, cos_powers in (([1, 3, 5, 7, 9], [0, 2, 4, 6, 8]), ([1, 3, 5], [0, 2, 4, 6])):
        c, err = lawson(np.sin, sin_powers, -q, q)
        print(f"sin deg {sin_powers[-1]}", [float(np.float32(x)) for x in c], "max err", err)
        c, err = lawson(np.cos, cos_powers, -q, q)
        print(f"cos deg {cos_powers[-1]}", [float(np.float32(x)) for x in c], "max err", err)


def atan_cells(n=32):
    """math::poly::atan2_fixed's table: atan on [0, 1] in n cells of width h = 1/n, in cell k
    atan(k·h + d) ≈ a + b·d − c·d² for d in [0, h), the quadratic through the cell's three
    Chebyshev nodes (its error is about 1/16 of the Taylor quadratic's), then rounded: a in
    Q29 (a₀ = 0, so that t = 0 gives exactly 0), b in Q15, c in Q16 (c ≥ 0: atan is concave
    on [0, 1]). Cell n holds t = 1 only. Prints the three arrays and the maximum error of
    the fixed-point evaluation (the kernel's arithmetic, in Python integers) over t in Q24."""
    h = 1.0 / n
    nodes = [h / 2 * (1 - math.cos((2 * i + 1) * math.pi / 6)) for i in range(3)]
    a_q, b_q, c_q = [], [], []
    for k in range(n + 1):
        m = np.array([[1.0, d, d * d] for d in nodes])
        a, b, c = np.linalg.solve(m, np.arctan(k * h + np.array(nodes)))
        a_q.append(0 if k == 0 else int(math.floor(a * 2.0**29 + 0.5)))
        b_q.append(int(math.floor(b * 2.0**15 + 0.5)))
        c_q.append(int(math.floor(-c * 2.0**16 + 0.5)))

    def fixed(big_t):
        k, d = big_t >> 19, (big_t & 0x7FFFF) >> 3
        lin = (d * b_q[k] + (1 << 6)) >> 7
        quad = (((d * d) >> 16) * c_q[k] + (1 << 12)) >> 13
        return a_q[k] + lin - quad

    err = max(abs(fixed(t) / 2.0**29 - math.atan(t / 2.0**24)) for t in range(0, (1 << 24) + 1, 5))
    print("atan cells a (Q29)", a_q)
    print("atan cells b (Q15)", b_q)
    print("atan cells c (Q16)", c_q)
    print("atan cells max err", err)


if __name__ == "__main__":
    main()
