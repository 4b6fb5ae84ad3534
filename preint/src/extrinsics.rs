//! An IMU that is not at the body origin: the exact map from the sensor's preintegrated deltas
//! to the body's, and GTSAM's per-sample lever-arm model (the model and its linearisation:
//! [`SensorPose`](crate::SensorPose)).

use crate::choices::{Level, LeverArm};
use crate::edges::{EdgeNoise, EdgeSource};
use crate::measurement::{BiasJacobians, Cov9, PreintegratedImu};
use crate::noise::white_scale;
use crate::params::SensorPose;
use crate::sample::ImuSample;
use nalgebra::{Matrix3, SMatrix, Vector3};
use preint_lie::{SO3, hat};

/// How `params` removes the lever arm of its `body_p_sensor`: the arm taken off every sample
/// before the loop ([`LeverArm::Centripetal`] with a non-zero arm), and the pose whose map
/// turns the sensor's measurement into the body's (rotation only in that case, since the
/// samples lost the arm already). `(None, None)` without a sensor pose.
pub(crate) fn plan(
    pose: Option<&SensorPose>,
    mode: LeverArm,
) -> (Option<CentripetalArm>, Option<SensorPose>) {
    match (pose, mode) {
        (Some(pose), LeverArm::Centripetal) if pose.translation != Vector3::zeros() => (
            Some(CentripetalArm {
                r: pose.rotation.inverse().act(&pose.translation),
            }),
            Some(SensorPose::new(pose.rotation, Vector3::zeros())),
        ),
        (pose, _) => (None, pose.copied()),
    }
}

/// GTSAM's per-sample lever-arm model ([`LeverArm::Centripetal`]) as a transform of the
/// samples before the loop: each specific force loses `c(ω) = ω × (ω × r)`, with `ω = ω_m − b̂_g`
/// [rad/s] and `r` the lever arm in sensor axes \[m\]. The transformed sample's accelerometer
/// input then depends on its rate through `D(ω) = −∂c/∂ω` (its [`RateMap`]), which the loop's
/// gains carry: the gyroscope noise and bias move the specific force.
///
/// [`RateMap`]: crate::propagation::RateMap
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CentripetalArm {
    /// The lever arm in sensor axes \[m\].
    pub r: Vector3<f64>,
}

impl CentripetalArm {
    /// Sample `s` with `ω × (ω × r)` taken off its specific force, `ω = ω_m − b_g`.
    #[inline(always)]
    pub(crate) fn map(&self, s: &ImuSample, b_g: &Vector3<f64>) -> ImuSample {
        let (w, r) = (s.gyro - b_g, &self.r);
        ImuSample::new(s.t_ns, s.gyro, s.acc - w.cross(&w.cross(r)))
    }
}

impl crate::propagation::RateMap for CentripetalArm {
    /// `D = ∂a_node/∂ω_node` of a node whose specific force lost `c(ω) = ω × (ω × r)`:
    /// `−∂c/∂ω = [ω × r]× + [ω]×[r]× = [ω × r]× + r ωᵀ − (ω·r) I`.
    #[inline(always)]
    fn d(&self, w: &Vector3<f64>) -> Matrix3<f64> {
        let r = &self.r;
        let (x, wr) = (w.cross(r), w.dot(r));
        let o = r * w.transpose();
        Matrix3::new(
            o[(0, 0)] - wr,
            o[(0, 1)] - x.z,
            o[(0, 2)] + x.y,
            o[(1, 0)] + x.z,
            o[(1, 1)] - wr,
            o[(1, 2)] - x.x,
            o[(2, 0)] - x.y,
            o[(2, 1)] + x.x,
            o[(2, 2)] - wr,
        )
    }
}

