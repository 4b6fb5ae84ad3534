//! Whether the ground truth's errors are correlated in time: the lag-one correlation of the
//! whitened residuals of back-to-back windows against what the fitted model predicts.
//!
//! The noise model takes each ground-truth row's error as independent of every other row's.
//! Two back-to-back windows `w`, `w+1` share the row at their junction, so under the model
//! their residuals correlate only through that row's error:
//! `E[r_w r_{w+1}ᵀ] = J_{j,w} S J_{i,w+1}ᵀ`, `S = diag(σ_R² I, σ_p² I, σ_v² I)` in the
//! `NavState` tangent [δφ, δp, δv]. With `u_w = L_w⁻¹ r_w` the whitened residual
//! (`L_w L_wᵀ = Σ_w`), the observed correlation per component is `ρ̂ = mean_w u_wᵀ u_{w+1} / 9`
//! and the model's `ρ = mean_w tr(L_w⁻¹ C_w L_{w+1}⁻ᵀ) / 9`. Each term `u_wᵀ u_{w+1} / 9` has a
//! variance close to 1/9 (nine products of nearly independent unit normals), so the standard
//! error of `ρ̂` over `n` pairs is taken as `1 / (3 √n)`. A smoothed ground truth (a spline or
//! a smoother's output, as motion-capture products are) has errors that change slowly from row
//! to row: the residuals of neighbouring windows then correlate beyond `ρ`, by more than
//! 3 standard errors.

use crate::noise_windows::Endpoints;
use nalgebra::{SMatrix, SVector};
use preint_calib::noise_fit::{self, NoiseFit, NoiseWindow};

/// The lag-one correlation of one window length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LagCorrelation {
    /// The window length \[s\].
    pub length_s: f64,
    /// Pairs of back-to-back windows (sharing a ground-truth row).
    pub pairs: usize,
    /// `ρ̂`, observed (module docs).
    pub observed: f64,
    /// `ρ`, what the fitted model with independent row errors predicts.
    pub expected: f64,
    /// The standard error of `ρ̂`, `1 / (3 √pairs)`.
    pub std_error: f64,
}

impl LagCorrelation {
    /// `|ρ̂ − ρ| > 3` standard errors.
    pub fn correlated(&self) -> bool {
        (self.observed - self.expected).abs() > 3.0 * self.std_error
    }
}

/// Per window length, in increasing length, over the pairs of `windows` (with their
/// `ends`, in the order they were cut) that share a row; lengths with fewer than 2 pairs are
/// left out. The residuals are taken at the fit's gravity when it is supported.
pub fn lag_one(windows: &[NoiseWindow], ends: &[Endpoints], fit: &NoiseFit) -> Vec<LagCorrelation> {
    let theta = noise_fit::theta_of(fit);
    let dg = fit.gravity.map_or(SVector::zeros(), |g| g.applied());
    let mut s = SMatrix::<f64, 9, 9>::zeros();
    for k in 0..3 {
        (s[(k, k)], s[(3 + k, 3 + k)], s[(6 + k, 6 + k)]) = (theta[4], theta[5], theta[6]);
    }
    let whiten: Vec<Option<SMatrix<f64, 9, 9>>> = windows
        .iter()
        .map(|w| noise_fit::covariance(w, &theta).cholesky().map(|c| c.l()))
        .collect();
    let mut lengths: Vec<f64> = windows.iter().map(|w| w.length_s).collect();
    lengths.sort_by(f64::total_cmp);
    lengths.dedup();
    let mut out = Vec::new();
    for l in lengths {
        let (mut n, mut obs, mut exp) = (0usize, 0.0, 0.0);
        for a in 0..windows.len().saturating_sub(1) {
            let b = a + 1;
            let adjacent = windows[a].length_s == l
                && windows[b].length_s == l
                && ends[a].t_ns.1 == ends[b].t_ns.0;
            let (Some(la), Some(lb), true) = (&whiten[a], &whiten[b], adjacent) else {
                continue;
            };
            let (Some(ia), Some(ib)) = (la.try_inverse(), lb.try_inverse()) else {
                continue;
            };
            let u = |i: &SMatrix<f64, 9, 9>, w: &NoiseWindow| i * (w.r + w.gravity_jacobian * dg);
            obs += u(&ia, &windows[a]).dot(&u(&ib, &windows[b])) / 9.0;
            let c = ends[a].state.1 * s * ends[b].state.0.transpose();
            exp += (ia * c * ib.transpose()).trace() / 9.0;
            n += 1;
        }
        if n >= 2 {
            out.push(LagCorrelation {
                length_s: l,
                pairs: n,
                observed: obs / n as f64,
                expected: exp / n as f64,
                std_error: 1.0 / (3.0 * (n as f64).sqrt()),
            });
        }
    }
    out
}

