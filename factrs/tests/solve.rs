//! A simulated visual-inertial-style problem solved twice from the same start: by factrs'
//! Gauss–Newton with [`ImuResidual`] / [`CombinedImuResidual`], and by preint-calib's
//! Gauss–Newton (`preint_calib::solve`, undamped) on the same cost written with preint's
//! factors directly. The two optima agree to 1e-6 of each coordinate's posterior standard
//! deviation; both are within 5σ of the simulator's truth.
//!
//! Problem: 2.5 s of the `aggressive` scene at 200 Hz with the EuRoC noise densities and a
//! constant nonzero bias; six keyframes 0.5 s apart; a noisy pose measurement at every
//! keyframe (σ 0.01 rad, 0.02 m; `[Log(R_mᵀR), p − p_m]`), a velocity prior at the first
//! (σ 0.1 m/s), a weak zero-mean bias prior (σ 0.1), and an IMU factor per window: one shared
//! bias with [`ImuResidual`], a bias per keyframe with [`CombinedImuResidual`]. Start: the
//! truth moved 0.2 m, 0.05 rad and 0.3 m/s, zero bias.

use factrs::containers::{Graph, Values};
use factrs::linalg::{Const, ForwardProp, Numeric, VectorX};
use factrs::noise::GaussianNoise;
use factrs::optimizers::{BaseOptParams, GaussNewton};
use factrs::residuals::{PriorResidual, Residual1};
use factrs::traits::{Optimizer, Variable};
use factrs::variables::{ImuBias, SE3, SO3, VectorVar3};
use factrs::{assign_symbols, fac};
use preint::lie::{Manifold, jr_inv};
use preint::nalgebra::{DMatrix, DVector, SVector, Vector3};
use preint::{
    CombinedImuFactor, ImuFactor, Level, NavState, NavTangent, PreintParams, preintegrate,
};
use preint_calib::{GaussNewton as OurGaussNewton, LeastSquares, solve};
use preint_factrs::{CombinedImuResidual, ImuResidual, bias, nav_state, to_factrs, to_factrs_bias};
use preint_sim::{EulerScene, Scene, SimConfig, simulate, t_s};

assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);

const K: usize = 6;
const SIGMA_ROT: f64 = 0.01;
const SIGMA_POS: f64 = 0.02;
const SIGMA_VEL: f64 = 0.1;
const SIGMA_BIAS: f64 = 0.1;

fn t_ns(k: usize) -> i64 {
    (k as i64) * 500_000_000
}

/// A pose measurement `(R_m, p_m)`: residual `[Log(R_mᵀR)/σ_rot, (p − p_m)/σ_pos]` on a
/// factrs `SE3` (automatic differentiation, factrs' own residual).
#[derive(Clone, Debug)]
struct PoseMeasurement {
    rot: SO3,
    pos: factrs::linalg::Vector3,
}

#[factrs::mark]
impl Residual1 for PoseMeasurement {
    type Differ = ForwardProp<Const<6>>;
    type V1 = SE3;
    type DimIn = Const<6>;
    type DimOut = Const<6>;

    fn residual1<T: Numeric>(&self, x: SE3<T>) -> VectorX<T> {
        let e = self.rot.cast::<T>().inverse().compose(x.rot()).log();
        let d = x.xyz() - self.pos.cast::<T>();
        let mut r = VectorX::zeros(6);
        for k in 0..3 {
            r[k] = e[k] / T::from(SIGMA_ROT);
            r[k + 3] = d[k] / T::from(SIGMA_POS);
        }
        r
    }
}

struct Problem {
    truth: Vec<NavState>,
    measured: Vec<NavState>,
    true_bias: preint::ImuBias,
    pims: Vec<preint::PreintegratedImu>,
}

