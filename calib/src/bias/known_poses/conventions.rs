//! Which convention error would explain a known-pose fit that is not credible?
//!
//! A pose file in another convention than the problem's (R_wb body → world as a Hamilton
//! quaternion w,x,y,z; world z up; poses of the IMU) gives a χ²/dof of thousands, and the
//! estimates are then meaningless. The usual errors are tried on the poses and the problem is
//! refitted, biases only ([`super::calibrate_known_poses`] with no `estimate`; the time offset
//! and intrinsics at their initial values):
//! - [`Convention::QuaternionXyzw`]: the quaternion columns are x,y,z,w (ROS, Eigen's
//!   `coeffs()`, scipy) read as w,x,y,z;
//! - [`Convention::InverseRotation`]: the attitudes are R_bw (world → body; e.g. a JPL
//!   quaternion), the positions the body's in the world;
//! - [`Convention::InversePose`]: the whole pose is T_bw (the world in the body frame);
//! - [`Convention::WorldZDown`]: the world's z axis points down (NED), gravity is `+|g|` along
//!   z (positions only: the attitude-only problem has no gravity);
//! - [`Convention::OtherFrame`]: the poses are of another frame rigidly attached to the IMU
//!   (a motion-capture body, a camera). The rotation `X = R_bi` (IMU → pose frame) is the
//!   hand-eye rotation of the rate vectors: over a window the IMU's rotation is
//!   `ΔR_imu = Xᵀ ΔR_body X`, so `Log ΔR_imu = Xᵀ Log ΔR_body`; `X` is the Kabsch (orthogonal
//!   Procrustes) solution over the windows after subtracting each set's mean, which removes the
//!   gyro bias' share `≈ −b_g Δt` of equal windows (Horn, JOSA A 1987; the rotation part of
//!   Tsai–Lenz hand-eye calibration). It is tried when `X` is more than
//!   [`MIN_FRAME_ANGLE_DEG`] from the identity, with the poses rotated to `R_wb X`.
//!
//! The candidate with the lowest χ²/dof is named when its fit is credible (and that of the
//! poses as given is not) or its χ²/dof is at least [`MIN_IMPROVEMENT`] times smaller.
//!
//! The gravity direction is estimated, so a world with z down often still fits, with the
//! estimated gravity ≈ 180° from the stated one: [`gravity_flipped`] says so.

use super::{
    KnownAttitude, KnownPose, KnownPoseOptions, calibrate_known_attitudes, calibrate_known_poses,
};
use crate::bias::BiasError;
use crate::bias::known_poses::extras::Estimate;
use crate::fit::Fit;
use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};
use preint::{ImuBias, ImuSample, preintegrate};
use preint_lie::SO3;

/// Smallest angle \[deg\] of the hand-eye rotation for which [`Convention::OtherFrame`] is
/// tried (below it the poses are taken as the IMU's).
pub const MIN_FRAME_ANGLE_DEG: f64 = 1.0;
/// Factor by which a convention must lower χ²/dof to be named when its fit is not credible
/// either.
pub const MIN_IMPROVEMENT: f64 = 10.0;

/// A convention error of a pose file (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Convention {
    /// Quaternion columns x,y,z,w read as w,x,y,z.
    QuaternionXyzw,
    /// Attitudes world → body (R_bw), positions as given.
    InverseRotation,
    /// Poses T_bw: attitude and position of the world in the body frame.
    InversePose,
    /// World z down: gravity `+|g|` along z.
    WorldZDown,
    /// Poses of another frame: `frame_from_imu` = R_bi rotates IMU vectors into it.
    OtherFrame {
        /// The hand-eye rotation R_bi.
        frame_from_imu: SO3,
    },
}

