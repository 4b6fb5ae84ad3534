//! `preint report`: one self-contained HTML page, on built-in scenes (no input files) or,
//! with `--imu`, on the user's recording ([`recording`]).
//!
//! On the built-in scenes, the sections, after a conclusions box computed from the figures
//! ([`crate::analysis::report::conclusions`]): accuracy against cost with the Pareto front
//! (`seed-ellipse`, `aggressive`), error against rate with the fitted convergence orders, what
//! `preint advise` recommends on simulated noisy recordings, the cost per sample of each scheme
//! and level, Monte Carlo NEES per scheme, the gimbal-lock failure of Euler-angle dead
//! reckoning, a bias calibration from a simulated static recording, and the Allan deviation of
//! both sensors with the fitted densities (the numbers: [`crate::analysis::report`]). The SVG
//! charts are written beside `index.html` and also embedded in it.

use crate::analysis::report::{self, ReportData, StaticCheck};
use crate::html::Page;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output, scheme};
use preint_analysis::progress;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

pub mod recording;
mod sections;

use sections::{
    accuracy_section, advice_section, allan_section, calibration_section, convergence_section,
    gimbal_lock_section, nees_section, speed_section,
};

/// Flags of `preint report`: without `--imu`, the built-in scenes; with it, the recording
/// ([`recording`]).
#[derive(clap::Args, Debug, Clone)]
#[command(mut_arg("imu", |a| a.required_unless_present(clap::builder::Resettable::<clap::Id>::Reset)))]
pub struct Args {
    /// Output directory (index.html and the SVG charts; with --imu also the fitted imu.yaml).
    #[arg(help_heading = "Output", long, default_value = "out/report")]
    pub out: PathBuf,
    /// A recording to report on instead of the built-in scenes (with the reader flags): the
    /// audit's verdict, the scheme and keyframe rate its motion needs, with --poses the
    /// consistency of the noise model per window length and the fitted noise model, and for a
    /// static recording the Allan deviation and the static calibration.
    #[command(flatten)]
    pub input: Option<ImuArgs>,
    /// With --imu: EuRoC ground truth with velocities and biases (p (m), q wxyz body->world,
    /// v (m/s), b_g (rad/s), b_a (m/s^2)), for the consistency per window length and the
    /// fitted noise model.
    #[arg(help_heading = "Ground truth", long)]
    pub poses: Option<PathBuf>,
    /// With --imu: Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(help_heading = "Sensor model", long)]
    pub noise: Option<PathBuf>,
    /// With --poses: standard deviation of the ground truth's attitudes (rad), added to the
    /// weight with the given noise (else 0) and held in the noise fit (else fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "RAD",
        allow_hyphen_values = true
    )]
    pub pose_rot_std: Option<f64>,
    /// With --poses: standard deviation of the ground truth's positions (m), added to the
    /// weight with the given noise (else 0) and held in the noise fit (else fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M",
        allow_hyphen_values = true
    )]
    pub pose_pos_std: Option<f64>,
    /// With --poses: standard deviation of the ground truth's velocities (m/s), added to the
    /// weight with the given noise (else 0) and held in the noise fit (else fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M/S",
        allow_hyphen_values = true
    )]
    pub vel_std: Option<f64>,
    /// With --poses: standard deviation (per axis) of the ground truth's gyroscope bias
    /// (rad/s), added to the weight through the measurement's bias Jacobian with the given
    /// noise (else 0) and held in the noise fit (else fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "RAD/S",
        allow_hyphen_values = true
    )]
    pub bias_gyro_std: Option<f64>,
    /// With --poses: standard deviation (per axis) of the ground truth's accelerometer bias
    /// (m/s^2), added to the weight through the measurement's bias Jacobian with the given
    /// noise (else 0) and held in the noise fit (else fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M/S2",
        allow_hyphen_values = true
    )]
    pub bias_acc_std: Option<f64>,
}

/// Runs `f` of `steps` steps with a progress bar at a terminal (`f` names each step as it
/// starts it), cleared when it ends.
pub(crate) fn with_progress<T>(
    steps: u64,
    f: impl FnOnce(&mut dyn FnMut(&str)) -> Result<T, CliError>,
) -> Result<T, CliError> {
    let pb = progress::bar(steps, "report");
    let out = f(&mut |msg| {
        if let Some(pb) = &pb {
            pb.set_message(msg.to_string());
            pb.inc(1);
        }
    });
    if let Some(pb) = &pb {
        pb.finish_and_clear();
    }
    out
}

/// The report's numbers, its conclusions and the files written.
#[derive(Clone, Debug)]
pub struct Report {
    /// The numbers.
    pub data: ReportData,
    /// The conclusions drawn from them (plain text, code between backticks).
    pub conclusions: Vec<String>,
    /// The SVG charts, then `index.html`.
    pub files: Vec<String>,
}

