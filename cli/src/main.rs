//! `preint`: the command line of the on-manifold IMU preintegration project.
//!
//! Every subcommand prints a human summary, or one JSON object on stdout with `--json`.
//! Errors go to stderr with a non-zero exit code and name the file, line and problem.

// Channel loops index several parallel arrays (axes, curves, fits) by the same index.
#![allow(clippy::needless_range_loop)]

mod args;
mod charts;
mod commands;
mod denoise;
mod html;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

const CONVENTIONS: &str = "\
Conventions: world frame z up, gravity (0, 0, -G) with G = 9.81 m/s² unless --gravity says \
otherwise; the accelerometer measures specific force (+G on the up axis at rest); rotations are \
perturbed on the right (R <- R Exp(dphi)); preintegration tangent order [dphi, dv, dp]; bias order \
[b_g, b_a]; timestamps integer nanoseconds.
IMU CSV (EuRoC imu0): a header line starting with '#', then rows of
  timestamp [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2]   (body frame, gyro first)
Noise file (Kalibr imu.yaml): continuous-time densities, not per-sample standard deviations:
  gyroscope_noise_density [rad/s/sqrt(Hz)], gyroscope_random_walk [rad/s^2/sqrt(Hz)],
  accelerometer_noise_density [m/s^2/sqrt(Hz)], accelerometer_random_walk [m/s^3/sqrt(Hz)], update_rate [Hz].";

