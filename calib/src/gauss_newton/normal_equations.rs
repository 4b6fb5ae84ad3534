//! The normal equations `H δ = −g` (`H = JᵀJ`, `g = Jᵀr`): factorisation, rank test and
//! steps (module docs of [`super`], "Iteration", steps 1 and 3).
//!
//! `H` is factored by Cholesky; a cheap rank test (power iteration for `λ_max`, inverse
//! iteration through the factor for `λ_min`) decides whether it is well conditioned. Only when
//! Cholesky fails or the test flags a (near) deficiency is the symmetric eigen-decomposition
//! computed, which splits the tangent into observable and unobservable directions; the steps
//! are then restricted to the observable subspace.

use super::GnError;
use nalgebra::{Cholesky, DMatrix, DVector, Dyn, SymmetricEigen};

/// Observability analysis of `H = JᵀJ`.
#[derive(Clone, Debug)]
pub(crate) struct Spectrum {
    /// Observable eigenvectors (columns).
    pub(crate) obs: DMatrix<f64>,
    /// Their eigenvalues.
    pub(crate) obs_eig: DVector<f64>,
    /// Unobservable eigenvectors (columns, signs made deterministic).
    pub(crate) unobs: DMatrix<f64>,
}

/// Eigen-decomposition of `h` split at `rel·λ_max`: eigenvalues above are observable.
fn spectrum(h: &DMatrix<f64>, rel: f64) -> Spectrum {
    let n = h.nrows();
    let eig = SymmetricEigen::new(h.clone());
    let lmax = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let thr = rel * lmax;
    let mut obs = Vec::new();
    let mut unobs = Vec::new();
    for i in 0..n {
        if lmax > 0.0 && eig.eigenvalues[i] > thr {
            obs.push(i);
        } else {
            unobs.push(i);
        }
    }
    let cols = |idx: &[usize]| DMatrix::from_fn(n, idx.len(), |r, c| eig.eigenvectors[(r, idx[c])]);
    Spectrum {
        obs: cols(&obs),
        obs_eig: DVector::from_iterator(obs.len(), obs.iter().map(|&i| eig.eigenvalues[i])),
        unobs: canonical_basis(cols(&unobs)),
    }
}

/// Makes the sign of each basis vector deterministic (largest-magnitude entry positive).
fn canonical_basis(mut b: DMatrix<f64>) -> DMatrix<f64> {
    for mut c in b.column_iter_mut() {
        let k = c.iamax();
        if c[k] < 0.0 {
            c.neg_mut();
        }
    }
    b
}

/// Safety factor of the Cholesky rank test (module docs): the system is treated as well
/// conditioned when the estimated `λ_min > RANK_TEST_SAFETY·rank_threshold·λ_max`.
const RANK_TEST_SAFETY: f64 = 100.0;
/// Power / inverse iterations of the rank test.
const RANK_TEST_ITERS: usize = 30;

