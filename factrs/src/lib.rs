//! # preint-factrs — preint's IMU factors as residuals of the factrs solver
//!
//! [`ImuResidual`] wraps [`preint::ImuFactor`] and [`CombinedImuResidual`] wraps
//! [`preint::CombinedImuFactor`] as [factrs](https://docs.rs/factrs/0.3) residuals, with
//! preint's analytic Jacobians (no automatic differentiation) expressed in factrs' own
//! perturbation of its variables.
//!
//! ```
//! use factrs::{assign_symbols, fac, core::Graph, variables::{ImuBias, SE3, VectorVar3}};
//! use preint_factrs::ImuResidual;
//! # use preint::{ImuBias as Bias, ImuFactor, ImuSample, PreintParams, Preintegrator};
//! # use preint::nalgebra::Vector3;
//! # let params = PreintParams::from_noise(&preint::ImuNoise::euroc());
//! # let mut pi = Preintegrator::new(params, Bias::zero()).unwrap();
//! # for k in 0..201i64 {
//! #     let s = ImuSample::new(k * 5_000_000, Vector3::new(0.0, 0.0, 0.2), Vector3::new(0.1, 0.0, 9.81));
//! #     pi.integrate(&s).unwrap();
//! # }
//! # let factor = ImuFactor::new(pi.finish().unwrap()).unwrap();
//! assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);
//!
//! let mut graph = Graph::new();
//! // `factor`: a preint::ImuFactor between keyframes 0 and 1.
//! graph.add_factor(fac![ImuResidual::new(factor), (X(0), V(0), X(1), V(1), B(0))]);
//! # assert_eq!(graph.len(), 1);
//! ```
//!
//! # Variables
//!
//! A keyframe's [`NavState`] is two factrs variables, the pose [`SE3`] (attitude body → world,
//! position in the world frame) and the world-frame velocity [`VectorVar3`]; the bias is
//! factrs' [`ImuBias`] (`[b_g, b_a]`, preint's order). Keys in GTSAM's order:
//!
//! | residual | keys | dim |
//! |---|---|---|
//! | [`ImuResidual`] | `(pose_i, vel_i, pose_j, vel_j, bias_i)` | 9 |
//! | [`CombinedImuResidual`] | `(pose_i, vel_i, pose_j, vel_j, bias_i, bias_j)` | 15 |
//!
//! [`nav_state`], [`to_factrs`], [`bias`] and [`to_factrs_bias`] convert between the two
//! representations.
//!
//! # Residual and whitening
//!
//! The residual is the preint factor's, whitened by its square-root information `U`
//! (`Σ⁻¹ = UᵀU`, [`preint::ImuFactor::sqrt_information`]): `U r` and `U J`. The factor therefore
//! takes **no noise model** (factrs' default `UnitNoise`); giving one weights it twice. A robust
//! kernel acts on the whitened norm, as for any factrs factor.
//!
//! # Jacobians and factrs' perturbation
//!
//! preint's Jacobians are w.r.t. `R ← R Exp(δφ)`, `p ← p + R δp`, `v ← v + δv`,
//! `b ← b + δb` ([`preint::ImuFactor`]). factrs perturbs an `SE3` with the tangent `[ω, ρ]`:
//! by default `T ⊕ ξ = T Exp(ξ)`, i.e. `R ← R Exp(ω)`, `p ← p + R V(ω) ρ`, whose first
//! derivatives at `ξ = 0` are `δφ = ω`, `δp = ρ`; the pose block is `[J_φ, J_p]`. With
//! factrs' `left` feature, `T ⊕ ξ = Exp(ξ) T`: `δφ = Rᵀω`, `δp = Rᵀ(ρ − [p]× ω)`, and the block
//! is `[J_φ Rᵀ − J_p Rᵀ [p]×, J_p Rᵀ]`. Which of the two factrs was built with is read from
//! its `oplus` once ([`left_perturbation`]). Vectors (velocity, bias) are perturbed additively
//! in both cases. Every block is checked against central differences through factrs' `oplus`
//! in `tests/jacobians.rs`.
//!
//! # factrs' generic entry points
//!
//! factrs builds a factor from a `ResidualN` type (its automatic-differentiation interface,
//! generic over dual numbers), so both residuals implement `Residual5`/`Residual6` as well;
//! factrs' graph and optimisers call the object-safe [`Residual`] methods, which evaluate
//! preint's analytic Jacobians. The generic `residual5`/`residual6` return the first-order
//! expansion `r + J (x ⊖ re(x))` at the real parts `re(x)` of their arguments, so factrs'
//! forward-mode differentiation (their `Differ`, `ForwardProp`) reproduces the analytic
//! Jacobian: that entry point is consistent with the other, never silently zero.
//!
//! Needs factrs built with `f64` (without its `f32` feature) and without its `serde` feature
//! (a serialisable residual must be registered with typetag).

