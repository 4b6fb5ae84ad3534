//! `preint simulate`: an IMU on a built-in scene, written as a EuRoC-style dataset.

use super::{CliError, Output};
use crate::Command;
use preint::ImuNoise;
use preint::io::read_kalibr_yaml;
use serde_json::json;

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Simulate {
        scene,
        rate,
        duration,
        noise,
        seed,
        out,
    } = cmd
    else {
        unreachable!()
    };
    let sc = preint_sim::scene_by_name(scene).ok_or_else(|| {
        CliError::Usage(format!(
            "unknown scene `{scene}`; expected one of {}",
            preint_sim::SCENE_NAMES.join(", ")
        ))
    })?;
    let noise_model: Option<ImuNoise> = match noise.as_deref() {
        Some("none") => None,
        Some(path) => Some(read_kalibr_yaml(std::path::Path::new(path))?),
        None => Some(ImuNoise::euroc()),
    };
    let cfg = match noise_model {
        Some(n) => preint_sim::SimConfig::with_noise(n),
        None => preint_sim::SimConfig::noise_free(),
    };
    let data = preint_sim::simulate(sc.as_ref(), *rate, *duration, &cfg, *seed)
        .map_err(|e| CliError::Failed(e.to_string()))?;
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Failed(format!("{}: {e}", out.display())))?;
    let yaml_noise = noise_model.unwrap_or(ImuNoise::zero(*rate));
    let files: Vec<String> = preint_sim::write_dataset(out, &data, &yaml_noise)
        .map_err(|e| CliError::Failed(e.to_string()))?
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let json = json!({"scene": scene, "samples": data.samples.len(), "rate_hz": rate, "duration_s": duration,
        "seed": seed, "noise": noise_model.map(|n| json!({"gyroscope_noise_density": n.gyro_noise_density,
            "gyroscope_random_walk": n.gyro_random_walk, "accelerometer_noise_density": n.acc_noise_density,
            "accelerometer_random_walk": n.acc_random_walk})), "files": files});
    let human = format!(
        "simulated `{scene}`: {} samples at {rate} Hz over {duration} s (seed {seed}, noise {}); wrote {}\n",
        data.samples.len(),
        if noise_model.is_some() {
            "on, bias random walk on"
        } else {
            "off"
        },
        files.join(", ")
    );
    Ok(Output { human, json })
}
