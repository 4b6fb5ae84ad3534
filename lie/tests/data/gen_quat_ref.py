#!/usr/bin/env python3
"""Writes quat_ref.txt: 60-digit mpmath references for Exp as a unit quaternion,
(cos(t/2), sin(t/2)/t), read by tests/so3.rs (`quaternion_exp_coefficients_within_an_ulp`).

Each line: theta, then the (hi, lo) pairs of cos(x/2) and sin(x/2)/x with hi = float(ref) and
lo = float(ref - hi), at x = sqrt(mpf(theta*theta)), the square root of the exact f64 theta^2
that `exp_quat_coeffs` receives (see gen_coeff_ref.py). Angles: 200 log-uniform in [1e-8, 0.1]
(the series), 100 uniform in [0.1, 6] (sqrt and sin_cos), and both sides of the edge 0.1.
Run: python3 gen_quat_ref.py  (needs mpmath; seed fixed, output deterministic).
"""
import random
from mpmath import mp, mpf, sin, cos

mp.dps = 60
rng = random.Random(20261202)
ts = [10 ** rng.uniform(-8, -1) for _ in range(200)]
ts += [rng.uniform(0.1, 6.0) for _ in range(100)]
ts += [0.1, 0.09999999999999999, 0.10000000000000002, 3.141592653589793]
with open("quat_ref.txt", "w") as fo:
    for t in ts:
        x = mp.sqrt(mpf(t * t))
        row = [repr(t)]
        for v in (cos(x / 2), sin(x / 2) / x):
            hi = float(v)
            row += [repr(hi), repr(float(v - hi))]
        fo.write(" ".join(row) + "\n")