fn problem() -> Problem {
    let scene = EulerScene::aggressive();
    let noise = preint::ImuNoise::euroc();
    let true_bias = preint::ImuBias::new(
        Vector3::new(0.004, -0.003, 0.002),
        Vector3::new(0.08, -0.05, 0.06),
    );
    let cfg = SimConfig {
        initial_bias: true_bias,
        bias_random_walk: false,
        ..SimConfig::with_noise(noise)
    };
    let sim = simulate(&scene, 200.0, 3.0, &cfg, 11).unwrap();
    let params = PreintParams {
        level: Level::Combined,
        ..PreintParams::from_noise(&noise)
    };
    let truth: Vec<NavState> = (0..K)
        .map(|k| {
            let s = scene.state(t_s(t_ns(k)));
            NavState::new(s.r_wb, s.p, s.v)
        })
        .collect();
    // Deterministic measurement errors of about one σ.
    let measured = truth
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let c = |a: f64| (a * (k as f64 + 1.0)).sin();
            let d = NavTangent::from_fn(|i, _| match i {
                0..3 => SIGMA_ROT * c(1.3 + i as f64),
                3..6 => SIGMA_POS * c(0.7 + 2.0 * i as f64),
                _ => 0.0,
            });
            x.retract(&d)
        })
        .collect();
    let zero = preint::ImuBias::zero();
    let pims = (0..K - 1)
        .map(|k| preintegrate(&params, &zero, &sim.samples, t_ns(k), t_ns(k + 1)).unwrap())
        .collect();
    Problem {
        truth,
        measured,
        true_bias,
        pims,
    }
}

fn start(p: &Problem) -> Vec<NavState> {
    p.truth
        .iter()
        .map(|x| {
            x.retract(&NavTangent::from_fn(|i, _| match i {
                0..3 => 0.05,
                3..6 => 0.2,
                _ => 0.3,
            }))
        })
        .collect()
}

// ------------------------------------------------------------------------------------------
// factrs
// ------------------------------------------------------------------------------------------

/// The problem in factrs, solved by its Gauss–Newton; the estimated states and biases.
fn solve_factrs(p: &Problem, combined: bool) -> (Vec<NavState>, Vec<preint::ImuBias>) {
    let mut graph = Graph::new();
    let mut values = Values::new();
    let nb = if combined { K } else { 1 };
    for (k, (x0, m)) in start(p).iter().zip(&p.measured).enumerate() {
        let k32 = k as u32;
        let (pose, vel) = to_factrs(x0);
        values.insert(X(k32), pose);
        values.insert(V(k32), vel);
        let (mpose, _) = to_factrs(m);
        let meas = PoseMeasurement {
            rot: mpose.rot().clone(),
            pos: mpose.xyz().into_owned(),
        };
        graph.add_factor(fac![meas, X(k32)]);
    }
    let (_, vel_truth) = to_factrs(&p.truth[0]);
    graph.add_factor(fac![
        PriorResidual::new(vel_truth),
        V(0),
        GaussianNoise::<3>::from_scalar_sigma(SIGMA_VEL)
    ]);
    for b in 0..nb {
        values.insert(B(b as u32), to_factrs_bias(&preint::ImuBias::zero()));
    }
    graph.add_factor(fac![
        PriorResidual::new(to_factrs_bias(&preint::ImuBias::zero())),
        B(0),
        GaussianNoise::<6>::from_scalar_sigma(SIGMA_BIAS)
    ]);
    for (k, m) in p.pims.iter().enumerate() {
        let (i, j) = (k as u32, k as u32 + 1);
        if combined {
            let r = CombinedImuResidual::new(CombinedImuFactor::new(m.clone()).unwrap());
            graph.add_factor(fac![r, (X(i), V(i), X(j), V(j), B(i), B(j))]);
        } else {
            let r = ImuResidual::new(ImuFactor::new(m.clone()).unwrap());
            graph.add_factor(fac![r, (X(i), V(i), X(j), V(j), B(0))]);
        }
    }
    let params = BaseOptParams {
        max_iterations: 30,
        error_tol_relative: 1e-14,
        error_tol_absolute: 1e-12,
        error_tol: 0.0,
    };
    let result = match GaussNewton::new(params, graph).optimize(values) {
        Ok(v) => v,
        Err(e) => panic!("factrs did not converge: {e:?}"),
    };
    let states = (0..K as u32)
        .map(|k| nav_state(result.get(X(k)).unwrap(), result.get(V(k)).unwrap()))
        .collect();
    let biases = (0..nb as u32)
        .map(|b| bias(result.get(B(b)).unwrap()))
        .collect();
    (states, biases)
}

