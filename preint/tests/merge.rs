//! `merge`: two consecutive windows merged equal the whole window integrated at once (deltas
//! to round-off, covariances and bias Jacobians to 1e-10 relative): Euler with an independent
//! Forster-Euler integration written here and with the crate's preintegrator; every scheme
//! with windows cut by `preintegrate` (the samples both windows share supply the cross
//! covariance; without it midpoint and hermite4 are off by ≈ 3e-3–5e-3). Levels are respected.
//! `tests/linearisation.rs` checks merges between samples against numeric differentiation.

use nalgebra::{Matrix3, SMatrix, Vector3};
use preint::edges::EdgeNoise;
use preint::{
    BiasJacobians, Cov9, Cov15, ImuBias, ImuNoise, ImuSample, Level, MergeError, PreintParams,
    PreintegratedImu, Scheme, merge, preintegrate,
};
use preint_lie::{SO3, hat, jr};

struct Rng(u64);
impl Rng {
    fn s(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        2.0 * ((self.0.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64) - 1.0
    }
    fn v3(&mut self, a: f64) -> Vector3<f64> {
        Vector3::new(self.s(), self.s(), self.s()) * a
    }
}

/// Irregular 200 Hz-ish stream (jittered integer-ns stamps), fast rotation and acceleration.
fn samples(n: usize, seed: u64) -> Vec<ImuSample> {
    let mut rng = Rng(seed);
    let mut t = 1_403_636_579_758_555_392i64;
    (0..n)
        .map(|k| {
            let s = ImuSample::new(
                t,
                Vector3::new(1.5 * (0.3 * k as f64).sin(), 0.8, -0.5) + rng.v3(0.3),
                Vector3::new(0.5, -0.3, 9.81) + rng.v3(2.0),
            );
            t += 5_000_000 + (rng.s() * 1_000_000.0) as i64;
            s
        })
        .collect()
}

const SG: f64 = 1.7e-4; // gyro noise density [rad/s/√Hz]
const SA: f64 = 2.0e-3; // acc noise density [m/s²/√Hz]
const SBG: f64 = 1.9e-5; // gyro random walk [rad/s²/√Hz]
const SBA: f64 = 3.0e-3; // acc random walk [m/s³/√Hz]

/// Independent Forster-Euler preintegration (sample k held over interval k) with the
/// 15-dim error state [δφ, δv, δp, δb_g, δb_a]: `e ← A e + G (n + δb)`, `δb ← δb + w`,
/// `J ← A J − G`.
fn euler(s: &[ImuSample], bias: &ImuBias) -> PreintegratedImu {
    let (mut r, mut v, mut p) = (Matrix3::identity(), Vector3::zeros(), Vector3::zeros());
    let mut p15 = Cov15::zeros();
    let mut jac = SMatrix::<f64, 9, 6>::zeros();
    for k in 0..s.len() - 1 {
        let dt = (s[k + 1].t_ns - s[k].t_ns) as f64 * 1e-9;
        let w = s[k].gyro - bias.gyro;
        let a = s[k].acc - bias.acc;
        let e = *SO3::exp(&(w * dt)).matrix();
        let mut am = SMatrix::<f64, 9, 9>::identity();
        am.fixed_view_mut::<3, 3>(0, 0).copy_from(&e.transpose());
        am.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(-r * hat(&a) * dt));
        am.fixed_view_mut::<3, 3>(6, 0)
            .copy_from(&(-r * hat(&a) * (0.5 * dt * dt)));
        am.fixed_view_mut::<3, 3>(6, 3)
            .copy_from(&(Matrix3::identity() * dt));
        let mut g = SMatrix::<f64, 9, 6>::zeros();
        g.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(jr(&(w * dt)) * dt));
        g.fixed_view_mut::<3, 3>(3, 3).copy_from(&(r * dt));
        g.fixed_view_mut::<3, 3>(6, 3)
            .copy_from(&(r * (0.5 * dt * dt)));
        let mut f = Cov15::identity();
        f.fixed_view_mut::<9, 9>(0, 0).copy_from(&am);
        f.fixed_view_mut::<9, 6>(0, 9).copy_from(&g);
        let qn = SMatrix::<f64, 6, 6>::from_diagonal(&SMatrix::<f64, 6, 1>::from_column_slice(&[
            SG * SG / dt,
            SG * SG / dt,
            SG * SG / dt,
            SA * SA / dt,
            SA * SA / dt,
            SA * SA / dt,
        ]));
        let mut q = Cov15::zeros();
        q.fixed_view_mut::<9, 9>(0, 0)
            .copy_from(&(g * qn * g.transpose()));
        for i in 9..12 {
            q[(i, i)] = SBG * SBG * dt;
            q[(i + 3, i + 3)] = SBA * SBA * dt;
        }
        p15 = f * p15 * f.transpose() + q;
        jac = am * jac - g;
        p += v * dt + r * a * (0.5 * dt * dt);
        v += r * a * dt;
        r *= e;
    }
    // 9×9: same recursion without the bias terms = A P Aᵀ + G Qn Gᵀ, which is exactly the
    // [0..9, 0..9] block of a run with zero random walk; recompute it that way.
    let cov = {
        let mut pp = Cov9::zeros();
        let mut rr = Matrix3::identity();
        for k in 0..s.len() - 1 {
            let dt = (s[k + 1].t_ns - s[k].t_ns) as f64 * 1e-9;
            let w = s[k].gyro - bias.gyro;
            let a = s[k].acc - bias.acc;
            let e = *SO3::exp(&(w * dt)).matrix();
            let mut am = Cov9::identity();
            am.fixed_view_mut::<3, 3>(0, 0).copy_from(&e.transpose());
            am.fixed_view_mut::<3, 3>(3, 0)
                .copy_from(&(-rr * hat(&a) * dt));
            am.fixed_view_mut::<3, 3>(6, 0)
                .copy_from(&(-rr * hat(&a) * (0.5 * dt * dt)));
            am.fixed_view_mut::<3, 3>(6, 3)
                .copy_from(&(Matrix3::identity() * dt));
            let jrm = jr(&(w * dt)) * dt;
            let mut add = Cov9::zeros();
            add.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(jrm * jrm.transpose() * (SG * SG / dt)));
            let (bv, bp) = (rr * dt, rr * (0.5 * dt * dt));
            let sa = SA * SA / dt;
            add.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&(bv * bv.transpose() * sa));
            add.fixed_view_mut::<3, 3>(3, 6)
                .copy_from(&(bv * bp.transpose() * sa));
            add.fixed_view_mut::<3, 3>(6, 3)
                .copy_from(&(bp * bv.transpose() * sa));
            add.fixed_view_mut::<3, 3>(6, 6)
                .copy_from(&(bp * bp.transpose() * sa));
            pp = am * pp * am.transpose() + add;
            rr *= e;
        }
        pp
    };
    let blk = |r: usize, c: usize| jac.fixed_view::<3, 3>(r, c).into_owned();
    PreintegratedImu {
        t_i_ns: s[0].t_ns,
        t_j_ns: s[s.len() - 1].t_ns,
        delta_t: (s[s.len() - 1].t_ns - s[0].t_ns) as f64 * 1e-9,
        delta_r: SO3::from_matrix(&r),
        delta_v: v,
        delta_p: p,
        cov,
        cov15: p15,
        jac: BiasJacobians {
            d_r_d_bg: blk(0, 0),
            d_v_d_bg: blk(3, 0),
            d_v_d_ba: blk(3, 3),
            d_p_d_bg: blk(6, 0),
            d_p_d_ba: blk(6, 3),
        },
        jac_td: Default::default(),
        bias_hat: *bias,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        omega_coriolis: None,
        coriolis: preint::CoriolisMode::Exact,
        level: Level::Combined,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    }
}

