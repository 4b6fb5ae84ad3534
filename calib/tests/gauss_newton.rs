//! Gauss-Newton / Levenberg-Marquardt on SO3 × R³ and on vectors: known answers, covariance
//! against Monte Carlo, rank deficiency, LM vs plain GN, argmin observers.

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Executor, KV};
use nalgebra::{DMatrix, DVector, Matrix3, Vector1, Vector3};
use preint_calib::{
    CheckOptions, GaussNewton, GnState, LeastSquares, NumericLeastSquares, StopReason,
    check_jacobian, finish, solve,
};
use preint_lie::{Manifold, SO3, hat};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use std::sync::{Arc, Mutex};

/// Point alignment: find (R, t) with q_i ≈ R p_i + t, isotropic noise σ [m].
/// Residual r_i = (R p_i + t − q_i)/σ; Jacobian w.r.t. (δφ, δt) with R ← R Exp(δφ), t ← t + δt:
/// [−R p̂_i, I]/σ (Solà eq. 168). (A first version had R instead of I in the t block;
/// `alignment_jacobian_is_right` caught it.)
struct Align {
    p: Vec<Vector3<f64>>,
    q: Vec<Vector3<f64>>,
    sigma: f64,
}

impl LeastSquares for Align {
    type State = (SO3, Vector3<f64>);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        let (r, t) = x;
        let m = self.p.len();
        let mut res = DVector::zeros(3 * m);
        let mut jac = DMatrix::zeros(3 * m, 6);
        for (i, (p, q)) in self.p.iter().zip(&self.q).enumerate() {
            let e = (r.act(p) + t - q) / self.sigma;
            res.fixed_rows_mut::<3>(3 * i).copy_from(&e);
            jac.fixed_view_mut::<3, 3>(3 * i, 0)
                .copy_from(&(-r.matrix() * hat(p) / self.sigma));
            jac.fixed_view_mut::<3, 3>(3 * i, 3)
                .copy_from(&(Matrix3::identity() / self.sigma));
        }
        (res, jac)
    }
}

fn normal3(rng: &mut StdRng) -> Vector3<f64> {
    Vector3::new(
        rng.sample(StandardNormal),
        rng.sample(StandardNormal),
        rng.sample(StandardNormal),
    )
}

fn make_align(rng: &mut StdRng, r: &SO3, t: &Vector3<f64>, sigma: f64) -> Align {
    let p: Vec<_> = (0..12).map(|_| normal3(rng) * 2.0).collect();
    let q = p
        .iter()
        .map(|p| r.act(p) + t + normal3(rng) * sigma)
        .collect();
    Align { p, q, sigma }
}

#[test]
fn alignment_jacobian_is_right() {
    let mut rng = StdRng::seed_from_u64(1);
    let r = SO3::exp(&Vector3::new(0.4, -1.0, 2.0));
    let t = Vector3::new(1.0, 2.0, -3.0);
    let a = make_align(&mut rng, &r, &t, 0.1);
    let x = (
        SO3::exp(&Vector3::new(0.1, 0.2, 0.3)),
        Vector3::new(0.5, 0.0, 1.0),
    );
    let (_, j) = a.residual_jacobian(&x);
    let rep = check_jacobian(
        |x: &(SO3, Vector3<f64>)| a.residual_jacobian(x).0,
        &x,
        &[j.columns(0, 3).into_owned(), j.columns(3, 3).into_owned()],
        &CheckOptions::default(),
    )
    .unwrap();
    assert!(rep.worst_rel_error < 1e-8, "{rep}");
}

#[test]
fn alignment_recovers_exact_pose_from_far_start() {
    let mut rng = StdRng::seed_from_u64(2);
    // 2.8 rad away from the identity start.
    let r = SO3::exp(&(Vector3::new(0.2, -0.6, 0.77).normalize() * 2.8));
    let t = Vector3::new(1.0, 2.0, -3.0);
    // Noise-free data (σ only scales the residuals).
    let mut a = make_align(&mut rng, &r, &t, 0.0);
    a.sigma = 0.01;
    for solver in [GaussNewton::levenberg_marquardt(), GaussNewton::undamped()] {
        let name = format!("{:?}", solver.damping);
        let sol = solve(
            Align {
                p: a.p.clone(),
                q: a.q.clone(),
                sigma: a.sigma,
            },
            (SO3::identity(), Vector3::zeros()),
            solver,
            100,
        )
        .unwrap();
        let err_r = sol.estimate.0.minus(&r).norm();
        let err_t = (sol.estimate.1 - t).norm();
        assert!(err_r < 1e-9 && err_t < 1e-9, "{name}: {err_r} {err_t}");
        assert!(sol.stop.converged(), "{name}: {:?}", sol.stop);
        assert!(sol.iterations < 50, "{name}: {}", sol.iterations);
        assert_eq!(sol.rank, 6);
        assert_eq!(sol.unobservable.ncols(), 0);
        assert!(sol.cost < 1e-16, "{name}: {}", sol.cost);
    }
}

