#!/usr/bin/env python3
"""Prints the polynomial tables of lie/src/so3/coeffs.rs (`QA_POLY`, `B_POLY`, `C_POLY`,
`D_POLY`, `ATAN_POLY`).

On the branch 0.01 <= t <= fl(pi^2), t = theta^2, the SO(3) coefficients are polynomials in
x = t - POLY_MID:
  b(t) = (1 - cos sqrt t)/t,  c(t) = (sqrt t - sin sqrt t)/t^1.5,
  a(t) = sin(sqrt t)/sqrt t = (pi^2 - t) * qa(t)   (the zero at t = pi^2 factored out, so that
                                                   a keeps its relative precision near pi).
Each table is the degree-9 Chebyshev interpolant (10 nodes, 50-digit mpmath) converted to
monomials in x and rounded to f64. Chebyshev interpolation is within a few percent of minimax
here; the printed maxima (in eps = 2^-52, f64 evaluation in the order of coeffs.rs's `poly`, at
20 000 random t plus the ends) are what tests/so3.rs bounds.
`D_POLY`: D = 1/theta^2 - (1 + cos theta)/(2 theta sin theta), the coefficient of Jr^-1 (and of
SE(3)'s Log), as a degree-14 polynomial in x the same way (its poles at t = 4 pi^2 are closer,
so it needs more terms); its printed error is that of Horner (coeffs.rs's `poly15`, Estrin for
c1..c14 and one Horner step, measured 0.82 eps at the same points).
`ATAN_POLY`: A(u) = atan(sqrt u)/sqrt u on 0 <= u <= 0.34, the kernel of SO(3)'s Log on its
half-angle branch (u = tan^2(theta/2) <= 1/3, theta <= pi/3), degree 14 in x = u - ATAN_MID,
evaluated as `poly15` (printed error measured that way, 20 000 points).
Run: python3 lie/tools/fit_poly.py  (needs mpmath).
"""
import random
import mpmath as mp

mp.mp.dps = 50
PI2 = mp.pi ** 2
PI2_HI = float(PI2)
PI2_LO = float(PI2 - mp.mpf(PI2_HI))
LO, HI, DEG = 0.01, PI2_HI, 9


def a(t):
    s = mp.sqrt(t)
    return mp.sin(s) / s


def b(t):
    return (1 - mp.cos(mp.sqrt(t))) / t


def c(t):
    s = mp.sqrt(t)
    return (s - mp.sin(s)) / (t * s)


def qa(t):
    return a(t) / (PI2 - t)


def cheb_mono(f, lo, hi, n):
    lo, hi = mp.mpf(lo), mp.mpf(hi)
    mid, h = (lo + hi) / 2, (hi - lo) / 2
    N = n + 1
    nodes = [mp.cos(mp.pi * (k + mp.mpf(1) / 2) / N) for k in range(N)]
    vals = [f(mid + h * z) for z in nodes]
    cc = [2 * mp.fsum(vals[k] * mp.cos(mp.pi * j * (k + mp.mpf(1) / 2) / N) for k in range(N)) / N
          for j in range(N)]
    cc[0] /= 2
    T = [[mp.mpf(1)], [mp.mpf(0), mp.mpf(1)]]
    for j in range(2, N):
        up = [mp.mpf(0)] + [2 * x for x in T[j - 1]]
        down = T[j - 2] + [mp.mpf(0)] * (len(up) - len(T[j - 2]))
        T.append([up[i] - down[i] for i in range(len(up))])
    mono = [mp.mpf(0)] * N
    for j in range(N):
        for i, x in enumerate(T[j]):
            mono[i] += cc[j] * x
    return float(mid), [float(mono[i] / h ** i) for i in range(N)]


def horner(x, cs):
    acc = cs[-1]
    for ck in reversed(cs[:-1]):
        acc = acc * x + ck
    return acc


def poly(x, c):
    """coeffs.rs's `poly`/`poly2`: Estrin for c2..c9, then two Horner steps."""
    x2 = x * x
    p = lambda i: c[i] + c[i + 1] * x
    tail = (p(2) + p(4) * x2) + (p(6) + p(8) * x2) * (x2 * x2)
    return (tail * x + c[1]) * x + c[0]


mid = cheb_mono(b, LO, HI, DEG)[0]
print(f"const PI2_HI: f64 = {PI2_HI!r};\nconst PI2_LO: f64 = {PI2_LO!r};\nconst POLY_MID: f64 = {mid!r};")
rng = random.Random(7)
pts = [rng.uniform(LO, HI) for _ in range(20000)] + [LO, HI, HI - 1e-9, HI - 1e-5]
for name, f, ref in [("QA_POLY", qa, a), ("B_POLY", b, b), ("C_POLY", c, c)]:
    m, cs = cheb_mono(f, LO, HI, DEG)
    assert m == mid
    worst = 0.0
    for t in pts:
        got = poly(t - mid, cs)
        if name == "QA_POLY":
            got = ((PI2_HI - t) + PI2_LO) * got
        r = ref(mp.mpf(t))
        worst = max(worst, float(abs((got - r) / r) / mp.mpf(2) ** -52))
    print(f"// max relative error {worst:.2f} eps")
    print(f"const {name}: [f64; {DEG + 1}] = [\n" + "".join(f"    {x!r},\n" for x in cs) + "];")

def d_of_t(t):
    th = mp.sqrt(t)
    return 1 / t - (1 + mp.cos(th)) / (2 * th * mp.sin(th))


D_DEG = 14
m3, cs = cheb_mono(d_of_t, LO, HI, D_DEG)
assert m3 == mid
worst = 0.0
for t in pts:
    got = horner(t - mid, cs)
    r = d_of_t(mp.mpf(t))
    worst = max(worst, float(abs((got - r) / r) / mp.mpf(2) ** -52))
print(f"// max relative error {worst:.2f} eps")
print(f"const D_POLY: [f64; {D_DEG + 1}] = [\n" + "".join(f"    {x!r},\n" for x in cs) + "];")


def quarter_atan(u):
    if u == 0:
        return mp.mpf(1)
    r = mp.sqrt(u)
    return mp.atan(r) / r


def poly15(x, c):
    """coeffs.rs's `poly15`: Estrin for c1..c14, then one Horner step."""
    x2 = x * x
    p = lambda i: c[i] + c[i + 1] * x
    x4 = x2 * x2
    q0, q1 = p(1) + p(3) * x2, p(5) + p(7) * x2
    q2, q3 = p(9) + p(11) * x2, p(13)
    tail = (q0 + q1 * x4) + (q2 + q3 * x4) * (x4 * x4)
    return tail * x + c[0]


U_MAX = 0.34
amid, cs = cheb_mono(quarter_atan, 0.0, U_MAX, 14)
upts = [rng.uniform(0.0, U_MAX) for _ in range(20000)] + [0.0, U_MAX]
worst = 0.0
for u in upts:
    r = quarter_atan(mp.mpf(u))
    worst = max(worst, float(abs((poly15(u - amid, cs) - r) / r) / mp.mpf(2) ** -52))
print(f"const ATAN_MID: f64 = {amid!r};")
print(f"// max relative error {worst:.2f} eps")
print(f"const ATAN_POLY: [f64; 15] = [\n" + "".join(f"    {x!r},\n" for x in cs) + "];")