impl Convention {
    /// What the poses look like, and how to fix the file, in one sentence.
    pub fn describe(&self) -> String {
        match self {
            Convention::QuaternionXyzw => "the poses' quaternions look like x,y,z,w order (read \
                 as w,x,y,z): reorder the columns to w,x,y,z"
                .into(),
            Convention::InverseRotation => "the attitudes look like world → body rotations (R_bw, \
                 e.g. JPL quaternions): give body → world (R_wb), i.e. conjugate the quaternions"
                .into(),
            Convention::InversePose => "the poses look like the world in the body frame (T_bw): \
                 give the body in the world (T_wb = T_bw⁻¹)"
                .into(),
            Convention::WorldZDown => "the poses' world frame looks like z down (gravity along \
                 +z, e.g. NED): rotate it to z up (R ← diag(1, −1, −1)·R, p ← diag(1, −1, −1)·p)"
                .into(),
            Convention::OtherFrame { frame_from_imu } => {
                let q = quaternion(frame_from_imu);
                format!(
                    "the poses look like those of another frame, rotated by {:.1}° from the IMU \
                     (the gyro and the pose rates are related by a fixed rotation): give poses of \
                     the IMU, or the IMU's rotation in the pose frame, quaternion w,x,y,z = \
                     {:.6},{:.6},{:.6},{:.6}",
                    frame_from_imu.log().norm().to_degrees(),
                    q.w,
                    q.i,
                    q.j,
                    q.k
                )
            }
        }
    }
}

/// A convention that explains the misfit: the refit with it and the one of the poses as given.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnosis {
    /// The convention.
    pub convention: Convention,
    /// The biases-only fit of the poses as given.
    pub as_given: Fit,
    /// The biases-only fit with the convention applied.
    pub with_convention: Fit,
}

impl Diagnosis {
    /// `"<describe>: with it χ²/dof is 1.3 instead of 137 097 (biases only)"`.
    pub fn message(&self) -> String {
        format!(
            "{}; with that convention χ²/dof is {:.3} instead of {:.3} (biases-only refit)",
            self.convention.describe(),
            self.with_convention.chi2_dof,
            self.as_given.chi2_dof
        )
    }
}

/// The quaternion (w ≥ 0) of a rotation.
fn quaternion(r: &SO3) -> UnitQuaternion<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r.matrix()));
    if q.w < 0.0 {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        q
    }
}

/// `r` as it would be had its quaternion's x,y,z,w columns been read in that order: the
/// quaternion read as (w, x, y, z) = (c₀, c₁, c₂, c₃) is (c₃; c₀, c₁, c₂). The sign of a
/// quaternion does not change its rotation, so the permutation is well defined on rotations.
fn reordered(r: &SO3) -> SO3 {
    let q = quaternion(r);
    let p = UnitQuaternion::from_quaternion(Quaternion::new(q.k, q.w, q.i, q.j));
    SO3::from_matrix(p.to_rotation_matrix().matrix())
}

/// The options of the refits: biases only, from the same start.
fn biases_only(opts: &KnownPoseOptions) -> KnownPoseOptions {
    KnownPoseOptions {
        estimate: Estimate::default(),
        ..opts.clone()
    }
}

/// The hand-eye rotation R_bi of the attitudes and the gyro (module docs), `None` when the
/// windows cannot be preintegrated or do not rotate about two independent axes.
pub fn hand_eye_rotation(
    samples: &[ImuSample],
    attitudes: &[(i64, SO3)],
    opts: &KnownPoseOptions,
) -> Option<SO3> {
    let mut pairs = Vec::with_capacity(attitudes.len());
    for w in attitudes.windows(2) {
        let m = preintegrate(&opts.params, &opts.initial_bias, samples, w[0].0, w[1].0).ok()?;
        let body = w[0].1.inverse().compose(&w[1].1).log();
        pairs.push((m.delta_r.log(), body));
    }
    let n = pairs.len() as f64;
    let (ma, mb) = pairs
        .iter()
        .fold((Vector3::zeros(), Vector3::zeros()), |s, p| {
            (s.0 + p.0 / n, s.1 + p.1 / n)
        });
    // Log ΔR_imu = Xᵀ Log ΔR_body: M = Xᵀ minimises Σ‖a − M b‖², H = Σ b aᵀ = U S Vᵀ,
    // M = V diag(1, 1, det(V Uᵀ)) Uᵀ.
    let h: Matrix3<f64> = pairs
        .iter()
        .map(|(a, b)| (b - mb) * (a - ma).transpose())
        .sum();
    let svd = h.svd(true, true);
    let s = svd.singular_values;
    let mut sorted = [s[0], s[1], s[2]];
    sorted.sort_by(|a, b| b.total_cmp(a));
    if sorted[1].is_nan() || sorted[1] <= 1e-6 * sorted[0] {
        return None;
    }
    let (u, v) = (svd.u?, svd.v_t?.transpose());
    let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, (v * u.transpose()).determinant()));
    let m = v * d * u.transpose();
    Some(SO3::from_matrix(&m.transpose()))
}

