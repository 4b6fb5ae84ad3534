//! The statistics of the overlapping Allan variance under a noise model: the covariance of two
//! of its estimates, the equivalent degrees of freedom (EDF) of one, and the normal-equivalent
//! deviate of an estimate against a model.
//!
//! # Covariance and EDF
//! An Allan variance estimate `σ̂²(τ)` is distributed as `σ²·χ²_ν/ν` for some `ν`, its
//! equivalent degrees of freedom (Howe, Allan, Barnes, "Properties of signal sources and
//! measurement methods", 35th Frequency Control Symposium, 1981; IEEE Std 952-1997 Annex C;
//! NIST SP 1065, 2008, §5.3), and its relative error in σ is `ε = 1/√(2ν)`. `ν` depends on the
//! noise: for the overlapping estimator at m samples per cluster over n samples, with
//! `r = (n + 1 − 2m)/m ≈ clusters − 2`, `ν ≈ 1.5 r` for white rate noise (white FM, slope −½)
//! but `≈ 0.93 r` for rate random walk (random-walk FM, slope +½): at 8 clusters 5.9, not the
//! `clusters − 1 = 7` of independent clusters.
//!
//! Computed as C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on
//! finite differences", 35th PTTI Meeting, 2003, eqs. (7)–(10), and extended to pairs of τ and to
//! mixtures. With the phase (angle) `x(t) = ∫ y`, the estimate at `τ = mΔt` is
//! `σ̂²(τ) = Σ_k D_τ(kΔt)²/(2τ²M)`, `D_τ(u) = x(u + 2τ) − 2x(u + τ) + x(u)`,
//! `M = n + 1 − 2m`. The second differences are Gaussian, so
//! `Cov(σ̂²(τ_i), σ̂²(τ_j)) = 2 Σ_s c(s) C_ij(sΔt)² / (4τ_i²τ_j² M_i M_j)` with
//! `C_ij(s) = Cov(D_{τ_i}(0), D_{τ_j}(s))` and `c(s)` the number of pairs of terms at lag s
//! (Greenhall's `(1 − j/M)` weights). `C_ij` is the double second difference of the phase's
//! generalised autocovariance (Greenhall's `sx`, in the limit F = ∞: the phase sampled at the
//! sample instants, each rate sample its increment over Δt, as an IMU's rate samples are),
//! for the two noises of the fitted model, independent so that they add,
//!
//! `R(t) = −N²|t|/2 + K²|t|³/12`
//!
//! (white noise of density N, rate random walk K; each term gives `Var D_τ = 2τ²σ²(τ)` with
//! `σ² = N²/τ + K²τ/3`, and both make `C_ij` vanish beyond `−2τ_j < s < 2τ_i`). Then
//! `ν = 2σ⁴/Var σ̂²`. For white noise it meets NIST SP 1065's Table 5 approximation
//! `[3(N_x − 1)/(2m) − 2(N_x − 2)/N_x]·4m²/(4m² + 5)` (N_x = n + 1 phase points) within 0.03 %
//! up to m = 100, and for long clusters Greenhall and Riley's Table 2, `1/ν = (a₀ − a₁/r)/r`
//! with (a₀, a₁) = (2/3, 1/3) for white noise and (1.079, 0.368) for a random walk, within
//! 0.1 % (`calib/tests/allan_edf.rs`, with Monte Carlo). The lag sum has at most
//! `2(m_i + m_j) − 1` terms; beyond [`EXACT_LAGS`] it is a trapezoid rule on that many
//! intervals (relative error < 1e-5).
//!
//! # Normal-equivalent deviate
//! [`normal_deviate`]: how far `σ̂²` lies from a model `σ_m²`, as the standard normal deviate of
//! the same tail probability under `σ̂² ~ σ_m² χ²_ν/ν` (statrs' χ² distribution, the
//! regularised incomplete gamma functions of [`crate::fit`], and its normal quantile). It is
//! `(σ̂ − σ_m)/(σ_m ε)` for large ν and keeps the skewed χ² tails at few degrees of freedom:
//! at 8 clusters of a random walk (ν = 5.9) a correct point lies below `σ_m/(1 + 3ε)` with
//! probability 5 %, which a linear band `σ(1 ± 3ε)` would call a 3σ event, and the point's
//! upper 4σ confidence limit is ≈ 7σ̂, not `(1 + 4ε)σ̂ = 2.2σ̂`. [`chi2_quantile_ratio`]
//! inverts it.

