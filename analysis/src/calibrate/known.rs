//! The known-pose and known-attitude problems of `preint calibrate`: the poses selected, the
//! problem solved with `--scheme`, its fit, and the likely cause of a misfit (a pose-file
//! convention error, [`preint_calib::bias::known_poses::conventions`]).

use super::{Calibrated, Calibration, Options, fail_in};
use crate::{Error, calibration_file, checks};
use nalgebra::Vector3;
use preint::{ImuNoise, ImuSample, PreintParams};
use preint_calib::Fit;
use preint_calib::bias::known_poses::conventions::{
    self, Convention, Diagnosis, diagnose_known_attitudes, diagnose_known_poses,
};
use preint_calib::bias::known_poses::{KnownAttitude, calibrate_known_attitudes};
use preint_calib::bias::{KnownPose, KnownPoseOptions, calibrate_known_poses};
use preint_lie::SO3;
use std::path::Path;

/// Largest time offset `--estimate time-offset` looks for \[ns\]: poses within this of the
/// recording's ends are not used, so that every shifted window stays inside the samples.
const MAX_TIME_OFFSET_NS: i64 = 100_000_000;

/// The poses of `pfile` inside the samples' time span (less a margin for the time offset),
/// `--pose-spacing` apart.
fn select_poses(
    args: &Options,
    pfile: &Path,
    samples: &[ImuSample],
    margin_ns: i64,
) -> Result<Vec<preint_io::PoseRow>, Error> {
    poses_in_span(pfile, samples, args.pose_spacing, margin_ns)
}

/// The rows of the pose file `pfile` inside the samples' time span less `margin_ns` at each
/// end, `spacing_s` apart; fewer than three is an error naming the file.
pub(crate) fn poses_in_span(
    pfile: &Path,
    samples: &[ImuSample],
    spacing_s: f64,
    margin_ns: i64,
) -> Result<Vec<preint_io::PoseRow>, Error> {
    let rows = preint_io::read_poses(pfile)?;
    let (t0, t1) = (
        samples[0].t_ns + margin_ns,
        samples[samples.len() - 1].t_ns - margin_ns,
    );
    let spacing = (spacing_s * 1e9).round() as i64;
    let mut kp: Vec<preint_io::PoseRow> = Vec::new();
    for s in rows.iter().filter(|s| s.t_ns >= t0 && s.t_ns <= t1) {
        if kp.last().is_none_or(|l| s.t_ns - l.t_ns >= spacing) {
            kp.push(*s);
        }
    }
    if kp.len() < 3 {
        return Err(Error::Failed(format!(
            "{}: fewer than three poses inside the IMU time span (poses ≥ {} s apart{} are \
             used)",
            pfile.display(),
            spacing_s,
            if margin_ns > 0 {
                format!(", ≥ {} s from its ends", margin_ns as f64 * 1e-9)
            } else {
                String::new()
            }
        )));
    }
    Ok(kp)
}

/// The likely cause of a known-pose (or attitude) misfit: the convention error the diagnosis
/// names (with the flag that fixes a frame error), or the usual suspects.
fn misfit_cause(
    diagnosis: Result<Option<Diagnosis>, preint_calib::bias::BiasError>,
    positions: bool,
) -> String {
    match diagnosis {
        Ok(Some(d)) => {
            let hint = match d.convention {
                Convention::OtherFrame { frame_from_imu } => {
                    let q = nalgebra::UnitQuaternion::from_rotation_matrix(
                        &nalgebra::Rotation3::from_matrix_unchecked(*frame_from_imu.matrix()),
                    );
                    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
                    format!(
                        " (--body-p-sensor 0,0,0,{:.6},{:.6},{:.6},{:.6} with a zero lever arm, or \
                         estimate the rotation and lever arm: --estimate \
                         extrinsic-rotation,lever-arm)",
                        s * q.w,
                        s * q.i,
                        s * q.j,
                        s * q.k
                    )
                }
                _ => String::new(),
            };
            format!("{}{hint}", d.message())
        }
        _ => format!(
            "no convention error of the pose file explains it (quaternion order, inverse \
             rotation{}, poses of another frame were tried); the noise densities (--noise){} are \
             too small, the biases drift over the span (shorten --from/--to), or the clocks \
             are offset (--estimate time-offset)",
            if positions {
                " or pose, world z down"
            } else {
                ""
            },
            if positions {
                " or the pose noise (--pose-rot-std, --pose-pos-std)"
            } else {
                " or the attitude noise (--pose-rot-std)"
            }
        ),
    }
}

