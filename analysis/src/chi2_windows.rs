//! The χ² of many factors at the ground truth, back-to-back windows of one length: are they
//! distributed as `χ²_dof`, as a correct noise model predicts?
//!
//! Per length: the mean and median χ², the fraction of windows above the 0.99 quantile of
//! `χ²_dof`, the Kolmogorov–Smirnov test of the windows' χ² against `χ²_dof` and the mean share
//! of the χ² each block carries (`r_bᵀ (Σ⁻¹ r)_b / χ²`, [`crate::consistency`]). Over all
//! lengths, a [`Verdict`]: the noise model is consistent, optimistic (its σ too small) from some
//! window length on, or pessimistic.
//!
//! # The Kolmogorov–Smirnov test
//! `D_n = sup_x |F_n(x) − F(x)|` over the empirical distribution `F_n` of the `n` values
//! (Kolmogorov 1933); at the sorted values `x_(1) ≤ … ≤ x_(n)`,
//! `D_n = max_i max(i/n − F(x_(i)), F(x_(i)) − (i − 1)/n)`. Its p-value is the asymptotic
//! Kolmogorov distribution `Q_KS(λ) = 2 Σ_{k≥1} (−1)^{k−1} exp(−2k²λ²)` at
//! `λ = (√n + 0.12 + 0.11/√n) D_n`, Stephens' small-sample correction (M. A. Stephens, "Use of
//! the Kolmogorov–Smirnov, Cramér–von Mises and related statistics without extensive tables",
//! J. R. Stat. Soc. B 32, 1970; Press et al., *Numerical Recipes*, 3rd ed., §14.3.3). `F` is
//! statrs' `ChiSquared` distribution function.

use crate::consistency::chi2_quantiles;
use serde_json::{Map, Value, json};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Mean `χ²/dof` above which a window length is optimistic.
pub const OPTIMISTIC_CHI2_DOF: f64 = 1.3;
/// Fraction of windows above `χ²_dof(0.99)` above which a window length is optimistic.
pub const OPTIMISTIC_FRACTION_P99: f64 = 0.05;
/// Mean `χ²/dof` (all windows of all lengths) below which the noise model is pessimistic.
pub const PESSIMISTIC_CHI2_DOF: f64 = 0.75;

/// One window's χ² and its blocks' shares `r_bᵀ (Σ⁻¹ r)_b` (summing to `chi2`).
#[derive(Clone, Debug, PartialEq)]
pub struct WindowChi2 {
    /// `rᵀ Σ⁻¹ r`.
    pub chi2: f64,
    /// Per 3-row block, in the residual's order.
    pub share: Vec<f64>,
}

/// The statistics of one window length's χ² (at least 2 windows).
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Stats {
    /// Mean χ².
    pub mean: f64,
    /// Median χ².
    pub median: f64,
    /// Fraction of windows with χ² above `χ²_dof(0.99)`.
    pub fraction_above_p99: f64,
    /// The Kolmogorov–Smirnov statistic `D_n` against `χ²_dof`.
    pub ks_statistic: f64,
    /// Its asymptotic p-value ([`kolmogorov_p_value`]); `None` when it cannot be computed.
    pub ks_p_value: Option<f64>,
    /// Per block: the mean over windows of `share_b / χ²` (they sum to 1).
    pub block_share: Vec<f64>,
}

/// One window length: how many windows, how many skipped and their statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct LengthSummary {
    /// The window length \[s\].
    pub length_s: f64,
    /// Windows evaluated.
    pub count: usize,
    /// Windows that could not be evaluated (a gap, too few samples).
    pub skipped: usize,
    /// Degrees of freedom of each window's χ².
    pub dof: usize,
    /// `None` with fewer than 2 windows.
    pub stats: Option<Chi2Stats>,
    /// Sum of the windows' χ².
    pub chi2_sum: f64,
}

