//! Checks 5 and 6 of the module docs: which scale of the gyro's integral explains how the
//! gravity direction seen by the accelerometer turns between quasi-static moments.
//!
//! The body turning by Ω over T moves the unit gravity direction u seen in the body frame by
//! Δu ≈ u × (sΩ − T b) (gravity is fixed in the world; small-angle form of
//! u_j = R_ijᵀ u_i with R_ij = Exp(sΩ − T b)). A gyro misread by a factor (deg/s as rad/s)
//! scales Ω by that factor; timestamps misread by a factor (s as ms) scale every interval
//! and hence Ω by it too: both are one scale s of the gyro's integral. For each candidate s
//! the constant bias b is fitted by least squares and the misfit is `|Δu − u × (sΩ − T b)|`.

use super::{G, acc_stats, median};
use nalgebra::{Matrix3, Vector3};
use preint::ImuSample;
use preint_lie::SO3;

/// Fewest pairs of quasi-static moments for a verdict of the fit.
pub const MIN_PAIRS: usize = 10;

/// Median misfit \[rad\] above which the reading as read does not explain the turning of
/// gravity (10°).
pub const MISFIT_REFUSED_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// Ratio by which another scale must fit better (refusal), or worse (exclusion of that
/// scale), than the reading as read.
pub const DECISIVE_RATIO: f64 = 3.0;

/// One pair of quasi-static moments: gravity direction u at the first and its change Δu, the
/// gyro's integral Ω \[rad, as read\] and the time T \[s, as read\] between them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TiltPair {
    u: Vector3<f64>,
    du: Vector3<f64>,
    omega: Vector3<f64>,
    t: f64,
}

/// The quasi-static windows of about 0.25 s of `samples` sampled every `dt` s (at least 5
/// samples; accelerometer mean norm within 0.6 m/s² of g, largest per-axis standard deviation
/// below 0.5 m/s²): the window length in samples, and each window's middle sample and gravity
/// direction (unit, sensor frame).
pub(crate) fn quasi_static(samples: &[ImuSample], dt: f64) -> (usize, Vec<(usize, Vector3<f64>)>) {
    let n = ((0.25 / dt).round() as usize).max(5);
    let quasi = samples
        .chunks(n)
        .enumerate()
        .filter_map(|(k, w)| {
            let (mean, sd) = acc_stats(w);
            ((mean.norm() - G).abs() < 0.6 && sd < 0.5)
                .then(|| (k * n + w.len() / 2, mean.normalize()))
        })
        .collect();
    (n, quasi)
}

/// The gyro's rotation over `samples[i..=j]`, `Π_k Exp(ω_k Δt_k)`, and the same of `−ω`.
pub(crate) fn gyro_turn(
    samples: &[ImuSample],
    (i, j): (usize, usize),
) -> (Matrix3<f64>, Matrix3<f64>) {
    let (mut plus, mut minus) = (Matrix3::identity(), Matrix3::identity());
    for (s0, s1) in samples[i..j].iter().zip(&samples[i + 1..=j]) {
        let w = s0.gyro * ((s1.t_ns - s0.t_ns) as f64 * 1e-9);
        plus *= SO3::exp(&w).matrix();
        minus *= SO3::exp(&-w).matrix();
    }
    (plus, minus)
}

/// The pairs of quasi-static windows ([`quasi_static`]) 1 s apart of `samples` sampled every
/// `dt` s. Ω and T are integrated with the timestamps as read, whatever `dt` (a candidate
/// interval) is.
pub(crate) fn tilt_pairs(samples: &[ImuSample], dt: f64) -> Vec<TiltPair> {
    let (n, quasi) = quasi_static(samples, dt);
    let mut pairs = Vec::new();
    for (a, &(i, u)) in quasi.iter().enumerate() {
        let Some(&(j, uj)) = quasi[a + 1..].iter().find(|(j, _)| *j == i + 4 * n) else {
            continue;
        };
        let omega = samples[i..j]
            .iter()
            .zip(&samples[i + 1..=j])
            .fold(Vector3::zeros(), |acc, (s0, s1)| {
                acc + s0.gyro * ((s1.t_ns - s0.t_ns) as f64 * 1e-9)
            });
        let t = (samples[j].t_ns - samples[i].t_ns) as f64 * 1e-9;
        pairs.push(TiltPair {
            u,
            du: uj - u,
            omega,
            t,
        });
    }
    pairs
}

