//! One interval of the Hermite scheme's deltas in lanes (module docs of the parent): the
//! vector operations over [`Lane`], `(E, x, y)` from the nodes ([`prepare`]), the prepared
//! interval's record and the chain through ΔR ([`State::step`]).

use super::super::QuatDeltas;
#[cfg(target_arch = "x86_64")]
use super::super::lanes::quad::F4;
use super::super::lanes::{F2, Lane};
use super::super::quat::Quat;
use crate::propagation::blocks::V3;

/// A 3-vector in lanes: `[x, y, z]`.
pub(super) type L3<T> = [T; 3];

/// `[f(0), f(1), f(2)]` (`array::map` is not always inlined, and a call in the lane code costs
/// more than the work).
#[inline(always)]
pub(super) fn by3<T>(f: impl Fn(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

#[inline(always)]
pub(super) fn add<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(super) fn sub<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(super) fn scale<T: Lane>(a: &L3<T>, s: T) -> L3<T> {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline(always)]
pub(super) fn cross<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `R(q)` for a unit quaternion `q = (w, x, y, z)`, by rows: `I + 2(w[q_v]× + [q_v]×²)`
/// (in lanes its 21 operations and the 15 of a product [`mv`] are all packed).
#[inline(always)]
pub(super) fn rot_matrix<T: Lane>(q: &[T; 4]) -> [L3<T>; 3] {
    let [w, x, y, z] = *q;
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, yy, zz) = (x * x2, y * y2, z * z2);
    let (xy, xz, yz) = (x * y2, x * z2, y * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let one = T::splat(1.0);
    [
        [one - (yy + zz), xy - wz, xz + wy],
        [xy + wz, one - (xx + zz), yz - wx],
        [xz - wy, yz + wx, one - (xx + yy)],
    ]
}

/// `M v`.
#[inline(always)]
pub(super) fn mv<T: Lane>(m: &[L3<T>; 3], v: &L3<T>) -> L3<T> {
    by3(|i| (m[i][0] * v[0] + m[i][1] * v[1]) + m[i][2] * v[2])
}

/// `α d₁₂ + β d₀₁`: a node's derivative from its two differences (as the plain scheme's `slope`).
#[inline(always)]
pub(super) fn slope<T: Lane>(d12: &L3<T>, d01: &L3<T>, alpha: T, beta: T) -> L3<T> {
    add(&scale(d12, alpha), &scale(d01, beta))
}

#[inline(always)]
pub(super) fn l3(v: &V3) -> L3<f64> {
    [v.x, v.y, v.z]
}

#[inline(always)]
pub(super) fn v3(l: &L3<f64>) -> V3 {
    V3::new(l[0], l[1], l[2])
}

/// `s = ω × a + ȧ` of a node (frame of the node), rounded as [`Carry`](super::carry::Carry) rounds it.
#[inline(always)]
pub(crate) fn s_of(w: &V3, a: &V3, da: &V3) -> V3 {
    v3(&add(&cross(&l3(w), &l3(a)), &l3(da)))
}

/// `(E, x, y)` of the interval (module docs) from its rule (`h/2`, `h²/12`), the rates and
/// accelerations of both nodes, node k's `ω̇_k` and `s_k`, and node k+1's `ω̇_k+1` and `s_k+1`.
/// `E` is the unit quaternion `(cos(θ/2), sin(θ/2)/θ Ω)` of
/// `Ω = h/2 (ω_k + ω_k+1) + h²/12 (ω̇_k − ω̇_k+1 + ω_k × ω_k+1)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn prepare<T: Lane>(
    h_2: T,
    h12: T,
    w0: &L3<T>,
    w1: &L3<T>,
    a0: &L3<T>,
    a1: &L3<T>,
    dw0: &L3<T>,
    s0: &L3<T>,
    dw1: &L3<T>,
    s1: &L3<T>,
) -> ([T; 4], L3<T>, L3<T>) {
    let om = add(
        &scale(&add(w0, w1), h_2),
        &scale(&add(&sub(dw0, dw1), &cross(w0, w1)), h12),
    );
    let (c, s) = T::exp_quat_coeffs((om[0] * om[0] + om[1] * om[1]) + om[2] * om[2]);
    let e = [c, s * om[0], s * om[1], s * om[2]];
    let m = rot_matrix(&e);
    let (eb, ea) = (mv(&m, &sub(&scale(a1, h_2), &scale(s1, h12))), mv(&m, a1));
    let x = add(&add(&scale(a0, h_2), &scale(s0, h12)), &eb);
    let y = add(&scale(&x, h_2), &scale(&sub(a0, &ea), h12));
    (e, x, y)
}

/// One prepared interval, laid out for [`State::step`]: `E = (c, e_x, e_y, e_z)` as the pairs
/// `(c, e_x)`, `(e_y, e_z)`; `(x_i, y_i)` by component; `(h, h)` \[s\].
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub(crate) struct Record {
    e1: F2,
    e2: F2,
    xy: [F2; 3],
    h: F2,
}

impl Record {
    #[inline(always)]
    pub(super) fn one(e: &[f64; 4], x: &L3<f64>, y: &L3<f64>, h: f64) -> Self {
        Self {
            e1: F2::new(e[0], e[1]),
            e2: F2::new(e[2], e[3]),
            xy: by3(|i| F2::new(x[i], y[i])),
            h: F2::splat(h),
        }
    }

    /// The records of the four intervals in lanes 0…3.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn four(e: &[F4; 4], x: &L3<F4>, y: &L3<F4>, h: F4) -> [Self; 4] {
        // (a0, b0, a2, b2), (a1, b1, a3, b3) split into the pairs of lanes 0, 2 and 1, 3.
        let split = |a: F4, b: F4| {
            let (l, h) = F4::interleave(a, b);
            let ((p0, p2), (p1, p3)) = (l.halves(), h.halves());
            [p0, p1, p2, p3]
        };
        let (e1, e2, hh) = (split(e[0], e[1]), split(e[2], e[3]), split(h, h));
        let xy: [[F2; 4]; 3] = by3(|i| split(x[i], y[i]));
        std::array::from_fn(|j| Self {
            e1: e1[j],
            e2: e2[j],
            xy: [xy[0][j], xy[1][j], xy[2][j]],
            h: hh[j],
        })
    }

    /// The records of the two intervals in lanes lo and hi.
    #[inline(always)]
    pub(super) fn two(e: &[F2; 4], x: &L3<F2>, y: &L3<F2>, h: F2) -> [Self; 2] {
        [
            Self {
                e1: F2::lows(e[0], e[1]),
                e2: F2::lows(e[2], e[3]),
                xy: by3(|i| F2::lows(x[i], y[i])),
                h: h.splat_lo(),
            },
            Self {
                e1: F2::highs(e[0], e[1]),
                e2: F2::highs(e[2], e[3]),
                xy: by3(|i| F2::highs(x[i], y[i])),
                h: h.splat_hi(),
            },
        ]
    }
}

