//! Overlapping Allan deviation and IMU noise-parameter fits (IEEE Std 952-1997, Annex C;
//! readings as in allan_variance_ros and kalibr_allan).
//!
//! - [`deviation`]: the overlapping Allan deviation `σ(τ)` of one channel at log-spaced cluster
//!   times, with the equivalent degrees of freedom and 1-σ error of every point.
//! - [`edf`]: the statistics of the estimator under a noise model: the equivalent degrees of
//!   freedom of a point and the covariance of two (Greenhall and Riley 2003), the normal
//!   deviate of a point against the model.
//! - [`fit`]: the white-noise density N (slope −½ region on τ ≥ 0.1 s, above the sensor's
//!   internal filtering, read at τ = 1 s) and the random walk K (slope +½ region, read at
//!   τ = 3 s), one weighted least-squares fit of both with errors from the points' covariance,
//!   each line kept below every point's upper 4σ limit; upper bounds, flagged, when a slope
//!   region is missing; the bias instability B (the curve's floor / 0.664); the goodness of
//!   fit of the model curve.
//! - [`stream`]: the same from a sample stream in bounded memory ([`AllanStream`], block means
//!   at a base cluster time τ₀ that grows with the recording's length).
//! - [`stillness`]: is a streamed recording static ([`StillnessMonitor`])? The Allan variance
//!   of a moving recording describes the motion, not the sensor.
//! - [`ImuAllan`]: the six channels of an IMU record and their Kalibr `imu.yaml` figures
//!   (`gyroscope_noise_density`, `gyroscope_random_walk`, `accelerometer_noise_density`,
//!   `accelerometer_random_walk`; the largest axis of each sensor).
//!
//! Units: a channel's signal unit `u` (rad/s or m/s²); N in u/√Hz, K in u/s/√Hz (u·√Hz), B in u.

pub mod deviation;
pub mod edf;
pub mod fit;
pub mod stillness;
pub mod stream;

pub use deviation::{AllanPoint, allan_deviation, log_spaced_cluster_sizes};
pub use fit::{
    BIAS_INSTABILITY_FACTOR, CAP_SIGMAS, MAX_MODEL_Z, ModelDeviation, NoiseFit,
    WHITE_NOISE_MIN_TAU, fit_noise, model_adev, model_deviation,
};
pub use stillness::{Stillness, StillnessMonitor, StillnessOptions};
pub use stream::{AllanStream, MAX_BASE_BLOCKS};

use preint::ImuNoise;
use preint::{ImuSample, dt_seconds};

/// Errors of the Allan analysis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AllanError {
    /// Not enough samples to form clusters.
    #[error("{0} samples: need at least 8 for an Allan deviation")]
    TooFewSamples(usize),
    /// The sample period is not positive and finite.
    #[error("invalid sample period {0} s")]
    BadPeriod(f64),
    /// A sample is NaN or infinite.
    #[error("channel {channel}: non-finite sample at index {index}")]
    NonFinite {
        /// Channel index.
        channel: usize,
        /// Sample index.
        index: usize,
    },
    /// Timestamps are not strictly increasing or not uniform.
    #[error("timestamps: {0}")]
    Timestamps(String),
    /// The curve has no reliable point (≥ 8 clusters): nothing can be read from it. (A curve
    /// without a slope −½ region gives an upper bound on N instead, see [`NoiseFit`].)
    #[error("channel {0}: no point with at least 8 clusters, white-noise density not fitted")]
    NoWhiteNoiseRegion(usize),
    /// The channel's readings never change: its Allan deviation is 0 at every τ, so there is
    /// no noise to read (a stuck channel, or one quantised more coarsely than its noise).
    #[error(
        "{}: the readings never change (Allan deviation 0 at every τ), so there is no noise to measure: a stuck channel, or one quantised more coarsely than its noise",
        CHANNELS.get(*.0).copied().unwrap_or("channel")
    )]
    NoNoise(usize),
    /// Channels have different lengths.
    #[error("channel lengths differ ({0} vs {1})")]
    LengthMismatch(usize, usize),
    /// The recording is not static ([`Stillness::verdict`] says why).
    #[error("{0}")]
    NotStatic(String),
    /// The recording is too short to judge (the message says what it needs).
    #[error("{0}")]
    TooShort(String),
}