/// Mean sample interval \[s\].
fn mean_interval_s(samples: &[ImuSample]) -> f64 {
    let n = samples.len();
    (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (n - 1).max(1) as f64
}

/// The known-pose problem on the poses of `pfile` inside the samples' time span (attitudes
/// only when the file has no positions), with its fit and, when that is not credible, the
/// likely cause.
pub(super) fn known_poses(
    args: &Options,
    pfile: &Path,
    samples: &[ImuSample],
    noise: &ImuNoise,
) -> Result<Calibrated, Error> {
    checks::positive("--pose-spacing", args.pose_spacing)?;
    let estimate = args.estimate.unwrap_or_default();
    let file = args
        .calibration
        .as_deref()
        .map(calibration_file::read)
        .transpose()?;
    let file_x = file.as_ref().and_then(|f| f.body_p_sensor);
    if file_x.is_some() && args.body_p_sensor.is_some() {
        return Err(Error::Usage(format!(
            "--body-p-sensor with --calibration {}, which holds the IMU's pose \
             (preint_body_p_sensor): give one of them",
            args.calibration
                .as_deref()
                .unwrap_or(Path::new(""))
                .display()
        )));
    }
    // With anything estimated, or a calibration file's transform, the IMU's pose is applied
    // to the poses (and is the start of what is estimated of it); otherwise as the
    // preintegration's lever arm.
    let on_poses = estimate.any() || file_x.is_some();
    let initial_extrinsic = if on_poses {
        args.body_p_sensor.or(file_x)
    } else {
        None
    };
    let td0 = file.as_ref().and_then(|f| f.time_offset_s);
    let time_offset = estimate.time_offset || td0.is_some();
    let margin = if time_offset {
        MAX_TIME_OFFSET_NS + calibration_file::time_offset_ns_of(td0).abs()
    } else {
        0
    };
    let rows = select_poses(args, pfile, samples, margin)?;
    let scheme = args.scheme;
    let mut notes = Vec::new();
    if let (Some(f), Some(path)) = (&file, &args.calibration) {
        notes.extend(calibration_file::scheme_note(
            f,
            path,
            scheme,
            mean_interval_s(samples),
        ));
    }
    let params = PreintParams {
        body_p_sensor: if on_poses { None } else { args.body_p_sensor },
        ..PreintParams::from_noise(noise)
            .with_scheme(scheme)
            .with_gravity(Vector3::new(0.0, 0.0, -args.gravity))
    };
    let mut opts = KnownPoseOptions {
        pose_rot_std: args.pose_rot_std,
        pose_pos_std: args.pose_pos_std,
        estimate,
        initial_time_offset_s: td0.unwrap_or(0.0),
        initial_extrinsic,
        ..KnownPoseOptions::new(params)
    };
    if let Some(f) = &file {
        opts.initial_intrinsics = f.intrinsics;
    }
    let problem = Problem {
        args,
        samples,
        opts: &opts,
        source: pfile.display().to_string(),
        time_offset,
    };
    let (calibration, fit) = if rows.iter().any(|r| r.p.is_none()) {
        problem.attitudes(&rows)?
    } else {
        problem.poses(&rows, &mut notes)?
    };
    Ok(Calibrated {
        calibration,
        fit,
        notes,
        scheme,
    })
}

/// A known-pose problem set up: the samples, the solver's options and what is printed with it.
struct Problem<'a> {
    args: &'a Options,
    samples: &'a [ImuSample],
    opts: &'a KnownPoseOptions,
    /// The pose file, as printed.
    source: String,
    /// Whether the time offset was asked for or given.
    time_offset: bool,
}

impl Problem<'_> {
    /// The gyroscope problem on attitudes only, with its fit (and the likely cause of a
    /// misfit).
    fn attitudes(self, rows: &[preint_io::PoseRow]) -> Result<(Calibration, Fit), Error> {
        let atts: Vec<KnownAttitude> = rows
            .iter()
            .map(|r| KnownAttitude {
                t_ns: r.t_ns,
                r: SO3::from_quaternion(&r.q),
            })
            .collect();
        let fail = fail_in(self.args.input.path());
        let c = calibrate_known_attitudes(self.samples, &atts, self.opts).map_err(fail)?;
        let mut fit = c.fit();
        if !fit.credible {
            let d = diagnose_known_attitudes(self.samples, &atts, self.opts);
            fit = fit.because(&misfit_cause(d, false));
        }
        let calibration = Calibration::KnownAttitudes {
            source: self.source,
            poses: atts.len(),
            pose_rot_std: self.args.pose_rot_std,
            c: Box::new(c),
            time_offset: self.time_offset,
        };
        Ok((calibration, fit))
    }

    /// The known-pose problem, with its fit (and the likely cause of a misfit); a gravity
    /// estimate upside down adds a warning to `notes`.
    fn poses(
        self,
        rows: &[preint_io::PoseRow],
        notes: &mut Vec<String>,
    ) -> Result<(Calibration, Fit), Error> {
        let kp: Vec<KnownPose> = rows
            .iter()
            .map(|r| KnownPose {
                t_ns: r.t_ns,
                r: SO3::from_quaternion(&r.q),
                p: r.p.unwrap_or_default(),
            })
            .collect();
        let fail = fail_in(self.args.input.path());
        let c = calibrate_known_poses(self.samples, &kp, self.opts).map_err(fail)?;
        let mut fit = c.fit();
        if !fit.credible {
            fit = fit.because(&misfit_cause(
                diagnose_known_poses(self.samples, &kp, self.opts),
                true,
            ));
        }
        if let Some(z) = conventions::gravity_flipped(c.gravity_tilt) {
            notes.push(format!(
                "warning: the estimated gravity is {:.1}° from (0, 0, −{}): {}",
                c.gravity_tilt.to_degrees(),
                self.args.gravity,
                z.describe()
            ));
        }
        let calibration = Calibration::KnownPoses {
            source: self.source,
            poses: kp.len(),
            pose_std: (self.args.pose_rot_std, self.args.pose_pos_std),
            c: Box::new(c),
            time_offset: self.time_offset,
        };
        Ok((calibration, fit))
    }
}
