//! IMU intrinsics: scale, misalignment, axis rotation and g-sensitivity of the gyroscope and
//! accelerometer, applied to raw samples before integration.
//!
//! # Model (OpenVINS, "IMU Intrinsic Calibration"; Kalibr `scale-misalignment`)
//!
//! Frames: `I` the IMU (body) frame the deltas are expressed in, `w` the gyroscope's axes, `a`
//! the accelerometer's. The sensors read (OpenVINS' documentation "IMU Intrinsic
//! Calibration" and `ov_msckf/src/state/Propagator.cpp`; Yang, Geneva, Zuo, Eckenhoff, Liu,
//! Huang, *Online IMU Intrinsic Calibration: Is It Necessary?*, RSS 2020):
//!
//! ```text
//! ω_m = T_w R_IMUtoGYRO ω_I + T_g a_I + b_g + n_g
//! a_m = T_a R_IMUtoACC a_I + b_a + n_a
//! ```
//!
//! with `ω_I` [rad/s] and `a_I` [m/s², specific force] the true rate and specific force in
//! frame I, `T_w`, `T_a` (dimensionless, 3×3) the scale-and-misalignment matrices mapping the
//! sensor-axes vector to the reading, `R_IMUtoGYRO` (rotates frame-I vectors into gyro axes),
//! `R_IMUtoACC` (frame I into accelerometer axes) and `T_g` [(rad/s)/(m/s²)] the gyroscope's
//! g-sensitivity (frame-I specific force to a gyro reading). Inverted, with `D_w = T_w⁻¹`,
//! `D_a = T_a⁻¹`:
//!
//! ```text
//! a_I = R_ACCtoIMU D_a (a_m − b_a)
//! ω_I = R_GYROtoIMU D_w (ω_m − T_g a_I − b_g)
//! ```
//!
//! exactly OpenVINS' `R_ACCtoIMU * Da * (am - b_a)` and `R_GYROtoIMU * Dw * (wm - b_g - Tg * a)`.
//! OpenVINS' `kalibr` model takes `T_w`, `T_a` lower triangular and estimates `R_IMUtoGYRO`
//! (`R_IMUtoACC = I`); its `rpng` model takes them upper triangular and estimates `R_IMUtoACC`
//! (`R_IMUtoGYRO = I`). Both rotations are applied whatever the model.
//!
//! Kalibr's `scale-misalignment` model (`IccSensors.py`, `IccScaledMisalignedImu`) is
//! `ω_m = M_w C_gyro_i ω_I + A (C_gyro_i a_I) + b_g`, `a_m = M_a a_I + b_a`, `M` lower
//! triangular: `T_w = M_w` (gyroscopes `M`), `R_IMUtoGYRO = C_gyro_i`, `T_a = M_a`
//! (accelerometers `M`), `R_IMUtoACC = I` and `T_g = A C_gyro_i` (Kalibr's `A` acts on the
//! specific force in gyro axes; OpenVINS' `T_g` on frame I: they are equal when
//! `C_gyro_i = I`, which OpenVINS' configuration comments assume).
//!
//! # Biases and noise
//!
//! The preintegrator subtracts its bias estimate from the corrected samples: its biases are in
//! frame I, `ω = ω' − b_g^I`, `a = a' − b_a^I` with
//!
//! ```text
//! a' = R_ACCtoIMU D_a a_m,   ω' = R_GYROtoIMU D_w (ω_m − T_g a')
//! ```
//!
//! This is OpenVINS' model with its biases mapped linearly: `b_a^I = R_ACCtoIMU D_a b_a`,
//! `b_g^I = R_GYROtoIMU D_w (b_g − T_g b_a^I)` ([`ImuIntrinsics::bias_to_imu`], inverse
//! [`ImuIntrinsics::bias_from_imu`]). Every bias Jacobian, bias correction and re-integration
//! of the crate then holds unchanged. The noise densities of
//! [`PreintParams`](crate::PreintParams) are those of the corrected samples (frame I).
//!
//! # Parameters of the Jacobians
//!
//! [`ImuIntrinsics::PARAMS`] = 24 columns, in this order (OpenVINS' state order of `vec_dw`,
//! `vec_da`, `vec_tg`): the 6 free entries of `T_w`, the 6 of `T_a` (lower triangular for
//! `kalibr`, column by column: (0,0), (1,0), (2,0), (1,1), (2,1), (2,2); upper for `rpng`:
//! (0,0), (0,1), (1,1), (0,2), (1,2), (2,2)), the model's rotation perturbed on the right
//! (`R_IMUtoGYRO ← R_IMUtoGYRO Exp(δθ)` for `kalibr`, `R_IMUtoACC ← R_IMUtoACC Exp(δθ)` for
//! `rpng`), and the 9 entries of `T_g` column by column. Derivatives are taken with the
//! frame-I biases held fixed. Of a corrected sample (`u = (ω', a')`):
//!
//! ```text
//! ∂ω'/∂T_w[r,c] = −K_w e_r (R_IMUtoGYRO ω')_c          K_w = R_GYROtoIMU D_w
//! ∂a'/∂T_a[r,c] = −K_a e_r (R_IMUtoACC a')_c,  ∂ω' = −K_w T_g ∂a'   K_a = R_ACCtoIMU D_a
//! ∂ω'/∂T_g[r,c] = −K_w e_r a'_c
//! kalibr: ∂ω'/∂δθ = [ω']×          rpng: ∂a'/∂δθ = [a']×,  ∂ω'/∂δθ = −K_w T_g [a']×
//! ```