/// Computes the report's numbers (with a progress bar at a terminal) and writes the page and
/// its charts into `--out`.
pub fn compute(args: &Args) -> Result<Report, CliError> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| CliError::out_path(out, e))?;
    let data = with_progress(report::STEPS, |step| report::compute(step))?;
    let conclusions = report::conclusions(&data);
    let files = write_page(&data, &conclusions, out)?;
    Ok(Report {
        data,
        conclusions,
        files,
    })
}

fn failed(e: String) -> CliError {
    CliError::Failed(e)
}

/// Writes the charts and `index.html` into `out` (the sections: [`sections`]); returns their paths (the page last).
pub fn write_page(
    data: &ReportData,
    conclusions: &[String],
    out: &Path,
) -> Result<Vec<String>, CliError> {
    let mut page = Page::new("preint report: which IMU integration scheme, at which rate");
    page.p(
        "Every figure below is computed on this machine by `preint report` from built-in \
            simulated scenes (no input files); costs are this machine's timings. Schemes: `euler` \
            (1st order), `midpoint` (2nd order), `hermite4` (4th order, uses the neighbouring \
            samples), `galilean` (1st order on smooth input, exact for input held over each \
            interval). Conventions: z-up world, g = (0, 0, −9.81) m/s², right perturbations, \
            tangent order [δφ, δv, δp], bias order [b_g, b_a].",
    );
    page.conclusions(conclusions).toc();
    let mut files = accuracy_section(&mut page, data, out)?;
    files.extend(convergence_section(&mut page, data, out)?);
    files.push(advice_section(&mut page, &data.advice, out)?);
    speed_section(&mut page, data);
    nees_section(&mut page, data);
    files.push(gimbal_lock_section(&mut page, data, out)?);
    calibration_section(&mut page, &data.calibration);
    files.extend(allan_section(&mut page, &data.allan, out)?);
    let index = out.join("index.html");
    page.write(&index).map_err(failed)?;
    files.push(index.display().to_string());
    Ok(files)
}

/// The JSON form: the files, the conclusions and a summary (200 Hz errors per scene, NEES, the
/// calibration, `advise`'s recommendations, ns per sample).
pub fn to_json(r: &Report) -> Value {
    let mut summary = serde_json::Map::new();
    for (scene, rows) in &r.data.accuracy {
        let at200: Vec<Value> = rows
            .iter()
            .filter(|r| r.rate == 200.0)
            .map(|r| {
                json!({"scheme": scheme::label(r.scheme), "rot_err": r.err[0],
                            "vel_err": r.err[1], "pos_err": r.err[2]})
            })
            .collect();
        summary.insert(scene.to_string(), json!(at200));
    }
    let nees: serde_json::Map<String, Value> = r
        .data
        .nees
        .iter()
        .map(|(scene, s, n)| (format!("{scene}/{}", scheme::label(*s)), json!(n)))
        .collect();
    summary.insert("nees".into(), Value::Object(nees));
    let StaticCheck { truth, cal } = &r.data.calibration;
    summary.insert(
        "static_calibration".into(),
        json!({"gyro_bias": [cal.gyro_bias.x, cal.gyro_bias.y, cal.gyro_bias.z],
               "gyro_bias_std": [cal.gyro_bias_std.x, cal.gyro_bias_std.y, cal.gyro_bias_std.z],
               "truth": [truth.gyro.x, truth.gyro.y, truth.gyro.z]}),
    );
    let advise: serde_json::Map<String, Value> = r
        .data
        .advice
        .iter()
        .map(|a| {
            let c = a.recommendation();
            let v = json!({"recommended_scheme": c.map(|c| scheme::label(c.scheme)),
                           "recommended_rate": c.map(|c| c.rate_hz)});
            (a.scene.to_string(), v)
        })
        .collect();
    summary.insert("advise".into(), Value::Object(advise));
    let speed: Vec<Value> = r
        .data
        .speed
        .iter()
        .map(|t| {
            json!({"scheme": scheme::label(t.scheme), "deltas": t.deltas,
                   "covariance": t.covariance, "combined": t.combined})
        })
        .collect();
    summary.insert("ns_per_sample".into(), json!(speed));
    json!({"files": r.files, "conclusions": r.conclusions, "summary": summary})
}

/// The human summary: where the page is, and the conclusions.
pub fn to_text(r: &Report) -> String {
    text(&r.files, &r.conclusions)
}

/// Where the page is (the last of `files`; the others beside it), and the conclusions.
fn text(files: &[String], conclusions: &[String]) -> String {
    let index = files.last().map_or("", String::as_str);
    let mut h = format!(
        "wrote {index} (charts beside it: {})\nconclusions:\n",
        files.len().saturating_sub(1)
    );
    for c in conclusions {
        h.push_str("- ");
        h.push_str(c);
        h.push('\n');
    }
    h
}

/// Runs `preint report`: on the recording with `--imu` ([`recording::run`]), else on the
/// built-in scenes.
pub fn run(args: &Args) -> Result<Output, CliError> {
    if let Some(o) = recording::options(args)? {
        return recording::run(&o);
    }
    let r = compute(args)?;
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}