/// A fixed pseudo-random unit vector (splitmix64 hash of the index): a start vector with no
/// structure, so that it is not orthogonal to the eigenvectors the test looks for.
fn start_vector(n: usize) -> DVector<f64> {
    let v = DVector::from_fn(n, |i, _| {
        let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let nrm = v.norm();
    v / nrm
}

/// Estimates `(λ_min, λ_max)` of the SPD matrix `h` with Cholesky factor `ch`: inverse
/// iteration (`λ_min` estimate ≥ the true value) and power iteration (≤ the true value, at
/// least `max diag`).
fn extreme_eigenvalues(h: &DMatrix<f64>, ch: &Cholesky<f64, Dyn>) -> (f64, f64) {
    let n = h.nrows();
    let mut v = start_vector(n);
    let mut lmax = h.diagonal().max();
    for _ in 0..RANK_TEST_ITERS {
        let w = h * &v;
        let nw = w.norm();
        if !(nw.is_finite() && nw > 0.0) {
            break;
        }
        lmax = lmax.max(nw);
        v = w / nw;
    }
    let mut v = start_vector(n);
    let mut lmin = f64::INFINITY;
    for _ in 0..RANK_TEST_ITERS {
        let w = ch.solve(&v);
        let nw = w.norm();
        if !(nw.is_finite() && nw > 0.0) {
            return (0.0, lmax);
        }
        lmin = 1.0 / nw;
        v = w / nw;
    }
    (lmin, lmax)
}

/// Factorisation of the normal equations `H = JᵀJ` (module docs, step 1).
pub(crate) enum Normal {
    /// Well conditioned: `H = LLᵀ`.
    Full(Cholesky<f64, Dyn>),
    /// Cholesky failed or the rank test flagged a deficiency: eigen-decomposition.
    Deficient(Spectrum),
}

impl Normal {
    /// Factorises `h` with the rank test at the relative threshold `rel`.
    pub(crate) fn of(h: &DMatrix<f64>, rel: f64) -> Self {
        let n = h.nrows();
        if n > 0
            && let Some(ch) = h.clone().cholesky()
        {
            let (lmin, lmax) = extreme_eigenvalues(h, &ch);
            if lmax.is_finite() && lmin > RANK_TEST_SAFETY * rel * lmax {
                return Normal::Full(ch);
            }
        }
        Normal::Deficient(spectrum(h, rel))
    }

    /// Number of observable directions of an n×n `H`.
    pub(crate) fn rank(&self, n: usize) -> usize {
        match self {
            Normal::Full(_) => n,
            Normal::Deficient(sp) => sp.obs.ncols(),
        }
    }

    /// The undamped Gauss-Newton step `−H⁺g`.
    pub(crate) fn gn_step(&self, g: &DVector<f64>) -> DVector<f64> {
        match self {
            Normal::Full(ch) => -ch.solve(g),
            Normal::Deficient(sp) => {
                let y = sp.obs.tr_mul(g).component_div(&sp.obs_eig);
                -(&sp.obs * y)
            }
        }
    }

    /// The damped step `−(H + μD)⁻¹g` (restricted to the observable subspace when deficient).
    pub(crate) fn damped_step(
        &self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        mu: f64,
        gn: &DVector<f64>,
    ) -> Result<DVector<f64>, GnError> {
        if mu == 0.0 {
            return Ok(gn.clone());
        }
        let n = h.nrows();
        let mut a = h.clone();
        for i in 0..n {
            a[(i, i)] += mu * h[(i, i)].clamp(1e-6, 1e32);
        }
        match self {
            Normal::Full(_) => match a.cholesky() {
                Some(ch) => Ok(-ch.solve(g)),
                None => Normal::Deficient(spectrum(h, 0.0)).damped_step(h, g, mu, gn),
            },
            Normal::Deficient(sp) => {
                if sp.obs.ncols() == 0 {
                    return Ok(DVector::zeros(n));
                }
                let ar = sp.obs.tr_mul(&(&a * &sp.obs));
                let ch = ar.cholesky().ok_or(GnError::Cholesky)?;
                Ok(-(&sp.obs * ch.solve(&sp.obs.tr_mul(g))))
            }
        }
    }
}

impl Normal {
    /// The covariance `H⁻¹` (well conditioned) or the pseudo-inverse `Σ_observable v vᵀ/λ`,
    /// the orthonormal basis of the unobservable directions (n×0 when there are none) and the
    /// rank.
    pub(crate) fn covariance(self, n: usize) -> (DMatrix<f64>, DMatrix<f64>, usize) {
        match self {
            Normal::Full(ch) => (ch.inverse(), DMatrix::zeros(n, 0), n),
            Normal::Deficient(sp) => {
                let inv =
                    DVector::from_iterator(sp.obs_eig.len(), sp.obs_eig.iter().map(|l| 1.0 / l));
                let cov = &sp.obs * DMatrix::from_diagonal(&inv) * sp.obs.transpose();
                let rank = sp.obs.ncols();
                (cov, sp.unobs, rank)
            }
        }
    }
}

/// `JᵀJ` through a transposed copy, so that nalgebra uses its blocked matrix product
/// (`tr_mul` evaluates one dot product per entry, ≈ 20× slower for the 1000×400 Jacobians of
/// the known-pose problem); symmetrised exactly.
pub(crate) fn gram(j: &DMatrix<f64>) -> DMatrix<f64> {
    let h = j.transpose() * j;
    (&h + h.transpose()) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(eigs: &[f64], seed: f64) -> DMatrix<f64> {
        let n = eigs.len();
        let a = DMatrix::from_fn(n, n, |i, j| ((i * n + j) as f64 * seed).sin());
        let q = a.qr().q();
        &q * DMatrix::from_diagonal(&DVector::from_column_slice(eigs)) * q.transpose()
    }

    /// The rank test's eigenvalue estimates against nalgebra's symmetric eigen-decomposition.
    #[test]
    fn extreme_eigenvalue_estimates_match_eigen_decomposition() {
        for eigs in [
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            vec![1e-6, 1e-3, 1.0, 10.0, 100.0, 1e4, 1e5, 1e6],
            vec![3.0, 3.0, 3.0, 3.0],
        ] {
            let h = spd(&eigs, 0.7);
            let ch = h.clone().cholesky().unwrap();
            let (lmin, lmax) = extreme_eigenvalues(&h, &ch);
            let e = SymmetricEigen::new(h.clone()).eigenvalues;
            let (tmin, tmax) = (e.min(), e.max());
            // Both sides carry round-off ≈ ε·λ_max in λ_min (1e-4 relative at cond 1e12).
            let tol = 1e-6 + 1e3 * f64::EPSILON * tmax / tmin;
            assert!(((lmin - tmin) / tmin).abs() < tol, "{lmin} vs {tmin}");
            assert!(((lmax - tmax) / tmax).abs() < 1e-6, "{lmax} vs {tmax}");
        }
    }

    /// Cholesky path for a well-conditioned matrix; eigen path when λ_min/λ_max is below
    /// 100·rank_threshold, or exactly singular; in both cases the covariance is right.
    #[test]
    fn rank_test_chooses_the_path() {
        let rel = 1e-10;
        let good = spd(&[1e-4, 1.0, 2.0, 50.0], 0.3);
        assert!(matches!(Normal::of(&good, rel), Normal::Full(_)));
        let near = spd(&[5e-9, 1.0, 2.0, 10.0], 0.3); // ratio 5e-10 < 100·1e-10 = 1e-8
        let Normal::Deficient(sp) = Normal::of(&near, rel) else {
            panic!("near-deficient matrix taken as well conditioned")
        };
        assert_eq!(sp.obs.ncols(), 4, "still above the rank threshold itself");
        let singular = spd(&[0.0, 1.0, 2.0, 10.0], 0.3);
        let Normal::Deficient(sp) = Normal::of(&singular, rel) else {
            panic!("singular matrix taken as well conditioned")
        };
        assert_eq!(sp.obs.ncols(), 3);
        // The undamped step agrees between the two paths on a full-rank system.
        let g = DVector::from_column_slice(&[1.0, -2.0, 0.5, 3.0]);
        let a = Normal::of(&good, rel).gn_step(&g);
        let b = Normal::Deficient(spectrum(&good, rel)).gn_step(&g);
        assert!((&a - &b).amax() < 1e-9 * a.amax(), "{a} vs {b}");
        let exact = -good.clone().try_inverse().unwrap() * &g;
        assert!((&a - &exact).amax() < 1e-9 * a.amax());
    }
}
