//! `preint allan`: overlapping Allan deviation of a static recording, fitted white-noise
//! density (slope −½ read at τ = 1 s), random walk (slope +½ read at τ = 3 s) and bias
//! instability (flat minimum / 0.664); Kalibr `imu.yaml` (max over axes) and a chart.

use super::{CliError, Output};
use crate::Command;
use crate::charts::{Chart, Series, draw};
use preint::io::{read_euroc_imu, write_kalibr_yaml};
use preint_calib::allan::ImuAllan;
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

const AXES: [&str; 6] = ["gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"];

/// Writes the Allan chart of the three axes of one sensor (gyro: channels 0..3, acc: 3..6),
/// with the fitted white-noise (slope −½) and random-walk (slope +½) lines.
pub fn allan_chart(a: &ImuAllan, sensor: usize, path: &Path) -> Result<(), CliError> {
    let mut series = Vec::new();
    for ch in sensor * 3..sensor * 3 + 3 {
        let pts = a.curves[ch].iter().map(|p| (p.tau, p.adev)).collect();
        series.push(Series::line(AXES[ch], pts));
    }
    let taus: Vec<f64> = a.curves[sensor * 3].iter().map(|p| p.tau).collect();
    for ch in sensor * 3..sensor * 3 + 3 {
        let f = &a.fits[ch];
        series.push(Series::reference(
            format!("{} N/√τ", AXES[ch]),
            taus.iter()
                .map(|&t| (t, f.white_density / t.sqrt()))
                .collect(),
        ));
        if !f.random_walk_is_bound {
            series.push(Series::reference(
                format!("{} K√(τ/3)", AXES[ch]),
                taus.iter()
                    .map(|&t| (t, f.random_walk * (t / 3.0).sqrt()))
                    .collect(),
            ));
        }
    }
    let (title, y) = if sensor == 0 {
        ("Allan deviation: gyroscope", "σ(τ) [rad/s]")
    } else {
        ("Allan deviation: accelerometer", "σ(τ) [m/s²]")
    };
    draw(
        path,
        &Chart {
            title,
            x_label: "τ [s]",
            y_label: y,
            log_x: true,
            log_y: true,
        },
        &series,
    )
    .map_err(CliError::Failed)
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Allan { imu, out } = cmd else {
        unreachable!()
    };
    let samples = read_euroc_imu(imu)?;
    let a = ImuAllan::from_samples(&samples, 10)
        .map_err(|e| CliError::Failed(format!("{}: {e}", imu.display())))?;
    let noise = a.to_imu_noise();
    let mut files = Vec::new();
    if let Some(dir) = out {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Failed(format!("{}: {e}", dir.display())))?;
        for (sensor, name) in [(0, "allan_gyro.svg"), (1, "allan_acc.svg")] {
            let p = dir.join(name);
            allan_chart(&a, sensor, &p)?;
            files.push(p.display().to_string());
        }
        let y = dir.join("imu.yaml");
        write_kalibr_yaml(&y, &noise)?;
        files.push(y.display().to_string());
    }
    let per_axis: Vec<_> = (0..6)
        .map(|c| {
            let f = &a.fits[c];
            json!({"axis": AXES[c], "noise_density": f.white_density, "noise_density_err": f.white_density_err,
                   "noise_density_is_upper_bound": f.white_density_is_bound,
                   "random_walk": f.random_walk, "random_walk_err": f.random_walk_err,
                   "random_walk_is_upper_bound": f.random_walk_is_bound,
                   "bias_instability": f.bias_instability, "bias_instability_tau": f.bias_instability_tau})
        })
        .collect();
    let json = json!({
        "samples": samples.len(),
        "sample_period_s": a.dt,
        "gyroscope_noise_density": [a.fits[0].white_density, a.fits[1].white_density, a.fits[2].white_density],
        "gyroscope_random_walk": [a.fits[0].random_walk, a.fits[1].random_walk, a.fits[2].random_walk],
        "accelerometer_noise_density": [a.fits[3].white_density, a.fits[4].white_density, a.fits[5].white_density],
        "accelerometer_random_walk": [a.fits[3].random_walk, a.fits[4].random_walk, a.fits[5].random_walk],
        "bias_instability": (0..6).map(|c| a.fits[c].bias_instability).collect::<Vec<_>>(),
        "units": {"gyroscope_noise_density": "rad/s/sqrt(Hz)", "gyroscope_random_walk": "rad/s^2/sqrt(Hz)",
                  "accelerometer_noise_density": "m/s^2/sqrt(Hz)", "accelerometer_random_walk": "m/s^3/sqrt(Hz)",
                  "bias_instability": "rad/s (gyro), m/s^2 (acc)"},
        "yaml_aggregate": "maximum over the three axes (conservative)",
        "per_axis": per_axis,
        "files": files,
    });
    let mut h = format!(
        "{}: {} samples at {:.1} Hz ({:.0} s)\n",
        imu.display(),
        samples.len(),
        1.0 / a.dt,
        a.dt * samples.len() as f64
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
            AXES[c],
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
        if files.is_empty() {
            String::new()
        } else {
            format!(" Wrote {}", files.join(", "))
        }
    );
    Ok(Output { human: h, json })
}
