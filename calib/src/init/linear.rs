//! The linear start of the initialisation: VINS-Mono's visual-inertial alignment (Qin et al.,
//! T-RO 2018, sec. V-B), in three linear least-squares steps on the windows between keyframes.
//!
//! 1. **Gyroscope bias** from the rotations (eq. 15): with the windows preintegrated at the
//!    initial bias, `δb_g = argmin Σ‖J_R δb_g − Log(ΔR̂ᵀ R_iᵀ R_j)‖²`, `J_R = ∂ΔR/∂b_g`.
//! 2. **Velocities, gravity and scale** (eqs. 16–18), linear once the accelerometer bias is
//!    neglected. With the IMU attitudes `R_k = R̃_k R_bs` and lever terms `l_k = R̃_k p_bs`:
//!
//!    ```text
//!    R_iᵀ(v_j − v_i − g Δt)                    = Δv
//!    R_iᵀ(s(p̃_j − p̃_i) − v_i Δt − ½ g Δt²)    = Δp − R_iᵀ(l_j − l_i)
//!    ```
//!
//!    each window's six rows whitened by its `[δv, δp]` covariance.
//! 3. **Gravity on its sphere** (sec. V-B-3): `g = |g|ĝ + B w`, `B` a basis of the plane
//!    normal to `ĝ`, solved for `w` with the velocities and scale, `ĝ ← (|g|ĝ + Bw)/‖·‖`,
//!    four times.
//!
//! The start is what the maximum-a-posteriori refinement ([`super::initialise`]) begins from;
//! it is printed beside the refined estimate.

use crate::bias::BiasError;
use crate::bias::KnownPose;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x2, Vector3};
use preint::{ImuBias, ImuSample, PreintParams, PreintegratedImu, SensorPose};
use preint_lie::SO3;

/// The linear start (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearStart {
    /// Gyroscope bias \[rad/s\] from the rotations (step 1).
    pub gyro_bias: Vector3<f64>,
    /// Scale \[m per unit of the poses\] (step 3; the given one when known). May be ≤ 0 when
    /// the motion does not show it.
    pub scale: f64,
    /// Gravity \[m/s², world frame of the poses\], of magnitude `|params.gravity|`.
    pub gravity: Vector3<f64>,
    /// Velocities of the IMU at the keyframes \[m/s, world\].
    pub velocities: Vec<Vector3<f64>>,
}

/// The windows between consecutive keyframes preintegrated at `bias`.
pub(crate) fn windows(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    poses: &[KnownPose],
) -> Result<Vec<PreintegratedImu>, BiasError> {
    poses
        .windows(2)
        .map(|w| {
            Ok(preint::preintegrate(
                params, bias, samples, w[0].t_ns, w[1].t_ns,
            )?)
        })
        .collect()
}

/// The linear start from `poses` (of the frame b, the IMU at `x_bs` in it) and the samples;
/// `scale`: the known scale, or `None` to estimate it.
pub fn linear_start(
    samples: &[ImuSample],
    poses: &[KnownPose],
    params: &PreintParams,
    x_bs: &SensorPose,
    scale: Option<f64>,
) -> Result<LinearStart, BiasError> {
    let atts: Vec<SO3> = poses.iter().map(|p| p.r.compose(&x_bs.rotation)).collect();
    let pims = windows(params, &ImuBias::zero(), samples, poses)?;
    let gyro_bias = gyro_bias(&pims, &atts);
    let bias = ImuBias::new(gyro_bias, Vector3::zeros());
    let pims = windows(params, &bias, samples, poses)?;
    let gnorm = params.gravity.norm();
    let lever: Vec<Vector3<f64>> = poses.iter().map(|p| p.r.act(&x_bs.translation)).collect();
    let a = Alignment {
        pims: &pims,
        atts: &atts,
        poses,
        lever: &lever,
        scale,
    };
    let (mut v, mut g, mut s) = a.solve(None);
    let mut dir = if g.norm() > 0.0 && g.iter().all(|x| x.is_finite()) {
        g.normalize()
    } else {
        params.gravity / gnorm
    };
    for _ in 0..4 {
        (v, g, s) = a.solve(Some(gnorm * dir));
        dir = g.normalize();
    }
    Ok(LinearStart {
        gyro_bias,
        scale: s,
        gravity: gnorm * dir,
        velocities: v,
    })
}

/// Step 1 (module docs).
fn gyro_bias(pims: &[PreintegratedImu], atts: &[SO3]) -> Vector3<f64> {
    let (mut h, mut b) = (Matrix3::zeros(), Vector3::zeros());
    for (k, m) in pims.iter().enumerate() {
        let rel = atts[k].inverse().compose(&atts[k + 1]);
        let r = m.delta_r.inverse().compose(&rel).log();
        let j = m.jac.d_r_d_bg;
        h += j.transpose() * j;
        b += j.transpose() * r;
    }
    h.try_inverse().map_or(Vector3::zeros(), |hi| hi * b)
}