/// On-manifold IMU preintegration: simulate, integrate, calibrate, measure noise, and chart
/// accuracy against cost.
#[derive(Parser, Debug)]
#[command(name = "preint", version, about, after_help = CONVENTIONS)]
pub struct Cli {
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long, global = true)]
    pub json: bool,
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Simulate an IMU on a built-in scene; writes imu.csv (EuRoC imu0), groundtruth.csv (EuRoC
    /// state_groundtruth_estimate0: p (m), q wxyz body->world, v (m/s), b_g (rad/s), b_a (m/s^2))
    /// and imu.yaml (Kalibr densities) into --out.
    Simulate {
        /// Scene: seed-ellipse, static, multi-pose-static, gimbal-lock, spin, aggressive.
        #[arg(long, default_value = "seed-ellipse")]
        scene: String,
        /// Sample rate (Hz).
        #[arg(long, default_value_t = 200.0)]
        rate: f64,
        /// Duration (s).
        #[arg(long, default_value_t = 10.0)]
        duration: f64,
        /// Noise: a Kalibr imu.yaml, or `none` for noise-free data. Default: EuRoC figures.
        #[arg(long)]
        noise: Option<String>,
        /// Random seed (same seed, same data on every machine).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
    },
    /// Preintegrate the samples with timestamps in [from, to] and print ΔR, Δv (m/s), Δp (m),
    /// Δt (s), the 9x9 covariance of [dphi, dv, dp] and the five bias Jacobians.
    Integrate {
        /// IMU CSV file (EuRoC imu0 format).
        #[arg(long)]
        imu: PathBuf,
        /// Integration scheme: euler, midpoint or rk4 (4th order, uses neighbouring samples).
        #[arg(long, default_value = "midpoint")]
        scheme: String,
        /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
        #[arg(long)]
        noise: Option<PathBuf>,
        /// Gravity magnitude G (m/s^2); gravity is (0, 0, -G).
        #[arg(long, default_value_t = 9.81)]
        gravity: f64,
        /// Gyro bias estimate b_g (rad/s) as x,y,z (negative values allowed: --bias-gyro=-0.01,0,0).
        #[arg(long, allow_hyphen_values = true, value_parser = args::vec3)]
        bias_gyro: Option<nalgebra::Vector3<f64>>,
        /// Accelerometer bias estimate b_a (m/s^2) as x,y,z.
        #[arg(long, allow_hyphen_values = true, value_parser = args::vec3)]
        bias_acc: Option<nalgebra::Vector3<f64>>,
        /// First keyframe time in ns (default: first sample).
        #[arg(long, allow_hyphen_values = true)]
        from: Option<i64>,
        /// Last keyframe time in ns (default: last sample).
        #[arg(long, allow_hyphen_values = true)]
        to: Option<i64>,
        /// Skip the check that the data looks like SI units (m/s^2, rad/s).
        #[arg(long)]
        no_unit_check: bool,
    },
    /// Evaluate the IMU factor at ground-truth states: residual, whitened residual and χ² of the
    /// window between the ground-truth rows nearest to --from and --to (is this IMU consistent
    /// with this ground truth?). The window is preintegrated with the ground truth's bias at
    /// keyframe i; --combined evaluates the 15-dim factor with the biases at i and j too.
    /// ImuFactor holds the bias constant over the window: on data whose bias drifts within
    /// the window (any real IMU over long windows), use --combined, whose weight includes the
    /// bias random walk. The χ² includes the ground truth's own errors unless they are given.
    Factor {
        /// IMU CSV file (EuRoC imu0 format).
        #[arg(long)]
        imu: PathBuf,
        /// Ground truth (EuRoC state_groundtruth_estimate0 format: p (m), q wxyz body->world,
        /// v (m/s), b_g (rad/s), b_a (m/s^2)), world frame z up.
        #[arg(long)]
        poses: PathBuf,
        /// Keyframe i: the ground-truth row nearest to this time (ns).
        #[arg(long, allow_hyphen_values = true)]
        from: i64,
        /// Keyframe j: the ground-truth row nearest to this time (ns).
        #[arg(long, allow_hyphen_values = true)]
        to: i64,
        /// Integration scheme: euler, midpoint or rk4.
        #[arg(long, default_value = "midpoint")]
        scheme: String,
        /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
        #[arg(long)]
        noise: Option<PathBuf>,
        /// Gravity magnitude G (m/s^2); gravity is (0, 0, -G).
        #[arg(long, default_value_t = 9.81)]
        gravity: f64,
        /// Evaluate CombinedImuFactor (15-dim residual with the bias change b_j - b_i, weighted
        /// by the covariance with the bias random walk) instead of ImuFactor (9-dim).
        #[arg(long)]
        combined: bool,
        /// Standard deviation of the ground truth's attitudes (rad), added to the weight.
        #[arg(long, default_value_t = 0.0)]
        pose_rot_std: f64,
        /// Standard deviation of the ground truth's positions (m), added to the weight.
        #[arg(long, default_value_t = 0.0)]
        pose_pos_std: f64,
        /// Standard deviation of the ground truth's velocities (m/s), added to the weight.
        #[arg(long, default_value_t = 0.0)]
        vel_std: f64,
        /// Skip the check that the data looks like SI units (m/s^2, rad/s).
        #[arg(long)]
        no_unit_check: bool,
    },
    /// Estimate IMU biases with Gauss-Newton, modelling only what the data makes observable.
    Calibrate {
        /// IMU CSV file (EuRoC imu0 format).
        #[arg(long)]
        imu: PathBuf,
        /// Known poses (EuRoC ground-truth format) for the known-pose problem.
        #[arg(long)]
        poses: Option<PathBuf>,
        /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
        #[arg(long)]
        noise: Option<PathBuf>,
        /// Gravity magnitude G (m/s^2).
        #[arg(long, default_value_t = 9.81)]
        gravity: f64,
        /// Use only samples (and poses) with timestamps >= this, in ns.
        #[arg(long, allow_hyphen_values = true)]
        from: Option<i64>,
        /// Use only samples (and poses) with timestamps <= this, in ns.
        #[arg(long, allow_hyphen_values = true)]
        to: Option<i64>,
        /// Known-pose problem: standard deviation of the given attitudes in rad (0: exact).
        /// E.g. 1.75e-3 (0.1°) and --pose-pos-std 0.005 for motion capture such as EuRoC's.
        #[arg(long, default_value_t = 0.0)]
        pose_rot_std: f64,
        /// Known-pose problem: standard deviation of the given positions in m (0: exact).
        #[arg(long, default_value_t = 0.0)]
        pose_pos_std: f64,
    },
    /// Overlapping Allan deviation, fitted noise density, random walk and bias instability;
    /// writes imu.yaml (Kalibr) and a chart into --out when given.
    Allan {
        /// IMU CSV file (EuRoC imu0 format), recorded at rest.
        #[arg(long)]
        imu: PathBuf,
        /// Output directory for allan.svg and imu.yaml.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Error against ground truth and cost per scheme and rate, with an accuracy-vs-cost chart.
    BenchSteps {
        /// Scene name.
        #[arg(long, default_value = "aggressive")]
        scene: String,
        /// Rates (Hz), comma-separated.
        #[arg(long, value_delimiter = ',', value_parser = args::positive, default_value = "25,50,100,200,400,800,1600,3200")]
        rates: Vec<f64>,
        /// Window length (s).
        #[arg(long, default_value_t = 1.0)]
        window: f64,
        /// Output directory for the charts.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Recommend the cheapest scheme and lowest rate whose discretisation error stays below a
    /// fraction of the noise-induced standard deviation.
    Advise {
        /// IMU CSV file (EuRoC imu0 format).
        #[arg(long)]
        imu: PathBuf,
        /// Kalibr imu.yaml with the noise densities.
        #[arg(long)]
        noise: PathBuf,
        /// Preintegration window (s).
        #[arg(long, default_value_t = 1.0)]
        window: f64,
        /// Allowed discretisation error as a fraction of the noise σ.
        #[arg(long, default_value_t = 0.1)]
        fraction: f64,
    },
    /// Throughput of each scheme on this machine (ns per sample), with and without covariance.
    Speed {
        /// Number of samples to integrate per measurement (default: the criterion bench's 10⁵).
        #[arg(long, default_value_t = 100_000)]
        samples: usize,
    },
    /// Everything above on built-in scenes, into one HTML page with charts.
    Report {
        /// Output directory (index.html and the SVG charts).
        #[arg(long, default_value = "out/report")]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match commands::run(&cli) {
        Ok(out) => {
            if cli.json {
                println!("{}", out.json);
            } else {
                print!("{}", out.human);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("preint: error: {e}");
            ExitCode::from(2)
        }
    }
}
