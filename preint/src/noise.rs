//! IMU noise parameters ([`ImuNoise`], whose documentation gives the continuous → discrete
//! conversion) and the conversion itself.

/// How the time cell `c` \[s\] of a sample follows from the intervals to its neighbours (its
/// white noise then has covariance `Σ/c`, see [`ImuNoise`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellRule {
    /// The sample is held over the interval that follows it (`euler`, GTSAM): `c = right`; a
    /// sample with no successor (never held by Euler) gets `c = left`.
    Held,
    /// The sample is the node of a quadrature rule (`midpoint`, `hermite4`): `c = ½(left + right)`,
    /// the mean length of its adjacent intervals; at an end of the stream the one interval
    /// there. A uniform stream gives `c = Δt` for every sample.
    Centered,
}

impl CellRule {
    /// The cell \[s\] from the intervals to the previous (`left_s`) and next (`right_s`) sample
    /// \[s\]; an interval is `0.0` when that neighbour does not exist (or is unknown). Returns
    /// `f64::INFINITY` (so `white_scale` = 0) if neither neighbour is known.
    #[inline(always)]
    pub fn cell_s(self, left_s: f64, right_s: f64) -> f64 {
        match (self, left_s > 0.0, right_s > 0.0) {
            (CellRule::Held, _, true) => right_s,
            (CellRule::Centered, true, true) => 0.5 * (left_s + right_s),
            (_, true, false) => left_s,
            (CellRule::Centered, false, true) => right_s,
            (_, false, false) => f64::INFINITY,
        }
    }
}

/// The factor turning a white-noise power spectral density into the covariance of one sample
/// whose time cell is `cell_s` \[s\]: `1/c` [1/s] (a sample is the mean of the continuous noise
/// over its cell). The one definition of the white-noise conversion in the crate.
#[inline(always)]
pub(crate) fn white_scale(cell_s: f64) -> f64 {
    1.0 / cell_s
}

/// Discrete variance of one sample: `psd·white_scale(cell_s)` = `σ²/c` for a density `σ`
/// (`psd = σ²`, e.g. [rad²/s] for the gyro) and a cell `c` \[s\].
#[inline(always)]
pub(crate) fn white_sample_variance(psd: f64, cell_s: f64) -> f64 {
    psd * white_scale(cell_s)
}

/// The factor turning a random-walk density into the variance added over a step of `h_s`
/// \[s\]: `h` \[s\]. The one definition of the random-walk conversion in the crate.
#[inline(always)]
pub(crate) fn walk_scale(h_s: f64) -> f64 {
    h_s
}

/// Variance of one random-walk step: `psd·walk_scale(h_s)` = `σ_b² h` for a density `σ_b`
/// (`psd = σ_b²`, e.g. [rad²/s³] for the gyro bias) over `h` \[s\].
#[inline(always)]
pub(crate) fn walk_step_variance(psd: f64, h_s: f64) -> f64 {
    psd * walk_scale(h_s)
}

/// Continuous-time IMU noise densities, as in Kalibr's `imu.yaml`.
///
/// # The continuous → discrete conversion
///
/// Users confuse a noise *density* with a per-sample standard deviation more than anything
/// else, so the unit is in every name and the discrete conversion lives in one place only:
/// - white noise of power spectral density `Σ` (= σ², σ in unit/√Hz) carried by a sample whose
///   time cell is `c` \[s\] has covariance `Σ·white_scale(c) = Σ/c` (`white_scale`,
///   `white_sample_variance`); for a uniform stream sampled every Δt, `c = Δt` and the
///   per-sample std is `σ/√Δt`;
/// - a bias random walk of density `Σ_b` (= σ_b², σ_b in unit/s/√Hz) adds `Σ_b·walk_scale(h) =
///   Σ_b h` over a step of `h` \[s\] (`walk_scale`, `walk_step_variance`); std `σ_b √h`;
/// - the time cell of a sample follows from the intervals to its neighbours by the scheme's
///   [`CellRule`].
///
/// The preintegrator multiplies the continuous covariances (fixed when it is built) by
/// `white_scale` of each sample's cell and by `walk_scale` of each interval; nothing else
/// in the crate converts densities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuNoise {
    /// Gyroscope white-noise density σ_g [rad/s/√Hz] (`gyroscope_noise_density`).
    pub gyro_noise_density: f64,
    /// Gyroscope bias random walk σ_bg [rad/s²/√Hz] (`gyroscope_random_walk`).
    pub gyro_random_walk: f64,
    /// Accelerometer white-noise density σ_a [m/s²/√Hz] (`accelerometer_noise_density`).
    pub acc_noise_density: f64,
    /// Accelerometer bias random walk σ_ba [m/s³/√Hz] (`accelerometer_random_walk`).
    pub acc_random_walk: f64,
    /// Nominal sample rate \[Hz\] (`update_rate`); informational, Δt comes from timestamps.
    pub update_rate_hz: f64,
}