/// The linear system of steps 2 and 3.
struct Alignment<'a> {
    pims: &'a [PreintegratedImu],
    atts: &'a [SO3],
    poses: &'a [KnownPose],
    lever: &'a [Vector3<f64>],
    scale: Option<f64>,
}

impl Alignment<'_> {
    /// Velocities, gravity and scale: gravity free (`None`), or on the sphere through
    /// `Some(g_c)` (the tangent plane at `g_c`).
    fn solve(&self, on_sphere: Option<Vector3<f64>>) -> (Vec<Vector3<f64>>, Vector3<f64>, f64) {
        let n = self.poses.len();
        let basis = on_sphere.map(tangent_basis);
        let gcols = if on_sphere.is_some() { 2 } else { 3 };
        let (go, so) = (3 * n, 3 * n + gcols);
        let cols = so + usize::from(self.scale.is_none());
        let mut a = DMatrix::zeros(6 * self.pims.len(), cols);
        let mut b = DVector::zeros(6 * self.pims.len());
        for (k, m) in self.pims.iter().enumerate() {
            let rit = *self.atts[k].inverse().matrix();
            let dt = m.delta_t;
            let row = 6 * k;
            let dp_given = self.poses[k + 1].p - self.poses[k].p;
            let mut rhs_v = m.delta_v;
            let mut rhs_p = m.delta_p - rit * (self.lever[k + 1] - self.lever[k]);
            a.view_mut((row, 3 * k), (3, 3)).copy_from(&(-rit));
            a.view_mut((row, 3 * k + 3), (3, 3)).copy_from(&rit);
            a.view_mut((row + 3, 3 * k), (3, 3)).copy_from(&(-rit * dt));
            let (gv, gp) = (-rit * dt, -rit * (0.5 * dt * dt));
            match (on_sphere, &basis) {
                (Some(gc), Some(bm)) => {
                    rhs_v -= gv * gc;
                    rhs_p -= gp * gc;
                    a.view_mut((row, go), (3, 2)).copy_from(&(gv * bm));
                    a.view_mut((row + 3, go), (3, 2)).copy_from(&(gp * bm));
                }
                _ => {
                    a.view_mut((row, go), (3, 3)).copy_from(&gv);
                    a.view_mut((row + 3, go), (3, 3)).copy_from(&gp);
                }
            }
            match self.scale {
                Some(s) => rhs_p -= rit * dp_given * s,
                None => a
                    .view_mut((row + 3, so), (3, 1))
                    .copy_from(&(rit * dp_given)),
            }
            b.fixed_rows_mut::<3>(row).copy_from(&rhs_v);
            b.fixed_rows_mut::<3>(row + 3).copy_from(&rhs_p);
            whiten(&mut a, &mut b, row, m);
        }
        let x = a
            .svd(true, true)
            .solve(&b, 1e-12)
            .unwrap_or_else(|_| DVector::zeros(cols));
        let v = (0..n)
            .map(|k| Vector3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]))
            .collect();
        let g = match (on_sphere, &basis) {
            (Some(gc), Some(bm)) => gc + bm * nalgebra::Vector2::new(x[go], x[go + 1]),
            _ => Vector3::new(x[go], x[go + 1], x[go + 2]),
        };
        (v, g, self.scale.unwrap_or_else(|| x[so]))
    }
}

/// Two unit vectors normal to `g` and to each other, scaled by |g| (so that `w` is an angle).
fn tangent_basis(g: Vector3<f64>) -> Matrix3x2<f64> {
    let d = g.normalize();
    let t = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let b1 = (t - d * d.dot(&t)).normalize();
    let b2 = d.cross(&b1);
    Matrix3x2::from_columns(&[b1, b2]) * g.norm()
}

/// Whitens the window's six rows at `row` by the inverse Cholesky factor of its `[δv, δp]`
/// covariance (left as they are when that is not positive definite).
fn whiten(a: &mut DMatrix<f64>, b: &mut DVector<f64>, row: usize, m: &PreintegratedImu) {
    let cov = m.cov.fixed_view::<6, 6>(3, 3).into_owned();
    let Some(l) = cov.cholesky() else {
        return;
    };
    let li = l
        .l()
        .try_inverse()
        .unwrap_or_else(nalgebra::Matrix6::identity);
    let rows = li * a.rows(row, 6);
    a.rows_mut(row, 6).copy_from(&rows);
    let rb = li * b.rows(row, 6);
    b.rows_mut(row, 6).copy_from(&rb);
}