/// `D_n` of `values` against the distribution function `cdf` (module docs).
///
/// # Panics
/// When `values` is empty or holds a NaN.
pub fn ks_statistic(values: &[f64], cdf: impl Fn(f64) -> f64) -> f64 {
    assert!(!values.is_empty(), "the KS statistic of no values");
    let mut x = values.to_vec();
    x.sort_by(|a, b| a.partial_cmp(b).expect("no NaN"));
    let n = x.len() as f64;
    x.iter()
        .enumerate()
        .map(|(i, &xi)| {
            let f = cdf(xi);
            ((i + 1) as f64 / n - f).max(f - i as f64 / n)
        })
        .fold(0.0, f64::max)
}

/// The asymptotic p-value `Q_KS(λ)` of `D_n = d` with `n` values (module docs); `None` for a
/// `d` outside [0, 1] or `n` = 0.
pub fn kolmogorov_p_value(d: f64, n: usize) -> Option<f64> {
    if n == 0 || !(0.0..=1.0).contains(&d) {
        return None;
    }
    let sn = (n as f64).sqrt();
    let lambda = (sn + 0.12 + 0.11 / sn) * d;
    // Below λ = 0.2 the series has not converged in 100 terms; Q_KS(0.2) = 1 − 4e-11.
    if lambda < 0.2 {
        return Some(1.0);
    }
    let mut q = 0.0;
    for k in 1..=100 {
        let kf = k as f64;
        let term = (-2.0 * kf * kf * lambda * lambda).exp();
        q += if k % 2 == 1 { 2.0 * term } else { -2.0 * term };
        if term < 1e-16 {
            break;
        }
    }
    Some(q.clamp(0.0, 1.0))
}

fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    }
}

/// The statistics of the windows of one length, each a χ² with `dof` (9 or 15) degrees of
/// freedom (module docs).
///
/// # Panics
/// For a `dof` other than 9 or 15, or a non-finite χ².
pub fn summarise(
    length_s: f64,
    dof: usize,
    windows: &[WindowChi2],
    skipped: usize,
) -> LengthSummary {
    let chi2: Vec<f64> = windows.iter().map(|w| w.chi2).collect();
    assert!(chi2.iter().all(|c| c.is_finite()), "a non-finite χ²");
    let chi2_sum = chi2.iter().sum();
    let stats = (windows.len() >= 2).then(|| stats(dof, windows, &chi2));
    LengthSummary {
        length_s,
        count: windows.len(),
        skipped,
        dof,
        stats,
        chi2_sum,
    }
}

fn stats(dof: usize, windows: &[WindowChi2], chi2: &[f64]) -> Chi2Stats {
    let n = chi2.len();
    let mut sorted = chi2.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (_, q99) = chi2_quantiles(dof);
    let dist = ChiSquared::new(dof as f64).expect("dof > 0");
    let d = ks_statistic(chi2, |x| dist.cdf(x));
    let blocks = dof / 3;
    let weighted: Vec<&WindowChi2> = windows.iter().filter(|w| w.chi2 > 0.0).collect();
    let block_share = (0..blocks)
        .map(|b| {
            let total: f64 = weighted.iter().map(|w| w.share[b] / w.chi2).sum();
            total / weighted.len().max(1) as f64
        })
        .collect();
    Chi2Stats {
        mean: chi2.iter().sum::<f64>() / n as f64,
        median: median(&sorted),
        fraction_above_p99: chi2.iter().filter(|&&c| c > q99).count() as f64 / n as f64,
        ks_statistic: d,
        ks_p_value: kolmogorov_p_value(d, n).filter(|p| p.is_finite()),
        block_share,
    }
}

/// What the windows of all lengths say about the noise model.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// No length is optimistic and the mean `χ²/dof` of all windows is ≥ 0.75.
    Consistent,
    /// Every length from `from_length_s` on has mean `χ²/dof` > 1.3 or more than 5 % of its
    /// windows above `χ²_dof(0.99)`; `factor` = √(mean χ²/dof) at `from_length_s`: the σ the
    /// noise model gives are that many times too small there.
    Optimistic {
        /// √(mean χ²/dof) at `from_length_s`.
        factor: f64,
        /// The shortest such length \[s\].
        from_length_s: f64,
    },
    /// The mean `χ²/dof` of all windows is below 0.75: the σ are `factor` = √(χ²/dof) times
    /// too large.
    Pessimistic {
        /// √(mean χ²/dof) over all windows.
        factor: f64,
    },
    /// No length has 2 windows: nothing to judge.
    Undetermined,
}

