//! IMU measurement synthesis with white noise and bias random walk, and the
//! dataset writer (EuRoC + Kalibr).
//!
//! Model, for sample `k` at `t_k` with the scene state (`R_wb`, `a_w`, `ω_b`):
//!
//! ```text
//! a_m,k = S_a R_wbᵀ (a_w − g) + b_a,k + n_a,k        n_a,k ~ N(0, (σ_a/√Δt)² I)
//! ω_m,k = S_g ω_b + b_g,k + n_g,k                    n_g,k ~ N(0, (σ_g/√Δt)² I)
//! b_k   = b_{k−1} + σ_b √Δt w_k  (k ≥ 1),  b_0 = initial bias,  w_k ~ N(0, I)
//! ```
//!
//! `σ_g, σ_a` are the white-noise densities and `σ_bg, σ_ba` the random-walk densities of
//! [`ImuNoise`] (Kalibr units); `Δt` is the sample period.
//!
//! **Random numbers.** The generator is ChaCha12 ([`rand::rngs::ChaCha12Rng`], the `chacha20`
//! crate: D. J. Bernstein's ChaCha stream cipher with 12 rounds, a fixed, documented algorithm
//! independent of platform and endianness), seeded with [`rng_from_seed`]: the 32-byte key holds
//! the seed as little-endian `u64` in bytes 0–7 and zeros elsewhere. Standard normals come from
//! `rand_distr::StandardNormal` (ziggurat, pinned by `rand_distr` 0.6). Draw order: for every
//! sample `k`, 12 normals in the order `w_bg (x,y,z), w_ba (x,y,z), n_g (x,y,z), n_a (x,y,z)`,
//! always drawn (also when a density is zero or the random walk is off), so switching one
//! noise term on or off does not change the others. The same seed gives bit-identical data
//! with these crate versions on any IEEE-754 machine (the ziggurat's rare tail branch,
//! |z| > 3.44, calls the platform `ln`).

use crate::scene::{Scene, t_s};
use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample, SensorPose};
use preint_io::{GroundTruthState, IoError};
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;
use rand_distr::{Distribution, StandardNormal};
use std::path::{Path, PathBuf};

/// Errors from the simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The sample rate is not a positive finite number, or rounds to a zero-ns period.
    #[error("invalid IMU rate {rate_hz} Hz: need a finite rate in (0, 1e9] Hz")]
    Rate {
        /// The rejected rate \[Hz\].
        rate_hz: f64,
    },
    /// The duration is negative, not finite, or too long for i64 nanoseconds.
    #[error("invalid duration {duration_s} s: need a finite value in [0, 9.2e9] s")]
    Duration {
        /// The rejected duration \[s\].
        duration_s: f64,
    },
    /// Rate × duration asks for more samples than [`MAX_SIM_SAMPLES`] (checked before
    /// allocating).
    #[error(
        "{rate_hz} Hz for {duration_s} s is {samples} samples, more than the simulator's limit of \
         {max} (≈ 190 bytes each in memory); lower --rate or --duration"
    )]
    TooLarge {
        /// The rate \[Hz\].
        rate_hz: f64,
        /// The duration \[s\].
        duration_s: f64,
        /// The samples asked for.
        samples: u64,
        /// [`MAX_SIM_SAMPLES`].
        max: usize,
    },
    /// A configuration value is not finite or is negative.
    #[error("invalid simulator configuration: {0}")]
    Config(String),
    /// Writing the dataset failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Creating the output directory failed.
    #[error("{path}: {source}")]
    CreateDir {
        /// Directory path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
}

/// Simulator configuration: gravity, noise densities, biases and sensor errors.
///
/// Defaults ([`SimConfig::default`]): `g = (0, 0, −9.81)` m/s², no noise
/// ([`ImuNoise::zero`]), zero initial bias, random walk on (it is zero anyway without
/// noise), `S_a = S_g = I` (no scale factor or misalignment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimConfig {
    /// World gravity vector g [m/s²].
    pub gravity: Vector3<f64>,
    /// Continuous-time noise densities (Kalibr units). `update_rate_hz` is informational;
    /// the period comes from the `rate_hz` argument of [`simulate`].
    pub noise: ImuNoise,
    /// Biases at the first sample `b_0` (gyro [rad/s], accelerometer [m/s²]).
    pub initial_bias: ImuBias,
    /// Whether the biases follow the random walk `b_k = b_{k−1} + σ_b √Δt w_k` (else constant).
    pub bias_random_walk: bool,
    /// Accelerometer scale-factor/misalignment matrix `S_a` (identity = ideal).
    pub acc_scale: Matrix3<f64>,
    /// Gyroscope scale-factor/misalignment matrix `S_g` (identity = ideal).
    pub gyro_scale: Matrix3<f64>,
    /// Pose of the IMU in the body frame (`None`: the IMU is the body). The scene moves the
    /// body; the IMU reads the rate and specific force of its own point and axes
    /// ([`SceneState::sensor_sample`](crate::SceneState::sensor_sample)); the ground truth
    /// stays the body's.
    pub body_p_sensor: Option<SensorPose>,
    /// Rotation rate of the navigation frame ω_ie [rad/s, navigation frame] (Earth rotation):
    /// the ideal readings are [`ideal_sample_rotating`](crate::rotating::ideal_sample_rotating)'s;
    /// `None` (default) = a non-rotating frame.
    pub earth_rate: Option<Vector3<f64>>,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            noise: ImuNoise::zero(200.0),
            initial_bias: ImuBias::zero(),
            bias_random_walk: true,
            acc_scale: Matrix3::identity(),
            gyro_scale: Matrix3::identity(),
            body_p_sensor: None,
            earth_rate: None,
        }
    }
}