/// The channels' names, in the order of [`ImuAllan::curves`].
pub const CHANNELS: [&str; 6] = ["gyro x", "gyro y", "gyro z", "acc x", "acc y", "acc z"];

/// Allan analysis of a six-axis IMU record.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuAllan {
    /// Sample period Δt \[s\].
    pub dt: f64,
    /// τ₀ \[s\]: the period of the series the curves were computed from, `Δt` for the
    /// samples themselves, `bΔt` for the base blocks of [`AllanStream`].
    pub tau0: f64,
    /// Curves, channel order `[ω_x, ω_y, ω_z, a_x, a_y, a_z]`.
    pub curves: [Vec<AllanPoint>; 6],
    /// Fits, same order (gyro in rad/s units, accelerometer in m/s² units).
    pub fits: [NoiseFit; 6],
}

impl ImuAllan {
    /// Analyses six channels `[ω_x, ω_y, ω_z, a_x, a_y, a_z]` sampled every `dt` \[s\], with
    /// `per_decade` log-spaced τ per decade (10 is typical).
    ///
    /// ```
    /// use preint_calib::allan::ImuAllan;
    /// use rand::{RngExt, SeedableRng};
    /// use rand_distr::StandardNormal;
    ///
    /// // 200 s at 100 Hz of white noise: gyro 1e-3 rad/s/√Hz, accelerometer 2e-2 m/s²/√Hz.
    /// let dt: f64 = 0.01;
    /// let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    /// let mut white = |density: f64| -> Vec<f64> {
    ///     (0..20_000)
    ///         .map(|_| density / dt.sqrt() * rng.sample::<f64, _>(StandardNormal))
    ///         .collect()
    /// };
    /// let ch: Vec<Vec<f64>> = [1e-3, 1e-3, 1e-3, 2e-2, 2e-2, 2e-2].map(&mut white).to_vec();
    /// let channels: [&[f64]; 6] = [&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]];
    /// let allan = ImuAllan::from_channels(channels, dt, 10).unwrap();
    /// let noise = allan.to_imu_noise(); // Kalibr imu.yaml figures, the largest axis
    /// assert!((noise.gyro_noise_density / 1e-3 - 1.0).abs() < 0.1);
    /// assert!((noise.acc_noise_density / 2e-2 - 1.0).abs() < 0.1);
    /// assert_eq!(noise.update_rate_hz, 100.0);
    /// ```
    pub fn from_channels(
        channels: [&[f64]; 6],
        dt: f64,
        per_decade: usize,
    ) -> Result<Self, AllanError> {
        let n = channels[0].len();
        for c in &channels {
            if c.len() != n {
                return Err(AllanError::LengthMismatch(n, c.len()));
            }
        }
        let ms = log_spaced_cluster_sizes(n / 2, per_decade);
        let mut curves: [Vec<AllanPoint>; 6] = Default::default();
        for (i, c) in channels.iter().enumerate() {
            curves[i] = allan_deviation(c, dt, &ms).map_err(|e| match e {
                AllanError::NonFinite { index, .. } => AllanError::NonFinite { channel: i, index },
                e => e,
            })?;
        }
        Self::from_curves(dt, dt, curves)
    }

    /// Fits the six curves of a recording sampled every `dt` \[s\], computed from a series of
    /// period `tau0` (`dt`, or the block length of [`AllanStream`]).
    pub fn from_curves(
        dt: f64,
        tau0: f64,
        curves: [Vec<AllanPoint>; 6],
    ) -> Result<Self, AllanError> {
        let fits = [
            fit_noise(&curves[0], 0)?,
            fit_noise(&curves[1], 1)?,
            fit_noise(&curves[2], 2)?,
            fit_noise(&curves[3], 3)?,
            fit_noise(&curves[4], 4)?,
            fit_noise(&curves[5], 5)?,
        ];
        Ok(Self {
            dt,
            tau0,
            curves,
            fits,
        })
    }

