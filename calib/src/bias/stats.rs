//! Sufficient statistics of a run of IMU samples: means, per-axis sample variances and the mean
//! sample period, from which the still-interval problems are built.

use nalgebra::Vector3;
use preint::{ImuSample, dt_seconds};

/// Mean sample period `(t_last − t_first)/(N − 1)` \[s\] of `samples` (N ≥ 2, not checked).
pub(crate) fn mean_period(samples: &[ImuSample]) -> f64 {
    let n = samples.len();
    dt_seconds(samples[0].t_ns, samples[n - 1].t_ns) / (n - 1) as f64
}

/// Sufficient statistics of a run of samples: per-axis means and sample variances of ω and a,
/// the count N and the mean sample period (`(t_last − t_first)/(N − 1)`) \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentStats {
    /// Number of samples N.
    pub count: usize,
    /// Mean sample period Δt \[s\].
    pub dt: f64,
    /// Mean gyro reading ω̄ \[rad/s\].
    pub gyro_mean: Vector3<f64>,
    /// Sample variance of the gyro readings per axis \[(rad/s)²\].
    pub gyro_var: Vector3<f64>,
    /// Mean specific force f̄ \[m/s²\].
    pub acc_mean: Vector3<f64>,
    /// Sample variance of the accelerometer readings per axis \[(m/s²)²\].
    pub acc_var: Vector3<f64>,
}

impl SegmentStats {
    /// Statistics of `samples` (≥ 2 samples, increasing timestamps, not re-checked). Sums
    /// are shifted by the first sample for accuracy.
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use preint::ImuSample;
    /// use preint_calib::bias::SegmentStats;
    ///
    /// // 200 Hz, gyro alternating ±1e-3 about 0.01 rad/s on x.
    /// let samples: Vec<ImuSample> = (0..200)
    ///     .map(|k| {
    ///         let w = 0.01 + if k % 2 == 0 { 1e-3 } else { -1e-3 };
    ///         ImuSample::new(k * 5_000_000, Vector3::new(w, 0.0, 0.0), Vector3::z() * 9.81)
    ///     })
    ///     .collect();
    /// let st = SegmentStats::of(&samples);
    /// assert!((st.dt - 0.005).abs() < 1e-15);
    /// assert!((st.gyro_mean.x - 0.01).abs() < 1e-12);
    /// assert!((st.gyro_var.x / (1e-6 * 200.0 / 199.0) - 1.0).abs() < 1e-9);
    /// assert!((st.averaging_time() - 1.0).abs() < 1e-12);
    /// ```
    pub fn of(samples: &[ImuSample]) -> Self {
        let n = samples.len();
        let (g0, a0) = (samples[0].gyro, samples[0].acc);
        let (mut sg, mut sg2, mut sa, mut sa2) = (
            Vector3::zeros(),
            Vector3::zeros(),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        for s in samples {
            let dg = s.gyro - g0;
            let da = s.acc - a0;
            sg += dg;
            sg2 += dg.component_mul(&dg);
            sa += da;
            sa2 += da.component_mul(&da);
        }
        let nf = n as f64;
        let var = |s: Vector3<f64>, s2: Vector3<f64>| {
            if n > 1 {
                (s2 - s.component_mul(&s) / nf) / (nf - 1.0)
            } else {
                Vector3::zeros()
            }
        };
        let dt = if n > 1 { mean_period(samples) } else { 0.0 };
        Self {
            count: n,
            dt,
            gyro_mean: g0 + sg / nf,
            gyro_var: var(sg, sg2),
            acc_mean: a0 + sa / nf,
            acc_var: var(sa, sa2),
        }
    }

    /// Effective averaging time `T = N·Δt` \[s\]: the mean of N samples of white noise of
    /// density σ has standard deviation `σ/√T` (per-sample std `σ/√Δt`).
    pub fn averaging_time(&self) -> f64 {
        self.count as f64 * self.dt
    }
}