/// The reported covariance (inverse information) matches the spread of the estimates over
/// 300 noisy data sets (same points, fresh noise), on the diagonal within 20 % (the sampling
/// error of a variance from 300 samples is √(2/300) ≈ 8 %).
#[test]
fn alignment_covariance_matches_monte_carlo() {
    let mut rng = StdRng::seed_from_u64(3);
    let r = SO3::exp(&Vector3::new(0.3, 0.1, -0.5));
    let t = Vector3::new(0.2, -0.1, 0.4);
    let sigma = 0.05;
    let base = make_align(&mut rng, &r, &t, 0.0);
    let truth = (r, t);
    let n = 300;
    let mut errs = Vec::with_capacity(n);
    let mut cov = DMatrix::zeros(6, 6);
    for _ in 0..n {
        let q = base
            .p
            .iter()
            .map(|p| r.act(p) + t + normal3(&mut rng) * sigma)
            .collect();
        let prob = Align {
            p: base.p.clone(),
            q,
            sigma,
        };
        let sol = solve(prob, truth, GaussNewton::default(), 50).unwrap();
        // Tangent error at the estimate: truth ⊖ estimate (right convention).
        errs.push(sol.estimate.local_vec(&truth));
        cov = sol.covariance;
    }
    let mut emp = DMatrix::zeros(6, 6);
    for e in &errs {
        emp += e * e.transpose();
    }
    emp /= n as f64;
    for i in 0..6 {
        let ratio = emp[(i, i)] / cov[(i, i)];
        assert!(
            (0.8..1.25).contains(&ratio),
            "coordinate {i}: ratio {ratio}"
        );
    }
}

/// All points on one line through the origin: the rotation about that line is unobservable.
/// The solver must report it (basis ≈ (a, 0)), still fit the data, and give infinite standard
/// deviations for the rotation coordinates that mix with it.
#[test]
fn collinear_points_make_rotation_about_the_line_unobservable() {
    let a = Vector3::new(1.0, 2.0, 2.0) / 3.0;
    let r = SO3::exp(&Vector3::new(0.3, -0.2, 0.4));
    let t = Vector3::new(1.0, 0.0, -1.0);
    let p: Vec<_> = [-2.0, -1.0, 0.5, 1.5, 3.0].iter().map(|s| a * *s).collect();
    let q = p.iter().map(|p| r.act(p) + t).collect();
    let sol = solve(
        Align {
            p: p.clone(),
            q,
            sigma: 0.01,
        },
        (SO3::identity(), Vector3::zeros()),
        GaussNewton::default(),
        100,
    )
    .unwrap();
    assert_eq!(sol.rank, 5, "{:?}", sol);
    assert_eq!(sol.unobservable.ncols(), 1);
    let u = sol.unobservable.column(0);
    let expected = DVector::from_column_slice(&[a[0], a[1], a[2], 0.0, 0.0, 0.0]);
    // Canonical sign: largest entry positive, so u = +expected.
    assert!((u - &expected).amax() < 1e-6, "{u}");
    // The fit is exact although the rotation about `a` is arbitrary.
    for pi in &p {
        let e = (sol.estimate.0.act(pi) + sol.estimate.1) - (r.act(pi) + t);
        assert!(e.norm() < 1e-9, "{e}");
    }
    assert!(sol.cost < 1e-12);
    let sd = sol.std_devs();
    assert!(sd.rows(0, 3).iter().all(|s| s.is_infinite()), "{sd}");
    assert!(sd.rows(3, 3).iter().all(|s| s.is_finite()), "{sd}");
    // The pseudo-inverse covariance carries nothing along the unobservable direction.
    assert!((&sol.covariance * &expected).amax() < 1e-9);
}

/// Linear, rank 2 of 3: r = (x₀ + x₁ − 1, x₂ − 2). From 0 the pseudo-inverse step is the
/// minimum-norm solution (½, ½, 2); the unobservable direction is (1, −1, 0)/√2; the covariance
/// is H⁺ = ¼[[1,1,0],[1,1,0],[0,0,0]] + e₂e₂ᵀ (worked by hand: H has eigenpair 2, (1,1,0)/√2).
#[test]
fn linear_rank_deficient_problem_gives_min_norm_solution_and_basis() {
    let prob = NumericLeastSquares::new(|x: &Vector3<f64>| {
        DVector::from_column_slice(&[x[0] + x[1] - 1.0, x[2] - 2.0])
    });
    let sol = solve(prob, Vector3::zeros(), GaussNewton::undamped(), 20).unwrap();
    assert!(
        (sol.estimate - Vector3::new(0.5, 0.5, 2.0)).amax() < 1e-8,
        "{}",
        sol.estimate
    );
    assert_eq!(sol.rank, 2);
    let u = sol.unobservable.column(0);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert!((u[0].abs() - s).abs() < 1e-8 && (u[0] + u[1]).abs() < 1e-8 && u[2].abs() < 1e-8);
    let expected =
        DMatrix::from_row_slice(3, 3, &[0.25, 0.25, 0.0, 0.25, 0.25, 0.0, 0.0, 0.0, 1.0]);
    assert!(
        (&sol.covariance - expected).amax() < 1e-6,
        "{}",
        sol.covariance
    );
    let sd = sol.std_devs();
    assert!(sd[0].is_infinite() && sd[1].is_infinite() && (sd[2] - 1.0).abs() < 1e-6);
}