#![deny(missing_docs)]

use std::sync::OnceLock;

use factrs::containers::{Key, Values};
use factrs::linalg::{Const, DiffResult, ForwardProp, MatrixX, Numeric, VectorX};
use factrs::residuals::{Residual, Residual5, Residual6};
use factrs::variables::{ImuBias, SE3, SO3, Variable, VectorVar3};
use preint::lie::SO3 as PreintSO3;
use preint::nalgebra::{Matrix3, Quaternion, SMatrix, UnitQuaternion, Vector3};
use preint::{CombinedImuFactor, FactorJacobians, ImuFactor, NavState};

// ------------------------------------------------------------------------------------------
// Conversions
// ------------------------------------------------------------------------------------------

fn vec3_to_preint(v: &factrs::linalg::Vector3) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

fn vec3_to_factrs(v: &Vector3<f64>) -> factrs::linalg::Vector3 {
    factrs::linalg::Vector3::new(v.x, v.y, v.z)
}

fn so3_to_preint(r: &SO3) -> PreintSO3 {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(r.w(), r.x(), r.y(), r.z()));
    PreintSO3::from_matrix_unchecked(*q.to_rotation_matrix().matrix())
}

fn so3_to_factrs(r: &PreintSO3) -> SO3 {
    let q = UnitQuaternion::from_rotation_matrix(
        &preint::nalgebra::Rotation3::from_matrix_unchecked(*r.matrix()),
    );
    SO3::from_xyzw(q.i, q.j, q.k, q.w)
}

/// The [`NavState`] of a factrs pose (attitude body → world, world position \[m\]) and
/// world-frame velocity \[m/s\].
pub fn nav_state(pose: &SE3, vel: &VectorVar3) -> NavState {
    NavState::new(
        so3_to_preint(pose.rot()),
        vec3_to_preint(&pose.xyz().into_owned()),
        vec3_to_preint(&vel.0),
    )
}

/// The factrs pose and velocity of a [`NavState`] (inverse of [`nav_state`]).
pub fn to_factrs(x: &NavState) -> (SE3, VectorVar3) {
    (
        SE3::from_rot_trans(so3_to_factrs(&x.r), vec3_to_factrs(&x.p)),
        VectorVar3::from(vec3_to_factrs(&x.v)),
    )
}

/// preint's [`preint::ImuBias`] of a factrs [`ImuBias`] (same order, `[b_g, b_a]`).
pub fn bias(b: &ImuBias) -> preint::ImuBias {
    preint::ImuBias::new(vec3_to_preint(b.gyro()), vec3_to_preint(b.accel()))
}

/// The factrs [`ImuBias`] of a [`preint::ImuBias`] (inverse of [`bias`]).
pub fn to_factrs_bias(b: &preint::ImuBias) -> ImuBias {
    ImuBias::new(
        factrs::residuals::Gyro(vec3_to_factrs(&b.gyro)),
        factrs::residuals::Accel(vec3_to_factrs(&b.acc)),
    )
}

/// The real parts of a pose, velocity and bias of any factrs scalar type (dual numbers too).
fn real_pose<T: Numeric>(x: &SE3<T>) -> SE3 {
    let re = |t: &T| -> f64 { t.to_subset_unchecked() };
    let q = &x.rot().xyzw;
    let t = x.xyz();
    SE3::from_rot_trans(
        SO3::from_xyzw(re(&q[0]), re(&q[1]), re(&q[2]), re(&q[3])),
        factrs::linalg::Vector3::new(re(&t[0]), re(&t[1]), re(&t[2])),
    )
}

fn real_vec<T: Numeric>(v: &VectorVar3<T>) -> VectorVar3 {
    let re = |t: &T| -> f64 { t.to_subset_unchecked() };
    VectorVar3::new(re(&v.0[0]), re(&v.0[1]), re(&v.0[2]))
}