impl SimConfig {
    /// Noise-free configuration with gravity `(0, 0, −9.81)` (same as `default()`).
    pub fn noise_free() -> Self {
        Self::default()
    }

    /// Default configuration with noise densities `noise`.
    pub fn with_noise(noise: ImuNoise) -> Self {
        Self {
            noise,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), SimError> {
        let n = &self.noise;
        let dens = [
            ("gyro_noise_density", n.gyro_noise_density),
            ("gyro_random_walk", n.gyro_random_walk),
            ("acc_noise_density", n.acc_noise_density),
            ("acc_random_walk", n.acc_random_walk),
        ];
        for (k, v) in dens {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::Config(format!(
                    "noise {k} = {v}: densities must be finite and ≥ 0"
                )));
            }
        }
        let finite = |m: &[f64]| m.iter().all(|x| x.is_finite());
        if !finite(self.gravity.as_slice()) {
            return Err(SimError::Config("gravity is not finite".into()));
        }
        if !finite(self.initial_bias.gyro.as_slice()) || !finite(self.initial_bias.acc.as_slice()) {
            return Err(SimError::Config("initial bias is not finite".into()));
        }
        if !finite(self.acc_scale.as_slice()) || !finite(self.gyro_scale.as_slice()) {
            return Err(SimError::Config("scale matrix is not finite".into()));
        }
        if let Some(pose) = &self.body_p_sensor
            && !pose.is_valid()
        {
            return Err(SimError::Config(
                "body_p_sensor: non-finite entry or rotation not orthonormal".into(),
            ));
        }
        if self.earth_rate.is_some_and(|w| !finite(w.as_slice())) {
            return Err(SimError::Config("earth rate is not finite".into()));
        }
        Ok(())
    }
}

/// Scale-factor and misalignment matrix `S = diag(1 + s)·(I + N)` with `N` strictly lower
/// triangular, `N₁₀ = m₀, N₂₀ = m₁, N₂₁ = m₂` (Kalibr's lower-triangular "scale-misalignment"
/// form, to first order). `scale_error` `s` is dimensionless (e.g. 1e-3 = 1000 ppm),
/// `misalignment` `m` in radians (small angles).
pub fn scale_misalignment(scale_error: &Vector3<f64>, misalignment: &Vector3<f64>) -> Matrix3<f64> {
    let n = Matrix3::new(
        1.0,
        0.0,
        0.0,
        misalignment.x,
        1.0,
        0.0,
        misalignment.y,
        misalignment.z,
        1.0,
    );
    Matrix3::from_diagonal(&scale_error.add_scalar(1.0)) * n
}

/// Simulated data: the samples and the true state (with the true biases) at each sample time.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOutput {
    /// IMU samples at `t_k = k·period_ns`, k = 0..n.
    pub samples: Vec<ImuSample>,
    /// True state at each sample time (same length and timestamps as `samples`):
    /// position, attitude body→world, velocity and the biases `b_k` contained in sample `k`.
    pub truth: Vec<GroundTruthState>,
}

/// The random generator used by [`simulate`]: ChaCha12 keyed with `seed` as little-endian
/// bytes 0–7 of the 32-byte seed (remaining bytes zero), stream 0, position 0.
pub fn rng_from_seed(seed: u64) -> ChaCha12Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    ChaCha12Rng::from_seed(key)
}

/// Sample period \[ns\] for a rate \[Hz\]: `round(1e9 / rate_hz)`. Errors if the rate is not
/// finite and positive or the period rounds to zero.
pub fn period_ns(rate_hz: f64) -> Result<i64, SimError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(SimError::Rate { rate_hz });
    }
    let p = (1e9 / rate_hz).round();
    if !(1.0..=9.2e18).contains(&p) {
        return Err(SimError::Rate { rate_hz });
    }
    Ok(p as i64)
}

