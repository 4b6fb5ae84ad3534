//! # evidence — shared helpers of the cross-crate evidence suite
//!
//! The tests live in `tests/tests/*.rs`, one file per topic; each file's header says what it
//! asserts and why each bound is what it is. Agreement with GTSAM 4.3 is checked where the code
//! under test lives, on the fixtures of `tests/fixtures/gtsam/` (inputs, parameters and GTSAM's
//! outputs, with the script that made them): `preint/tests/gtsam_euler.rs` (ΔR, Δv, Δp,
//! covariance and bias Jacobians of the Euler scheme to 1e-12 relative on nine inputs) and
//! `preint/tests/factor_gtsam.rs` (factor residual, Jacobians and prediction after the
//! documented sign/chart mapping). This library holds no expected value of the code under
//! test, only the means of getting and judging one: a seeded Gaussian generator (so the suite
//! does not depend on a particular `rand` version's stream), paths, statistics (median,
//! log-log slope), the JSON writer for `target/evidence/`, a scene's true state as a
//! `NavState`, a window of its ideal readings, the preintegration of a whole slice of samples
//! (the measurement the tests then check), and the Monte Carlo NEES harness
//! ([`monte_carlo`]: the realisations, NEES `eᵀΣ⁻¹e` with the covariance the code under test
//! gives, and the χ² mean a correct covariance predicts).
//!
//! Environment:
//! - `PREINT_FULL=1` runs the heavy Monte Carlo / long-stream cases at full size (see each test).
//! - `EVIDENCE_OUT=DIR` writes the JSON records to `DIR` instead of `<workspace>/target/evidence`.

use nalgebra::Vector3;
use preint_lie::SO3;
use std::path::PathBuf;

pub mod monte_carlo;

/// The suite's gravity, `(0, 0, −9.81)` m/s² in the world frame.
pub fn gravity() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

/// The constant bias the Monte Carlo scenes' samples carry: `b_g = (0.01, −0.02, 0.015)`
/// rad/s, `b_a = (0.1, −0.05, 0.2)` m/s².
pub fn scene_bias() -> preint::ImuBias {
    preint::ImuBias::new(
        Vector3::new(0.01, -0.02, 0.015),
        Vector3::new(0.1, -0.05, 0.2),
    )
}

/// A window `[t_i, t_j]` of a scene under the suite's [`gravity`]: the scene's true states at
/// both ends and its ideal readings (`SceneState::ideal_sample`) every `period_ns` from `t_i`
/// to `t_j` (both included), each plus a constant bias.
pub struct SceneWindow {
    /// The true state at `t_i`.
    pub state_i: preint::NavState,
    /// The true state at `t_j`.
    pub state_j: preint::NavState,
    /// The noise-free samples.
    pub clean: Vec<preint::ImuSample>,
}

impl SceneWindow {
    /// The window `[t_i_ns, t_j_ns]` of `scene` sampled every `period_ns`, the readings plus
    /// `bias`.
    pub fn new(
        scene: &dyn preint_sim::Scene,
        (t_i_ns, t_j_ns): (i64, i64),
        period_ns: i64,
        bias: &preint::ImuBias,
    ) -> Self {
        let clean = (0..=(t_j_ns - t_i_ns) / period_ns)
            .map(|k| {
                let t = t_i_ns + k * period_ns;
                let s = scene.state(preint_sim::t_s(t)).ideal_sample(t, &gravity());
                preint::ImuSample::new(t, s.gyro + bias.gyro, s.acc + bias.acc)
            })
            .collect();
        Self {
            state_i: true_state(scene, t_i_ns),
            state_j: true_state(scene, t_j_ns),
            clean,
        }
    }
}

/// The scene's exact state at `t_ns` as a [`preint::NavState`]: attitude body → world,
/// position \[m\] and velocity [m/s] in the world frame.
pub fn true_state(scene: &dyn preint_sim::Scene, t_ns: i64) -> preint::NavState {
    let s = scene.state(preint_sim::t_s(t_ns));
    preint::NavState::new(s.r_wb, s.p, s.v)
}

/// Every sample of `samples` pushed through one [`preint::Preintegrator`] with the bias
/// estimate `bias`: the window from the first to the last sample.
pub fn integrate_all(
    params: &preint::PreintParams,
    bias: &preint::ImuBias,
    samples: &[preint::ImuSample],
) -> preint::PreintegratedImu {
    let mut pi = preint::Preintegrator::with_capacity(params.clone(), *bias, samples.len())
        .expect("valid parameters");
    pi.integrate_slice(samples).expect("valid samples");
    pi.finish().expect("a measurement")
}

/// `<workspace>/tests/data` (real recordings, see its README).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// True when `PREINT_FULL=1` (full-size heavy runs).
pub fn full_run() -> bool {
    std::env::var("PREINT_FULL").is_ok_and(|v| v == "1")
}

/// Directory for JSON records: `$EVIDENCE_OUT` or `<workspace>/target/evidence` (created).
pub fn out_dir() -> PathBuf {
    let dir = std::env::var_os("EVIDENCE_OUT")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/evidence"));
    std::fs::create_dir_all(&dir).expect("create evidence output directory");
    dir
}