/// The bias b minimising `Σ |Δu − u × (sΩ − T b)|²` (zero if unobservable).
fn fitted_bias(pairs: &[TiltPair], s: f64) -> Vector3<f64> {
    let (mut normal, mut rhs) = (Matrix3::zeros(), Vector3::zeros());
    for p in pairs {
        // Δu − s u×Ω = −T u×b = A b with A = −T [u]×.
        let a = -p.t * preint_lie::so3::hat(&p.u);
        normal += a.transpose() * a;
        rhs += a.transpose() * (p.du - p.u.cross(&p.omega) * s);
    }
    normal
        .try_inverse()
        .map_or(Vector3::zeros(), |inv| inv * rhs)
}

/// Median misfit \[rad\] of the gravity direction over `pairs` with the gyro's integral
/// scaled by `s` (its bias fitted).
pub(crate) fn median_misfit(pairs: &[TiltPair], s: f64) -> f64 {
    let b = fitted_bias(pairs, s);
    median(
        pairs
            .iter()
            .map(|p| (p.du - p.u.cross(&(p.omega * s - b * p.t))).norm())
            .collect(),
    )
}

/// Median turn \[rad\] of the gravity direction between the moments of `pairs` (`|Δu|`).
pub(crate) fn median_turn(pairs: &[TiltPair]) -> f64 {
    median(pairs.iter().map(|p| p.du.norm()).collect())
}

/// How well each gyro scale explains the turning of the gravity direction, with the
/// timestamps as read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroScaleFit {
    /// Number of window pairs compared.
    pub pairs: usize,
    /// Median misfit \[rad\] of the gravity direction with the gyro scaled by π/180, 1 and
    /// 180/π (a constant bias fitted for each).
    pub median_error: [f64; 3],
}

/// The candidate gyro scales of [`GyroScaleFit::median_error`].
pub const GYRO_SCALES: [f64; 3] = [
    std::f64::consts::PI / 180.0,
    1.0,
    180.0 / std::f64::consts::PI,
];

impl GyroScaleFit {
    /// The error message if a scale other than 1 explains the data much better: the gyro as
    /// read misses by more than 10° (median) and another scale by less than a third of that.
    pub fn verdict(&self) -> Option<String> {
        let [deg, one, rad] = self.median_error;
        let best_other = deg.min(rad);
        if one < MISFIT_REFUSED_RAD || best_other >= one / DECISIVE_RATIO {
            return None;
        }
        let (scale, fix) = if deg < rad {
            ("π/180", "the gyro looks like deg/s: set --gyro-unit deg/s")
        } else {
            (
                "180/π",
                "the gyro looks like rad/s, not deg/s: set --gyro-unit rad/s",
            )
        };
        Some(format!(
            "the gyro does not explain how the accelerometer's gravity direction turns: over {} \
             pairs of quasi-static moments 1 s apart it misses by {:.1}° (median), scaled by \
             {scale} by {:.1}°; {fix} (or --no-unit-check)",
            self.pairs,
            one.to_degrees(),
            best_other.to_degrees()
        ))
    }
}

/// Compares the gyro scales of [`GYRO_SCALES`] on the pairs of quasi-static 0.25 s windows
/// 1 s apart (module docs of this file) of `samples` sampled every `dt` s. `None` when fewer
/// than [`MIN_PAIRS`] pairs exist.
pub fn gyro_scale_fit(samples: &[ImuSample], dt: f64) -> Option<GyroScaleFit> {
    let pairs = tilt_pairs(samples, dt);
    if pairs.len() < MIN_PAIRS {
        return None;
    }
    Some(GyroScaleFit {
        pairs: pairs.len(),
        median_error: GYRO_SCALES.map(|s| median_misfit(&pairs, s)),
    })
}