use crate::error::PreintError;
use crate::fast::correction::Columns;
use crate::sample::{ImuBias, ImuSample};
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Which triangle of `T_w`, `T_a` is free and which rotation is estimated (OpenVINS'
/// `imu_model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum IntrinsicsModel {
    /// `T_w`, `T_a` lower triangular, `R_IMUtoGYRO` estimated (OpenVINS `kalibr`, also
    /// `calibrated`; Kalibr's `scale-misalignment`).
    #[default]
    Kalibr,
    /// `T_w`, `T_a` upper triangular, `R_IMUtoACC` estimated (OpenVINS `rpng`).
    Rpng,
}

impl IntrinsicsModel {
    /// The name in OpenVINS' `kalibr_imu_chain.yaml`: `kalibr` or `rpng`.
    pub fn name(self) -> &'static str {
        match self {
            IntrinsicsModel::Kalibr => "kalibr",
            IntrinsicsModel::Rpng => "rpng",
        }
    }

    /// The model called `name` (`calibrated` is OpenVINS' alias of `kalibr`).
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "kalibr" | "calibrated" => Some(IntrinsicsModel::Kalibr),
            "rpng" => Some(IntrinsicsModel::Rpng),
            _ => None,
        }
    }

    /// The free `(row, column)` entries of `T_w` and `T_a`, in parameter order.
    pub fn free_entries(self) -> [(usize, usize); 6] {
        match self {
            IntrinsicsModel::Kalibr => [(0, 0), (1, 0), (2, 0), (1, 1), (2, 1), (2, 2)],
            IntrinsicsModel::Rpng => [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)],
        }
    }
}

/// The intrinsics of one IMU (module docs: model, frames, units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuIntrinsics {
    /// Which entries are parameters (and which rotation).
    pub model: IntrinsicsModel,
    /// `T_w`: gyro-axes rate to reading (scale and misalignment), dimensionless.
    pub t_w: Matrix3<f64>,
    /// `T_a`: accelerometer-axes specific force to reading, dimensionless.
    pub t_a: Matrix3<f64>,
    /// `R_IMUtoGYRO`: rotates frame-I vectors into the gyroscope's axes.
    pub r_imu_to_gyro: Matrix3<f64>,
    /// `R_IMUtoACC`: rotates frame-I vectors into the accelerometer's axes.
    pub r_imu_to_acc: Matrix3<f64>,
    /// `T_g` [(rad/s)/(m/s²)]: frame-I specific force to gyro reading (g-sensitivity).
    pub t_g: Matrix3<f64>,
}

impl Default for ImuIntrinsics {
    fn default() -> Self {
        Self::identity(IntrinsicsModel::Kalibr)
    }
}