/// The body's deltas `(ΔR, Δv [m/s], Δp [m])` from the sensor's `(ΔR_s, Δv_s, Δp_s)` over
/// `dt_s` \[s\], with the bias-corrected sensor rates `w_i`, `w_j` [rad/s] at the window's ends
/// (module docs).
pub(crate) fn body_deltas(
    pose: &SensorPose,
    (dr_s, dv_s, dp_s): (&SO3, &Vector3<f64>, &Vector3<f64>),
    dt_s: f64,
    (w_i, w_j): (&Vector3<f64>, &Vector3<f64>),
) -> (SO3, Vector3<f64>, Vector3<f64>) {
    let (rm, r) = (*pose.rotation.matrix(), pose.translation);
    let dr = pose
        .rotation
        .compose(dr_s)
        .compose(&pose.rotation.inverse());
    let (wi, wj) = (rm * w_i, rm * w_j);
    let dv = rm * dv_s + wi.cross(&r) - dr.act(&wj.cross(&r));
    let dp = rm * dp_s + wi.cross(&r) * dt_s + r - dr.act(&r);
    (dr, dv, dp)
}

/// A stream sample an end rate is made of: timestamp \[ns\], weight, and its intervals to its
/// stream neighbours \[s\] (0 if unknown).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct EndSource {
    pub t_ns: i64,
    pub w: f64,
    pub left_s: f64,
    pub right_s: f64,
}

/// The end rates of a window: bias-corrected sensor rates [rad/s] at the first and last
/// sample, and the stream samples each is made of.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EndRates {
    pub w_i: Vector3<f64>,
    pub w_j: Vector3<f64>,
    pub src_i: [EndSource; 4],
    pub n_i: usize,
    pub src_j: [EndSource; 4],
    pub n_j: usize,
}

impl EndRates {
    /// Weight of stream sample `t_ns` in the rate at the start (`start = true`) or end.
    fn weight(&self, t_ns: i64, start: bool) -> f64 {
        self.sources(start)
            .iter()
            .filter(|s| s.t_ns == t_ns)
            .map(|s| s.w)
            .sum()
    }

    fn sources(&self, start: bool) -> &[EndSource] {
        if start {
            &self.src_i[..self.n_i]
        } else {
            &self.src_j[..self.n_j]
        }
    }
}

type M9 = SMatrix<f64, 9, 9>;
type M93 = SMatrix<f64, 9, 3>;

/// `A`, `B_i`, `B_j` of the module docs for a measurement `m` of the sensor.
fn linearisation(m: &PreintegratedImu, pose: &SensorPose, ends: &EndRates) -> (M9, M93, M93) {
    let (rm, r) = (*pose.rotation.matrix(), pose.translation);
    let dr = pose
        .rotation
        .compose(&m.delta_r)
        .compose(&pose.rotation.inverse());
    let drm = *dr.matrix();
    let wj = rm * ends.w_j;
    let mut a = M9::zeros();
    for k in 0..3 {
        a.fixed_view_mut::<3, 3>(3 * k, 3 * k).copy_from(&rm);
    }
    a.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(drm * hat(&wj.cross(&r)) * rm));
    a.fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(drm * hat(&r) * rm));
    let mut bi = M93::zeros();
    bi.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hat(&r)));
    bi.fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(-hat(&r) * m.delta_t));
    let mut bj = M93::zeros();
    bj.fixed_view_mut::<3, 3>(3, 0).copy_from(&(drm * hat(&r)));
    (a, bi, bj)
}