fn optimistic(s: &Chi2Stats, dof: usize) -> bool {
    s.mean / dof as f64 > OPTIMISTIC_CHI2_DOF || s.fraction_above_p99 > OPTIMISTIC_FRACTION_P99
}

/// The verdict over `lengths` (any order; the lengths with fewer than 2 windows are left out).
pub fn verdict(lengths: &[LengthSummary]) -> Verdict {
    let mut judged: Vec<(&LengthSummary, &Chi2Stats)> = lengths
        .iter()
        .filter_map(|l| l.stats.as_ref().map(|s| (l, s)))
        .collect();
    if judged.is_empty() {
        return Verdict::Undetermined;
    }
    judged.sort_by(|a, b| a.0.length_s.total_cmp(&b.0.length_s));
    let first_bad = (0..judged.len())
        .rev()
        .take_while(|&k| optimistic(judged[k].1, judged[k].0.dof))
        .last();
    if let Some(k) = first_bad {
        let (l, s) = judged[k];
        return Verdict::Optimistic {
            factor: (s.mean / l.dof as f64).sqrt(),
            from_length_s: l.length_s,
        };
    }
    let chi2: f64 = judged.iter().map(|(l, _)| l.chi2_sum).sum();
    let dof: usize = judged.iter().map(|(l, _)| l.count * l.dof).sum();
    let r = chi2 / dof as f64;
    if r < PESSIMISTIC_CHI2_DOF {
        Verdict::Pessimistic { factor: r.sqrt() }
    } else {
        Verdict::Consistent
    }
}

impl Verdict {
    /// One line: `consistent`, `noise model optimistic by ×k (σ) at windows ≥ T s`, …
    pub fn text(&self) -> String {
        match self {
            Verdict::Consistent => "consistent".into(),
            Verdict::Optimistic {
                factor,
                from_length_s,
            } => {
                format!("noise model optimistic by ×{factor:.2} (σ) at windows ≥ {from_length_s} s")
            }
            Verdict::Pessimistic { factor } => {
                format!("noise model pessimistic by ×{factor:.2} (σ)")
            }
            Verdict::Undetermined => "undetermined: no window length has 2 windows".into(),
        }
    }

    /// `consistent`, `optimistic`, `pessimistic` or `undetermined`.
    pub fn kind(&self) -> &'static str {
        match self {
            Verdict::Consistent => "consistent",
            Verdict::Optimistic { .. } => "optimistic",
            Verdict::Pessimistic { .. } => "pessimistic",
            Verdict::Undetermined => "undetermined",
        }
    }
}

/// The blocks of a factor's residual, as the JSON names them.
const BLOCKS: [&str; 5] = ["rotation", "velocity", "position", "gyro_bias", "acc_bias"];

/// One length's summary as JSON: `{length_s, count, skipped, dof, mean_chi2, median_chi2,
/// fraction_above_p99, ks_statistic, ks_p_value?, block_share}` (a `note` instead of the
/// statistics with fewer than 2 windows).
pub fn length_json(l: &LengthSummary) -> Value {
    let mut v =
        json!({"length_s": l.length_s, "count": l.count, "skipped": l.skipped, "dof": l.dof});
    match &l.stats {
        Some(s) => {
            v["mean_chi2"] = json!(s.mean);
            v["median_chi2"] = json!(s.median);
            v["fraction_above_p99"] = json!(s.fraction_above_p99);
            v["ks_statistic"] = json!(s.ks_statistic);
            if let Some(p) = s.ks_p_value {
                v["ks_p_value"] = json!(p);
            }
            let share: Map<String, Value> = BLOCKS
                .iter()
                .zip(&s.block_share)
                .map(|(b, x)| ((*b).to_string(), json!(x)))
                .collect();
            v["block_share"] = Value::Object(share);
        }
        None => v["note"] = json!("fewer than 2 windows: no statistics for this length"),
    }
    v
}

