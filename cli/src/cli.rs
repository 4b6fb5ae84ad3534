//! The command line: the global flags ([`Cli`]) and the subcommands ([`Command`]), each with
//! its own flags in its module under [`crate::commands`].

use crate::commands::{advise, allan, bench_steps, calibrate, convert, factor, integrate, report};
use crate::commands::{initialise, simulate, speed};
use clap::{Parser, Subcommand};

const CONVENTIONS: &str = "\
Conventions: world frame z up, gravity (0, 0, -G) with G = 9.81 m/s² unless --gravity says \
otherwise; the accelerometer measures specific force (+G on the up axis at rest); rotations are \
perturbed on the right (R <- R Exp(dphi)); preintegration tangent order [dphi, dv, dp]; bias order \
[b_g, b_a]; timestamps integer nanoseconds.
Recordings (--imu FILE; the format is detected from the extension and the first lines, and what \
was decided is printed with the result, \"input\" in the JSON):
  EuRoC / TUM-VI imu0/data.csv    t [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2]
  UZH-FPV imu.txt                 id t [s] w a, space separated
  KITTI (GTSAM's example file)    Time dt accelX accelY accelZ omegaX omegaY omegaZ
  ROS 1 .bag, ROS 2 .mcap / .db3  sensor_msgs/Imu: --topic, --stamp header|record
  split gyroscope/accelerometer   --gyro FILE --accel FILE, or --gyro-topic T --accel-topic T
  any delimited text              columns from the header's names or --columns, units from \
--time-unit, --gyro-unit, --accel-unit
  Samples are body (IMU) frame, gyro in rad/s, accelerometer in m/s^2; each subcommand's --help \
lists the reader flags, the README's \"Your own data\" the details, `preint audit` what may be \
wrong with a recording and `preint convert` writes any of them as EuRoC CSV.
Noise file (Kalibr imu.yaml): continuous-time densities, not per-sample standard deviations:
  gyroscope_noise_density [rad/s/sqrt(Hz)], gyroscope_random_walk [rad/s^2/sqrt(Hz)],
  accelerometer_noise_density [m/s^2/sqrt(Hz)], accelerometer_random_walk [m/s^3/sqrt(Hz)], update_rate [Hz].
{schemes}
Exit status: 0 on success, 2 on an error (the message names the file, line or flag) or a refusal \
(e.g. audit --strict on a defect); output cut short by a closed pipe (`| head`) ends quietly, \
with the command's own status.
Examples:
  preint simulate --scene spin --duration 2 --out sim
  preint integrate --imu sim/imu.csv --noise sim/imu.yaml --from 0 --to 1000000000
  preint factor --imu sim/imu.csv --poses sim/groundtruth.csv --from 0 --to 1000000000";

/// [`CONVENTIONS`] with its `{schemes}` line: every scheme of the registry, its one-line help
/// and its aliases ([`crate::scheme::describe`]).
fn conventions() -> String {
    CONVENTIONS.replace(
        "{schemes}",
        &format!("Schemes: {}.", crate::scheme::describe()),
    )
}

/// On-manifold IMU preintegration: simulate, integrate, calibrate, measure noise, and chart
/// accuracy against cost.
#[derive(Parser, Debug)]
#[command(name = "preint", version, about, after_help = conventions())]
pub struct Cli {
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(help_heading = "Output", long, global = true)]
    pub json: bool,
    /// The subcommand and its flags.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Simulate an IMU on a built-in scene; writes imu.csv (EuRoC imu0), groundtruth.csv (EuRoC
    /// state_groundtruth_estimate0: p (m), q wxyz body->world, v (m/s), b_g (rad/s), b_a (m/s^2))
    /// and imu.yaml (Kalibr densities) into --out.
    Simulate(simulate::Args),
    /// Preintegrate the samples with timestamps in [from, to] and print ΔR, Δv (m/s), Δp (m),
    /// Δt (s), the 9x9 covariance of [dphi, dv, dp] (the JSON also has the 15x15 one with the
    /// biases) and the five bias Jacobians.
    Integrate(integrate::Args),
    /// Evaluate the IMU factor at ground-truth states: residual, whitened residual and χ² of the
    /// window between the ground-truth rows nearest to --from and --to (is this IMU consistent
    /// with this ground truth?).
    ///
    /// The window is preintegrated with the ground truth's bias at keyframe i; --combined evaluates the 15-dim factor with the biases at i and j too.
    /// ImuFactor holds the bias constant over the window: on data whose bias drifts within
    /// the window (any real IMU over long windows), use --combined, whose weight includes the
    /// bias random walk. The χ² includes the ground truth's own errors unless they are given.
    Factor(factor::Args),
    /// Estimate IMU biases with Gauss-Newton, modelling only what the data makes observable.
    ///
    /// The model follows from the input: with --poses, the known-pose problem (both biases,
    /// the velocities and gravity, from poses --pose-spacing apart; attitudes
    /// only: the gyro bias; --estimate adds the time offset and the intrinsics); otherwise, with
    /// still intervals at 3 or more distinct attitudes (more than 20° apart), the
    /// multi-position problem (both biases, the attitudes and, if BIC supports them, scale and
    /// misalignment); otherwise the single-attitude static problem on the longest still
    /// interval (gyro bias, roll and pitch; the accelerometer bias cannot be told from tilt
    /// and is printed as unobservable). A recording with neither poses nor a still interval is
    /// refused (exit 2). The model chosen is printed ("model" in the JSON).
    Calibrate(calibrate::Args),
    /// Visual-inertial initialisation from a front end's keyframe poses (known up to scale, or
    /// metric): gravity, scale, keyframe velocities and both biases with their covariance, and
    /// whether they are known well enough to start from ("ready"; a window that is not ready
    /// still exits 0 and says why). A linear start (VINS-Mono's alignment), then the
    /// maximum-a-posteriori refinement on the preintegrated windows, the scale by its profile
    /// likelihood.
    Initialise(initialise::Args),
    /// Overlapping Allan deviation, fitted noise density, random walk and bias instability;
    /// writes imu.yaml (Kalibr) and the charts allan_gyro.svg and allan_acc.svg into --out when
    /// given.
    Allan(allan::Args),
    /// Error against the exact deltas and cost per scheme and rate on a built-in scene
    /// (noise-free), with the accuracy-vs-cost and convergence charts into --out when given.
    BenchSteps(bench_steps::Args),
    /// Recommend the cheapest scheme and lowest rate whose discretisation error stays below a
    /// fraction of the noise-induced standard deviation.
    Advise(advise::Args),
    /// Throughput of each scheme on this machine (ns per sample), with and without covariance.
    Speed(speed::Args),
    /// Write any readable recording (text in any layout and units, bag, MCAP, db3, split
    /// streams) as EuRoC CSV (t ns, w rad/s, a m/s^2).
    Convert(convert::Args),
    /// Audit a recording: rate, drift, jitter, gaps, duplicates, out-of-order samples, clipping,
    /// units, stillness; a verdict, exit 2 on a defect with --strict.
    Audit(crate::commands::audit::Args),
    /// Everything above on built-in scenes, into one HTML page with charts; with --imu, on a
    /// recording: audit, advice, with --poses the noise model's consistency and its fit, for a
    /// static recording Allan and the static calibration.
    Report(report::Args),
}