fn real_bias<T: Numeric>(b: &ImuBias<T>) -> ImuBias {
    let re = |t: &T| -> f64 { t.to_subset_unchecked() };
    let (g, a) = (b.gyro(), b.accel());
    ImuBias::new(
        factrs::residuals::Gyro::new(re(&g[0]), re(&g[1]), re(&g[2])),
        factrs::residuals::Accel::new(re(&a[0]), re(&a[1]), re(&a[2])),
    )
}

/// `r + J δ` in the scalar type `T`, with `δ` the stacked tangent offsets `x ⊖ re(x)` of the
/// arguments from their real parts (zero real part; for dual numbers, their derivative parts):
/// the first-order expansion that carries `J` into automatic differentiation.
fn propagate<T: Numeric>(r: &VectorX, j: &MatrixX, offsets: &[VectorX<T>]) -> VectorX<T> {
    let d: Vec<T> = offsets.iter().flat_map(|o| o.iter().copied()).collect();
    debug_assert_eq!(d.len(), j.ncols());
    VectorX::from_fn(r.len(), |i, _| {
        d.iter()
            .enumerate()
            .fold(T::from_subset(&r[i]), |acc, (c, dc)| {
                acc + T::from_subset(&j[(i, c)]) * *dc
            })
    })
}

// ------------------------------------------------------------------------------------------
// Chart
// ------------------------------------------------------------------------------------------

/// Whether factrs perturbs its variables on the left (`x ⊕ ξ = Exp(ξ) x`, its `left`
/// feature) rather than on the right (`x Exp(ξ)`, its default), read once from
/// `SE3::oplus` at a generic pose.
pub fn left_perturbation() -> bool {
    static LEFT: OnceLock<bool> = OnceLock::new();
    *LEFT.get_or_init(|| {
        let xi = VectorX::from_vec(vec![0.3, -0.2, 0.5, 1.0, 2.0, -1.5]);
        let x = SE3::exp(xi.as_view());
        let d = VectorX::from_vec(vec![0.1, 0.2, -0.3, 0.4, -0.5, 0.6]);
        let got = x.oplus(d.as_view());
        let right = x.oplus_right(d.as_view());
        (got.xyz() - right.xyz()).norm() > 1e-9
    })
}

/// `∂r/∂[ω, ρ]` of factrs' SE3 perturbation from preint's `∂r/∂δφ`, `∂r/∂δp` at the attitude
/// `r` and position `p` (module docs).
fn pose_block<const R: usize>(
    j_phi: &SMatrix<f64, R, 3>,
    j_p: &SMatrix<f64, R, 3>,
    r: &PreintSO3,
    p: &Vector3<f64>,
) -> SMatrix<f64, R, 6> {
    let mut out = SMatrix::<f64, R, 6>::zeros();
    if left_perturbation() {
        let rt: Matrix3<f64> = r.matrix().transpose();
        out.fixed_columns_mut::<3>(0)
            .copy_from(&(j_phi * rt - j_p * rt * preint::lie::hat(p)));
        out.fixed_columns_mut::<3>(3).copy_from(&(j_p * rt));
    } else {
        out.fixed_columns_mut::<3>(0).copy_from(j_phi);
        out.fixed_columns_mut::<3>(3).copy_from(j_p);
    }
    out
}

/// The whitened Jacobian in factrs' key order `(pose_i, vel_i, pose_j, vel_j, bias_i[, bias_j])`
/// and factrs' tangents.
fn to_factrs_jacobian<const R: usize>(
    j: &FactorJacobians<R>,
    xi: &NavState,
    xj: &NavState,
    with_bias_j: bool,
) -> MatrixX {
    let cols = if with_bias_j { 30 } else { 24 };
    let mut m = MatrixX::zeros(R, cols);
    let mut put = |col: usize, block: &[f64], width: usize| {
        // `block` is column-major R × width.
        for c in 0..width {
            for r in 0..R {
                m[(r, col + c)] = block[c * R + r];
            }
        }
    };
    put(0, pose_block(&j.phi_i, &j.p_i, &xi.r, &xi.p).as_slice(), 6);
    put(6, j.v_i.as_slice(), 3);
    put(9, pose_block(&j.phi_j, &j.p_j, &xj.r, &xj.p).as_slice(), 6);
    put(15, j.v_j.as_slice(), 3);
    put(18, j.bias_i().as_slice(), 6);
    if with_bias_j {
        put(24, j.bias_j().as_slice(), 6);
    }
    m
}