/// The credible, or much better, of the candidates (module docs).
fn best(as_given: Fit, candidates: Vec<(Convention, Fit)>) -> Option<Diagnosis> {
    let (convention, with_convention) = candidates
        .into_iter()
        .filter(|(_, f)| f.chi2_dof.is_finite())
        .min_by(|a, b| a.1.chi2_dof.total_cmp(&b.1.chi2_dof))?;
    let better = with_convention.chi2_dof * MIN_IMPROVEMENT <= as_given.chi2_dof;
    let credible = with_convention.credible && !as_given.credible;
    (better || credible).then_some(Diagnosis {
        convention,
        as_given,
        with_convention,
    })
}

/// Tries the convention errors on known poses (module docs) and names the one that explains
/// the misfit, if any. Refits that fail are skipped; an error only when the poses as given
/// cannot be fitted.
pub fn diagnose_known_poses(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
) -> Result<Option<Diagnosis>, BiasError> {
    let o = biases_only(opts);
    let fit = |p: &[KnownPose], o: &KnownPoseOptions| {
        calibrate_known_poses(samples, p, o)
            .ok()
            .map(|c| Fit::new(c.chi2, c.dof))
    };
    let as_given = calibrate_known_poses(samples, poses, &o)?;
    let as_given = Fit::new(as_given.chi2, as_given.dof);
    let map = |f: &dyn Fn(&KnownPose) -> KnownPose| poses.iter().map(f).collect::<Vec<_>>();
    let mut candidates: Vec<(Convention, Vec<KnownPose>, KnownPoseOptions)> = vec![
        (
            Convention::QuaternionXyzw,
            map(&|p| KnownPose {
                r: reordered(&p.r),
                ..*p
            }),
            o.clone(),
        ),
        (
            Convention::InverseRotation,
            map(&|p| KnownPose {
                r: p.r.inverse(),
                ..*p
            }),
            o.clone(),
        ),
        (
            Convention::InversePose,
            map(&|p| KnownPose {
                r: p.r.inverse(),
                p: -(p.r.inverse().act(&p.p)),
                ..*p
            }),
            o.clone(),
        ),
        (Convention::WorldZDown, poses.to_vec(), {
            let mut z = o.clone();
            z.params.gravity = -z.params.gravity;
            z
        }),
    ];
    let atts: Vec<(i64, SO3)> = poses.iter().map(|p| (p.t_ns, p.r)).collect();
    if let Some(x) = other_frame(samples, &atts, &o) {
        let rotated = map(&|p| KnownPose {
            r: p.r.compose(&x),
            ..*p
        });
        candidates.push((
            Convention::OtherFrame { frame_from_imu: x },
            rotated,
            o.clone(),
        ));
    }
    let fits = candidates
        .iter()
        .filter_map(|(c, p, o)| fit(p, o).map(|f| (*c, f)))
        .collect();
    Ok(best(as_given, fits))
}

/// Largest angle \[deg\] between the estimated and the stated gravity of a plausible fit:
/// beyond it the poses' world frame is upside down (z down) rather than tilted.
pub const MAX_GRAVITY_TILT_DEG: f64 = 90.0;

/// [`Convention::WorldZDown`] when the estimated gravity is more than
/// [`MAX_GRAVITY_TILT_DEG`] from the stated one (`tilt_rad`, e.g.
/// [`super::KnownPoseCalibration::gravity_tilt`]).
pub fn gravity_flipped(tilt_rad: f64) -> Option<Convention> {
    (tilt_rad.to_degrees() > MAX_GRAVITY_TILT_DEG).then_some(Convention::WorldZDown)
}

/// The hand-eye rotation when it is far enough from the identity to try.
fn other_frame(samples: &[ImuSample], atts: &[(i64, SO3)], o: &KnownPoseOptions) -> Option<SO3> {
    let x = hand_eye_rotation(
        samples,
        atts,
        &KnownPoseOptions {
            initial_bias: ImuBias::zero(),
            ..o.clone()
        },
    )?;
    (x.log().norm().to_degrees() > MIN_FRAME_ANGLE_DEG).then_some(x)
}

