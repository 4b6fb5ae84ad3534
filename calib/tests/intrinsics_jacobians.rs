//! The Jacobians of ΔR, Δv, Δp with respect to every IMU intrinsic parameter
//! ([`preint::intrinsics`]: 6 entries of `T_w`, 6 of `T_a`, the model's rotation as a right
//! perturbation, 9 of `T_g`) from [`Preintegrator::finish_with_intrinsic_jacobian`], checked
//! against Ridders' differentiation of **re-integrated** windows (the raw samples integrated
//! again with perturbed intrinsics; output differenced as `[Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀]`)
//! with this crate's checker ([`check_jacobian`], relative error ≤ 1e-8), for every scheme,
//! both models (`kalibr`, `rpng`), realistic intrinsics (1 % scale, 2 mrad misalignment and
//! axis rotation, g-sensitivity 1e-3 (rad/s)/(m/s²)) and a non-zero bias estimate, on a window
//! of the `aggressive` scene and a static one.

use nalgebra::{DMatrix, DVector, Vector3};
use preint::intrinsics::{AppliedIntrinsics, ImuIntrinsics, IntrinsicsModel};
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, PreintegratedImu, Preintegrator, Scheme};
use preint_calib::{CheckOptions, NumDiffOptions, check_jacobian};
use preint_sim::{EulerScene, Scene, SimConfig, StaticScene, simulate};

/// Ridders base step [parameter units]: the parameters are O(1e-3..1) and the deltas are far
/// from linear in them at the default 1e-2 (a 1e-2 change of `T_g` is 0.1 rad/s).
const STEP: f64 = 1e-4;

/// The library's example intrinsics (1 % scale, 2 mrad misalignment and axis rotations,
/// g-sensitivity 1e-3 (rad/s)/(m/s²)).
fn realistic(model: IntrinsicsModel) -> ImuIntrinsics {
    ImuIntrinsics::example(model)
}

fn bias() -> ImuBias {
    ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.08),
    )
}

/// 1 s of the scene's noise-free samples from t = 0.5 s.
fn samples(scene: &dyn Scene) -> Vec<ImuSample> {
    let out = simulate(scene, 200.0, 2.0, &SimConfig::default(), 0).unwrap();
    out.samples[100..=300].to_vec()
}

fn run(params: &PreintParams, s: &[ImuSample]) -> Preintegrator {
    let mut pi = Preintegrator::new(params.clone(), bias()).unwrap();
    pi.integrate_slice(s).unwrap();
    pi
}

#[test]
fn intrinsic_jacobians_match_reintegration_every_scheme_and_model() {
    let scenes: [(&str, Box<dyn Scene>); 2] = [
        ("aggressive", Box::new(EulerScene::aggressive())),
        ("static", Box::new(StaticScene::default())),
    ];
    for (name, scene) in &scenes {
        let s = samples(scene.as_ref());
        for &scheme in Scheme::ALL {
            for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
                let x0 = realistic(model);
                let base = PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(scheme);
                let with = |x: ImuIntrinsics, jac: bool| PreintParams {
                    intrinsics: Some(AppliedIntrinsics {
                        model: x,
                        jacobians: jac,
                    }),
                    ..base.clone()
                };
                let (m, jac) = run(&with(x0, true), &s)
                    .finish_with_intrinsic_jacobian()
                    .unwrap();
                // The Jacobian path integrates exactly as the plain one.
                let plain: PreintegratedImu = run(&with(x0, false), &s).finish().unwrap();
                assert_eq!(m, plain, "{name} {scheme:?} {model:?}");
                let f = |d: &DVector<f64>| {
                    let delta = nalgebra::SVector::<f64, 24>::from_column_slice(d.as_slice());
                    let q = run(&with(x0.perturbed(&delta), false), &s)
                        .finish()
                        .unwrap();
                    (q.delta_r, q.delta_v, q.delta_p)
                };
                let blocks = [DMatrix::from_column_slice(9, 24, jac.as_slice())];
                let opts = CheckOptions {
                    numdiff: NumDiffOptions::with_ridders_step(STEP),
                    ..CheckOptions::default()
                };
                let rep = check_jacobian(f, &DVector::zeros(24), &blocks, &opts)
                    .unwrap_or_else(|e| panic!("{name} {scheme:?} {model:?}: {e}"));
                println!(
                    "intrinsic Jacobians, {name}, {scheme:?}, {model:?}: worst relative error {:.2e}",
                    rep.worst_rel_error
                );
            }
        }
    }
}