/// Most samples [`simulate`] produces in one call: 20 million (≈ 3.8 GB of samples and ground
/// truth; 28 h at 200 Hz).
pub const MAX_SIM_SAMPLES: usize = 20_000_000;

/// Synthesises IMU samples of `scene` at `rate_hz` over `[0, duration_s]` (see the module
/// docs for the model and the random generator).
///
/// Timestamps are integer: `t_k = k·round(1e9/rate_hz)` ns for `k = 0 … ⌊duration_ns/period⌋`
/// (so `⌊duration/period⌋ + 1` samples; the effective rate is `1e9/period_ns`). The noise
/// uses `Δt = period_ns·1e-9` s. Returns a typed error for a bad rate, duration or config, or
/// for more than [`MAX_SIM_SAMPLES`] samples (before allocating).
pub fn simulate(
    scene: &dyn Scene,
    rate_hz: f64,
    duration_s: f64,
    config: &SimConfig,
    seed: u64,
) -> Result<SimOutput, SimError> {
    let period = period_ns(rate_hz)?;
    if !(duration_s.is_finite() && (0.0..=9.2e9).contains(&duration_s)) {
        return Err(SimError::Duration { duration_s });
    }
    config.validate()?;
    let duration_ns = (duration_s * 1e9).round() as i64;
    let samples = (duration_ns / period) as u64 + 1;
    if samples > MAX_SIM_SAMPLES as u64 {
        return Err(SimError::TooLarge {
            rate_hz,
            duration_s,
            samples,
            max: MAX_SIM_SAMPLES,
        });
    }
    let n = samples as usize;
    let dt = period as f64 * 1e-9;
    let nz = &config.noise;
    let (sg, sa) = (nz.gyro_sample_std(dt), nz.acc_sample_std(dt));
    let (sbg, sba) = if config.bias_random_walk {
        (nz.gyro_bias_step_std(dt), nz.acc_bias_step_std(dt))
    } else {
        (0.0, 0.0)
    };
    let mut rng = rng_from_seed(seed);
    let mut normal3 = || {
        let mut d = || -> f64 { StandardNormal.sample(&mut rng) };
        Vector3::new(d(), d(), d())
    };
    let mut bias = config.initial_bias;
    let mut samples = Vec::with_capacity(n);
    let mut truth = Vec::with_capacity(n);
    for k in 0..n {
        let t_ns = k as i64 * period;
        let (w_bg, w_ba, n_g, n_a) = (normal3(), normal3(), normal3(), normal3());
        if k > 0 {
            bias.gyro += w_bg * sbg;
            bias.acc += w_ba * sba;
        }
        let st = scene.state(t_s(t_ns));
        // The readings are those of the sensor's own point and axes (rigid-body kinematics,
        // in the rotating frame if one is set); the truth stays the body's.
        let sensor = match &config.body_p_sensor {
            Some(pose) => st.at_sensor(pose),
            None => st,
        };
        let ideal = crate::rotating::ideal_sample_rotating(
            &sensor,
            t_ns,
            &config.gravity,
            config.earth_rate.as_ref(),
        );
        let acc = config.acc_scale * ideal.acc + bias.acc + n_a * sa;
        let gyro = config.gyro_scale * ideal.gyro + bias.gyro + n_g * sg;
        samples.push(ImuSample { t_ns, gyro, acc });
        truth.push(GroundTruthState {
            t_ns,
            p: st.p,
            q: st.r_wb.to_quaternion(),
            v: st.v,
            bias,
        });
    }
    Ok(SimOutput { samples, truth })
}

/// Writes a simulated dataset into directory `dir` (created if missing):
/// `imu.csv` (EuRoC `imu0/data.csv` format), `groundtruth.csv` (EuRoC
/// `state_groundtruth_estimate0/data.csv`: p, q w,x,y,z body→world, v, b_g, b_a) and
/// `imu.yaml` (Kalibr densities `noise`). All through `preint_io` (lossless floats).
/// Returns the three paths in that order.
pub fn write_dataset(
    dir: &Path,
    output: &SimOutput,
    noise: &ImuNoise,
) -> Result<Vec<PathBuf>, SimError> {
    std::fs::create_dir_all(dir).map_err(|source| SimError::CreateDir {
        path: dir.display().to_string(),
        source,
    })?;
    let imu = dir.join("imu.csv");
    let gt = dir.join("groundtruth.csv");
    let yaml = dir.join("imu.yaml");
    preint_io::write_euroc_imu(&imu, &output.samples)?;
    preint_io::write_euroc_groundtruth(&gt, &output.truth)?;
    preint_io::write_kalibr_yaml(&yaml, noise)?;
    Ok(vec![imu, gt, yaml])
}