/// Writes `value` pretty-printed to `out_dir()/name` and returns the path.
pub fn write_json(name: &str, value: &serde_json::Value) -> PathBuf {
    let path = out_dir().join(name);
    std::fs::write(&path, serde_json::to_string_pretty(value).unwrap() + "\n")
        .expect("write evidence JSON");
    path
}

/// Rotation angle \[rad\] of `aᵀ b` (geodesic distance on SO(3)).
pub fn rot_angle(a: &SO3, b: &SO3) -> f64 {
    a.inverse().compose(b).log().norm()
}

/// Median (of a copy); NaN-free input expected. Panics on empty input.
pub fn median(v: &[f64]) -> f64 {
    quantile(v, 0.5)
}

/// Empirical quantile with linear interpolation between order statistics.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    assert!(!v.is_empty(), "quantile of an empty set");
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.partial_cmp(b).expect("NaN in quantile input"));
    let x = q * (s.len() - 1) as f64;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    s[lo] + (s[hi] - s[lo]) * (x - lo as f64)
}

/// Mean of a slice.
pub fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Least-squares slope of `log y` against `log x`.
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    assert_eq!(x.len(), y.len());
    assert!(x.len() >= 2, "need at least two points for a slope");
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let (mx, my) = (mean(&lx), mean(&ly));
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Wraps an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut r = a.rem_euclid(t);
    if r > std::f64::consts::PI {
        r -= t;
    }
    r
}

/// Deterministic Gaussian generator: xoshiro256** seeded by SplitMix64, Box–Muller normals.
/// Self-contained so the Monte Carlo results do not change with a dependency's version.
#[derive(Clone, Debug)]
pub struct Gauss {
    s: [u64; 4],
    spare: Option<f64>,
}

impl Gauss {
    /// A generator from a 64-bit seed.
    pub fn new(seed: u64) -> Self {
        let mut z = seed;
        let mut next = || {
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut x = z;
            x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            x ^ (x >> 31)
        };
        Self {
            s: [next(), next(), next(), next()],
            spare: None,
        }
    }

    /// Next raw 64-bit value (xoshiro256**).
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let r = s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        r
    }

    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }

    /// A vector of three independent normals scaled by `sigma`.
    pub fn normal3(&mut self, sigma: f64) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.normal(), self.normal(), self.normal()) * sigma
    }
}

/// `clean` with white noise of per-sample standard deviations `(σ_g, σ_a)` [rad/s, m/s²] and,
/// with `walk = Some((σ_bg, σ_ba))` (per-step standard deviations), a bias random walk from
/// zero, `b_k = b_{k−1} + w_k` for k ≥ 1, added to every sample; returns the samples and the
/// walk's value at the last one (`[b_g, b_a]`). Draws, per sample: the walk step (gyro, then
/// accelerometer; always drawn when `walk` is given), then the gyro noise, then the
/// accelerometer noise.
pub fn noisy_stream(
    clean: &[preint::ImuSample],
    rng: &mut Gauss,
    (sg, sa): (f64, f64),
    walk: Option<(f64, f64)>,
) -> (Vec<preint::ImuSample>, preint::ImuBias) {
    let (mut bg, mut ba) = (nalgebra::Vector3::zeros(), nalgebra::Vector3::zeros());
    let samples = clean
        .iter()
        .enumerate()
        .map(|(k, s)| {
            if let Some((sbg, sba)) = walk {
                let (wg, wa) = (rng.normal3(sbg), rng.normal3(sba));
                if k > 0 {
                    bg += wg;
                    ba += wa;
                }
            }
            let gyro = s.gyro + bg + rng.normal3(sg);
            preint::ImuSample::new(s.t_ns, gyro, s.acc + ba + rng.normal3(sa))
        })
        .collect();
    (samples, preint::ImuBias::new(bg, ba))
}

/// χ² quantiles used by the suite (tabulated values, e.g. scipy.stats.chi2.ppf).
pub mod chi2 {
    /// χ²₉ 0.99 quantile.
    pub const Q99_DOF9: f64 = 21.665_994;
    /// χ²₃ 0.99 quantile.
    pub const Q99_DOF3: f64 = 11.344_867;
    /// χ²₁₅ 0.99 quantile.
    pub const Q99_DOF15: f64 = 30.577_914;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_has_unit_variance() {
        let mut g = Gauss::new(7);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let m = mean(&xs);
        let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1) as f64;
        // Std of the mean is 1/√n ≈ 0.0022; of the variance √(2/n) ≈ 0.0032: 5σ bounds.
        assert!(m.abs() < 0.012, "mean {m}");
        assert!((var - 1.0).abs() < 0.016, "variance {var}");
    }

    #[test]
    fn slope_of_a_power_law() {
        let x = [1.0, 2.0, 4.0, 8.0];
        let y: Vec<f64> = x.iter().map(|v: &f64| 3.0 * v.powf(-2.5)).collect();
        assert!((loglog_slope(&x, &y) + 2.5).abs() < 1e-12);
    }
}