/// Jacobians of a window's deltas with respect to the intrinsics' parameters
/// ([`ImuIntrinsics::PARAMS`] columns, module docs), rows `[δφ, δv, δp]` in the chart of
/// [`PreintegratedImu`](crate::PreintegratedImu), at the frame-I bias estimate of the measurement.
pub type IntrinsicJacobian = SMatrix<f64, 9, { ImuIntrinsics::PARAMS }>;

impl ImuIntrinsics {
    /// Number of parameters: 6 (`T_w`) + 6 (`T_a`) + 3 (rotation) + 9 (`T_g`).
    pub const PARAMS: usize = 24;

    /// Perfect sensors: `T_w = T_a = I`, both rotations `I`, `T_g = 0`.
    pub fn identity(model: IntrinsicsModel) -> Self {
        let i = Matrix3::identity();
        Self {
            model,
            t_w: i,
            t_a: i,
            r_imu_to_gyro: i,
            r_imu_to_acc: i,
            t_g: Matrix3::zeros(),
        }
    }

    /// An example of a MEMS IMU's intrinsics, for tests, benchmarks and examples: ±1 % scales,
    /// 2 mrad misalignments in the model's triangle of `T_w` and `T_a`, both sensor axes
    /// rotated by about 3 mrad, and g-sensitivity entries of 0.5–3e-3 (rad/s)/(m/s²).
    pub fn example(model: IntrinsicsModel) -> Self {
        let (t_w, t_a) = match model {
            IntrinsicsModel::Kalibr => (
                Matrix3::new(1.01, 0.0, 0.0, 0.002, 0.99, 0.0, -0.002, 0.002, 1.005),
                Matrix3::new(0.99, 0.0, 0.0, -0.002, 1.01, 0.0, 0.002, 0.002, 1.0),
            ),
            IntrinsicsModel::Rpng => (
                Matrix3::new(1.01, 0.002, -0.002, 0.0, 0.99, 0.002, 0.0, 0.0, 1.005),
                Matrix3::new(0.99, -0.002, 0.002, 0.0, 1.01, 0.002, 0.0, 0.0, 1.0),
            ),
        };
        let rot = |x: f64, y: f64, z: f64| *preint_lie::SO3::exp(&Vector3::new(x, y, z)).matrix();
        Self {
            model,
            t_w,
            t_a,
            r_imu_to_gyro: rot(0.002, -0.002, 0.001),
            r_imu_to_acc: rot(-0.001, 0.002, 0.002),
            t_g: Matrix3::from_fn(|i, j| 1e-3 * (1.0 + i as f64 - 0.5 * j as f64)),
        }
    }

    /// True when applying the intrinsics changes nothing (exactly the identity).
    pub fn is_identity(&self) -> bool {
        *self == Self::identity(self.model)
    }

    /// Checks finite entries, invertible `T_w`, `T_a` and orthonormal rotations
    /// (`‖RᵀR − I‖_max ≤ 1e-6`, `det R > 0`).
    pub fn validate(&self) -> Result<(), PreintError> {
        let bad = |reason| {
            Err(PreintError::InvalidParameter {
                name: "intrinsics",
                reason,
            })
        };
        let mats = [
            self.t_w,
            self.t_a,
            self.r_imu_to_gyro,
            self.r_imu_to_acc,
            self.t_g,
        ];
        if !mats.iter().all(|m| m.iter().all(|x| x.is_finite())) {
            return bad("non-finite entry");
        }
        for t in [&self.t_w, &self.t_a] {
            if t.determinant().abs() < 1e-6 || t.try_inverse().is_none() {
                return bad("T_w or T_a not invertible");
            }
        }
        for r in [&self.r_imu_to_gyro, &self.r_imu_to_acc] {
            if (r.transpose() * r - Matrix3::identity()).amax() > 1e-6 || r.determinant() <= 0.0 {
                return bad("R_IMUtoGYRO or R_IMUtoACC not a rotation");
            }
        }
        Ok(())
    }

