//! The Jacobians [`ImuResidual`] and [`CombinedImuResidual`] hand to factrs against central
//! differences of their residual through factrs' own retraction (`Variable::oplus` of each
//! key's variable), for both residual modes, at states away from the measurement (a nonzero
//! residual) with a nonzero bias; and the generic `residual5`/`residual6` against the
//! object-safe residual.

use factrs::containers::{Key, Values};
use factrs::linalg::{MatrixX, VectorX};
use factrs::residuals::{Residual, Residual5, Residual6};
use factrs::variables::{ImuBias, SE3, Variable, VectorVar3};
use preint::nalgebra::Vector3;
use preint::{
    CombinedImuFactor, ImuFactor, Level, NavState, PreintParams, ResidualMode, Scheme, preintegrate,
};
use preint_factrs::{CombinedImuResidual, ImuResidual, to_factrs, to_factrs_bias};
use preint_sim::{EulerScene, Scene, SimConfig, simulate, t_s};

use factrs::assign_symbols;
assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);

/// The six variables of a combined factor (the plain one uses the first five).
#[derive(Clone)]
struct Vars {
    pose_i: SE3,
    vel_i: VectorVar3,
    pose_j: SE3,
    vel_j: VectorVar3,
    bias_i: ImuBias,
    bias_j: ImuBias,
}

const DIMS: [usize; 6] = [6, 3, 6, 3, 6, 6];

fn keys() -> Vec<Key> {
    vec![
        X(0).into(),
        V(0).into(),
        X(1).into(),
        V(1).into(),
        B(0).into(),
        B(1).into(),
    ]
}

impl Vars {
    /// Every variable moved by factrs' `oplus` with its slice of `d` (tangents in key order).
    fn oplus(&self, d: &VectorX) -> Self {
        let mut at = 0;
        let mut next = |n: usize| {
            let s = d.rows(at, n).into_owned();
            at += n;
            s
        };
        Self {
            pose_i: self.pose_i.oplus(next(6).as_view()),
            vel_i: self.vel_i.oplus(next(3).as_view()),
            pose_j: self.pose_j.oplus(next(6).as_view()),
            vel_j: self.vel_j.oplus(next(3).as_view()),
            bias_i: self.bias_i.oplus(next(6).as_view()),
            bias_j: self.bias_j.oplus(next(6).as_view()),
        }
    }

    fn values(&self) -> Values {
        let mut v = Values::new();
        v.insert(X(0), self.pose_i.clone());
        v.insert(V(0), self.vel_i.clone());
        v.insert(X(1), self.pose_j.clone());
        v.insert(V(1), self.vel_j.clone());
        v.insert(B(0), self.bias_i.clone());
        v.insert(B(1), self.bias_j.clone());
        v
    }
}

/// A 1 s window of the `aggressive` scene (EuRoC noise densities, combined level), its
/// factors' variables 2 cm / 0.02 rad / 0.05 m/s away from the truth, and a nonzero bias.
fn setup(scheme: Scheme) -> (preint::PreintegratedImu, Vars) {
    let scene = EulerScene::aggressive();
    let noise = preint::ImuNoise::euroc();
    let cfg = SimConfig {
        bias_random_walk: false,
        ..SimConfig::with_noise(noise)
    };
    let sim = simulate(&scene, 200.0, 3.0, &cfg, 3).unwrap();
    let (t_i, t_j) = (1_000_000_000, 2_000_000_000);
    let bias_hat = preint::ImuBias::new(
        Vector3::new(0.002, -0.001, 0.003),
        Vector3::new(0.05, -0.02, 0.03),
    );
    let params = PreintParams {
        level: Level::Combined,
        ..PreintParams::from_noise(&noise).with_scheme(scheme)
    };
    let m = preintegrate(&params, &bias_hat, &sim.samples, t_i, t_j).unwrap();
    let state = |t: i64, d: f64| {
        let s = scene.state(t_s(t));
        NavState::new(s.r_wb, s.p, s.v).retract(&preint::NavTangent::from_fn(|k, _| {
            d * [1.0, -0.5, 0.7, 2.0, 1.0, -1.0, 2.5, -2.0, 1.5][k]
        }))
    };
    let (pose_i, vel_i) = to_factrs(&state(t_i, 0.01));
    let (pose_j, vel_j) = to_factrs(&state(t_j, -0.02));
    let bias_i = to_factrs_bias(&preint::ImuBias::new(
        Vector3::new(0.003, -0.002, 0.001),
        Vector3::new(0.02, 0.04, -0.03),
    ));
    let bias_j = to_factrs_bias(&preint::ImuBias::new(
        Vector3::new(0.001, -0.003, 0.002),
        Vector3::new(0.03, 0.01, -0.05),
    ));
    let vars = Vars {
        pose_i,
        vel_i,
        pose_j,
        vel_j,
        bias_i,
        bias_j,
    };
    (m, vars)
}

/// Central differences of `residual` through `Vars::oplus`, the first `cols` tangent columns.
fn numeric(res: &dyn Residual, vars: &Vars, cols: usize) -> MatrixX {
    let keys = keys();
    let h = 1e-6;
    let rows = res.dim_out();
    let mut j = MatrixX::zeros(rows, cols);
    for c in 0..cols {
        let mut d = VectorX::zeros(DIMS.iter().sum());
        d[c] = h;
        let plus = res.residual(&vars.oplus(&d).values(), &keys);
        d[c] = -h;
        let minus = res.residual(&vars.oplus(&d).values(), &keys);
        j.set_column(c, &((plus - minus) / (2.0 * h)));
    }
    j
}

