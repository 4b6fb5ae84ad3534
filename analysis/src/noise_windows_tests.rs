use super::*;
use crate::consistency::evaluate;
use nalgebra::{SVector, Vector3};
use preint::{ImuNoise, predict};
use preint_calib::noise_fit::chi2;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

const RATE_HZ: f64 = 200.0;
const OMEGA: [f64; 3] = [0.3, -0.2, 0.5];
const ACC: [f64; 3] = [0.5, 0.2, 10.1];

/// A seeded standard normal.
struct Normal(StdRng);

impl Normal {
    fn seeded(seed: u64) -> Self {
        Self(StdRng::seed_from_u64(seed))
    }
    fn next(&mut self) -> f64 {
        self.0.sample(StandardNormal)
    }
}

/// 1 s at 200 Hz of a constant rotation rate and specific force, plus `bias(k)`.
fn samples(bias: impl Fn(usize) -> ImuBias) -> Vec<ImuSample> {
    (0..=RATE_HZ as usize)
        .map(|k| {
            let b = bias(k);
            ImuSample::new(
                (k as f64 * 1e9 / RATE_HZ).round() as i64,
                Vector3::from(OMEGA) + b.gyro,
                Vector3::from(ACC) + b.acc,
            )
        })
        .collect()
}

fn params_at(level: Level) -> PreintParams {
    PreintParams {
        level,
        ..PreintParams::from_noise(&ImuNoise::euroc())
    }
}

fn params() -> PreintParams {
    params_at(Level::Covariance)
}

fn truth(t_ns: i64, x: &NavState) -> GroundTruthState {
    GroundTruthState {
        t_ns,
        p: x.p,
        q: x.r.to_quaternion(),
        v: x.v,
        bias: ImuBias::zero(),
    }
}

/// The states at 0 and 1 s of the motion without bias.
fn states() -> (GroundTruthState, GroundTruthState) {
    let s = samples(|_| ImuBias::zero());
    let x_i = NavState::new(
        preint::lie::SO3::exp(&Vector3::new(0.1, 0.2, -0.3)),
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(1.0, 0.0, 0.5),
    );
    let pim = preintegrate(&params(), &ImuBias::zero(), &s, 0, 1_000_000_000).unwrap();
    let x_j = predict(&pim, &x_i, &ImuBias::zero());
    (truth(0, &x_i), truth(1_000_000_000, &x_j))
}

/// The preintegration covariance is linear in the squared white-noise densities:
/// `cov(N_g, N_a) = N_g² A_{N_g} + N_a² A_{N_a}`.
#[test]
fn white_noise_covariance_is_linear_in_the_squared_densities() {
    let s = samples(|_| ImuBias::zero());
    let span = (0, 1_000_000_000);
    let p = params();
    let b = ImuBias::zero();
    let ag = unit_basis(&p, Source::GyroWhite, &b, &s, span).unwrap();
    let aa = unit_basis(&p, Source::AccWhite, &b, &s, span).unwrap();
    let pim = preintegrate(&p, &b, &s, span.0, span.1).unwrap();
    let n = ImuNoise::euroc();
    let sum = ag * n.gyro_noise_density.powi(2) + aa * n.acc_noise_density.powi(2);
    assert!(
        (sum - pim.cov).amax() < 1e-9 * pim.cov.amax(),
        "{sum} vs {}",
        pim.cov
    );
    assert!(ag.fixed_view::<3, 3>(0, 0).trace() > 0.0);
    assert_eq!(
        aa.fixed_view::<3, 3>(0, 0).amax(),
        0.0,
        "no acc noise in rotation"
    );
}

/// The factor's residual at the true states while the true bias drifts as a random walk of
/// density K (the measurement integrated at the bias at i): its sample covariance over 400
/// seeded draws matches `K² A_K` block by block (trace of each 3×3 diagonal block within 20 %,
/// about 3σ of a 400-draw variance estimate).
#[test]
fn bias_walk_basis_matches_a_monte_carlo_of_drifting_biases() {
    let (gi, gj) = (states().0, states().1);
    let (xi, xj) = (nav(&gi), nav(&gj));
    let p = params();
    let h = 1.0 / RATE_HZ;
    let mut rng = Normal::seeded(0x9e37_79b9_7f4a_7c15);
    for (source, k) in [(Source::GyroWalk, 0.02), (Source::AccWalk, 0.2)] {
        let draws = 400;
        let mut cov = SMatrix::<f64, 9, 9>::zeros();
        for _ in 0..draws {
            let mut walk = vec![Vector3::zeros(); RATE_HZ as usize + 1];
            for j in 1..walk.len() {
                let n = Vector3::new(rng.next(), rng.next(), rng.next());
                walk[j] = walk[j - 1] + n * (k * h.sqrt());
            }
            let s = samples(|j| match source {
                Source::GyroWalk => ImuBias::new(walk[j], Vector3::zeros()),
                _ => ImuBias::new(Vector3::zeros(), walk[j]),
            });
            let pim = preintegrate(&p, &ImuBias::zero(), &s, 0, 1_000_000_000).unwrap();
            let f = ImuFactor::with_mode(pim, ResidualMode::ComponentWise).unwrap();
            let r = f.evaluate(&xi, &xj, &ImuBias::zero()).0;
            cov += r * r.transpose() / draws as f64;
        }
        let basis = unit_basis(
            &p,
            source,
            &ImuBias::zero(),
            &samples(|_| ImuBias::zero()),
            (0, 1_000_000_000),
        )
        .unwrap()
            * (k * k);
        for b in 0..3 {
            let (mc, a) = (
                cov.fixed_view::<3, 3>(3 * b, 3 * b).trace(),
                basis.fixed_view::<3, 3>(3 * b, 3 * b).trace(),
            );
            if source == Source::AccWalk && b == 0 {
                assert!(a.abs() < 1e-15 && mc < 1e-15, "{a} {mc}");
                continue;
            }
            assert!(
                (mc / a - 1.0).abs() < 0.2,
                "{source:?} block {b}: MC {mc:.3e} vs {a:.3e}"
            );
        }
    }
}