    /// The linear map of a raw sample to the corrected one (module docs), fixed once. A
    /// singular `T_w` or `T_a` ([`ImuIntrinsics::validate`] refuses them) gives NaN entries,
    /// so that nothing computed from it passes for a result.
    pub fn correction(&self) -> Correction {
        let inv = |m: &Matrix3<f64>| m.try_inverse().unwrap_or_else(|| Matrix3::repeat(f64::NAN));
        let (d_w, d_a) = (inv(&self.t_w), inv(&self.t_a));
        let k_w = self.r_imu_to_gyro.transpose() * d_w;
        let k_a = self.r_imu_to_acc.transpose() * d_a;
        let k_wa = -(k_w * self.t_g * k_a);
        Correction {
            k_w,
            k_wa,
            k_a,
            columns: Columns::of(&k_w, &k_wa, &k_a),
        }
    }

    /// Sample `s` corrected (no bias removed): `(ω', a')` of the module docs.
    pub fn apply(&self, s: &ImuSample) -> ImuSample {
        self.correction().apply(s)
    }

    /// OpenVINS' biases (`b_g` in gyro readings [rad/s], `b_a` in accelerometer readings
    /// [m/s²]) as the frame-I biases the preintegrator subtracts (module docs).
    pub fn bias_to_imu(&self, raw: &ImuBias) -> ImuBias {
        let c = self.correction();
        ImuBias::new(c.k_w * raw.gyro + c.k_wa * raw.acc, c.k_a * raw.acc)
    }

    /// The inverse of [`ImuIntrinsics::bias_to_imu`].
    pub fn bias_from_imu(&self, imu: &ImuBias) -> ImuBias {
        let acc = self.t_a * self.r_imu_to_acc * imu.acc;
        let c = self.correction();
        let gyro = self.t_w * self.r_imu_to_gyro * (imu.gyro - c.k_wa * acc);
        ImuBias::new(gyro, acc)
    }

    /// The parameters as a vector (module docs' order; the rotation entries are 0: it is
    /// perturbed about its current value).
    pub fn params(&self) -> SMatrix<f64, { Self::PARAMS }, 1> {
        let mut p = SMatrix::<f64, { Self::PARAMS }, 1>::zeros();
        for (i, &(r, c)) in self.model.free_entries().iter().enumerate() {
            p[i] = self.t_w[(r, c)];
            p[6 + i] = self.t_a[(r, c)];
        }
        for (i, x) in self.t_g.iter().enumerate() {
            p[15 + i] = *x;
        }
        p
    }

    /// The intrinsics moved by `delta` in parameter space (module docs): entries added, the
    /// model's rotation `R ← R Exp(δθ)`.
    pub fn perturbed(&self, delta: &SMatrix<f64, { Self::PARAMS }, 1>) -> Self {
        let mut out = *self;
        for (i, &(r, c)) in self.model.free_entries().iter().enumerate() {
            out.t_w[(r, c)] += delta[i];
            out.t_a[(r, c)] += delta[6 + i];
        }
        let rot = *preint_lie::SO3::exp(&Vector3::new(delta[12], delta[13], delta[14])).matrix();
        match self.model {
            IntrinsicsModel::Kalibr => out.r_imu_to_gyro = self.r_imu_to_gyro * rot,
            IntrinsicsModel::Rpng => out.r_imu_to_acc = self.r_imu_to_acc * rot,
        }
        for i in 0..9 {
            out.t_g[i] += delta[15 + i]; // column-major: entry (i % 3, i / 3)
        }
        out
    }