// ------------------------------------------------------------------------------------------
// preint-calib's Gauss–Newton on the same cost
// ------------------------------------------------------------------------------------------

type State = (Vec<NavState>, Vec<SVector<f64, 6>>);

enum Imu {
    Plain(Vec<ImuFactor>),
    Combined(Vec<CombinedImuFactor>),
}

struct Ours<'a> {
    p: &'a Problem,
    imu: Imu,
}

fn to_bias(v: &SVector<f64, 6>) -> preint::ImuBias {
    preint::ImuBias::new(
        v.fixed_rows::<3>(0).into_owned(),
        v.fixed_rows::<3>(3).into_owned(),
    )
}

impl LeastSquares for Ours<'_> {
    type State = State;

    fn residual_jacobian(&self, x: &State) -> (DVector<f64>, DMatrix<f64>) {
        let (states, biases) = x;
        let n = x.dim();
        let bias_col = |b: usize| 9 * K + 6 * b;
        let mut rows: Vec<(DVector<f64>, DMatrix<f64>)> = Vec::new();
        // Pose measurements.
        for (k, (s, m)) in states.iter().zip(&self.p.measured).enumerate() {
            let e = m.r.inverse().compose(&s.r).log();
            let mut r = DVector::zeros(6);
            let mut j = DMatrix::zeros(6, n);
            r.rows_mut(0, 3).copy_from(&(e / SIGMA_ROT));
            r.rows_mut(3, 3).copy_from(&((s.p - m.p) / SIGMA_POS));
            j.view_mut((0, 9 * k), (3, 3))
                .copy_from(&(jr_inv(&e) / SIGMA_ROT));
            j.view_mut((3, 9 * k + 3), (3, 3))
                .copy_from(&(s.r.matrix() / SIGMA_POS));
            rows.push((r, j));
        }
        // Velocity prior at keyframe 0 and the bias prior on the first bias.
        let mut r = DVector::zeros(9);
        let mut j = DMatrix::zeros(9, n);
        r.rows_mut(0, 3)
            .copy_from(&((states[0].v - self.p.truth[0].v) / SIGMA_VEL));
        j.view_mut((0, 6), (3, 3)).fill_with_identity();
        j.view_mut((0, 6), (3, 3)).scale_mut(1.0 / SIGMA_VEL);
        r.rows_mut(3, 6).copy_from(&(biases[0] / SIGMA_BIAS));
        j.view_mut((3, bias_col(0)), (6, 6)).fill_with_identity();
        j.view_mut((3, bias_col(0)), (6, 6))
            .scale_mut(1.0 / SIGMA_BIAS);
        rows.push((r, j));
        // IMU factors.
        for k in 0..K - 1 {
            let (xi, xj) = (&states[k], &states[k + 1]);
            match &self.imu {
                Imu::Plain(f) => {
                    let (r, jac) = f[k].evaluate_whitened(xi, xj, &to_bias(&biases[0]));
                    let mut j = DMatrix::zeros(9, n);
                    j.view_mut((0, 9 * k), (9, 9)).copy_from(&jac.state_i());
                    j.view_mut((0, 9 * k + 9), (9, 9)).copy_from(&jac.state_j());
                    j.view_mut((0, bias_col(0)), (9, 6))
                        .copy_from(&jac.bias_i());
                    rows.push((DVector::from_column_slice(r.as_slice()), j));
                }
                Imu::Combined(f) => {
                    let (bi, bj) = (to_bias(&biases[k]), to_bias(&biases[k + 1]));
                    let (r, jac) = f[k].evaluate_whitened(xi, xj, &bi, &bj);
                    let mut j = DMatrix::zeros(15, n);
                    j.view_mut((0, 9 * k), (15, 9)).copy_from(&jac.state_i());
                    j.view_mut((0, 9 * k + 9), (15, 9))
                        .copy_from(&jac.state_j());
                    j.view_mut((0, bias_col(k)), (15, 6))
                        .copy_from(&jac.bias_i());
                    j.view_mut((0, bias_col(k + 1)), (15, 6))
                        .copy_from(&jac.bias_j());
                    rows.push((DVector::from_column_slice(r.as_slice()), j));
                }
            }
        }
        let m: usize = rows.iter().map(|(r, _)| r.len()).sum();
        let mut r = DVector::zeros(m);
        let mut j = DMatrix::zeros(m, n);
        let mut at = 0;
        for (ri, ji) in rows {
            r.rows_mut(at, ri.len()).copy_from(&ri);
            j.rows_mut(at, ri.len()).copy_from(&ji);
            at += ri.len();
        }
        (r, j)
    }
}

