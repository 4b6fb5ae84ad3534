//! IMU noise parameters as continuous-time densities (Kalibr `imu.yaml` semantics).
//!
//! Users confuse a noise *density* with a per-sample standard deviation more than anything
//! else, so the unit is in every name and the discrete conversion happens only here:
//! - white noise of density σ [unit/√Hz] sampled every Δt has per-sample std `σ/√Δt`;
//! - a bias random walk of density σ_b [unit/s/√Hz] has per-step std `σ_b·√Δt` over a step Δt.

/// Continuous-time IMU noise densities, as in Kalibr's `imu.yaml`.
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
    /// Nominal sample rate [Hz] (`update_rate`); informational, Δt comes from timestamps.
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

    /// Per-sample gyro white-noise std [rad/s] for a sample period `dt_s` [s]: σ_g/√Δt.
    #[inline]
    pub fn gyro_sample_std(&self, dt_s: f64) -> f64 {
        self.gyro_noise_density / dt_s.sqrt()
    }

    /// Per-sample accelerometer white-noise std [m/s²] for a period `dt_s` [s]: σ_a/√Δt.
    #[inline]
    pub fn acc_sample_std(&self, dt_s: f64) -> f64 {
        self.acc_noise_density / dt_s.sqrt()
    }

    /// Std of one gyro-bias random-walk step [rad/s] over `dt_s` [s]: σ_bg·√Δt.
    #[inline]
    pub fn gyro_bias_step_std(&self, dt_s: f64) -> f64 {
        self.gyro_random_walk * dt_s.sqrt()
    }

    /// Std of one accelerometer-bias random-walk step [m/s²] over `dt_s` [s]: σ_ba·√Δt.
    #[inline]
    pub fn acc_bias_step_std(&self, dt_s: f64) -> f64 {
        self.acc_random_walk * dt_s.sqrt()
    }
}