    /// `∂(ω', a')/∂θ` (6 × [`ImuIntrinsics::PARAMS`], rows ω then a) of a corrected sample
    /// `(w, a)` = `(ω', a')` (module docs).
    pub fn sample_jacobian(&self, w: &Vector3<f64>, a: &Vector3<f64>) -> SMatrix<f64, 6, 24> {
        let c = self.correction();
        let mut j = SMatrix::<f64, 6, 24>::zeros();
        let kwtg = c.k_w * self.t_g;
        let wg = self.r_imu_to_gyro * w;
        let aa = self.r_imu_to_acc * a;
        for (i, &(r, col)) in self.model.free_entries().iter().enumerate() {
            let dw = -c.k_w.column(r) * wg[col];
            j.fixed_view_mut::<3, 1>(0, i).copy_from(&dw);
            let da = -c.k_a.column(r) * aa[col];
            j.fixed_view_mut::<3, 1>(3, 6 + i).copy_from(&da);
            j.fixed_view_mut::<3, 1>(0, 6 + i)
                .copy_from(&(-(kwtg * da)));
        }
        match self.model {
            IntrinsicsModel::Kalibr => {
                j.fixed_view_mut::<3, 3>(0, 12)
                    .copy_from(&preint_lie::hat(w));
            }
            IntrinsicsModel::Rpng => {
                let s = preint_lie::hat(a);
                j.fixed_view_mut::<3, 3>(3, 12).copy_from(&s);
                j.fixed_view_mut::<3, 3>(0, 12).copy_from(&(-(kwtg * s)));
            }
        }
        for i in 0..9 {
            let (r, col) = (i % 3, i / 3);
            j.fixed_view_mut::<3, 1>(0, 15 + i)
                .copy_from(&(-c.k_w.column(r) * a[col]));
        }
        j
    }
}

/// The intrinsics as the linear map a raw sample goes through:
/// `a' = K_a a_m`, `ω' = K_w ω_m + K_wa a_m` with `K_w = R_GYROtoIMU D_w`,
/// `K_a = R_ACCtoIMU D_a`, `K_wa = −K_w T_g K_a` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correction {
    /// `K_w = R_GYROtoIMU T_w⁻¹`.
    pub k_w: Matrix3<f64>,
    /// `K_wa = −K_w T_g K_a` [(rad/s)/(m/s²)].
    pub k_wa: Matrix3<f64>,
    /// `K_a = R_ACCtoIMU T_a⁻¹`.
    pub k_a: Matrix3<f64>,
    /// `M = [[K_w, K_wa], [0, K_a]]` as the correction loads it.
    pub(crate) columns: Columns,
}

impl Correction {
    /// Sample `s` corrected, its timestamp kept: each output entry is the fused multiply-add
    /// chain over the inputs in the order `ω_x, ω_y, ω_z, a_x, a_y, a_z`,
    /// `ω'_r = fma(K_wa[r,2], a_z, fma(K_wa[r,1], a_y, fma(K_wa[r,0], a_x, fma(K_w[r,2], ω_z,
    /// fma(K_w[r,1], ω_y, K_w[r,0] ω_x)))))` and `a'_r = fma(K_a[r,2], a_z, fma(K_a[r,1], a_y,
    /// K_a[r,0] a_x))`, one rounding per step. With AVX2 and FMA it runs as four- and two-lane
    /// vector instructions, with the same roundings.
    #[inline(always)]
    pub fn apply(&self, s: &ImuSample) -> ImuSample {
        self.columns.apply(s)
    }

    /// [`Correction::apply`] without vector instructions: the arithmetic as written there.
    pub fn apply_plain(&self, s: &ImuSample) -> ImuSample {
        self.columns.apply_plain(s)
    }

    /// [`Correction::apply`] to every sample of `src` into `dst` (the shorter length).
    pub fn apply_all(&self, src: &[ImuSample], dst: &mut [ImuSample]) {
        self.columns.apply_all(src, dst)
    }
}

/// Intrinsics as [`PreintParams::intrinsics`](crate::PreintParams::intrinsics) holds them:
/// the model applied to every raw sample, and whether the Jacobians of the deltas with respect
/// to its parameters are accumulated ([`crate::Preintegrator::finish_with_intrinsic_jacobian`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AppliedIntrinsics {
    /// The intrinsics.
    pub model: ImuIntrinsics,
    /// Accumulate `∂(ΔR, Δv, Δp)/∂θ` (about 250 multiply-adds per sample); default `false`.
    pub jacobians: bool,
}

impl AppliedIntrinsics {
    /// `model` applied, no Jacobians.
    pub fn new(model: ImuIntrinsics) -> Self {
        Self {
            model,
            jacobians: false,
        }
    }

    /// The same with the Jacobians accumulated.
    pub fn with_jacobians(mut self) -> Self {
        self.jacobians = true;
        self
    }
}
