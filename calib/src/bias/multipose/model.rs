//! The multi-position sensor model (Tedaldi, Pretto, Menegatti, ICRA 2014; imu_tk) and the
//! layout of its parameter vector.
//!
//! ```text
//! gyro     ω_m = S_g ω_b + b_g(t) + n_g         S_g = diag(1 + s_g)·(I + M_g)
//! accel    a_m = S_a R_kᵀ(−g) + b_a(t) + n_a    S_a = diag(1 + s_a)·(I + N_a)   (at rest)
//! ```
//!
//! `N_a` is strictly lower triangular, `m_a = (N₁₀, N₂₀, N₂₁)`: the body frame is the
//! orthogonalised accelerometer frame, which leaves three misalignment angles. `M_g` is a full
//! off-diagonal matrix, `m_g = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)`: the six small angles of the gyro
//! axes in that frame. Scale errors `s` are dimensionless, misalignments in radians.
//!
//! Parameter vector of a [`MultiPoseModel`]: `[b_g, b_a, s_a?, m_a?, s_g?, m_g?]` (rad/s, m/s²,
//! then the terms the model has, in this order); the attitudes of the still intervals are a
//! separate part of the state.

use nalgebra::{DVector, Matrix3, SVector, Vector3};

/// Candidate calibration models, from the simplest (module docs for the sensor model).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MultiPoseModel {
    /// `b_g`, `b_a` and the attitudes (6 parameters besides the attitudes).
    BiasOnly,
    /// Plus accelerometer scale factors `s_a` (9).
    AccScale,
    /// Plus accelerometer and gyro scale factors `s_a`, `s_g` (12).
    Scale,
    /// Bias plus accelerometer scale factors and misalignment `s_a`, `m_a` (12).
    AccMisalignment,
    /// `AccMisalignment` plus gyro scale factors `s_g` (15).
    AccMisalignmentGyroScale,
    /// The full Tedaldi et al. / imu_tk model: `s_a`, `m_a`, `s_g`, `m_g` (21).
    ScaleMisalignment,
}

impl MultiPoseModel {
    /// All candidates, from the simplest.
    pub const ALL: [MultiPoseModel; 6] = [
        MultiPoseModel::BiasOnly,
        MultiPoseModel::AccScale,
        MultiPoseModel::Scale,
        MultiPoseModel::AccMisalignment,
        MultiPoseModel::AccMisalignmentGyroScale,
        MultiPoseModel::ScaleMisalignment,
    ];
    fn acc_scale(self) -> bool {
        !matches!(self, MultiPoseModel::BiasOnly)
    }
    fn acc_mis(self) -> bool {
        matches!(
            self,
            MultiPoseModel::AccMisalignment
                | MultiPoseModel::AccMisalignmentGyroScale
                | MultiPoseModel::ScaleMisalignment
        )
    }
    fn gyro_scale(self) -> bool {
        matches!(
            self,
            MultiPoseModel::Scale
                | MultiPoseModel::AccMisalignmentGyroScale
                | MultiPoseModel::ScaleMisalignment
        )
    }
    fn gyro_mis(self) -> bool {
        matches!(self, MultiPoseModel::ScaleMisalignment)
    }
    /// Offsets of `(s_a, m_a, s_g, m_g)` in the parameter vector (`None` when absent).
    pub(crate) fn layout(self) -> Layout {
        let mut o = 6;
        let mut take = |on: bool, n: usize| {
            on.then(|| {
                let at = o;
                o += n;
                at
            })
        };
        Layout {
            acc_scale: take(self.acc_scale(), 3),
            acc_mis: take(self.acc_mis(), 3),
            gyro_scale: take(self.gyro_scale(), 3),
            gyro_mis: take(self.gyro_mis(), 6),
        }
    }
    /// Number of parameters besides the attitudes.
    pub fn param_count(self) -> usize {
        6 + 3 * (self.acc_scale() as usize)
            + 3 * (self.acc_mis() as usize)
            + 3 * (self.gyro_scale() as usize)
            + 6 * (self.gyro_mis() as usize)
    }
    /// Number of gyro model parameters (`s_g`, `m_g`) that enter the links.
    pub(crate) fn gyro_params(self) -> usize {
        3 * (self.gyro_scale() as usize) + 6 * (self.gyro_mis() as usize)
    }
    /// Short name (`"bias-only"`, `"acc-scale"`, `"scale"`, `"acc-misalignment"`,
    /// `"acc-misalignment+gyro-scale"`, `"scale-misalignment"`).
    pub fn name(self) -> &'static str {
        match self {
            MultiPoseModel::BiasOnly => "bias-only",
            MultiPoseModel::AccScale => "acc-scale",
            MultiPoseModel::Scale => "scale",
            MultiPoseModel::AccMisalignment => "acc-misalignment",
            MultiPoseModel::AccMisalignmentGyroScale => "acc-misalignment+gyro-scale",
            MultiPoseModel::ScaleMisalignment => "scale-misalignment",
        }
    }
    /// The parameter vector `p` of this model, unpacked; absent terms are zero.
    pub(crate) fn unpack(self, p: &DVector<f64>) -> Params {
        let l = self.layout();
        let v3 = |o: Option<usize>| o.map_or(Vector3::zeros(), |o| p.fixed_rows::<3>(o).into());
        Params {
            b_g: v3(Some(0)),
            b_a: v3(Some(3)),
            s_a: v3(l.acc_scale),
            m_a: v3(l.acc_mis),
            s_g: v3(l.gyro_scale),
            m_g: l
                .gyro_mis
                .map_or(SVector::zeros(), |o| p.fixed_rows::<6>(o).into()),
        }
    }
}

