//! The numbers of `preint report`, on built-in simulated scenes (no input files).
//!
//! 1. Accuracy against cost and convergence order on `seed-ellipse` and `aggressive`
//!    ([`super::accuracy`], rates [`RATES`], 1 s window).
//! 2. Monte Carlo NEES per scene and scheme ([`mean_nees`]).
//! 3. Attitude error of dead reckoning with quaternions, rotation matrices and ZYX Euler angles
//!    through the `gimbal-lock` scene ([`gimbal_lock`]).
//! 4. A static single-attitude bias calibration of a simulated recording with known biases
//!    ([`static_calibration`]).
//! 5. The Allan deviation of a simulated static hour and its fitted densities ([`allan_hour`]).
//! 6. `advise` on simulated noisy recordings of [`ADVISE_SCENES`] ([`advise_scene`]).
//! 7. Throughput per scheme and level ([`preint_analysis::speed::throughput`]).
//!
//! [`conclusions()`] turns these numbers into the statements at the top of the page.

mod conclusions;

pub use conclusions::conclusions;

use super::accuracy::{self, Row};
use crate::{CliError, input, scheme};
use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, Level, NavState, PreintParams, Scheme, preintegrate};
use preint_analysis::advise::{self, Candidate};
use preint_analysis::denoise::denoise;
use preint_analysis::speed::{self, Throughput};
use preint_calib::allan::ImuAllan;
use preint_calib::bias::StaticCalibration;
use preint_sim::{Attitude, Rule, SimConfig, rotation_error, t_s};

/// The scenes of the accuracy and NEES sections.
pub const SCENES: [&str; 2] = ["seed-ellipse", "aggressive"];
/// The rates \[Hz\] of the accuracy section.
pub const RATES: [f64; 8] = [25.0, 50.0, 100.0, 200.0, 400.0, 800.0, 1600.0, 3200.0];
/// Noise realisations per NEES row.
pub const NEES_RUNS: u64 = 200;

/// The scenes `advise` runs on.
pub const ADVISE_SCENES: [&str; 2] = ["seed-ellipse", "aggressive"];
/// Rate \[Hz\] and length \[s\] of the recordings `advise` runs on.
pub const ADVISE_RECORDING: (f64, f64) = (400.0, 30.0);
/// `advise`'s window \[s\] and threshold (fraction of the noise σ): its defaults.
pub const ADVISE_WINDOW_FRACTION: (f64, f64) = (1.0, 0.1);
/// Samples per speed measurement and runs (the median is reported).
pub const SPEED_SAMPLES_RUNS: (usize, usize) = (20_000, 5);

