//! `preint allan`: overlapping Allan deviation of a static recording, fitted white-noise
//! density (slope −½ read at τ = 1 s), random walk (slope +½ read at τ = 3 s) and bias
//! instability (flat minimum / 0.664); Kalibr `imu.yaml` (max over axes) and a chart
//! (IEEE Std 952-1997, annex C).

use crate::charts::figures;
use crate::format::IMU_AXES;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output};
use preint_calib::allan::ImuAllan;
use preint_io::write_kalibr_yaml;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Flags of `preint allan`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording (at rest) and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Output directory for allan.svg and imu.yaml.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The Allan deviations, their fits, and the files written.
#[derive(Clone, Debug)]
pub struct AllanRun {
    /// The IMU file, as printed.
    pub imu: String,
    /// Number of samples.
    pub samples: usize,
    /// Curves and fits per channel (order [`IMU_AXES`]).
    pub allan: ImuAllan,
    /// Charts and `imu.yaml`, when `--out` is given.
    pub files: Vec<String>,
}

/// Computes the Allan deviations and, with `--out`, writes the two charts and `imu.yaml`.
pub fn compute(args: &Args) -> Result<AllanRun, CliError> {
    let (samples, _) = args.input.read_all()?;
    let a = ImuAllan::from_samples(&samples, 10)
        .map_err(|e| CliError::failed_in(args.input.path(), e))?;
    let mut files = Vec::new();
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).map_err(|e| CliError::failed_in(dir, e))?;
        for (sensor, name) in [(0, "allan_gyro.svg"), (1, "allan_acc.svg")] {
            let p = dir.join(name);
            figures::allan(&a, sensor, &p)?;
            files.push(p.display().to_string());
        }
        let y = dir.join("imu.yaml");
        write_kalibr_yaml(&y, &a.to_imu_noise())?;
        files.push(y.display().to_string());
    }
    Ok(AllanRun {
        imu: args.input.label(),
        samples: samples.len(),
        allan: a,
        files,
    })
}

/// The JSON form: per-sensor densities (per axis), bias instability, per-axis details, files.
pub fn to_json(r: &AllanRun) -> Value {
    let a = &r.allan;
    let per_axis: Vec<_> = (0..6)
        .map(|c| {
            let f = &a.fits[c];
            json!({"axis": IMU_AXES[c], "noise_density": f.white_density, "noise_density_err": f.white_density_err,
                   "noise_density_is_upper_bound": f.white_density_is_bound,
                   "random_walk": f.random_walk, "random_walk_err": f.random_walk_err,
                   "random_walk_is_upper_bound": f.random_walk_is_bound,
                   "bias_instability": f.bias_instability, "bias_instability_tau": f.bias_instability_tau})
        })
        .collect();
    let white = |c0: usize| {
        (c0..c0 + 3)
            .map(|c| a.fits[c].white_density)
            .collect::<Vec<_>>()
    };
    let walk = |c0: usize| {
        (c0..c0 + 3)
            .map(|c| a.fits[c].random_walk)
            .collect::<Vec<_>>()
    };
    json!({
        "samples": r.samples,
        "sample_period_s": a.dt,
        "gyroscope_noise_density": white(0),
        "gyroscope_random_walk": walk(0),
        "accelerometer_noise_density": white(3),
        "accelerometer_random_walk": walk(3),
        "bias_instability": (0..6).map(|c| a.fits[c].bias_instability).collect::<Vec<_>>(),
        "units": {"gyroscope_noise_density": "rad/s/sqrt(Hz)", "gyroscope_random_walk": "rad/s^2/sqrt(Hz)",
                  "accelerometer_noise_density": "m/s^2/sqrt(Hz)", "accelerometer_random_walk": "m/s^3/sqrt(Hz)",
                  "bias_instability": "rad/s (gyro), m/s^2 (acc)"},
        "yaml_aggregate": "maximum over the three axes (conservative)",
        "per_axis": per_axis,
        "files": r.files,
    })
}

/// The human summary: a table of the fits per axis.
pub fn to_text(r: &AllanRun) -> String {
    let a = &r.allan;
    let mut h = format!(
        "{}: {} samples at {:.1} Hz ({:.0} s)\n",
        r.imu,
        r.samples,
        1.0 / a.dt,
        a.dt * r.samples as f64
    );
    let _ = writeln!(
        h,
        "{:<8} {:>16} {:>16} {:>16}",
        "axis", "noise density", "random walk", "bias instab."
    );
    for c in 0..6 {
        let f = &a.fits[c];
        let _ = writeln!(
            h,
            "{:<8} {:>15.4e}{} {:>15.4e}{} {:>16.4e}",
            IMU_AXES[c],
            f.white_density,
            if f.white_density_is_bound { "≤" } else { " " },
            f.random_walk,
            if f.random_walk_is_bound { "≤" } else { " " },
            f.bias_instability
        );
    }
    let _ = writeln!(
        h,
        "units: gyro rad/s/√Hz, rad/s²/√Hz, rad/s; acc m/s²/√Hz, m/s³/√Hz, m/s². ≤: upper bound (no region of slope −½ resp. +½ in the data)"
    );
    let _ = writeln!(
        h,
        "imu.yaml uses the maximum over the axes.{}",
        if r.files.is_empty() {
            String::new()
        } else {
            format!(" Wrote {}", r.files.join(", "))
        }
    );
    h
}

/// Runs `preint allan`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}
