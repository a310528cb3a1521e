#!/usr/bin/env python3
"""Refits the coefficients of the gather's rational erf (src/pipeline/photons/fast_math.rs).

erf(x) ~ x P(x^2) / Q(x^2) on [0, 4], P of degree 6 and Q of degree 5 in x^2,
Q's constant term 1. The fit is linear least squares on x P(t) - erf(x) Q(t)
(t = x^2) at 4,000 Chebyshev nodes, each row divided by the previous
iteration's Q so the residual is the approximation's own error (Sanathanan &
Koerner, IEEE Trans. Automatic Control 8(1), 1963), then reweighted by the
square root of the error (Lawson's iteration) toward equal ripple, the
minimax fit. Prints the f64 error, the error after Horner's rule in f32, and
the coefficients rounded to f32.

Usage: tools/reference/fit_erf.py    (needs numpy: tools/setup's environment)
"""
import math

import numpy as np

M, N = 6, 5  # degrees of P and Q in t = x^2
NODES = 4000


def fit():
    x = np.sort(2.0 + 2.0 * np.cos(np.pi * (np.arange(NODES) + 0.5) / NODES))
    f = np.array([math.erf(v) for v in x])
    t = x * x
    a = np.hstack([np.stack([x * t**k for k in range(M + 1)], 1), np.stack([-f * t**k for k in range(1, N + 1)], 1)])
    q_prev, w = np.ones(NODES), np.ones(NODES)
    for it in range(60):
        rows = (w / np.abs(q_prev))[:, None]
        s = np.linalg.lstsq(a * rows, f * rows[:, 0], rcond=None)[0]
        p, q = s[: M + 1], np.concatenate([[1.0], s[M + 1 :]])
        q_prev = sum(q[k] * t**k for k in range(N + 1))
        err = x * sum(p[k] * t**k for k in range(M + 1)) / q_prev - f
        if it > 10:
            w = w * np.sqrt(np.abs(err))
            w /= w.max()
    return p, q, np.abs(err).max()


def horner32(c, t):
    acc = np.float32(c[-1])
    for k in reversed(c[:-1]):
        acc = acc * t + np.float32(k)
    return acc


def main():
    p, q, err64 = fit()
    p32, q32 = [np.float32(v) for v in p], [np.float32(v) for v in q]
    xs = np.linspace(0.0, 4.0, 400_001).astype(np.float32)
    ts = xs * xs
    got = xs * horner32(p32, ts) / horner32(q32, ts)
    want = np.array([math.erf(float(v)) for v in xs])
    print(f"max error: {err64:.3g} (f64), {np.abs(got.astype(np.float64) - want).max():.3g} (f32)")
    print("P:", ", ".join(repr(float(v)) for v in p32))
    print("Q:", ", ".join(repr(float(v)) for v in q32))


if __name__ == "__main__":
    main()
