//! Reading and selecting the inputs: IMU files, ground-truth rows, built-in scenes.

use crate::CliError;
use preint::ImuSample;

/// Number of samples with timestamps in `[t_i, t_j]` (ns).
pub fn count_in(samples: &[ImuSample], t_i: i64, t_j: i64) -> usize {
    samples
        .iter()
        .filter(|s| s.t_ns >= t_i && s.t_ns <= t_j)
        .count()
}

pub use preint_analysis::truth_windows::nearest_row;

/// The built-in scene called `name` (one of [`preint_sim::SCENE_NAMES`]).
pub fn scene(name: &str) -> Result<Box<dyn preint_sim::Scene + Send + Sync>, CliError> {
    preint_sim::scene_by_name(name).ok_or_else(|| {
        CliError::Usage(format!(
            "unknown scene `{name}`; expected one of {}",
            preint_sim::SCENE_NAMES.join(", ")
        ))
    })
}