impl ImuNoise {
    /// The EuRoC / ADIS16448 figures (Kimera's and the EuRoC `sensor.yaml`): σ_g = 1.6968e-4,
    /// σ_bg = 1.9393e-5, σ_a = 2.0e-3, σ_ba = 3.0e-3, 200 Hz.
    pub fn euroc() -> Self {
        Self {
            gyro_noise_density: 1.6968e-4,
            gyro_random_walk: 1.9393e-5,
            acc_noise_density: 2.0e-3,
            acc_random_walk: 3.0e-3,
            update_rate_hz: 200.0,
        }
    }

    /// No noise at all (every density zero).
    pub fn zero(update_rate_hz: f64) -> Self {
        Self {
            gyro_noise_density: 0.0,
            gyro_random_walk: 0.0,
            acc_noise_density: 0.0,
            acc_random_walk: 0.0,
            update_rate_hz,
        }
    }

    /// Per-sample gyro white-noise std [rad/s] for a sample period (cell) `dt_s` \[s\]:
    /// `√(white_sample_variance(σ_g², Δt))` = σ_g/√Δt.
    #[inline]
    pub fn gyro_sample_std(&self, dt_s: f64) -> f64 {
        white_sample_variance(self.gyro_noise_density.powi(2), dt_s).sqrt()
    }

    /// Per-sample accelerometer white-noise std [m/s²] for a period `dt_s` \[s\]: σ_a/√Δt.
    #[inline]
    pub fn acc_sample_std(&self, dt_s: f64) -> f64 {
        white_sample_variance(self.acc_noise_density.powi(2), dt_s).sqrt()
    }

    /// Std of one gyro-bias random-walk step [rad/s] over `dt_s` \[s\]:
    /// `√(walk_step_variance(σ_bg², Δt))` = σ_bg·√Δt.
    #[inline]
    pub fn gyro_bias_step_std(&self, dt_s: f64) -> f64 {
        walk_step_variance(self.gyro_random_walk.powi(2), dt_s).sqrt()
    }

    /// Std of one accelerometer-bias random-walk step [m/s²] over `dt_s` \[s\]: σ_ba·√Δt.
    #[inline]
    pub fn acc_bias_step_std(&self, dt_s: f64) -> f64 {
        walk_step_variance(self.acc_random_walk.powi(2), dt_s).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 4.0 * f64::EPSILON * b.abs()
    }

    /// The conversions against the formulas written out: `σ²/c`, `σ_b² h`, `1/c`, `h`; a
    /// sample without a neighbour gets no noise (scale 0), never a division by zero.
    #[test]
    fn white_and_walk_conversions() {
        for dt in [1e-3, 5e-3, 0.0123, 0.1] {
            assert!(close(white_sample_variance(4e-6, dt), 4e-6 / dt));
            assert!(close(walk_step_variance(9e-6, dt), 9e-6 * dt));
            assert_eq!(white_scale(dt), 1.0 / dt);
            assert_eq!(walk_scale(dt), dt);
        }
        for rule in [CellRule::Held, CellRule::Centered] {
            assert_eq!(white_scale(rule.cell_s(0.0, 0.0)), 0.0);
        }
    }
}