/// Dennis & Schnabel (1996) Example 10.2.4-like large-residual problem:
/// r(x) = (x + 1, λx² + x − 1), λ = −2; its minimum is x = 0, F = 1 (a grid search over
/// [−5, 5] finds nothing lower). Undamped Gauss-Newton from x = 3 oscillates and never
/// converges; Levenberg-Marquardt converges to 0.
#[test]
fn lm_converges_where_plain_gauss_newton_oscillates() {
    let f = |x: &Vector1<f64>| {
        let x = x[0];
        DVector::from_column_slice(&[x + 1.0, -2.0 * x * x + x - 1.0])
    };
    // Independent check of the minimum.
    let fmin = (0..100_001)
        .map(|i| -5.0 + 1e-4 * i as f64)
        .map(|x| 0.5 * f(&Vector1::new(x)).norm_squared())
        .fold(f64::INFINITY, f64::min);
    assert!((fmin - 1.0).abs() < 1e-12);

    let x0 = Vector1::new(3.0);
    let gn = solve(
        NumericLeastSquares::new(f),
        x0,
        GaussNewton::undamped(),
        200,
    )
    .unwrap();
    assert_eq!(gn.stop, StopReason::MaxIters);
    assert_eq!(gn.iterations, 200);

    let lm = solve(NumericLeastSquares::new(f), x0, GaussNewton::default(), 200).unwrap();
    assert!(lm.stop.converged(), "{:?}", lm.stop);
    assert!(lm.estimate[0].abs() < 1e-6, "{}", lm.estimate[0]);
    assert!((lm.cost - 1.0).abs() < 1e-12);
    assert!(lm.iterations < 100, "{}", lm.iterations);
}