fn rel<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>, b: &SMatrix<f64, R, C>) -> f64 {
    (a - b).amax() / b.amax()
}

fn jac_list(j: &BiasJacobians) -> [Matrix3<f64>; 5] {
    [j.d_r_d_bg, j.d_v_d_bg, j.d_v_d_ba, j.d_p_d_bg, j.d_p_d_ba]
}

fn assert_merged_equals_whole(m: &PreintegratedImu, w: &PreintegratedImu, what: &str) {
    assert_eq!((m.t_i_ns, m.t_j_ns), (w.t_i_ns, w.t_j_ns));
    assert!((m.delta_t - w.delta_t).abs() < 1e-15, "{what}: Δt");
    assert!(m.delta_r.minus(&w.delta_r).norm() < 1e-14, "{what}: ΔR");
    assert!(
        (m.delta_v - w.delta_v).amax() < 1e-13 * (1.0 + w.delta_v.amax()),
        "{what}: Δv"
    );
    assert!(
        (m.delta_p - w.delta_p).amax() < 1e-13 * (1.0 + w.delta_p.amax()),
        "{what}: Δp"
    );
    // Per 3×3 block, so that small blocks are not hidden by large ones.
    for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
        let a = m.cov.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
        let b = w.cov.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
        assert!(
            rel(&a, &b) < 1e-10,
            "{what}: cov block ({r},{c}) rel {:e}",
            rel(&a, &b)
        );
    }
    for (r, c) in (0..5).flat_map(|r| (0..5).map(move |c| (r, c))) {
        let a = m.cov15.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
        let b = w.cov15.fixed_view::<3, 3>(3 * r, 3 * c).into_owned();
        if b.amax() == 0.0 {
            assert!(
                a.amax() < 1e-30 * w.cov15.amax(),
                "{what}: cov15 block ({r},{c}) not zero"
            );
        } else {
            assert!(
                rel(&a, &b) < 1e-10,
                "{what}: cov15 block ({r},{c}) rel {:e}",
                rel(&a, &b)
            );
        }
    }
    for (k, (a, b)) in jac_list(&m.jac).iter().zip(jac_list(&w.jac)).enumerate() {
        assert!(
            rel(a, &b) < 1e-10,
            "{what}: bias Jacobian {k} rel {:e}",
            rel(a, &b)
        );
    }
}