/// One sentence: whether the ground truth's errors look correlated in time, and where.
pub fn verdict(rows: &[LagCorrelation]) -> String {
    let bad: Vec<String> = rows
        .iter()
        .filter(|r| r.correlated())
        .map(|r| {
            format!(
                "{} s (ρ̂ = {:.3}, the model {:.3} ± {:.3})",
                r.length_s, r.observed, r.expected, r.std_error
            )
        })
        .collect();
    if rows.is_empty() {
        "no back-to-back windows: the correlation in time cannot be told".into()
    } else if bad.is_empty() {
        "the residuals of back-to-back windows correlate as independent row errors predict: no \
         sign of ground-truth errors correlated in time"
            .into()
    } else {
        format!(
            "the residuals of back-to-back windows correlate beyond what independent row errors \
             predict at {}: the ground truth's errors look correlated in time (a smoothed \
             product); the fitted ground-truth σ then stand for a correlated error",
            bad.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use preint_calib::noise_fit::{NoiseFitOptions, PARAMS, fit};
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;

    /// A seeded standard normal.
    struct Normal(StdRng);

    impl Normal {
        fn next(&mut self) -> f64 {
            self.0.sample(StandardNormal)
        }
        fn vec9(&mut self) -> SVector<f64, 9> {
            SVector::from_fn(|_, _| self.next())
        }
        fn mat9(&mut self) -> SMatrix<f64, 9, 9> {
            SMatrix::from_fn(|_, _| self.next())
        }
    }

    /// `n` back-to-back windows of 1 s: white noise of unit basis `B_w = M Mᵀ/9` plus the
    /// ground truth's error at the shared rows, `r_w = n_w + J_i e_w + J_j e_{w+1}`
    /// (`J_i ≈ −J_j`), the row
    /// errors `e_k` an AR(1) sequence of coefficient `phi` (0: independent) and unit variance
    /// per component (`σ_R = σ_p = σ_v = 1`).
    fn windows(n: usize, phi: f64, seed: u64) -> (Vec<NoiseWindow>, Vec<Endpoints>) {
        let mut g = Normal(StdRng::seed_from_u64(seed));
        let mut e = g.vec9();
        let mut rows = vec![e];
        for _ in 0..n {
            e = e * phi + g.vec9() * (1.0 - phi * phi).sqrt();
            rows.push(e);
        }
        let unit = |k: usize| {
            SMatrix::<f64, 9, 9>::from_fn(|r, c| if r == c && r / 3 == k { 1.0 } else { 0.0 })
        };
        // As in a real factor, ∂r/∂x_i ≈ −∂r/∂x_j: the shared row moves neighbours apart.
        let a = g.mat9() * 0.5;
        (0..n)
            .map(|w| {
                let m = g.mat9();
                let (ji, jj) = (-a + g.mat9() * 0.1, a + g.mat9() * 0.1);
                let white = m * m.transpose() / 9.0;
                let l = white.cholesky().unwrap().l();
                let r = l * g.vec9() + ji * rows[w] + jj * rows[w + 1];
                let mut basis = [SMatrix::<f64, 9, 9>::zeros(); PARAMS];
                basis[0] = white;
                for k in 0..3 {
                    let p = unit(k);
                    basis[4 + k] = ji * p * ji.transpose() + jj * p * jj.transpose();
                }
                let t = w as i64 * 1_000_000_000;
                (
                    NoiseWindow {
                        length_s: 1.0,
                        r,
                        basis,
                        gravity_jacobian: SMatrix::zeros(),
                        block: w,
                    },
                    Endpoints {
                        t_ns: (t, t + 1_000_000_000),
                        state: (ji, jj),
                    },
                )
            })
            .unzip()
    }

    fn lag(phi: f64, seed: u64) -> LagCorrelation {
        let (w, e) = windows(300, phi, seed);
        let held = [
            None,
            Some(0.0),
            Some(0.0),
            Some(0.0),
            None,
            None,
            None,
            Some(0.0),
            Some(0.0),
        ];
        let opts = NoiseFitOptions {
            held,
            ..NoiseFitOptions::default()
        };
        let f = fit(&w, &opts).unwrap();
        let rows = lag_one(&w, &e, &f);
        assert_eq!(rows.len(), 1);
        rows[0]
    }

    /// Independent row errors: the observed lag-one correlation matches the model's
    /// (negative: the shared row enters both windows) in at least 19 of 20 seeds; row errors
    /// correlated from row to row (AR(1), φ = 0.8) are told in every seed.
    #[test]
    fn tells_row_errors_correlated_in_time_from_independent_ones() {
        let mut agree = 0;
        for seed in 1..=20 {
            let r = lag(0.0, seed);
            assert!(r.expected < -2.0 * r.std_error, "{r:?}");
            agree += usize::from(!r.correlated());
            let c = lag(0.8, 100 + seed);
            assert!(c.correlated() && c.observed > c.expected, "{c:?}");
        }
        assert!(
            agree >= 19,
            "independent errors agreed in {agree} of 20 seeds"
        );
        assert!(verdict(&[lag(0.8, 7)]).contains("correlated in time"));
        assert!(verdict(&[lag(0.0, 7)]).contains("no sign"));
    }
}