fn get<V: factrs::variables::VariableDtype + 'static>(values: &Values, key: Key) -> &V {
    values.get_unchecked(key).unwrap_or_else(|| {
        panic!(
            "key {key:?} missing from the values, or not a {}",
            std::any::type_name::<V>()
        )
    })
}

fn nav_at(values: &Values, pose: Key, vel: Key) -> NavState {
    nav_state(get::<SE3>(values, pose), get::<VectorVar3>(values, vel))
}

/// The two keyframes `(pose_i, vel_i, pose_j, vel_j)` of `keys[0..4]`.
fn keyframes_at(values: &Values, keys: &[Key]) -> (NavState, NavState) {
    (
        nav_at(values, keys[0], keys[1]),
        nav_at(values, keys[2], keys[3]),
    )
}

/// The two keyframes at the real parts of generic arguments, and the arguments' tangent
/// offsets from them (the first four of [`propagate`]'s offsets).
fn real_keyframes<T: Numeric>(
    (pose_i, vel_i): (&SE3<T>, &VectorVar3<T>),
    (pose_j, vel_j): (&SE3<T>, &VectorVar3<T>),
) -> ((NavState, NavState), Vec<VectorX<T>>) {
    let (pi, vi, pj, vj) = (
        real_pose(pose_i),
        real_vec(vel_i),
        real_pose(pose_j),
        real_vec(vel_j),
    );
    let offsets = vec![
        pose_i.ominus(&pi.cast()),
        vel_i.ominus(&vi.cast()),
        pose_j.ominus(&pj.cast()),
        vel_j.ominus(&vj.cast()),
    ];
    ((nav_state(&pi, &vi), nav_state(&pj, &vj)), offsets)
}

// ------------------------------------------------------------------------------------------
// ImuResidual
// ------------------------------------------------------------------------------------------

/// [`preint::ImuFactor`] as a factrs residual over `(pose_i, vel_i, pose_j, vel_j, bias_i)`
/// (`SE3`, `VectorVar3`, `SE3`, `VectorVar3`, `ImuBias`): 9 rows, whitened, analytic
/// Jacobians (crate docs). Add it with `fac![ImuResidual::new(factor), (X(i), V(i), X(j),
/// V(j), B(i))]` and no noise model.
#[derive(Clone, Debug)]
pub struct ImuResidual {
    factor: ImuFactor,
}

impl ImuResidual {
    /// Wraps a factor (in either [`preint::ResidualMode`]).
    pub fn new(factor: ImuFactor) -> Self {
        Self { factor }
    }

    /// The wrapped factor.
    pub fn factor(&self) -> &ImuFactor {
        &self.factor
    }

    fn whitened(
        &self,
        xi: &NavState,
        xj: &NavState,
        b: &preint::ImuBias,
    ) -> (VectorX, FactorJacobians<9>) {
        let (r, j) = self.factor.evaluate_whitened(xi, xj, b);
        (VectorX::from_column_slice(r.as_slice()), j)
    }
}

impl Residual for ImuResidual {
    fn dim_in(&self) -> usize {
        24
    }

    fn dim_out(&self) -> usize {
        9
    }

    fn residual(&self, values: &Values, keys: &[Key]) -> VectorX {
        let (xi, xj) = keyframes_at(values, keys);
        let b = bias(get::<ImuBias>(values, keys[4]));
        self.whitened(&xi, &xj, &b).0
    }

    fn residual_jacobian(&self, values: &Values, keys: &[Key]) -> DiffResult<VectorX, MatrixX> {
        let (xi, xj) = keyframes_at(values, keys);
        let b = bias(get::<ImuBias>(values, keys[4]));
        let (value, j) = self.whitened(&xi, &xj, &b);
        DiffResult {
            value,
            diff: to_factrs_jacobian(&j, &xi, &xj, false),
        }
    }
}

impl Residual5 for ImuResidual {
    type V1 = SE3;
    type V2 = VectorVar3;
    type V3 = SE3;
    type V4 = VectorVar3;
    type V5 = ImuBias;
    type DimIn = Const<24>;
    type DimOut = Const<9>;
    type Differ = ForwardProp<Const<24>>;