#[test]
fn merge_equals_whole_window_independent_euler() {
    let s = samples(81, 1);
    let bias = ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.2),
    );
    for split in [1, 17, 40, 79] {
        let a = euler(&s[..=split], &bias);
        let b = euler(&s[split..], &bias);
        let whole = euler(&s, &bias);
        let m = merge(&a, &b).unwrap();
        assert_merged_equals_whole(&m, &whole, &format!("split {split}"));
        // Three windows, merged left and right-associatively.
        if split < 60 {
            let c = euler(&s[60..], &bias);
            let b2 = euler(&s[split..=60], &bias);
            let l = merge(&merge(&a, &b2).unwrap(), &c).unwrap();
            let r = merge(&a, &merge(&b2, &c).unwrap()).unwrap();
            assert_merged_equals_whole(&l, &whole, "left-assoc");
            assert_merged_equals_whole(&r, &whole, "right-assoc");
        }
    }
}

#[test]
fn merge_equals_whole_window_crate_preintegrator_euler() {
    let s = samples(121, 2);
    let noise = ImuNoise {
        gyro_noise_density: SG,
        gyro_random_walk: SBG,
        acc_noise_density: SA,
        acc_random_walk: SBA,
        update_rate_hz: 200.0,
    };
    let params = PreintParams::from_noise(&noise).with_scheme(Scheme::Euler);
    let bias = ImuBias::new(
        Vector3::new(0.003, 0.0, -0.01),
        Vector3::new(-0.1, 0.2, 0.05),
    );
    let (t0, tk, t1) = (s[0].t_ns, s[50].t_ns, s[120].t_ns);
    // With `Level::Combined`, `cov` must be the white-noise covariance alone (the random-walk
    // part lives only in `cov15`): it must equal a `Level::Covariance` run and compose by the
    // 9×9 rule below.
    let p9 = params.clone().with_level(Level::Covariance);
    let run = |t_a, t_b| {
        let x = preintegrate(&params, &bias, &s, t_a, t_b).unwrap();
        let white = preintegrate(&p9, &bias, &s, t_a, t_b).unwrap().cov;
        assert!(
            (x.cov - white).amax() <= 1e-15 * white.amax(),
            "cov includes the bias random walk"
        );
        let walk = x.cov15.fixed_view::<9, 9>(0, 0) - x.cov;
        assert!(
            walk.amax() > 1e-6 * white.amax(),
            "cov15 lost the random-walk part"
        );
        x
    };
    let (a, b, whole) = (run(t0, tk), run(tk, t1), run(t0, t1));
    assert!(whole.cov15.fixed_view::<6, 6>(9, 9).amax() > 0.0);
    let m = merge(&a, &b).unwrap();
    assert_merged_equals_whole(&m, &whole, "crate euler");
}

#[test]
fn merge_rejects_inconsistent_windows() {
    let s = samples(21, 3);
    let bias = ImuBias::zero();
    let a = euler(&s[..=10], &bias);
    let b = euler(&s[10..], &bias);
    let gap = euler(&s[11..], &bias);
    assert_eq!(
        merge(&a, &gap),
        Err(MergeError::NotConsecutive {
            a_t_j_ns: s[10].t_ns,
            b_t_i_ns: s[11].t_ns
        })
    );
    // Reversed order is not consecutive either.
    assert!(matches!(
        merge(&b, &a),
        Err(MergeError::NotConsecutive { .. })
    ));
    let other_bias = PreintegratedImu {
        bias_hat: ImuBias::new(Vector3::new(1e-9, 0.0, 0.0), Vector3::zeros()),
        ..b.clone()
    };
    assert_eq!(merge(&a, &other_bias), Err(MergeError::BiasMismatch));
    let other_g = PreintegratedImu {
        gravity: Vector3::new(0.0, 0.0, -9.80665),
        ..b.clone()
    };
    assert_eq!(merge(&a, &other_g), Err(MergeError::GravityMismatch));
    let group = PreintegratedImu {
        bias_correction: preint::BiasCorrection::Group,
        ..b.clone()
    };
    assert_eq!(
        merge(&a, &group),
        Err(MergeError::BiasCorrectionMismatch {
            a: preint::BiasCorrection::Additive,
            b: preint::BiasCorrection::Group
        })
    );
    // Equal corrections merge and keep it.
    let a_group = PreintegratedImu {
        bias_correction: preint::BiasCorrection::Group,
        ..a.clone()
    };
    let m = merge(&a_group, &group).unwrap();
    assert_eq!(m.bias_correction, preint::BiasCorrection::Group);
}

