#!/usr/bin/env python3
"""Writes coeff_ref.txt: 60-digit mpmath references for the SO(3) coefficients, read by
tests/so3.rs (`coefficients_within_a_few_eps_on_dense_angles`).

Each line: theta, then for each of a = sin t/t, b = (1 - cos t)/t^2, c = (t - sin t)/t^3,
D = 1/t^2 - (1 + cos t)/(2 t sin t) the pair (hi, lo) with hi = float(ref) and
lo = float(ref - hi), so a test can measure errors below one ulp. mpf(theta) is the exact
binary value of an f64, and the references are at sqrt(mpf(theta*theta)): the square root of
the exact f64 theta^2 (`theta * theta` rounded, as the code forms it), which is the input the
theta^2-taking coefficient functions really receive. (At theta = 3.14159 the rounding of theta^2
alone moves sin t/t by ~1e-11 relative, so a reference at theta itself would test the
rounding of the square, not the function.)
Run: python3 gen_coeff_ref.py  (needs mpmath; seed fixed, output deterministic).
"""
import random
from mpmath import mp, mpf, sin, cos

mp.dps = 60
rng = random.Random(20240611)
pi = 3.141592653589793
ts = [rng.uniform(1.0, pi) for _ in range(300)]
ts += [10 ** rng.uniform(-8, 0) for _ in range(100)]
ts += [rng.uniform(3.5, 5.5) for _ in range(50)]  # beyond pi: the closed form
ts += [pi - 10.0 ** (-k) for k in range(1, 16)] + [pi, 1.0, 1.0000000000000002, 0.9999999999999999,
                                                   0.1, 0.09999999999999999, 0.5, 0.49999999999999994]
with open("coeff_ref.txt", "w") as fo:
    for t in ts:
        x = mp.sqrt(mpf(t * t))
        vals = [sin(x) / x, (1 - cos(x)) / x**2, (x - sin(x)) / x**3,
                1 / x**2 - (1 + cos(x)) / (2 * x * sin(x))]
        out = [repr(t)]
        for v in vals:
            hi = float(v)
            out += [repr(hi), repr(float(v - mpf(hi)))]
        fo.write(" ".join(out) + "\n")