/// The running deltas in lanes: ΔR's quaternion as `(w, x)`, `(y, z)` and `(Δv_i, Δp_i)` by
/// component.
#[derive(Clone, Copy, Debug)]
pub(crate) struct State {
    qa: F2,
    qb: F2,
    vp: [F2; 3],
}

impl State {
    #[inline(always)]
    pub(crate) fn load(d: &QuatDeltas) -> Self {
        let (q, v, p) = (&d.q, &d.v, &d.p);
        Self {
            qa: F2::new(q.w, q.v.x),
            qb: F2::new(q.v.y, q.v.z),
            vp: by3(|i| F2::new(v[i], p[i])),
        }
    }

    #[inline(always)]
    pub(crate) fn store(&self, d: &mut QuatDeltas) {
        d.q = Quat {
            w: self.qa.lo(),
            v: V3::new(self.qa.hi(), self.qb.lo(), self.qb.hi()),
        };
        d.v = V3::new(self.vp[0].lo(), self.vp[1].lo(), self.vp[2].lo());
        d.p = V3::new(self.vp[0].hi(), self.vp[1].hi(), self.vp[2].hi());
    }

    /// One interval: `Δv += ΔR_k x`, `Δp = (Δp + h Δv) + ΔR_k y`, `q = q ⊗ E`.
    #[inline(always)]
    pub(crate) fn step(&mut self, r: &Record) {
        let (w, x) = (self.qa.splat_lo(), self.qa.splat_hi());
        let (y, z) = (self.qb.splat_lo(), self.qb.splat_hi());
        // R(q) P = P + w t + q_v × t, t = 2 q_v × P (Quat::rotate, both vectors at once).
        let (qv, p) = ([x, y, z], &r.xy);
        let t = cross(&qv, p);
        let t = add(&t, &t);
        let rxy = add(&add(p, &scale(&t, w)), &cross(&qv, &t));
        let zero = F2::splat(0.0);
        for (vp, o) in self.vp.iter_mut().zip(&rxy) {
            // (v + 0, p + v h) + (R x, R y)_i
            *vp = (*vp + F2::lows(zero, *vp) * r.h) + *o;
        }
        // q ⊗ E, the lanes of (w', x') and (y', z') (Hamilton product, as Quat::mul).
        let (e1, e2) = (r.e1, r.e2);
        let (e1s, e2s) = (e1.swap(), e2.swap());
        self.qa = (w * e1 + x * e1s.flip(true, false))
            + (y * e2.flip(true, false) + z * e2s.flip(true, true));
        self.qb = (w * e2 + x * e2s.flip(true, false)) + (y * e1.flip(false, true) + z * e1s);
    }
}