/// Every scheme, windows cut by `preintegrate` at a stream sample of a jittered stream: the
/// shared samples' covariance (midpoint: the sample at the split; hermite4: also its stencil
/// neighbours) makes the merge equal the whole window, deltas to round-off and covariances,
/// combined covariance and bias Jacobians to 1e-10. Also for Euler and midpoint windows
/// whose samples were pushed into preintegrators directly (each window then sees one
/// neighbour of the shared sample; the merge uses both).
#[test]
fn merge_equals_whole_window_every_scheme() {
    let s = samples(121, 4);
    let params = PreintParams::default().with_level(Level::Combined);
    let bias = ImuBias::new(
        Vector3::new(0.003, 0.0, -0.01),
        Vector3::new(-0.1, 0.2, 0.05),
    );
    for &scheme in Scheme::ALL {
        let p = params.clone().with_scheme(scheme);
        for (i, k, j) in [(3, 50, 117), (3, 4, 117), (0, 60, 120), (10, 11, 12)] {
            let w = |a: usize, b: usize| preintegrate(&p, &bias, &s, s[a].t_ns, s[b].t_ns).unwrap();
            let m = merge(&w(i, k), &w(k, j)).unwrap();
            assert_merged_equals_whole(&m, &w(i, j), &format!("{scheme:?} split {i}-{k}-{j}"));
            // Without the shared samples the covariance is measurably off (except Euler and
            // Galilean, which hold samples and share nothing at a sample).
            let mut a = w(i, k);
            a.edge_noise = EdgeNoise::default();
            let mi = merge(&a, &w(k, j)).unwrap();
            let e = rel(&mi.cov, &w(i, j).cov);
            eprintln!("{scheme:?} split {i}-{k}-{j}: merged as independent: cov rel {e:.1e}");
            let held = matches!(scheme, Scheme::Euler | Scheme::Galilean);
            assert!((e > 1e-4) != held, "{scheme:?}: {e}");
        }
        if scheme != Scheme::Hermite4 {
            let run = |x: &[ImuSample]| {
                let mut pi = preint::Preintegrator::new(p.clone(), bias).unwrap();
                pi.integrate_slice(x).unwrap();
                pi.finish().unwrap()
            };
            for k in [1, 40, 119] {
                let m = merge(&run(&s[..=k]), &run(&s[k..])).unwrap();
                assert_merged_equals_whole(&m, &run(&s), &format!("{scheme:?} direct split {k}"));
            }
        }
    }
}

/// `Level::Covariance` measurements carry no random-walk effect on the deltas: their merge
/// keeps `cov15 = diag(cov, Σ_bb)` (no invented cross blocks) and equals the whole window's.
/// Mixing levels is an error.
#[test]
fn merge_respects_the_level() {
    let s = samples(61, 5);
    let bias = ImuBias::zero();
    let p = PreintParams::default()
        .with_scheme(Scheme::Midpoint)
        .with_level(Level::Covariance);
    let w = |p: &PreintParams, a: usize, b: usize| {
        preintegrate(p, &bias, &s, s[a].t_ns, s[b].t_ns).unwrap()
    };
    let m = merge(&w(&p, 0, 30), &w(&p, 30, 60)).unwrap();
    assert_eq!(m.level, Level::Covariance);
    assert_eq!(m.cov15.fixed_view::<9, 6>(0, 9).amax(), 0.0);
    assert_eq!(m.cov15.fixed_view::<6, 9>(9, 0).amax(), 0.0);
    assert_merged_equals_whole(&m, &w(&p, 0, 60), "covariance level");
    let bb = m.cov15.fixed_view::<6, 6>(9, 9).into_owned();
    let dt = (s[60].t_ns - s[0].t_ns) as f64 * 1e-9;
    let expected = p.gyro_bias_rw_cov[(0, 0)] * dt;
    assert!((bb[(0, 0)] - expected).abs() < 1e-12 * expected);
    let c = p.clone().with_level(Level::Combined);
    assert_eq!(
        merge(&w(&p, 0, 30), &w(&c, 30, 60)),
        Err(MergeError::LevelMismatch {
            a: Level::Covariance,
            b: Level::Combined
        })
    );
}
