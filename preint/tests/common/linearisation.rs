//! The exact first-order linearisation of a preintegration, for comparing the code's
//! covariance with (`linearisation.rs`, `scheme_contract.rs`): `Σ_k J_k Q_k J_kᵀ` over the
//! stream samples, `J_k` by central differences of the deltas alone, `Q_k` from the documented
//! cell rule (the reference's accuracy: the module docs of `linearisation.rs`).

use super::V3;
use nalgebra::{Matrix3, SMatrix};
use preint::{
    CellRule, ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Preintegrator, Scheme,
};
use preint_lie::SO3;

pub type M9 = SMatrix<f64, 9, 9>;
pub type M96 = SMatrix<f64, 9, 6>;

pub const TOL: f64 = 1e-9;
pub const EPS: f64 = 1e-3;

/// Smooth motion sampled from t = 1 s every 5 ms (± 1.5 ms uniform jitter if asked).
pub fn stream(n: usize, jitter: bool) -> Vec<ImuSample> {
    let mut t: i64 = 1_000_000_000;
    let mut st: u64 = 12345;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let x = t as f64 * 1e-9;
        out.push(ImuSample::new(
            t,
            V3::new(
                0.8 * (1.3 * x).sin() + 0.2,
                -0.5 * (0.7 * x).cos(),
                1.1 * (2.1 * x).sin(),
            ),
            V3::new(
                (0.9 * x).sin(),
                0.5 + 0.3 * (1.7 * x).cos(),
                9.81 + 0.7 * (2.5 * x).sin(),
            ),
        ));
        let mut dt = 5_000_000i64;
        if jitter {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            dt += ((st >> 33) % 3_000_000) as i64 - 1_500_000;
        }
        t += dt;
    }
    out
}

pub fn bias() -> ImuBias {
    ImuBias::new(V3::new(0.01, -0.02, 0.005), V3::new(0.1, 0.05, -0.2))
}

pub fn params(scheme: Scheme, aniso: bool) -> PreintParams {
    let mut p = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Covariance);
    if aniso {
        p.acc_cov = Matrix3::new(4.0, 1.0, 0.5, 1.0, 2.0, -0.3, 0.5, -0.3, 1.0) * 1e-4;
        p.gyro_cov = Matrix3::new(3.0, 0.2, 0.1, 0.2, 2.0, -0.1, 0.1, -0.1, 1.0) * 1e-7;
    }
    p
}

pub fn direct(p: &PreintParams, s: &[ImuSample]) -> PreintegratedImu {
    let mut pi = Preintegrator::new(p.clone(), bias()).unwrap();
    pi.integrate_slice(s).unwrap();
    pi.finish().unwrap()
}

/// The documented cell of stream sample k [s] (the scheme's `preint::CellRule`), written
/// out: the interval held (`Held`: the one after, the one before for the last sample) or the
/// mean of the adjacent intervals (`Centered`: the one there at an end).
pub fn cell(scheme: Scheme, s: &[ImuSample], k: usize) -> f64 {
    let h = |i: usize| (s[i + 1].t_ns - s[i].t_ns) as f64 * 1e-9;
    let n = s.len();
    match scheme.cell_rule() {
        CellRule::Held => {
            if k + 1 < n {
                h(k)
            } else {
                h(k - 1)
            }
        }
        CellRule::Centered => {
            if k == 0 {
                h(0)
            } else if k + 1 == n {
                h(n - 2)
            } else {
                0.5 * (h(k - 1) + h(k))
            }
        }
    }
}

/// `[Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀]` as a 9-vector.
pub fn err9(r: &SO3, v: &V3, p: &V3, r0: &SO3, v0: &V3, p0: &V3) -> SMatrix<f64, 9, 1> {
    let e = r0.inverse().compose(r).log();
    let (dv, dp) = (v - v0, p - p0);
    SMatrix::<f64, 9, 1>::from_iterator(e.iter().chain(dv.iter()).chain(dp.iter()).copied())
}

/// Deltas of one evaluation: `(ΔR, Δv, Δp)`.
pub type Deltas = (SO3, V3, V3);

pub fn of(m: &PreintegratedImu) -> Deltas {
    (m.delta_r, m.delta_v, m.delta_p)
}

/// `Σ_k J_k Q_k J_kᵀ` over the samples `range` of `s`, `J_k` by central differences of `f`.
pub fn brute(
    scheme: Scheme,
    prm: &PreintParams,
    s: &[ImuSample],
    range: std::ops::Range<usize>,
    f: &dyn Fn(&[ImuSample]) -> Deltas,
) -> M9 {
    let (r0, v0, p0) = f(s);
    let mut cov = M9::zeros();
    let mut buf = s.to_vec();
    for k in range {
        let mut jk = M96::zeros();
        for c in 0..6 {
            let mut eval = |e: f64| {
                buf[k] = s[k];
                if c < 3 {
                    buf[k].gyro[c] += e;
                } else {
                    buf[k].acc[c - 3] += e;
                }
                let (r, v, p) = f(&buf);
                err9(&r, &v, &p, &r0, &v0, &p0)
            };
            let col = (eval(EPS) - eval(-EPS)) / (2.0 * EPS);
            buf[k] = s[k];
            jk.fixed_view_mut::<9, 1>(0, c).copy_from(&col);
        }
        let sc = 1.0 / cell(scheme, s, k);
        let mut q = SMatrix::<f64, 6, 6>::zeros();
        q.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(prm.gyro_cov * sc));
        q.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(prm.acc_cov * sc));
        cov += jk * q * jk.transpose();
    }
    cov
}

/// Largest over the 3×3 blocks of `‖A_rc − B_rc‖ / √(‖B_rr‖ ‖B_cc‖)` (Frobenius).
pub fn block_rel(a: &M9, b: &M9) -> f64 {
    let mut w: f64 = 0.0;
    for r in 0..3 {
        for c in 0..3 {
            let x = a.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
            let y = b.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
            let dr = b.fixed_view::<3, 3>(3 * r, 3 * r).norm();
            let dc = b.fixed_view::<3, 3>(3 * c, 3 * c).norm();
            w = w.max((x - y).norm() / (dr * dc).sqrt());
        }
    }
    w
}

pub fn check(what: &str, code: &M9, exact: &M9) -> f64 {
    let e = block_rel(code, exact);
    eprintln!("{what:58} block rel {e:.2e}");
    assert!(
        e < TOL,
        "{what}: covariance differs from the linearisation by {e:e}"
    );
    e
}