/// Makes the sensor's measurement `m` the body's (module docs): deltas, covariances, bias
/// Jacobians and edge sources. `m.level` decides what is transformed.
pub(crate) fn to_body(m: &mut PreintegratedImu, pose: &SensorPose, ends: &EndRates) {
    let rm = *pose.rotation.matrix();
    let (a, bi, bj) = linearisation(m, pose, ends);
    let sensor = (&m.delta_r, &m.delta_v, &m.delta_p);
    (m.delta_r, m.delta_v, m.delta_p) =
        body_deltas(pose, sensor, m.delta_t, (&ends.w_i, &ends.w_j));
    if m.level == Level::Deltas {
        return;
    }
    // Bias Jacobians: gyro columns also through the end rates.
    let mut jb = a * m.jac.as_matrix();
    let gyro_extra = -(bi + bj) * rm;
    jb.fixed_view_mut::<9, 3>(0, 0)
        .zip_apply(&gyro_extra, |x, y| *x += y);
    m.jac = BiasJacobians::from_matrix(&jb);
    // Edge sources: their gains through A and the end rates. Each sample's noise is
    // block-diagonal (gyro, accelerometer), so a source read by an end rate swaps its share
    // `(A G) Q (A G)ᵀ` of `A Σ_s Aᵀ` for `G' Q G'ᵀ`, `G' = A G + [E, 0]`: the difference is
    // `X + Xᵀ + E Q_g Eᵀ` with `X = (A G)_g Q_g Eᵀ`.
    let sensor = &m.edge_noise;
    let mut noise = EdgeNoise::new(sensor.gyro_cov, sensor.acc_cov, sensor.cell_rule);
    let mut extra = Cov9::zeros();
    let mut add = |s: &EdgeSource| {
        let mut g = a * s.gain;
        let (w_i, w_j) = (ends.weight(s.t_ns, true), ends.weight(s.t_ns, false));
        if w_i != 0.0 || w_j != 0.0 {
            let qg = sensor.gyro_cov * white_scale(sensor.cell_rule.cell_s(s.left_s, s.right_s));
            let e = (bi * w_i + bj * w_j) * rm;
            let x = g.fixed_view::<9, 3>(0, 0) * qg * e.transpose();
            extra += x + x.transpose() + e * qg * e.transpose();
            g.fixed_view_mut::<9, 3>(0, 0).zip_apply(&e, |x, y| *x += y);
        }
        noise.push(EdgeSource { gain: g, ..*s });
    };
    for s in sensor.sources() {
        add(s);
    }
    // End-rate samples no interval reads (Euler's last sample) enter through the end rate
    // alone: sources with a zero integration gain.
    for start in [true, false] {
        for src in ends.sources(start) {
            if sensor.find(src.t_ns).is_none() {
                add(&EdgeSource {
                    t_ns: src.t_ns,
                    gain: SMatrix::zeros(),
                    left_s: src.left_s,
                    right_s: src.right_s,
                    start,
                    end: !start,
                });
            }
        }
    }
    m.edge_noise = noise;
    let cov = a * m.cov * a.transpose() + extra;
    m.cov = (cov + cov.transpose()) * 0.5;
    // Combined covariance: [e; δb] ↦ [[A, K], [0, I]] [e_s; δb] with K = B_j R on the δb_g
    // columns, plus the end-rate noise (`extra`).
    if m.level == Level::Covariance {
        // No random walk in the deltas at this level: `cov15 = diag(cov, Σ_bb)`.
        m.cov15.fixed_view_mut::<9, 9>(0, 0).copy_from(&m.cov);
    } else {
        let k = bj * rm;
        let p = m.cov15.fixed_view::<9, 9>(0, 0).into_owned();
        let c = m.cov15.fixed_view::<9, 6>(0, 9).into_owned();
        let pbb = m.cov15.fixed_view::<6, 6>(9, 9).into_owned();
        let ack = a * c.fixed_view::<9, 3>(0, 0) * k.transpose();
        let pgg = pbb.fixed_view::<3, 3>(0, 0).into_owned();
        let p_new = a * p * a.transpose() + ack + ack.transpose() + k * pgg * k.transpose() + extra;
        let c_new = a * c + k * pbb.fixed_view::<3, 6>(0, 0);
        m.cov15
            .fixed_view_mut::<9, 9>(0, 0)
            .copy_from(&((p_new + p_new.transpose()) * 0.5));
        m.cov15.fixed_view_mut::<9, 6>(0, 9).copy_from(&c_new);
        m.cov15
            .fixed_view_mut::<6, 9>(9, 0)
            .copy_from(&c_new.transpose());
    }
}

/// The time-offset column of a sensor measurement mapped into the body by a rotation-only
/// `body_p_sensor` (`R_bs`): `diag(R_bs, R_bs, R_bs) j`. With a lever arm the body column is
/// unknown from the end samples ([`crate::time_offset`]) and this returns zero.
pub(crate) fn time_offset_to_body(
    j: &nalgebra::SVector<f64, 9>,
    pose: &SensorPose,
) -> nalgebra::SVector<f64, 9> {
    if pose.translation != Vector3::zeros() {
        return nalgebra::SVector::zeros();
    }
    let rm = pose.rotation.matrix();
    let mut out = nalgebra::SVector::<f64, 9>::zeros();
    for k in 0..3 {
        let b = rm * j.fixed_rows::<3>(3 * k);
        out.fixed_rows_mut::<3>(3 * k).copy_from(&b);
    }
    out
}