/// Largest error of `analytic` against `numeric`, relative to the largest entry of each
/// variable's block (so that a block of whitened velocity columns is not judged against the
/// scale of the rotation columns).
fn block_error(analytic: &MatrixX, numeric: &MatrixX) -> f64 {
    let mut worst: f64 = 0.0;
    let mut at = 0;
    for &n in DIMS.iter() {
        if at >= analytic.ncols() {
            break;
        }
        let a = analytic.columns(at, n);
        let scale = a.amax().max(1.0);
        worst = worst.max((a - numeric.columns(at, n)).amax() / scale);
        at += n;
    }
    worst
}

#[test]
fn imu_residual_jacobian_matches_central_differences_through_factrs_oplus() {
    assert!(
        !preint_factrs::left_perturbation(),
        "factrs' default, right perturbation"
    );
    for scheme in [Scheme::Midpoint, Scheme::Euler] {
        for mode in [ResidualMode::Logmap, ResidualMode::ComponentWise] {
            let (m, vars) = setup(scheme);
            let res = ImuResidual::new(ImuFactor::with_mode(m, mode).unwrap());
            let got = res.residual_jacobian(&vars.values(), &keys());
            assert_eq!((got.diff.nrows(), got.diff.ncols()), (9, 24));
            assert!(got.value.amax() > 1.0, "a residual away from zero");
            let num = numeric(&res, &vars, 24);
            let err = block_error(&got.diff, &num);
            println!("ImuResidual {scheme:?} {mode:?}: max relative error {err:.1e}");
            assert!(err < 1e-6, "{scheme:?} {mode:?}: relative error {err:e}");
        }
    }
}

#[test]
fn combined_residual_jacobian_matches_central_differences_through_factrs_oplus() {
    for mode in [ResidualMode::Logmap, ResidualMode::ComponentWise] {
        let (m, vars) = setup(Scheme::Midpoint);
        let res = CombinedImuResidual::new(CombinedImuFactor::with_mode(m, mode).unwrap());
        let got = res.residual_jacobian(&vars.values(), &keys());
        assert_eq!((got.diff.nrows(), got.diff.ncols()), (15, 30));
        let num = numeric(&res, &vars, 30);
        let err = block_error(&got.diff, &num);
        println!("CombinedImuResidual {mode:?}: max relative error {err:.1e}");
        assert!(err < 1e-6, "{mode:?}: relative error {err:e}");
        // The bias-at-j block is nonzero (the random-walk rows).
        assert!(got.diff.columns(24, 6).amax() > 1.0);
    }
}

#[test]
fn residual_is_the_whitened_preint_residual_and_the_generic_entry_point_agrees() {
    let (m, vars) = setup(Scheme::Midpoint);
    let factor = ImuFactor::new(m.clone()).unwrap();
    let xi = preint_factrs::nav_state(&vars.pose_i, &vars.vel_i);
    let xj = preint_factrs::nav_state(&vars.pose_j, &vars.vel_j);
    let b = preint_factrs::bias(&vars.bias_i);
    let (want, _) = factor.evaluate_whitened(&xi, &xj, &b);
    let res = ImuResidual::new(factor);
    let got = res.residual(&vars.values(), &keys());
    let generic = res.residual5(
        vars.pose_i.clone(),
        vars.vel_i.clone(),
        vars.pose_j.clone(),
        vars.vel_j.clone(),
        vars.bias_i.clone(),
    );
    for k in 0..9 {
        assert!((got[k] - want[k]).abs() <= 1e-12 * want.amax());
        assert!((generic[k] - got[k]).abs() <= 1e-12 * want.amax());
    }
    // factrs' generic Jacobian (forward-mode dual numbers through residual5) is the analytic one.
    let analytic = res.residual_jacobian(&vars.values(), &keys()).diff;
    let generic_j = res.residual5_jacobian(&vars.values(), &keys()).diff;
    let e = block_error(&analytic, &generic_j);
    assert!(e < 1e-12, "generic Jacobian: {e:e}");

    let combined = CombinedImuResidual::new(CombinedImuFactor::new(m).unwrap());
    let got = combined.residual(&vars.values(), &keys());
    let generic = combined.residual6(
        vars.pose_i.clone(),
        vars.vel_i.clone(),
        vars.pose_j.clone(),
        vars.vel_j.clone(),
        vars.bias_i.clone(),
        vars.bias_j.clone(),
    );
    assert!((got - generic).amax() <= 1e-12 * want.amax());
    let analytic = combined.residual_jacobian(&vars.values(), &keys()).diff;
    let generic_j = combined.residual6_jacobian(&vars.values(), &keys()).diff;
    let e = block_error(&analytic, &generic_j);
    assert!(e < 1e-12, "generic Jacobian: {e:e}");
}

#[test]
fn conversions_round_trip() {
    let (_, vars) = setup(Scheme::Midpoint);
    let x = preint_factrs::nav_state(&vars.pose_i, &vars.vel_i);
    let (pose, vel) = to_factrs(&x);
    let back = preint_factrs::nav_state(&pose, &vel);
    assert!(x.local(&back).amax() < 1e-14);
    let b = preint_factrs::bias(&vars.bias_j);
    let bb = preint_factrs::bias(&to_factrs_bias(&b));
    assert_eq!((b.gyro, b.acc), (bb.gyro, bb.acc));
}