    /// Analyses IMU samples; the period is `(t_last − t_first)/(N − 1)` and every interval must
    /// lie within ±10 % of it (no gaps or reordering).
    pub fn from_samples(samples: &[ImuSample], per_decade: usize) -> Result<Self, AllanError> {
        if samples.len() < 8 {
            return Err(AllanError::TooFewSamples(samples.len()));
        }
        let n = samples.len();
        let dt = dt_seconds(samples[0].t_ns, samples[n - 1].t_ns) / (n - 1) as f64;
        for (i, w) in samples.windows(2).enumerate() {
            let d = dt_seconds(w[0].t_ns, w[1].t_ns);
            if !(d > 0.0 && (d - dt).abs() <= 0.1 * dt) {
                return Err(AllanError::Timestamps(format!(
                    "interval {i} is {d} s, mean period {dt} s (gap or reordering)"
                )));
            }
        }
        let ch: Vec<Vec<f64>> = (0..6)
            .map(|c| {
                samples
                    .iter()
                    .map(|s| if c < 3 { s.gyro[c] } else { s.acc[c - 3] })
                    .collect()
            })
            .collect();
        Self::from_channels(
            [&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]],
            dt,
            per_decade,
        )
    }

    /// The goodness of fit of the six channels' models (module docs of [`fit`], "Goodness of
    /// fit"): `Σz²` and the number of points over all channels as `chi2` and `dof` (no χ²
    /// distribution: the p-values are NaN), credible while every channel's `max |z|` is at
    /// most [`MAX_MODEL_Z`]; `why` names the worst channel (`CHANNELS` order), its τ and
    /// which line misses.
    pub fn fit(&self) -> crate::Fit {
        let d: Vec<ModelDeviation> = (0..6)
            .map(|c| model_deviation(&self.curves[c], &self.fits[c]))
            .collect();
        let (chi2, dof) = d
            .iter()
            .fold((0.0, 0), |a, d| (a.0 + d.sum_z2, a.1 + d.points));
        let (worst, w) = d
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.max_abs_z.total_cmp(&b.1.max_abs_z))
            .unwrap_or((0, &d[0]));
        let credible = w.max_abs_z <= MAX_MODEL_Z;
        let line = if w.in_white_range {
            "white-noise"
        } else {
            "random-walk"
        };
        let why = if w.points == 0 {
            "no channel has a fitted line (every N and K is a bound): nothing to compare".into()
        } else if credible {
            format!(
                "the model curves √(N²/τ + K²τ/3) stay within {:.2} statistical errors of the \
                 measured Allan deviation over their fitted τ ranges ({dof} points; at most \
                 {MAX_MODEL_Z})",
                w.max_abs_z
            )
        } else {
            format!(
                "the model curve of {} misses the measured Allan deviation by {:.1} statistical \
                 errors at τ = {:.3} s (at most {MAX_MODEL_Z}), in the {line} line's range, the \
                 curve {} the model; likely cause: a noise the model lacks (bias instability, \
                 the sensor's filter, a disturbance, motion) shaping the curve where the {line} \
                 line was fitted, or the line held {} by a point of the curve: read the curve \
                 before using N and K",
                CHANNELS[worst],
                w.max_abs_z,
                w.tau_at_max,
                if w.z_at_max > 0.0 { "above" } else { "below" },
                if w.z_at_max > 0.0 { "down" } else { "up" }
            )
        };
        crate::Fit::from_band(chi2, dof, credible, why)
    }

    /// Kalibr noise parameters, aggregated over the three axes of each sensor by the **maximum**
    /// (conservative: a VIO back end fed a too-small noise becomes overconfident). Densities
    /// and random walks that are only upper bounds are used as they are (conservative too).
    /// `update_rate = 1/Δt`.
    pub fn to_imu_noise(&self) -> ImuNoise {
        let max = |r: std::ops::Range<usize>, f: fn(&NoiseFit) -> f64| {
            self.fits[r].iter().map(f).fold(0.0, f64::max)
        };
        ImuNoise {
            gyro_noise_density: max(0..3, |f| f.white_density),
            gyro_random_walk: max(0..3, |f| f.random_walk),
            acc_noise_density: max(3..6, |f| f.white_density),
            acc_random_walk: max(3..6, |f| f.random_walk),
            update_rate_hz: 1.0 / self.dt,
        }
    }
}
