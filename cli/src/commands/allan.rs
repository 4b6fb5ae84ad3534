//! `preint allan`: the overlapping Allan deviation of a static recording and its noise fits
//! ([`preint_analysis::allan`]: method, checks and the goodness of fit), with `--out` the Kalibr
//! `imu.yaml` (max over axes) and the charts allan_gyro.svg and allan_acc.svg.

use crate::charts::figures;
use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output};
use preint_analysis::allan::{AllanRun, Options};
use preint_analysis::format::IMU_AXES;
use preint_calib::allan::StillnessOptions;
use preint_io::write_kalibr_yaml;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Flags of `preint allan`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording (at rest) and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Output directory for the charts allan_gyro.svg and allan_acc.svg and the Kalibr imu.yaml.
    #[arg(help_heading = "Output", long)]
    pub out: Option<PathBuf>,
    /// Skip the check that the recording is static (the Allan deviation of a moving recording
    /// describes the motion, not the sensor's noise).
    #[arg(help_heading = "Input", long)]
    pub no_still_check: bool,
    /// Exit with status 2 (after printing the result) when the fit is not credible: the model
    /// curve √(N²/τ + K²τ/3) more than 5 statistical errors from the measured Allan deviation
    /// somewhere in the τ ranges its lines were fitted on.
    #[arg(help_heading = "Output", long)]
    pub strict: bool,
}

impl Args {
    /// What the library computes on.
    pub fn options(&self) -> Options {
        Options {
            input: self.input.to_input(),
            no_still_check: self.no_still_check,
        }
    }
}

/// Computes the Allan deviations and, with `--out`, writes the two charts and `imu.yaml`.
pub fn compute(args: &Args) -> Result<AllanRun, CliError> {
    let mut r = preint_analysis::allan::compute(&args.options())?;
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).map_err(|e| CliError::out_path(dir, e))?;
        for (sensor, name) in [(0, "allan_gyro.svg"), (1, "allan_acc.svg")] {
            let p = dir.join(name);
            figures::allan(&r.allan, sensor, &p)?;
            r.files.push(p.display().to_string());
        }
        let y = dir.join("imu.yaml");
        write_kalibr_yaml(&y, &r.allan.to_imu_noise())?;
        r.files.push(y.display().to_string());
    }
    Ok(r)
}

/// `still: …`: the stillness check's findings (with the accelerometer bias walk when it, not
/// motion, turns gravity) and whether the units were checked.
fn still_line(r: &AllanRun) -> String {
    let st = &r.stillness;
    let walk = if st.max_tilt_deg > StillnessOptions::default().max_tilt_deg {
        if st.tilt_is_bias_walk() {
            format!(
                " (the accelerometer bias walk: its norm changes by {:.3} m/s² as well; \
                 {:.2}° across moving windows)",
                st.max_norm_change_ms2, st.step_tilt_deg
            )
        } else {
            String::new()
        }
    } else {
        String::new()
    };
    format!(
        "still: {:.1} % of {} one-second windows, gravity turns by up to {:.2}°{walk}; units {}\n",
        100.0 * st.still_fraction(),
        st.windows,
        st.max_tilt_deg,
        if r.units_checked {
            "checked on the first 60 s"
        } else {
            "not checked"
        }
    )
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
    h.push_str(&still_line(r));
    h.push_str(&preint_analysis::recording::input_text(
        &r.source,
        &r.unit_check,
    ));
    if r.block_len > 1 {
        let _ = writeln!(
            h,
            "curves from means of {} samples (τ from {:.3} s; bounded memory)",
            r.block_len, a.tau0
        );
    }
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
    h.push_str(&fit_text(&a.fit(), "Allan noise model"));
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
    let output = Output {
        human: to_text(&r),
        json: preint_analysis::allan::to_json(&r),
    };
    crate::fit::strict(args.strict, output, &r.allan.fit(), "Allan noise model")
}
