//! Rotation preintegration of a link window with the gyro model, and its right Jacobians.
//!
//! Between two still intervals the attitudes are linked by `ΔR_k(b_g, S_g)`, the midpoint-rule
//! rotation preintegration (the `preint` midpoint scheme, `ΔR ← ΔR·Exp(φ_i)`,
//! `φ_i = ½(u_i + u_i+1)Δt_i`) of the corrected rates `u = S_g⁻¹(ω_m − b_g)` over the link
//! window, from the last sample of interval k to the first of interval k+1. It is re-integrated
//! exactly at every evaluation together with its right Jacobians (the bias-Jacobian recursion of
//! Forster et al., T-RO 2017, extended to the gyro model parameters θ):
//!
//! ```text
//! J_b ← Exp(φ_i)ᵀ J_b − Jr(φ_i) S_g⁻¹ Δt_i                        J_b = ∂ΔR/∂b_g   [s]
//! J_θ ← Exp(φ_i)ᵀ J_θ + Jr(φ_i) ∂φ_i/∂θ,  ∂φ_i/∂θ = −S_g⁻¹ (∂S_g/∂θ) φ_i      J_θ = ∂ΔR/∂θ
//! ```
//!
//! For `S_g = I`, `J_b` is `preint`'s `d_r_d_bg`.

use nalgebra::{DMatrix, Matrix3, Vector3};
use preint::{ImuSample, dt_seconds};
use preint_lie::SO3;

/// Midpoint rotation preintegration of `u_i = S_g⁻¹(ω_i − b_g)` over `samples` with its right
/// Jacobians (module docs): returns `(ΔR, ∂ΔR/∂b_g \[s\], ∂ΔR/∂θ)` where column k of the 3×K
/// matrix is the derivative along `∂S_g/∂θ_k = dirs[k]` \[rad per unit of θ_k\]. `S_g` must be
/// invertible (else the result is non-finite); `samples` must have increasing timestamps (not
/// checked here).
pub fn rotation_preintegration_general(
    samples: &[ImuSample],
    b_g: &Vector3<f64>,
    s_g: &Matrix3<f64>,
    dirs: &[Matrix3<f64>],
) -> (SO3, Matrix3<f64>, DMatrix<f64>) {
    let inv = s_g
        .try_inverse()
        .unwrap_or_else(|| Matrix3::from_element(f64::NAN));
    let u = |s: &ImuSample| inv * (s.gyro - b_g);
    let inv_dirs: Vec<Matrix3<f64>> = dirs.iter().map(|d| -inv * d).collect();
    let mut dr = SO3::identity();
    let mut jb = Matrix3::zeros();
    let mut jt = DMatrix::zeros(3, dirs.len());
    for w in samples.windows(2) {
        let dt = dt_seconds(w[0].t_ns, w[1].t_ns);
        let phi = (u(&w[0]) + u(&w[1])) * (0.5 * dt);
        let (e, jrp) = SO3::exp_jr(&phi);
        let et_m = *e.inverse().matrix();
        jb = et_m * jb - jrp * inv * dt;
        for (k, d) in inv_dirs.iter().enumerate() {
            let col: Vector3<f64> = et_m * jt.fixed_view::<3, 1>(0, k) + jrp * (d * phi);
            jt.set_column(k, &col);
        }
        dr = dr.compose(&e);
    }
    (dr, jb, jt)
}

/// Midpoint rotation preintegration of `u_i = (ω_i − b_g) ⊘ (1 + s_g)` (diagonal `S_g`) with
/// its right Jacobians: returns `(ΔR, ∂ΔR/∂b_g, ∂ΔR/∂s_g)` \[-, s, rad\]. Special case of
/// [`rotation_preintegration_general`]. `samples` must have increasing timestamps (not checked
/// here).
///
/// ```
/// use nalgebra::Vector3;
/// use preint::ImuSample;
/// use preint_calib::bias::multipose::rotation_preintegration;
///
/// // 1 s at 0.5 rad/s about z, 100 Hz, with a gyro bias of 0.01 rad/s on z.
/// let samples: Vec<ImuSample> = (0..=100)
///     .map(|k| ImuSample::new(k * 10_000_000, Vector3::new(0.0, 0.0, 0.51), Vector3::zeros()))
///     .collect();
/// let bias = Vector3::new(0.0, 0.0, 0.01);
/// let (dr, d_bg, _) = rotation_preintegration(&samples, &bias, &Vector3::zeros());
/// assert!((dr.log() - Vector3::new(0.0, 0.0, 0.5)).norm() < 1e-12);
/// assert!((d_bg[(2, 2)] + 1.0).abs() < 1e-12); // ∂θ_z/∂b_gz = −T
/// ```
pub fn rotation_preintegration(
    samples: &[ImuSample],
    b_g: &Vector3<f64>,
    s_g: &Vector3<f64>,
) -> (SO3, Matrix3<f64>, Matrix3<f64>) {
    let dirs: Vec<Matrix3<f64>> = (0..3)
        .map(|k| {
            let mut e = Matrix3::zeros();
            e[(k, k)] = 1.0;
            e
        })
        .collect();
    let s = Matrix3::from_diagonal(&s_g.add_scalar(1.0));
    let (dr, jb, js) = rotation_preintegration_general(samples, b_g, &s, &dirs);
    (dr, jb, Matrix3::from_column_slice(js.as_slice()))
}

#[cfg(test)]
mod tests {
    use super::super::model::{GyroModel, gyro_scale_matrix};
    use super::super::test_data::data;
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use nalgebra::SVector;

    /// The general rotation preintegration's θ-Jacobian against Ridders, for a non-diagonal
    /// `S_g` (all nine directions), and its diagonal special case against the general one.
    #[test]
    fn rotation_preintegration_jacobians_match_ridders() {
        let (samples, _) = data();
        let seg = &samples[300..800];
        let s = Vector3::new(0.01, -0.02, 0.005);
        let m = SVector::<f64, 6>::new(0.01, -0.004, 0.006, 0.002, -0.008, 0.003);
        let gm = GyroModel::new(&s, &m, true, true);
        let bg = Vector3::new(0.002, -0.001, 0.003);
        let (_, jb, jt) = rotation_preintegration_general(seg, &bg, &gm.s, &gm.dirs);
        let f = |x: &(Vector3<f64>, SVector<f64, 9>)| {
            let sx = Vector3::new(x.1[0], x.1[1], x.1[2]);
            let mx = SVector::<f64, 6>::from_fn(|i, _| x.1[3 + i]);
            rotation_preintegration_general(seg, &x.0, &gyro_scale_matrix(&sx, &mx), &[]).0
        };
        let theta = SVector::<f64, 9>::from_fn(|i, _| if i < 3 { s[i] } else { m[i - 3] });
        let rep = check_jacobian(
            f,
            &(bg, theta),
            &[crate::to_dmatrix(&jb), jt.clone()],
            &CheckOptions::default(),
        )
        .unwrap();
        println!("rotation preintegration: {:.2e}", rep.worst_rel_error);
        let (dr, jb2, js) = rotation_preintegration(seg, &bg, &s);
        let gd = GyroModel::new(&s, &SVector::zeros(), true, false);
        let (dr3, jb3, js3) = rotation_preintegration_general(seg, &bg, &gd.s, &gd.dirs);
        assert!(dr.minus(&dr3).norm() < 1e-14);
        assert!((jb2 - jb3).amax() < 1e-14);
        assert!((crate::to_dmatrix(&js) - js3).amax() < 1e-14);
    }
}