use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};
use statrs::function::gamma::ln_gamma;

/// Levels of the noise model `σ²(τ) = N²/τ + K²τ/3`, in the squared units of the signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseLevels {
    /// `N²`: white rate noise of density N \[u/√Hz\] (white FM).
    pub white: f64,
    /// `K²`: rate random walk K \[u/s/√Hz\] (random-walk FM).
    pub random_walk: f64,
}

impl NoiseLevels {
    /// White noise of density `n` only.
    pub fn white(n: f64) -> Self {
        Self {
            white: n * n,
            random_walk: 0.0,
        }
    }

    /// The model's Allan variance at τ \[s\].
    pub fn avar(&self, tau: f64) -> f64 {
        self.white / tau + self.random_walk * tau / 3.0
    }

    /// The generalised autocovariance of the phase at lag t \[s\] (module docs).
    fn phase_autocovariance(&self, t: f64) -> f64 {
        let a = t.abs();
        -0.5 * self.white * a + self.random_walk * a * a * a / 12.0
    }

    /// `Cov(D_{τ_i}(0), D_{τ_j}(s))` (module docs).
    fn second_difference_covariance(&self, tau_i: f64, tau_j: f64, s: f64) -> f64 {
        const C: [f64; 3] = [1.0, -2.0, 1.0];
        let mut sum = 0.0;
        for (p, cp) in C.iter().enumerate() {
            for (q, cq) in C.iter().enumerate() {
                sum += cp * cq * self.phase_autocovariance(p as f64 * tau_i - s - q as f64 * tau_j);
            }
        }
        sum
    }
}

/// Lags of the covariance sum taken one by one; longer sums are integrated (module docs).
pub const EXACT_LAGS: usize = 400;

/// `Cov(σ̂²(m_iΔt), σ̂²(m_jΔt))` of the overlapping estimator over `n` samples of period `dt`
/// under the model `levels` (module docs). NaN when a cluster size is 0 or `2m > n`.
pub fn avar_covariance(levels: &NoiseLevels, dt: f64, n: usize, m_i: usize, m_j: usize) -> f64 {
    if m_i == 0 || m_j == 0 || 2 * m_i > n || 2 * m_j > n {
        return f64::NAN;
    }
    let (ti, tj) = (m_i as f64 * dt, m_j as f64 * dt);
    let (mi, mj) = ((n + 1 - 2 * m_i) as f64, (n + 1 - 2 * m_j) as f64);
    // Pairs (k, l = k + s) with 0 ≤ k < M_i, 0 ≤ l < M_j.
    let pairs = |s: f64| (mi.min(mj - s) - (-s).max(0.0)).max(0.0);
    let term = |s: f64| pairs(s) * levels.second_difference_covariance(ti, tj, s * dt).powi(2);
    // C_ij vanishes outside −2m_j < s < 2m_i, the pairs outside −M_i < s < M_j.
    let lo = -((2 * m_j).min(n + 1 - 2 * m_i) as i64);
    let hi = (2 * m_i).min(n + 1 - 2 * m_j) as i64;
    let sum = if hi - lo - 1 <= EXACT_LAGS as i64 {
        (lo + 1..hi).map(|s| term(s as f64)).sum::<f64>()
    } else {
        let (lo, hi) = (lo as f64, hi as f64);
        let h = (hi - lo) / EXACT_LAGS as f64;
        h * (1..EXACT_LAGS)
            .map(|k| term(lo + k as f64 * h))
            .sum::<f64>()
    };
    2.0 * sum / (4.0 * ti * ti * tj * tj * mi * mj)
}

/// The EDF `ν = 2σ⁴/Var σ̂²` of the overlapping Allan variance at `m` samples per cluster over
/// `n` samples of period `dt` under the model `levels` (module docs); NaN without a positive
/// model variance or for `2m > n`.
///
/// ```
/// use preint_calib::allan::edf::{NoiseLevels, edf};
/// // 80 000 samples, m = 10 000 (8 clusters, r = 6): white noise 9.82, random walk 5.90
/// // (Greenhall–Riley Table 2: r/(2/3 − 1/(3r)) and r/(1.079 − 0.368/r)).
/// let walk = NoiseLevels { white: 0.0, random_walk: 1.0 };
/// let (w, k) = (edf(&NoiseLevels::white(1.0), 0.01, 80_000, 10_000), edf(&walk, 0.01, 80_000, 10_000));
/// assert!((w - 9.82).abs() < 0.01 && (k - 5.90).abs() < 0.01, "{w} {k}");
/// ```
pub fn edf(levels: &NoiseLevels, dt: f64, n: usize, m: usize) -> f64 {
    let s2 = levels.avar(m as f64 * dt);
    if s2.is_nan() || s2 <= 0.0 {
        return f64::NAN;
    }
    2.0 * s2 * s2 / avar_covariance(levels, dt, n, m, m)
}

