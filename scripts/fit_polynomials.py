#!/usr/bin/env python3
"""Fits the polynomial coefficients of kin-core's `Fast` math backend.

Lawson's iteratively re-weighted least squares converges to the minimax (equi-ripple) fit.
Prints each fit's coefficients and its maximum error in f64 and when evaluated in f32 Horner
form. Needs numpy. Run: python3 scripts/fit_polynomials.py
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
    # atan(t), t in [0, 1], odd degree 15 (fit on [-1, 1] for symmetry).
    c, err = lawson(np.arctan, [1, 3, 5, 7, 9, 11, 13, 15], -1.0, 1.0)
    print("atan  ", [float(np.float32(x)) for x in c], "max err", err)
    q = np.pi / 4
    c, err = lawson(np.sin, [1, 3, 5, 7, 9], -q, q)
    print("sin   ", [float(np.float32(x)) for x in c], "max err", err)
    c, err = lawson(np.cos, [0, 2, 4, 6, 8], -q, q)
    print("cos   ", [float(np.float32(x)) for x in c], "max err", err)


if __name__ == "__main__":
    main()