/// [`diagnose_known_poses`] for attitudes only (no gravity: [`Convention::WorldZDown`] and
/// [`Convention::InversePose`] are not tried).
pub fn diagnose_known_attitudes(
    samples: &[ImuSample],
    attitudes: &[KnownAttitude],
    opts: &KnownPoseOptions,
) -> Result<Option<Diagnosis>, BiasError> {
    let o = biases_only(opts);
    let fit = |a: &[KnownAttitude]| {
        calibrate_known_attitudes(samples, a, &o)
            .ok()
            .map(|c| Fit::new(c.chi2, c.dof))
    };
    let as_given = calibrate_known_attitudes(samples, attitudes, &o)?;
    let as_given = Fit::new(as_given.chi2, as_given.dof);
    let map = |f: &dyn Fn(&SO3) -> SO3| {
        attitudes
            .iter()
            .map(|a| KnownAttitude { r: f(&a.r), ..*a })
            .collect::<Vec<_>>()
    };
    let mut candidates = vec![
        (Convention::QuaternionXyzw, map(&reordered)),
        (Convention::InverseRotation, map(&|r| r.inverse())),
    ];
    let atts: Vec<(i64, SO3)> = attitudes.iter().map(|a| (a.t_ns, a.r)).collect();
    if let Some(x) = other_frame(samples, &atts, &o) {
        candidates.push((
            Convention::OtherFrame { frame_from_imu: x },
            map(&|r| r.compose(&x)),
        ));
    }
    let fits = candidates
        .iter()
        .filter_map(|(c, a)| fit(a).map(|f| (*c, f)))
        .collect();
    Ok(best(as_given, fits))
}

#[cfg(test)]
mod tests {
    use super::super::test_data::setup;
    use super::*;
    use preint::ImuNoise;

    /// The x,y,z,w permutation of a known quaternion.
    #[test]
    fn reordering_permutes_the_quaternion() {
        let q = UnitQuaternion::from_quaternion(Quaternion::new(0.5, 0.1, -0.7, 0.3));
        let r = SO3::from_matrix(q.to_rotation_matrix().matrix());
        let p = quaternion(&reordered(&r));
        let expect = UnitQuaternion::from_quaternion(Quaternion::new(0.3, 0.5, 0.1, -0.7));
        assert!(p.angle_to(&expect) < 1e-12, "{p} vs {expect}");
    }

    /// Poses of a frame rotated by a known X from the IMU (simulated, biased gyro): the
    /// hand-eye rotation recovers X to a fraction of a degree, and the diagnosis names it; the
    /// poses of the IMU themselves are not diagnosed.
    #[test]
    fn another_frame_is_found_and_the_imu_frame_is_not_diagnosed() {
        let s = setup(ImuNoise::euroc());
        let opts = KnownPoseOptions::new(s.params.clone());
        let x = SO3::exp(&Vector3::new(0.4, -1.1, 0.7));
        // R_wb = R_wi Xᵀ: the IMU's attitude is R_wb X.
        let body: Vec<KnownPose> = s
            .poses
            .iter()
            .map(|p| KnownPose {
                r: p.r.compose(&x.inverse()),
                ..*p
            })
            .collect();
        let atts: Vec<(i64, SO3)> = body.iter().map(|p| (p.t_ns, p.r)).collect();
        let xh = hand_eye_rotation(&s.samples, &atts, &opts).unwrap();
        let err = xh.inverse().compose(&x).log().norm().to_degrees();
        assert!(err < 0.5, "hand-eye error {err}°");
        let d = diagnose_known_poses(&s.samples, &body, &opts)
            .unwrap()
            .unwrap();
        assert!(
            matches!(d.convention, Convention::OtherFrame { .. }),
            "{d:?}"
        );
        assert!(
            d.with_convention.chi2_dof * 10.0 < d.as_given.chi2_dof,
            "{d:?}"
        );
        assert!(d.message().contains("another frame"), "{}", d.message());
        let none = diagnose_known_poses(&s.samples, &s.poses, &opts).unwrap();
        assert!(none.is_none(), "{none:?}");
    }
}
