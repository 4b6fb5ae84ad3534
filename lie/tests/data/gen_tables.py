#!/usr/bin/env python3
"""Prints the REF table of tests/so3.rs and the QREF table of tests/se3.rs.

Every reference is evaluated at mpf(theta), the exact binary value of the f64 theta (what the
code receives), with 100 significant digits, and printed to 21 digits.
Run: python3 gen_tables.py  (needs mpmath).
"""
from mpmath import mp, mpf, sin, cos
mp.dps = 100
def so3(t):
    t = mp.sqrt(mpf(t * t))  # at the exact f64 theta^2 that the code forms (see tests/so3.rs)
    return [sin(t)/t, (1-cos(t))/t**2, (t-sin(t))/t**3, 1/t**2 - (1+cos(t))/(2*t*sin(t))]
def q(t):
    t = mpf(t)
    return [(t**2+2*cos(t)-2)/(2*t**4), (2*t-3*sin(t)+t*cos(t))/(2*t**5)]
def f(x): return mp.nstr(x, 21, min_fixed=-5, max_fixed=5)
print("SO3")
for t in [1e-8,1e-4,0.01,0.09999,0.10001,0.3,0.49999,0.50001,1.0,2.0,3.0,3.14159,3.5,4.0]:
    r = so3(t)
    print(f"    (\n        {t!r},\n        [\n" + "".join(f"            {f(x)},\n" for x in r) + "        ],\n    ),")
print("Q")
for t in [1e-8,0.01,0.5,1.0,1.9999,2.0001,3.0]:
    r = q(t)
    print(f"    ({t!r}, [{f(r[0])}, {f(r[1])}]),")
