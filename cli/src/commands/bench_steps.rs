//! `preint bench-steps`: accuracy against cost per scheme and rate on a built-in scene
//! (method: [`crate::analysis::accuracy`]), with the accuracy-vs-cost and convergence charts.

use crate::analysis::accuracy::{Row, measure, order};
use crate::charts::figures;
use crate::{CliError, Output, scheme};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Flags of `preint bench-steps`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Built-in scene (each one's motion is described in the preint-sim crate's `scenes` docs).
    #[arg(help_heading = "Scene", long, default_value = "aggressive",
          value_parser = clap::builder::PossibleValuesParser::new(preint_sim::SCENE_NAMES))]
    pub scene: String,
    /// Rates (Hz), comma-separated.
    #[arg(help_heading = "Scene", long, value_delimiter = ',', value_parser = preint_analysis::parse::positive, allow_hyphen_values = true,
          default_value = "25,50,100,200,400,800,1600,3200")]
    pub rates: Vec<f64>,
    /// Window length (s).
    #[arg(
        help_heading = "Scene",
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub window: f64,
    /// Output directory for the charts accuracy_vs_cost_SCENE.svg and convergence_SCENE.svg.
    #[arg(help_heading = "Output", long)]
    pub out: Option<PathBuf>,
}

/// The table and the charts written.
#[derive(Clone, Debug)]
pub struct Bench {
    /// The scene.
    pub scene: String,
    /// The window length \[s\].
    pub window: f64,
    /// Every scheme at every rate.
    pub rows: Vec<Row>,
    /// The charts, when `--out` is given.
    pub files: Vec<String>,
}

/// Writes the accuracy-vs-cost and convergence charts of `rows` into `dir`; returns the paths.
pub fn write_charts(rows: &[Row], scene: &str, dir: &Path) -> Result<Vec<String>, CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::out_path(dir, e))?;
    let p1 = figures::accuracy_vs_cost(rows, scene, dir)?;
    let p2 = figures::convergence(rows, scene, dir)?;
    Ok(vec![p1.display().to_string(), p2.display().to_string()])
}

/// Measures every scheme at every rate and, with `--out`, writes the charts.
pub fn compute(args: &Args) -> Result<Bench, CliError> {
    let rows = measure(&args.scene, &args.rates, args.window)?;
    let files = match &args.out {
        Some(dir) => write_charts(&rows, &args.scene, dir)?,
        None => Vec::new(),
    };
    Ok(Bench {
        scene: args.scene.clone(),
        window: args.window,
        rows,
        files,
    })
}

/// The JSON form: the rows, the fitted order per scheme and component, the units, the files.
pub fn to_json(b: &Bench) -> Value {
    let json_rows: Vec<_> = b
        .rows
        .iter()
        .map(|r| json!({"scheme": scheme::label(r.scheme), "rate": r.rate, "ns_per_sample": r.ns_per_sample,
                        "cost_ns_per_s": r.cost_per_s(), "rot_err": r.err[0], "vel_err": r.err[1], "pos_err": r.err[2]}))
        .collect();
    let orders: serde_json::Map<String, Value> = scheme::ALL
        .iter()
        .map(|&s| {
            let o = |c| order(&b.rows, s, c);
            (
                scheme::label(s).to_string(),
                json!({"rot": o(0), "vel": o(1), "pos": o(2)}),
            )
        })
        .collect();
    json!({"scene": b.scene, "window_s": b.window, "rows": json_rows, "fitted_order": orders,
        "units": {"rot_err": "rad", "vel_err": "m/s", "pos_err": "m", "ns_per_sample": "ns (with covariance and bias Jacobians)"},
        "files": b.files})
}

/// The human summary: the table, the fitted orders and the files written.
pub fn to_text(b: &Bench) -> String {
    let mut h = format!(
        "{}: noise-free, window [1 s, {} s], errors against the exact deltas\n",
        b.scene,
        1.0 + b.window
    );
    let _ = writeln!(
        h,
        "{:<9} {:>8} {:>11} {:>12} {:>11} {:>11} {:>11}",
        "scheme", "rate Hz", "ns/sample", "µs/s data", "rot [rad]", "vel [m/s]", "pos [m]"
    );
    for r in &b.rows {
        let _ = writeln!(
            h,
            "{:<9} {:>8.1} {:>11.1} {:>12.1} {:>11.2e} {:>11.2e} {:>11.2e}",
            scheme::label(r.scheme),
            r.rate,
            r.ns_per_sample,
            r.cost_per_s() * 1e-3,
            r.err[0],
            r.err[1],
            r.err[2]
        );
    }
    for s in scheme::ALL {
        let f = |c| order(&b.rows, s, c).map_or("-".into(), |o: f64| format!("{o:.2}"));
        let _ = writeln!(
            h,
            "fitted order {:<9} rot {} vel {} pos {}",
            scheme::label(s),
            f(0),
            f(1),
            f(2)
        );
    }
    if !b.files.is_empty() {
        let _ = writeln!(h, "wrote {}", b.files.join(", "));
    }
    h
}

/// Runs `preint bench-steps`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let b = compute(args)?;
    Ok(Output {
        human: to_text(&b),
        json: to_json(&b),
    })
}
