//! `preint simulate`: an IMU on a built-in scene, written as a EuRoC-style dataset
//! (`imu.csv`, `groundtruth.csv`, `imu.yaml`).

use crate::{CliError, Output, input};
use preint::ImuNoise;
use preint_analysis::noise;
use preint_io::read_kalibr_yaml;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Flags of `preint simulate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Built-in scene (each one's motion is described in the preint-sim crate's `scenes` docs).
    #[arg(help_heading = "Scene", long, default_value = "seed-ellipse",
          value_parser = clap::builder::PossibleValuesParser::new(preint_sim::SCENE_NAMES))]
    pub scene: String,
    /// Sample rate (Hz), positive.
    #[arg(help_heading = "Sensor", long, default_value_t = 200.0, allow_hyphen_values = true,
          value_parser = preint_analysis::parse::positive)]
    pub rate: f64,
    /// Duration (s), positive.
    #[arg(help_heading = "Scene", long, default_value_t = 10.0, allow_hyphen_values = true,
          value_parser = preint_analysis::parse::positive)]
    pub duration: f64,
    /// Noise: a Kalibr imu.yaml, or `none` for noise-free data. Default: EuRoC figures.
    #[arg(help_heading = "Sensor", long)]
    pub noise: Option<String>,
    /// Random seed (same seed, same data on every machine).
    #[arg(
        help_heading = "Sensor",
        long,
        default_value_t = 1,
        allow_hyphen_values = true
    )]
    pub seed: u64,
    /// Output directory (created if missing).
    #[arg(help_heading = "Output", long)]
    pub out: PathBuf,
    /// Mount the IMU at this pose in the body, x,y,z,qw,qx,qy,qz: sensor origin in body
    /// coordinates (m) and the unit quaternion rotating sensor vectors into the body frame.
    /// The samples are the IMU's (rate in its axes, specific force of its point); the ground
    /// truth stays the body's.
    #[arg(help_heading = "Sensor", long, value_parser = preint_analysis::parse::sensor_pose, allow_hyphen_values = true)]
    pub body_p_sensor: Option<preint::SensorPose>,
    /// A rotating world frame (Earth rotation).
    #[command(flatten)]
    pub earth: crate::earth_args::EarthRateArgs,
}

/// What `simulate` wrote.
#[derive(Clone, Debug)]
pub struct Simulation {
    /// The flags it ran with.
    pub args: Args,
    /// Number of IMU samples written.
    pub samples: usize,
    /// The noise simulated (`None`: noise-free, no bias random walk).
    pub noise: Option<ImuNoise>,
    /// The files written.
    pub files: Vec<String>,
}

/// Simulates the scene and writes the dataset into `--out`.
pub fn compute(args: &Args) -> Result<Simulation, CliError> {
    let sc = input::scene(&args.scene)?;
    let noise_model: Option<ImuNoise> = match args.noise.as_deref() {
        Some("none") => None,
        Some(path) => Some(read_kalibr_yaml(Path::new(path))?),
        None => Some(ImuNoise::euroc()),
    };
    let mut cfg = match noise_model {
        Some(n) => preint_sim::SimConfig::with_noise(n),
        None => preint_sim::SimConfig::noise_free(),
    };
    cfg.body_p_sensor = args.body_p_sensor;
    cfg.earth_rate = args.earth.rate();
    let pb = preint_analysis::progress::bar(2, "simulate");
    if let Some(pb) = &pb {
        pb.set_message("synthesising the samples and the ground truth");
    }
    let data = preint_sim::simulate(sc.as_ref(), args.rate, args.duration, &cfg, args.seed)
        .map_err(CliError::failed)?;
    if let Some(pb) = &pb {
        pb.inc(1);
        pb.set_message("writing the files");
    }
    std::fs::create_dir_all(&args.out).map_err(|e| CliError::out_path(&args.out, e))?;
    let yaml_noise = noise_model.unwrap_or(ImuNoise::zero(args.rate));
    let files = preint_sim::write_dataset(&args.out, &data, &yaml_noise)
        .map_err(CliError::failed)?
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(Simulation {
        args: args.clone(),
        samples: data.samples.len(),
        noise: noise_model,
        files,
    })
}

/// The JSON form: scene, samples, rate_hz, duration_s, seed, noise densities (or `null`), files,
/// earth_rate (rad/s, world frame, or `null`).
pub fn to_json(s: &Simulation) -> Value {
    let a = &s.args;
    json!({"scene": a.scene, "samples": s.samples, "rate_hz": a.rate, "duration_s": a.duration,
        "seed": a.seed, "noise": s.noise.as_ref().map(noise::densities_json), "files": s.files,
        "earth_rate": a.earth.rate().map(|w| preint_analysis::format::list(&w))})
}

/// The human summary: one line.
pub fn to_text(s: &Simulation) -> String {
    let a = &s.args;
    let earth = match a.earth.rate() {
        Some(w) => format!(
            ", world frame rotating at [{:e}, {:e}, {:e}] rad/s",
            w.x, w.y, w.z
        ),
        None => String::new(),
    };
    format!(
        "simulated `{}`: {} samples at {} Hz over {} s (seed {}, noise {}{earth}); wrote {}\n",
        a.scene,
        s.samples,
        a.rate,
        a.duration,
        a.seed,
        if s.noise.is_some() {
            "on, bias random walk on"
        } else {
            "off"
        },
        s.files.join(", ")
    )
}

/// Runs `preint simulate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let s = compute(args)?;
    Ok(Output {
        human: to_text(&s),
        json: to_json(&s),
    })
}