/// The verdict as JSON: `{kind, text}` and its `factor` (and `from_length_s`).
pub fn verdict_json(v: &Verdict) -> Value {
    let mut j = json!({"kind": v.kind(), "text": v.text()});
    match v {
        Verdict::Optimistic {
            factor,
            from_length_s,
        } => {
            j["factor"] = json!(factor);
            j["from_length_s"] = json!(from_length_s);
        }
        Verdict::Pessimistic { factor } => j["factor"] = json!(factor),
        Verdict::Consistent | Verdict::Undetermined => {}
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three values 0.1, 0.4, 0.7 against the uniform distribution on [0, 1]:
    /// i/n − F = 1/3 − 0.1, 2/3 − 0.4, 1 − 0.7 = 0.233, 0.267, 0.3 and F − (i−1)/n = 0.1,
    /// 0.067, 0.033: D = 0.3. Its p-value: λ = (√3 + 0.12 + 0.11/√3)·0.3 = 0.5747,
    /// Q_KS = 2(e^{−0.6606} − e^{−2.6424} + e^{−5.945} − …) = 0.8960.
    #[test]
    fn ks_statistic_of_a_small_example() {
        let d = ks_statistic(&[0.7, 0.1, 0.4], |x| x.clamp(0.0, 1.0));
        assert!((d - 0.3).abs() < 1e-12, "{d}");
        let p = kolmogorov_p_value(d, 3).unwrap();
        assert!((p - 0.8960).abs() < 5e-4, "{p}");
        // A sample far from the distribution: all values at the top.
        let d = ks_statistic(&[0.99; 50], |x| x.clamp(0.0, 1.0));
        assert!((d - 0.99).abs() < 1e-12);
        assert!(kolmogorov_p_value(d, 50).unwrap() < 1e-12);
        assert_eq!(kolmogorov_p_value(1.5, 3), None);
    }

    fn length(length_s: f64, chi2: &[f64]) -> LengthSummary {
        let w: Vec<WindowChi2> = chi2
            .iter()
            .map(|&c| WindowChi2 {
                chi2: c,
                share: vec![c / 2.0, c / 4.0, c / 4.0],
            })
            .collect();
        summarise(length_s, 9, &w, 0)
    }

    /// Mean, median, fraction above χ²₉(0.99) = 21.67, shares; the verdict from the first
    /// length from which every longer one is optimistic.
    #[test]
    fn summaries_and_verdicts() {
        let a = length(0.5, &[8.0, 9.0, 10.0, 30.0]);
        let s = a.stats.as_ref().unwrap();
        assert_eq!((s.mean, s.median, s.fraction_above_p99), (14.25, 9.5, 0.25));
        assert_eq!(s.block_share, vec![0.5, 0.25, 0.25]);
        let fine = length(1.0, &[8.0, 9.0, 10.0, 9.0]);
        let high = length(2.0, &[13.0, 14.0, 12.0, 13.0]);
        assert_eq!(
            verdict(&[a.clone(), fine.clone(), high.clone()]),
            Verdict::Optimistic {
                factor: (13.0f64 / 9.0).sqrt(),
                from_length_s: 2.0
            }
        );
        assert_eq!(verdict(&[a.clone(), fine.clone()]), Verdict::Consistent);
        assert!(
            matches!(verdict(&[length(1.0, &[2.0, 3.0])]), Verdict::Pessimistic { factor } if (factor - (2.5f64 / 9.0).sqrt()).abs() < 1e-12)
        );
        let one = length(5.0, &[9.0]);
        assert!(one.stats.is_none());
        assert_eq!(verdict(&[one]), Verdict::Undetermined);
    }
}