/// A named curve of `(x, y)` points.
pub type Curve = (&'static str, Vec<(f64, f64)>);

/// Everything the report shows.
#[derive(Clone, Debug)]
pub struct ReportData {
    /// Per scene of [`SCENES`]: every scheme at every rate of [`RATES`].
    pub accuracy: Vec<(&'static str, Vec<Row>)>,
    /// (scene, scheme, mean NEES over [`NEES_RUNS`] runs).
    pub nees: Vec<(&'static str, Scheme, f64)>,
    /// Attitude error against time per attitude representation: (name, [(t \[s\], error \[rad\])]).
    pub gimbal_lock: Vec<Curve>,
    /// The static calibration and its true biases.
    pub calibration: StaticCheck,
    /// The Allan analysis of the simulated hour.
    pub allan: AllanCheck,
    /// `advise` per scene of [`ADVISE_SCENES`].
    pub advice: Vec<AdviceCheck>,
    /// Median ns/sample per scheme and level ([`SPEED_SAMPLES_RUNS`]).
    pub speed: Vec<Throughput>,
}

/// `advise` on a simulated noisy recording of a built-in scene.
#[derive(Clone, Debug)]
pub struct AdviceCheck {
    /// The scene.
    pub scene: &'static str,
    /// Low-pass cutoffs \[Hz\] found for (gyro, accelerometer).
    pub cutoffs: [Option<f64>; 2],
    /// Every (scheme, rate) evaluated.
    pub candidates: Vec<Candidate>,
    /// Index of the recommended candidate, if any is acceptable.
    pub recommended: Option<usize>,
}

impl AdviceCheck {
    /// The recommended candidate, if any.
    pub fn recommendation(&self) -> Option<&Candidate> {
        self.recommended.map(|i| &self.candidates[i])
    }
}

/// A bias calibration against the biases it was simulated with.
#[derive(Clone, Debug)]
pub struct StaticCheck {
    /// The simulated (constant) biases.
    pub truth: ImuBias,
    /// The estimate.
    pub cal: StaticCalibration,
}

/// An Allan analysis against the densities it was simulated with.
#[derive(Clone, Debug)]
pub struct AllanCheck {
    /// The simulated densities.
    pub simulated: ImuNoise,
    /// Curves and fits (the fitted densities: [`ImuAllan::to_imu_noise`]).
    pub allan: ImuAllan,
}

/// Number of `progress` calls of [`compute`].
pub const STEPS: u64 = 7;

/// Computes every section, calling `progress` with the name of each finished one ([`STEPS`]
/// calls).
pub fn compute(progress: &mut dyn FnMut(&str)) -> Result<ReportData, CliError> {
    let accuracy = SCENES
        .iter()
        .map(|&scene| Ok((scene, accuracy::measure(scene, &RATES, 1.0)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    progress("accuracy and cost");
    let mut nees = Vec::new();
    for scene in SCENES {
        for scheme in scheme::ALL {
            nees.push((scene, scheme, mean_nees(scene, scheme, NEES_RUNS)?));
        }
    }
    progress("Monte Carlo NEES");
    let gimbal_lock = gimbal_lock()?;
    progress("gimbal lock");
    let calibration = static_calibration()?;
    progress("calibration");
    let allan = allan_hour()?;
    progress("Allan deviation");
    let advice = ADVISE_SCENES
        .iter()
        .map(|&s| advise_scene(s))
        .collect::<Result<Vec<_>, _>>()?;
    progress("advise");
    let speed = speed::throughput(SPEED_SAMPLES_RUNS.0, SPEED_SAMPLES_RUNS.1)?;
    progress("speed");
    Ok(ReportData {
        accuracy,
        nees,
        gimbal_lock,
        calibration,
        allan,
        advice,
        speed,
    })
}

/// Mean NEES of `runs` noisy preintegrations of `scene` (200 Hz, window [1 s, 2 s], EuRoC white
/// noise, fixed zero bias) against the noise-free run of the same scheme: the mean of
/// `eᵀΣ⁻¹e` with `e = [Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀]`; 9 for a consistent covariance.
pub fn mean_nees(scene: &str, scheme: Scheme, runs: u64) -> Result<f64, CliError> {
    let sc = input::scene(scene)?;
    let noise = ImuNoise::euroc();
    let params = PreintParams::from_noise(&noise)
        .with_scheme(scheme)
        .with_level(Level::Covariance);
    let (t_i, t_j) = (1_000_000_000, 2_000_000_000);
    let clean = preint_sim::simulate(sc.as_ref(), 200.0, 3.0, &SimConfig::noise_free(), 0)
        .map_err(CliError::failed)?;
    let m0 = preintegrate(&params, &ImuBias::zero(), &clean.samples, t_i, t_j)
        .map_err(CliError::failed)?;
    let cfg = SimConfig {
        bias_random_walk: false,
        ..SimConfig::with_noise(noise)
    };
    let mut sum = 0.0;
    for seed in 0..runs {
        let noisy = preint_sim::simulate(sc.as_ref(), 200.0, 3.0, &cfg, 1000 + seed)
            .map_err(CliError::failed)?;
        let m = preintegrate(&params, &ImuBias::zero(), &noisy.samples, t_i, t_j)
            .map_err(CliError::failed)?;
        let e = m.delta_error(&m0);
        let chol = m
            .cov
            .cholesky()
            .ok_or_else(|| CliError::failed("covariance not positive definite"))?;
        sum += e.dot(&chol.solve(&e));
    }
    Ok(sum / runs as f64)
}

/// Attitude error against time of 200 Hz midpoint dead reckoning through the `gimbal-lock`
/// scene (noise-free, 12 s, every 10th sample), with quaternions, rotation matrices (`Exp`)
/// and ZYX Euler angles. Errors are floored at 1e-16 rad for a log axis; a non-finite error
/// (the Euler-angle state blown up) is NaN.
pub fn gimbal_lock() -> Result<Vec<Curve>, CliError> {
    let sc = input::scene("gimbal-lock")?;
    let g = Vector3::new(0.0, 0.0, -9.81);
    let step = 5_000_000i64;
    let samples: Vec<_> = (0..=2400)
        .map(|k| sc.state(t_s(k * step)).ideal_sample(k * step, &g))
        .collect();
    let s0 = sc.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let mut curves = Vec::new();
    for (name, att) in [
        ("quaternion", Attitude::Quaternion),
        ("rotation matrix (Exp)", Attitude::Matrix),
        ("Euler angles ZYX", Attitude::EulerZyx),
    ] {
        let tr =
            preint_sim::dead_reckon(&samples, &init, &ImuBias::zero(), &g, Rule::Midpoint, att);
        let pts = tr
            .iter()
            .zip(&samples)
            .step_by(10)
            .map(|(x, s)| {
                let e = rotation_error(&sc.state(t_s(s.t_ns)).r_wb, &x.r);
                let e = if e.is_finite() {
                    e.max(1e-16)
                } else {
                    f64::NAN
                };
                (t_s(s.t_ns), e)
            })
            .collect();
        curves.push((name, pts));
    }
    Ok(curves)
}

/// Gyro bias and tilt from 60 s of the `static` scene at 200 Hz (EuRoC white noise, constant
/// biases b_g = (0.002, −0.0015, 0.001) rad/s, b_a = (0.05, −0.03, 0.02) m/s², seed 42).
pub fn static_calibration() -> Result<StaticCheck, CliError> {
    let st = input::scene("static")?;
    let truth = ImuBias::new(
        Vector3::new(0.002, -0.0015, 0.001),
        Vector3::new(0.05, -0.03, 0.02),
    );
    let cfg = SimConfig {
        initial_bias: truth,
        bias_random_walk: false,
        ..SimConfig::with_noise(ImuNoise::euroc())
    };
    let rec = preint_sim::simulate(st.as_ref(), 200.0, 60.0, &cfg, 42).map_err(CliError::failed)?;
    let cal =
        preint_calib::bias::calibrate_static(&rec.samples, &ImuNoise::euroc(), &Default::default())
            .map_err(CliError::failed)?;
    Ok(StaticCheck { truth, cal })
}

/// Allan analysis of a simulated static hour at 100 Hz (EuRoC densities with bias random
/// walk, seed 7).
pub fn allan_hour() -> Result<AllanCheck, CliError> {
    let st = input::scene("static")?;
    let simulated = ImuNoise {
        update_rate_hz: 100.0,
        ..ImuNoise::euroc()
    };
    let cfg = SimConfig::with_noise(simulated);
    let hour =
        preint_sim::simulate(st.as_ref(), 100.0, 3600.0, &cfg, 7).map_err(CliError::failed)?;
    let allan = ImuAllan::from_samples(&hour.samples, 10).map_err(CliError::failed)?;
    Ok(AllanCheck { simulated, allan })
}

/// `advise` ([`preint_analysis::advise`], after [`preint_analysis::denoise`]) on a noisy recording of `scene`
/// ([`ADVISE_RECORDING`], EuRoC densities with bias random walk, seed 1), with the default
/// window and threshold ([`ADVISE_WINDOW_FRACTION`]).
pub fn advise_scene(scene: &'static str) -> Result<AdviceCheck, CliError> {
    let sc = input::scene(scene)?;
    let (rate, duration) = ADVISE_RECORDING;
    let noise = ImuNoise {
        update_rate_hz: rate,
        ..ImuNoise::euroc()
    };
    let rec = preint_sim::simulate(
        sc.as_ref(),
        rate,
        duration,
        &SimConfig::with_noise(noise),
        1,
    )
    .map_err(CliError::failed)?;
    let (signal, cutoffs) = denoise(
        &rec.samples,
        noise.gyro_noise_density,
        noise.acc_noise_density,
    );
    let (window, fraction) = ADVISE_WINDOW_FRACTION;
    let candidates = advise::evaluate(&signal, &noise, 9.81, window, fraction)?;
    let recommended = advise::recommend(&candidates)
        .and_then(|r| candidates.iter().position(|c| std::ptr::eq(c, r)));
    Ok(AdviceCheck {
        scene,
        cutoffs,
        candidates,
        recommended,
    })
}

/// The worst ratio of discretisation error to noise σ over rotation, velocity and position.
pub fn worst_ratio(c: &Candidate) -> f64 {
    (0..3)
        .map(|k| c.disc_err[k] / c.noise_sigma[k])
        .fold(0.0, f64::max)
}

/// Indices of the Pareto-optimal points when minimising both coordinates (cost, error), in
/// order of increasing cost.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut best = f64::INFINITY;
    let mut front = Vec::new();
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// A run of consecutive points of one scheme on the Pareto front of position error against
/// cost: for every error budget from its smallest error up to the previous run's smallest
/// error, this scheme (at one of these rates) is the cheapest.
#[derive(Clone, Debug)]
pub struct FrontRun {
    /// The scheme.
    pub scheme: Scheme,
    /// Its front points, in order of increasing cost (decreasing error).
    pub rows: Vec<Row>,
}

impl FrontRun {
    /// The smallest position error \[m\] of the run.
    pub fn min_err(&self) -> f64 {
        self.rows.last().map_or(f64::NAN, |r| r.err[2])
    }
}

/// The Pareto front of position error against cost (per second of data) of `rows`, split into
/// runs of one scheme, in order of increasing cost.
pub fn front_runs(rows: &[Row]) -> Vec<FrontRun> {
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.cost_per_s(), r.err[2])).collect();
    let mut runs: Vec<FrontRun> = Vec::new();
    for i in pareto_front(&pts) {
        let r = rows[i].clone();
        match runs.last_mut() {
            Some(run) if run.scheme == r.scheme => run.rows.push(r),
            _ => runs.push(FrontRun {
                scheme: r.scheme,
                rows: vec![r],
            }),
        }
    }
    runs
}

/// Half width of the 3σ band of a mean NEES over `runs` runs: the NEES of a consistent 9×9
/// covariance is χ²₉ (variance 18).
pub fn nees_band_half(runs: u64) -> f64 {
    3.0 * (18.0 / runs as f64).sqrt()
}

/// A rate \[Hz\] as printed: at most three decimals, without trailing zeros (a decimated rate
/// such as 400/16 is computed as 24.999… Hz).
pub fn hz(rate: f64) -> String {
    format!("{}", (rate * 1e3).round() / 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [
            (1.0, 10.0),
            (2.0, 5.0),
            (3.0, 7.0),
            (4.0, 1.0),
            (5.0, 1.0),
            (0.5, f64::NAN),
        ];
        assert_eq!(pareto_front(&pts), vec![0, 1, 3]);
    }

    fn row(scheme: Scheme, rate: f64, ns: f64, pos: f64) -> Row {
        Row {
            scheme,
            rate,
            ns_per_sample: ns,
            err: [0.0, 0.0, pos],
        }
    }

    /// Euler's cheapest point, then midpoint at two rates, then hermite4; galilean never.
    pub(super) fn rows() -> Vec<Row> {
        vec![
            row(Scheme::Euler, 25.0, 10.0, 1e-1),
            row(Scheme::Euler, 50.0, 10.0, 5e-2),
            row(Scheme::Galilean, 25.0, 14.0, 1e-1),
            row(Scheme::Galilean, 50.0, 14.0, 5e-2),
            row(Scheme::Midpoint, 25.0, 12.0, 1e-2),
            row(Scheme::Midpoint, 50.0, 12.0, 2.5e-3),
            row(Scheme::Hermite4, 25.0, 40.0, 1e-4),
            row(Scheme::Hermite4, 50.0, 40.0, 6e-6),
        ]
    }

    #[test]
    fn front_runs_split_the_front_by_scheme() {
        let runs = front_runs(&rows());
        let schemes: Vec<Scheme> = runs.iter().map(|r| r.scheme).collect();
        assert_eq!(schemes, [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4]);
        assert_eq!(runs[1].rows.len(), 2);
        assert_eq!(runs[1].min_err(), 2.5e-3);
        assert_eq!(hz(400.0 / 16.0 * (1.0 - 1e-16)), "25");
        assert_eq!(hz(12.5), "12.5");
    }
}
