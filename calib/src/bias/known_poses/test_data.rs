//! Simulated recordings shared by the unit tests of this module.

use super::KnownPose;
use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, PreintegratedImu, Scheme, preintegrate};
use preint_sim::{EulerScene, SimConfig, simulate};

pub(super) struct Setup {
    pub(super) samples: Vec<ImuSample>,
    pub(super) truth: Vec<preint_sim::GroundTruthState>,
    pub(super) poses: Vec<KnownPose>,
    pub(super) params: PreintParams,
}

/// 3 s of the `aggressive` scene at 200 Hz, poses every 0.25 s from the ground truth.
pub(super) fn setup(noise: ImuNoise) -> Setup {
    let cfg = SimConfig {
        noise,
        initial_bias: ImuBias::new(
            Vector3::new(0.004, -0.003, 0.006),
            Vector3::new(0.08, -0.05, 0.12),
        ),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&EulerScene::aggressive(), 200.0, 3.0, &cfg, 3).unwrap();
    let poses = (0..=12)
        .map(|k| {
            let st = &out.truth[50 * k];
            KnownPose {
                t_ns: st.t_ns,
                r: st.rotation(),
                p: st.p,
            }
        })
        .collect();
    let params = PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(Scheme::Hermite4);
    Setup {
        samples: out.samples,
        truth: out.truth,
        poses,
        params,
    }
}

/// The windows between consecutive poses, preintegrated at `b`.
pub(super) fn pims(s: &Setup, b: &ImuBias) -> Vec<PreintegratedImu> {
    s.poses
        .windows(2)
        .map(|w| preintegrate(&s.params, b, &s.samples, w[0].t_ns, w[1].t_ns).unwrap())
        .collect()
}