/// `Σ(θ)` of the window's basis is the weight `factor` uses: the χ² of [`chi2`] equals
/// [`evaluate`]'s with the same densities and ground-truth errors.
#[test]
fn the_basis_rebuilds_the_weight_of_factor() {
    let (gi, mut gj) = states();
    gj.p += Vector3::new(0.01, -0.02, 0.005);
    let s = samples(|_| ImuBias::zero());
    let p = params_at(Level::Combined);
    let w = noise_window(&p, &s, (&gi, &gj), 1.0).unwrap();
    let n = ImuNoise::euroc();
    let tn = TruthNoise {
        rot_rad: 1e-3,
        pos_m: 5e-3,
        vel_m_s: 1e-2,
        bias_gyro_rad_s: 1e-4,
        bias_acc_m_s2: 1e-2,
    };
    let theta = SVector::<f64, PARAMS>::from_column_slice(
        &[
            n.gyro_noise_density,
            n.acc_noise_density,
            n.gyro_random_walk,
            n.acc_random_walk,
            tn.rot_rad,
            tn.pos_m,
            tn.vel_m_s,
            tn.bias_gyro_rad_s,
            tn.bias_acc_m_s2,
        ]
        .map(|x: f64| x * x),
    );
    let pim = preintegrate(&p, &gi.bias, &s, gi.t_ns, gj.t_ns).unwrap();
    let walk = pim.cov15.fixed_view::<9, 9>(0, 0).into_owned();
    let f = ImuFactor::with_mode(pim, ResidualMode::ComponentWise).unwrap();
    let (r, j) = f.evaluate(&nav(&gi), &nav(&gj), &gi.bias);
    let jac = ResidualJacobians {
        state_i: j.state_i(),
        state_j: j.state_j(),
        bias_i: j.bias_i(),
    };
    // cov15's deltas block holds the white noise and the walk: the weight of `factor` with the
    // walk added.
    let ev = evaluate(r, jac, walk, tn).unwrap();
    let ours = chi2(&w, &theta);
    assert!(ev.chi2 > 1.0, "{}", ev.chi2);
    assert!(
        (ours - ev.chi2).abs() < 1e-6 * ev.chi2,
        "{ours} vs {}",
        ev.chi2
    );
}

/// `gravity_jacobian` is the derivative of the window's residual with respect to the world
/// gravity vector: each column against a central difference of windows built with gravity
/// `g ± ε e_k` (the residual is linear in `g`, so the difference is exact to rounding), and
/// the rotation rows are zero.
#[test]
fn gravity_jacobian_is_the_residuals_derivative_in_gravity() {
    let (gi, gj) = states();
    let s = samples(|_| ImuBias::zero());
    let p = params();
    let g = noise_window(&p, &s, (&gi, &gj), 1.0)
        .unwrap()
        .gravity_jacobian;
    let eps = 1e-3;
    for k in 0..3 {
        let at = |sign: f64| {
            let mut gv = p.gravity;
            gv[k] += sign * eps;
            let q = p.clone().with_gravity(gv);
            noise_window(&q, &s, (&gi, &gj), 1.0).unwrap().r
        };
        let numeric: SVector<f64, 9> = (at(1.0) - at(-1.0)) / (2.0 * eps);
        let col = g.column(k);
        assert!(
            (numeric - col).amax() < 1e-7,
            "column {k}: numeric {numeric} analytic {col}"
        );
        assert!(col.rows(3, 3).norm() > 0.5, "velocity rows carry Δt = 1 s");
    }
    assert_eq!(g.fixed_view::<3, 3>(0, 0).amax(), 0.0);
}