/// The same problem solved by preint-calib's undamped Gauss–Newton: the estimate and the
/// posterior standard deviation of every tangent coordinate.
fn solve_ours(p: &Problem, combined: bool) -> (State, DVector<f64>) {
    let nb = if combined { K } else { 1 };
    let imu = if combined {
        Imu::Combined(
            p.pims
                .iter()
                .map(|m| CombinedImuFactor::new(m.clone()).unwrap())
                .collect(),
        )
    } else {
        Imu::Plain(
            p.pims
                .iter()
                .map(|m| ImuFactor::new(m.clone()).unwrap())
                .collect(),
        )
    };
    let x0: State = (start(p), vec![SVector::zeros(); nb]);
    let sol = solve(Ours { p, imu }, x0, OurGaussNewton::undamped(), 50).unwrap();
    assert!(sol.stop.converged(), "{:?}", sol.stop);
    assert_eq!(sol.rank, 9 * K + 6 * nb, "every coordinate observable");
    let std = sol.std_devs();
    (sol.estimate, std)
}

/// factrs' estimate minus ours (preint's tangent at ours, then the bias differences),
/// in units of our posterior standard deviations, and the largest |difference| in the
/// position coordinates [m].
fn compare(p: &Problem, combined: bool) -> (f64, f64) {
    let (fs, fb) = solve_factrs(p, combined);
    let ((os, ob), std) = solve_ours(p, combined);
    let mut diff = Vec::new();
    let mut pos: f64 = 0.0;
    for (o, f) in os.iter().zip(&fs) {
        let d = o.local(f);
        pos = pos.max(d.fixed_rows::<3>(3).amax());
        diff.extend(d.iter().copied());
    }
    for (o, f) in ob.iter().zip(&fb) {
        let o = to_bias(o);
        diff.extend((f.gyro - o.gyro).iter().copied());
        diff.extend((f.acc - o.acc).iter().copied());
    }
    let worst = diff
        .iter()
        .zip(std.iter())
        .map(|(d, s)| (d / s).abs())
        .fold(0.0, f64::max);
    // Both near the truth: ours within 5σ per coordinate.
    for (k, (o, t)) in os.iter().zip(&p.truth).enumerate() {
        let d = t.local(o);
        for i in 0..9 {
            let z = d[i] / std[9 * k + i];
            assert!(
                z.abs() < 5.0,
                "keyframe {k} coordinate {i}: {z:.2}σ from the truth"
            );
        }
    }
    let b = to_bias(&ob[0]);
    let gyro_err = (b.gyro - p.true_bias.gyro).amax();
    assert!(gyro_err < 5.0 * std[9 * K], "gyro bias off by {gyro_err:e}");
    (worst, pos)
}

#[test]
fn imu_residual_factrs_and_preint_calib_reach_the_same_optimum() {
    let p = problem();
    let (worst, pos) = compare(&p, false);
    println!("ImuResidual: max |factrs − ours| = {worst:.2e} σ, {pos:.2e} m");
    assert!(worst < 1e-6, "{worst:e} σ");
    assert!(pos < 1e-8, "{pos:e} m");
}

#[test]
fn combined_residual_factrs_and_preint_calib_reach_the_same_optimum() {
    let p = problem();
    let (worst, pos) = compare(&p, true);
    println!("CombinedImuResidual: max |factrs − ours| = {worst:.2e} σ, {pos:.2e} m");
    assert!(worst < 1e-6, "{worst:e} σ");
    assert!(pos < 1e-8, "{pos:e} m");
}