/// Offsets of the optional terms in the parameter vector (`None` when absent).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    pub(crate) acc_scale: Option<usize>,
    pub(crate) acc_mis: Option<usize>,
    pub(crate) gyro_scale: Option<usize>,
    pub(crate) gyro_mis: Option<usize>,
}

impl Layout {
    /// Offset of the first gyro term (`s_g`, else `m_g`): the gyro terms are contiguous.
    pub(crate) fn gyro(&self) -> Option<usize> {
        self.gyro_scale.or(self.gyro_mis)
    }
}

/// A parameter vector, unpacked (module docs for the units).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    pub(crate) b_g: Vector3<f64>,
    pub(crate) b_a: Vector3<f64>,
    pub(crate) s_a: Vector3<f64>,
    pub(crate) m_a: Vector3<f64>,
    pub(crate) s_g: Vector3<f64>,
    pub(crate) m_g: SVector<f64, 6>,
}

/// `I + N` with `N` strictly lower triangular, `N₁₀ = m₀, N₂₀ = m₁, N₂₁ = m₂`.
pub(crate) fn acc_misalignment_matrix(m: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, m[0], 1.0, 0.0, m[1], m[2], 1.0)
}

/// `diag(1 + s)·(I + N)` with `N` strictly lower triangular, `N₁₀ = m₀, N₂₀ = m₁, N₂₁ = m₂`:
/// the accelerometer scale/misalignment matrix `S_a` (module docs).
pub fn acc_scale_matrix(s: &Vector3<f64>, m: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::from_diagonal(&s.add_scalar(1.0)) * acc_misalignment_matrix(m)
}

/// Index pairs (row, column) of the gyro misalignments `m_g` (module docs).
const GYRO_MIS: [(usize, usize); 6] = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];

/// `I + M` with the off-diagonal `M` in the order `m = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)`.
fn gyro_misalignment_matrix(m: &SVector<f64, 6>) -> Matrix3<f64> {
    let mut im = Matrix3::identity();
    for (k, &(r, c)) in GYRO_MIS.iter().enumerate() {
        im[(r, c)] = m[k];
    }
    im
}

/// `diag(1 + s)·(I + M)` with the off-diagonal `M` in the order
/// `m = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)`: the gyro
/// scale/misalignment matrix `S_g` (module docs).
pub fn gyro_scale_matrix(s: &Vector3<f64>, m: &SVector<f64, 6>) -> Matrix3<f64> {
    Matrix3::from_diagonal(&s.add_scalar(1.0)) * gyro_misalignment_matrix(m)
}

/// `S_g` and its derivatives `∂S_g/∂θ` along the gyro parameters θ of a model.
pub(crate) struct GyroModel {
    /// `S_g`.
    pub(crate) s: Matrix3<f64>,
    /// `∂S_g/∂θ_k`, `s_g` first, then `m_g` (present terms only).
    pub(crate) dirs: Vec<Matrix3<f64>>,
}

impl GyroModel {
    /// `S_g` at `(s, m)` and `∂S_g/∂θ` for the terms present (`scale`: `s_g`, `mis`: `m_g`):
    /// `∂S_g/∂s_k = e_k e_kᵀ(I + M)` (row k of `I + M`), `∂S_g/∂M_rc = (1 + s_r) e_r e_cᵀ`.
    pub(crate) fn new(s: &Vector3<f64>, m: &SVector<f64, 6>, scale: bool, mis: bool) -> Self {
        let im = gyro_misalignment_matrix(m);
        let mut dirs = Vec::new();
        if scale {
            for k in 0..3 {
                let mut e = Matrix3::zeros();
                e.set_row(k, &im.row(k));
                dirs.push(e);
            }
        }
        if mis {
            for &(r, c) in &GYRO_MIS {
                let mut e = Matrix3::zeros();
                e[(r, c)] = 1.0 + s[r];
                dirs.push(e);
            }
        }
        GyroModel {
            s: Matrix3::from_diagonal(&s.add_scalar(1.0)) * im,
            dirs,
        }
    }

    /// The gyro model of `model` at the parameters `p`.
    pub(crate) fn of(model: MultiPoseModel, p: &Params) -> Self {
        Self::new(&p.s_g, &p.m_g, model.gyro_scale(), model.gyro_mis())
    }
}