/// The standard normal deviate of `ratio = σ̂²/σ_m²` under `σ̂² ~ σ_m² χ²_ν/ν` (module docs):
/// the `z` with `Φ(z) = P(χ²_ν/ν ≤ ratio)`, positive when the estimate lies above the model.
/// Where that tail probability underflows (|z| > 37) it is taken from the leading term of the
/// tail and of the normal's (`−∞` at `ratio = 0`). NaN for `ν ≤ 0`.
pub fn normal_deviate(ratio: f64, nu: f64) -> f64 {
    let (Ok(chi2), Ok(normal)) = (ChiSquared::new(nu), Normal::new(0.0, 1.0)) else {
        return f64::NAN;
    };
    let (x, a) = (nu * ratio.max(0.0), 0.5 * nu);
    if ratio >= 1.0 {
        let z = -normal.inverse_cdf(chi2.sf(x));
        if z.is_finite() {
            return z;
        }
        // Q(a, x/2) ≈ (x/2)^{a−1} e^{−x/2}/Γ(a) for x ≫ a.
        normal_tail_deviate((a - 1.0) * (0.5 * x).ln() - 0.5 * x - ln_gamma(a))
    } else {
        let z = normal.inverse_cdf(chi2.cdf(x));
        if z.is_finite() {
            return z;
        }
        // P(a, x/2) ≈ (x/2)^a/Γ(a + 1) for x ≪ a.
        -normal_tail_deviate(a * (0.5 * x).ln() - ln_gamma(a + 1.0))
    }
}

/// The `t > 0` with `ln Φ(−t) = ln_p` for `ln_p` below the smallest normal f64 (t > 37), from
/// `ln Φ(−t) ≈ −t²/2 − ln t − ln √(2π)` by Newton's method (`∞` for `ln_p = −∞`).
fn normal_tail_deviate(ln_p: f64) -> f64 {
    if ln_p == f64::NEG_INFINITY {
        return f64::INFINITY;
    }
    let mut t = (-2.0 * ln_p).sqrt();
    for _ in 0..8 {
        let f = -0.5 * t * t - t.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln() - ln_p;
        t -= f / (-t - 1.0 / t);
    }
    t
}

/// The ratio `σ̂²/σ_m²` whose [`normal_deviate`] is `z` (its inverse): the `Φ(z)` quantile of
/// `χ²_ν/ν`, by bisection on `ln r` from the Wilson–Hilferty approximation
/// `(1 − 2/(9ν) + z√(2/(9ν)))³` (E. B. Wilson, M. M. Hilferty, "The distribution of
/// chi-square", PNAS 17, 1931), to 1e-12 relative. NaN for `ν ≤ 0`.
pub fn chi2_quantile_ratio(z: f64, nu: f64) -> f64 {
    let (Ok(chi2), Ok(normal)) = (ChiSquared::new(nu), Normal::new(0.0, 1.0)) else {
        return f64::NAN;
    };
    // `above(r)`: r lies above the quantile (the tail beyond it is the smaller one, taken from
    // the side where it is computed without cancellation).
    let above = |r: f64| {
        if z <= 0.0 {
            chi2.cdf(nu * r) > normal.cdf(z)
        } else {
            chi2.sf(nu * r) < normal.cdf(-z)
        }
    };
    let v = 2.0 / (9.0 * nu);
    let guess = (1.0 - v + z * v.sqrt()).max(0.0).powi(3);
    let (mut lo, mut hi) = if guess > 0.0 {
        (0.5 * guess, 2.0 * guess)
    } else {
        (1e-300, 1.0)
    };
    while above(lo) && lo > 1e-300 {
        lo = (lo * 1e-3).max(1e-300);
    }
    while !above(hi) && hi < 1e300 {
        hi *= 4.0;
    }
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if above(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi <= lo * (1.0 + 1e-12) {
            break;
        }
    }
    (lo * hi).sqrt()
}
