#!/usr/bin/env python3
"""Fits the polynomial coefficients of kin-core's `Fast` math backend.

Lawson's iteratively re-weighted least squares converges to the minimax (equi-ripple) fit.
Prints each fit's coefficients (rounded to f32) and its maximum error in f64; the error of the
f32 evaluation is checked by kin-core's unit tests (`math::tests`). Needs numpy. Run: python3 scripts/fit_polynomials.py
"""
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
    # The degree-9 coefficients' magnitudes in the fixed-point formats of
    # math::poly::atan2_fixed's Horner levels (Q16, Q16, Q17, Q18, Q20): ATAN_DEG9_Q.
    q = [int(np.floor(abs(x) * 2.0**f + 0.5)) for x, f in zip(c, (16, 16, 17, 18, 20))]
    print("atan deg  9 fixed", q)
    q = np.pi / 4
    # sin/cos on the reduced range [-pi/4, pi/4]: degree 9/8 (math::poly::sin_cos_deg9) and
    # degree 5/6 (math::poly::sin_cos_deg5).
    for sin_powers, cos_powers in (([1, 3, 5, 7, 9], [0, 2, 4, 6, 8]), ([1, 3, 5], [0, 2, 4, 6])):
        c, err = lawson(np.sin, sin_powers, -q, q)
        print(f"sin deg {sin_powers[-1]}", [float(np.float32(x)) for x in c], "max err", err)
        c, err = lawson(np.cos, cos_powers, -q, q)
        print(f"cos deg {cos_powers[-1]}", [float(np.float32(x)) for x in c], "max err", err)


if __name__ == "__main__":
    main()