/// argmin observers see every iteration, with the key/values the solver emits; LM costs never
/// increase.
#[test]
fn argmin_observers_receive_iterations() {
    #[derive(Clone, Default)]
    struct Record(Arc<Mutex<Vec<(f64, bool)>>>);
    impl Observe<GnState<(SO3, Vector3<f64>)>> for Record {
        fn observe_iter(
            &mut self,
            state: &GnState<(SO3, Vector3<f64>)>,
            kv: &KV,
        ) -> Result<(), argmin::core::Error> {
            let accepted = kv
                .get("accepted")
                .and_then(|v| v.get_bool())
                .unwrap_or(false);
            self.0.lock().unwrap().push((state.get_cost(), accepted));
            Ok(())
        }
    }
    let mut rng = StdRng::seed_from_u64(4);
    let r = SO3::exp(&Vector3::new(1.0, 1.0, -1.0));
    let a = make_align(&mut rng, &r, &Vector3::new(0.0, 1.0, 0.0), 0.01);
    let rec = Record::default();
    let res = Executor::new(a, GaussNewton::default())
        .configure(|s| s.param((SO3::identity(), Vector3::zeros())).max_iters(100))
        .add_observer(rec.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    let sol = finish(res).unwrap();
    let log = rec.0.lock().unwrap().clone();
    assert_eq!(log.len() as u64, sol.iterations);
    assert!(log.iter().any(|(_, acc)| *acc));
    for w in log.windows(2) {
        assert!(w[1].0 <= w[0].0, "{log:?}");
    }
    assert!((log.last().unwrap().0 - sol.cost).abs() <= 1e-12 * sol.cost.max(1.0));
}

#[test]
fn bad_problems_give_typed_errors() {
    let nan = NumericLeastSquares::new(|_: &Vector1<f64>| DVector::from_element(1, f64::NAN));
    assert!(matches!(
        solve(nan, Vector1::new(0.0), GaussNewton::default(), 10),
        Err(preint_calib::GnError::NonFinite(_))
    ));
    struct Wrong;
    impl LeastSquares for Wrong {
        type State = Vector3<f64>;
        fn residual_jacobian(&self, _: &Vector3<f64>) -> (DVector<f64>, DMatrix<f64>) {
            (DVector::zeros(2), DMatrix::zeros(2, 2))
        }
    }
    assert!(matches!(
        solve(Wrong, Vector3::zeros(), GaussNewton::default(), 10),
        Err(preint_calib::GnError::Shape {
            cols: 2,
            dim: 3,
            ..
        })
    ));
    let mut bad = GaussNewton::default();
    bad.rank_threshold = -1.0;
    let ok = NumericLeastSquares::new(|x: &Vector1<f64>| DVector::from_element(1, x[0]));
    assert!(matches!(
        solve(ok, Vector1::new(1.0), bad, 10),
        Err(preint_calib::GnError::InvalidOption(_))
    ));
}

/// Records the `cholesky` flag of every iteration.
#[derive(Clone, Default)]
struct PathLog(Arc<Mutex<Vec<bool>>>);
impl<X> Observe<GnState<X>> for PathLog {
    fn observe_iter(&mut self, _: &GnState<X>, kv: &KV) -> Result<(), argmin::core::Error> {
        let c = kv.get("cholesky").and_then(|v| v.get_bool());
        self.0
            .lock()
            .unwrap()
            .push(c.expect("the solver emits `cholesky`"));
        Ok(())
    }
}

/// A well-conditioned problem is solved by Cholesky at every iteration; the collinear (rank 5)
/// problem falls back to the eigen path at every iteration (module docs of `gauss_newton`).
#[test]
fn cholesky_path_when_well_conditioned_eigen_path_when_deficient() {
    let mut rng = StdRng::seed_from_u64(5);
    let r = SO3::exp(&Vector3::new(0.5, -0.4, 0.9));
    let good = make_align(&mut rng, &r, &Vector3::new(1.0, 0.0, 2.0), 0.01);
    let log = PathLog::default();
    let res = Executor::new(good, GaussNewton::default())
        .configure(|s| s.param((SO3::identity(), Vector3::zeros())).max_iters(50))
        .add_observer(log.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    let sol = finish(res).unwrap();
    assert!(sol.stop.converged(), "{:?}", sol.stop);
    let paths = log.0.lock().unwrap().clone();
    assert!(!paths.is_empty() && paths.iter().all(|c| *c), "{paths:?}");

    let a = Vector3::new(1.0, 2.0, 2.0) / 3.0;
    let p: Vec<_> = [-2.0, -1.0, 0.5, 1.5, 3.0].iter().map(|s| a * *s).collect();
    let q = p.iter().map(|p| r.act(p)).collect();
    let log = PathLog::default();
    let res = Executor::new(Align { p, q, sigma: 0.01 }, GaussNewton::default())
        .configure(|s| s.param((SO3::identity(), Vector3::zeros())).max_iters(50))
        .add_observer(log.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    let sol = finish(res).unwrap();
    assert_eq!(sol.rank, 5);
    let paths = log.0.lock().unwrap().clone();
    assert!(!paths.is_empty() && paths.iter().all(|c| !*c), "{paths:?}");
}

/// A Jacobian with the wrong sign makes every LM step go uphill: every step is rejected, μ
/// grows until the step is ≈ 0. That is **not** convergence: the solver must report
/// `DampingExhausted` (not `StepNorm`, which would claim convergence).
#[test]
fn rejected_steps_with_huge_damping_are_not_convergence() {
    struct Wrong;
    impl LeastSquares for Wrong {
        type State = Vector3<f64>;
        fn residual_jacobian(&self, x: &Vector3<f64>) -> (DVector<f64>, DMatrix<f64>) {
            let r = DVector::from_column_slice((x - Vector3::new(1.0, 2.0, 3.0)).as_slice());
            (r, -DMatrix::identity(3, 3))
        }
    }
    let sol = solve(Wrong, Vector3::zeros(), GaussNewton::default(), 500).unwrap();
    assert_eq!(sol.stop, StopReason::DampingExhausted);
    assert!(!sol.stop.converged());
    assert!(sol.iterations < 500, "{}", sol.iterations);
    assert_eq!(sol.estimate, Vector3::zeros());
}

/// At an exact optimum (zero residual after one step of a linear problem) LM stops with a
/// convergence reason, not `DampingExhausted`, even though round-off may reject steps.
#[test]
fn optimum_of_a_linear_problem_is_converged() {
    let prob = NumericLeastSquares::new(|x: &Vector3<f64>| {
        DVector::from_column_slice(&[
            2.0 * x[0] - x[1] - 1.0,
            x[1] + 3.0 * x[2] - 2.0,
            x[0] + x[2] + 0.5,
            x[0] - x[1] + x[2],
        ])
    });
    let sol = solve(
        prob,
        Vector3::new(5.0, -3.0, 2.0),
        GaussNewton::default(),
        100,
    )
    .unwrap();
    assert!(sol.stop.converged(), "{:?}", sol.stop);
    assert!(sol.iterations < 20, "{}", sol.iterations);
}