    fn residual5<T: Numeric>(
        &self,
        pose_i: SE3<T>,
        vel_i: VectorVar3<T>,
        pose_j: SE3<T>,
        vel_j: VectorVar3<T>,
        bias_i: ImuBias<T>,
    ) -> VectorX<T> {
        let ((xi, xj), mut offsets) = real_keyframes((&pose_i, &vel_i), (&pose_j, &vel_j));
        let bi = real_bias(&bias_i);
        offsets.push(bias_i.ominus(&bi.cast()));
        let (r, j) = self.whitened(&xi, &xj, &bias(&bi));
        propagate(&r, &to_factrs_jacobian(&j, &xi, &xj, false), &offsets)
    }
}

// ------------------------------------------------------------------------------------------
// CombinedImuResidual
// ------------------------------------------------------------------------------------------

/// [`preint::CombinedImuFactor`] as a factrs residual over `(pose_i, vel_i, pose_j, vel_j,
/// bias_i, bias_j)` (`SE3`, `VectorVar3`, `SE3`, `VectorVar3`, `ImuBias`, `ImuBias`): 15 rows
/// (the bias random walk included, so no separate bias factor), whitened, analytic Jacobians.
#[derive(Clone, Debug)]
pub struct CombinedImuResidual {
    factor: CombinedImuFactor,
}

impl CombinedImuResidual {
    /// Wraps a factor (in either [`preint::ResidualMode`]).
    pub fn new(factor: CombinedImuFactor) -> Self {
        Self { factor }
    }

    /// The wrapped factor.
    pub fn factor(&self) -> &CombinedImuFactor {
        &self.factor
    }

    fn whitened(
        &self,
        xi: &NavState,
        xj: &NavState,
        bi: &preint::ImuBias,
        bj: &preint::ImuBias,
    ) -> (VectorX, FactorJacobians<15>) {
        let (r, j) = self.factor.evaluate_whitened(xi, xj, bi, bj);
        (VectorX::from_column_slice(r.as_slice()), j)
    }
}

impl Residual for CombinedImuResidual {
    fn dim_in(&self) -> usize {
        30
    }

    fn dim_out(&self) -> usize {
        15
    }

    fn residual(&self, values: &Values, keys: &[Key]) -> VectorX {
        let (xi, xj) = keyframes_at(values, keys);
        let bi = bias(get::<ImuBias>(values, keys[4]));
        let bj = bias(get::<ImuBias>(values, keys[5]));
        self.whitened(&xi, &xj, &bi, &bj).0
    }

    fn residual_jacobian(&self, values: &Values, keys: &[Key]) -> DiffResult<VectorX, MatrixX> {
        let (xi, xj) = keyframes_at(values, keys);
        let bi = bias(get::<ImuBias>(values, keys[4]));
        let bj = bias(get::<ImuBias>(values, keys[5]));
        let (value, j) = self.whitened(&xi, &xj, &bi, &bj);
        DiffResult {
            value,
            diff: to_factrs_jacobian(&j, &xi, &xj, true),
        }
    }
}

impl Residual6 for CombinedImuResidual {
    type V1 = SE3;
    type V2 = VectorVar3;
    type V3 = SE3;
    type V4 = VectorVar3;
    type V5 = ImuBias;
    type V6 = ImuBias;
    type DimIn = Const<30>;
    type DimOut = Const<15>;
    type Differ = ForwardProp<Const<30>>;

    fn residual6<T: Numeric>(
        &self,
        pose_i: SE3<T>,
        vel_i: VectorVar3<T>,
        pose_j: SE3<T>,
        vel_j: VectorVar3<T>,
        bias_i: ImuBias<T>,
        bias_j: ImuBias<T>,
    ) -> VectorX<T> {
        let ((xi, xj), mut offsets) = real_keyframes((&pose_i, &vel_i), (&pose_j, &vel_j));
        let (bi, bj) = (real_bias(&bias_i), real_bias(&bias_j));
        offsets.push(bias_i.ominus(&bi.cast()));
        offsets.push(bias_j.ominus(&bj.cast()));
        let (r, j) = self.whitened(&xi, &xj, &bias(&bi), &bias(&bj));
        propagate(&r, &to_factrs_jacobian(&j, &xi, &xj, true), &offsets)
    }
}
