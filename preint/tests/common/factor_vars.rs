//! What the factor tests share: a seeded generator, random measurements and factor variables,
//! the variables' retraction, and the Jacobians by central differences and as one matrix.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};
use preint::FactorJacobians;
use preint::edges::EdgeNoise;
use preint::lie::SO3;
use preint::{BiasJacobians, CoriolisMode, ImuBias, Level, NavState, PreintegratedImu};

/// xorshift64* — deterministic, no dev-dependency.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn u(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [−1, 1).
    pub fn s(&mut self) -> f64 {
        2.0 * self.u() - 1.0
    }
    pub fn v3(&mut self, a: f64) -> Vector3<f64> {
        Vector3::new(self.s(), self.s(), self.s()) * a
    }
    pub fn m3(&mut self, a: f64) -> Matrix3<f64> {
        Matrix3::from_fn(|_, _| self.s() * a)
    }
    /// A rotation of angle up to ~2.5 rad.
    pub fn rot(&mut self) -> SO3 {
        SO3::exp(&self.v3(1.4))
    }
    pub fn spd<const N: usize>(&mut self, scale: f64) -> SMatrix<f64, N, N> {
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| self.s());
        (a * a.transpose() + SMatrix::<f64, N, N>::identity() * 0.1) * scale
    }
}

/// A random 0.7 s measurement from `t_i_ns` with ΔR `delta_r` (drawn first when `None`) and
/// the Earth rate and mode `omega`.
pub fn random_pim(
    rng: &mut Rng,
    t_i_ns: i64,
    delta_r: Option<SO3>,
    omega: Option<(Vector3<f64>, CoriolisMode)>,
) -> PreintegratedImu {
    let delta_r = delta_r.unwrap_or_else(|| rng.rot());
    PreintegratedImu {
        t_i_ns,
        t_j_ns: t_i_ns + 700_000_000,
        delta_t: 0.7,
        delta_r,
        delta_v: rng.v3(3.0),
        delta_p: rng.v3(2.0),
        cov: rng.spd::<9>(1e-4),
        cov15: rng.spd::<15>(1e-4),
        jac: BiasJacobians {
            d_r_d_bg: rng.m3(0.7),
            d_v_d_bg: rng.m3(2.0),
            d_v_d_ba: rng.m3(0.7),
            d_p_d_bg: rng.m3(1.0),
            d_p_d_ba: rng.m3(0.3),
        },
        jac_td: Default::default(),
        bias_hat: ImuBias::new(rng.v3(0.01), rng.v3(0.1)),
        gravity: Vector3::new(0.0, 0.0, -9.81),
        omega_coriolis: omega.map(|o| o.0),
        coriolis: omega.map_or(CoriolisMode::Exact, |o| o.1),
        level: Level::Combined,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    }
}

/// Variables of the combined factor, perturbed block by block through their retractions:
/// (x_i, x_j, b_i, b_j), tangent [φ_i, p_i, v_i, φ_j, p_j, v_j, bg_i, ba_i, bg_j, ba_j].
pub type Vars = (NavState, NavState, ImuBias, ImuBias);

pub fn retract_vars(x: &Vars, d: &SVector<f64, 30>) -> Vars {
    let s = |k: usize| d.fixed_rows::<3>(k).into_owned();
    let t9 = |k: usize| SVector::<f64, 9>::from_fn(|r, _| d[k + r]);
    (
        x.0.retract(&t9(0)),
        x.1.retract(&t9(9)),
        ImuBias::new(x.2.gyro + s(18), x.2.acc + s(21)),
        ImuBias::new(x.3.gyro + s(24), x.3.acc + s(27)),
    )
}

/// Central differences: column k = (f(x ⊕ h e_k) − f(x ⊖ h e_k)) / 2h (residuals are vectors,
/// so `local` on the output is a subtraction).
pub fn numeric<const R: usize>(
    x: &Vars,
    f: impl Fn(&Vars) -> SVector<f64, R>,
    h: f64,
) -> DMatrix<f64> {
    let mut j = DMatrix::zeros(R, 30);
    for k in 0..30 {
        let mut d = SVector::<f64, 30>::zeros();
        d[k] = h;
        let col = (f(&retract_vars(x, &d)) - f(&retract_vars(x, &(-d)))) / (2.0 * h);
        j.column_mut(k).copy_from(&col);
    }
    j
}

/// The analytic Jacobian blocks as one R×30 matrix in the order of [`Vars`].
pub fn analytic<const R: usize>(j: &FactorJacobians<R>) -> DMatrix<f64> {
    let blocks = [
        j.phi_i, j.p_i, j.v_i, j.phi_j, j.p_j, j.v_j, j.bg_i, j.ba_i, j.bg_j, j.ba_j,
    ];
    let mut m = DMatrix::zeros(R, 30);
    for (b, blk) in blocks.iter().enumerate() {
        m.view_mut((0, 3 * b), (R, 3)).copy_from(blk);
    }
    m
}

/// The names of the blocks of [`Vars`].
pub const NAMES: [&str; 10] = [
    "phi_i", "p_i", "v_i", "phi_j", "p_j", "v_j", "bg_i", "ba_i", "bg_j", "ba_j",
];
