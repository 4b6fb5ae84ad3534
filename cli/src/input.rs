//! Reading and selecting the inputs: IMU files, ground-truth rows, built-in scenes.

use crate::CliError;
use preint::ImuSample;
use preint_io::GroundTruthState;

/// Number of samples with timestamps in `[t_i, t_j]` (ns).
pub fn count_in(samples: &[ImuSample], t_i: i64, t_j: i64) -> usize {
    samples
        .iter()
        .filter(|s| s.t_ns >= t_i && s.t_ns <= t_j)
        .count()
}

/// The ground-truth row nearest to `t_ns` (rows sorted by time, at least one).
pub fn nearest_row(gt: &[GroundTruthState], t_ns: i64) -> &GroundTruthState {
    let k = gt.partition_point(|s| s.t_ns < t_ns);
    let candidates = [k.saturating_sub(1), k.min(gt.len() - 1)];
    let best = candidates
        .into_iter()
        .min_by_key(|&c| (gt[c].t_ns - t_ns).unsigned_abs())
        .unwrap();
    &gt[best]
}

/// The built-in scene called `name` (one of [`preint_sim::SCENE_NAMES`]).
pub fn scene(name: &str) -> Result<Box<dyn preint_sim::Scene + Send + Sync>, CliError> {
    preint_sim::scene_by_name(name).ok_or_else(|| {
        CliError::Usage(format!(
            "unknown scene `{name}`; expected one of {}",
            preint_sim::SCENE_NAMES.join(", ")
        ))
    })
}
