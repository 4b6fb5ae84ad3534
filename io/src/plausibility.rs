//! Are these readings plausible for an IMU on Earth in the units they were read as? Checks
//! that catch data in g, deg/s or the wrong time unit before it gives a confident wrong answer.
//!
//! [`check_units`] runs, in order:
//! 1. **Time unit.** The median sample interval must lie in [20 µs, 10 s] (50 kHz to 0.1 Hz):
//!    milliseconds read as nanoseconds give ≈ 5 ns, microseconds ≈ 5 µs.
//! 2. **Accelerometer unit.** The median accelerometer norm must lie in [4, 20] m/s² (specific
//!    force near the Earth's surface; data in g reads ≈ 1).
//! 3. **Gyroscope, moving.** The median gyro norm must stay below 20 rad/s (data in deg/s of a
//!    moving IMU reads tens to hundreds).
//!    A gyro that reads exactly zero on every sample (≥ 100) while the accelerometer varies is
//!    no gyroscope (an accelerometer-only topic, a wrong column): no real gyro is noise-free.
//!    (Noise-free simulated data at rest, with a constant accelerometer, passes.)
//! 4. **Gyroscope, still.** Over the windows where the accelerometer is steady
//!    ([`still_windows`]: decided from the accelerometer only, so the gyro's unit does not
//!    matter), the gyro's mean reading across the gravity direction must stay below
//!    [`MAX_STILL_GYRO_RAD_S`] = 0.1 rad/s (median over the windows). A steady accelerometer
//!    means the body turns at most about the vertical (any turn about a horizontal axis tilts
//!    gravity in the body frame), so what the gyro reads across the vertical is its bias:
//!    MEMS gyro biases are a few mrad/s to a few tens of mrad/s, while a bias in deg/s read as
//!    rad/s is 57× larger (0.4 deg/s → 0.4 "rad/s"). Steady turning about the vertical (a
//!    turntable) passes.
//! 5. **Gyroscope against gravity.** On moving data, the gyro must explain how the gravity
//!    direction seen by the accelerometer turns ([`gyro_scale_fit`]): between quasi-static
//!    moments 1 s apart, the gyro scaled by s (and a fitted constant bias) predicts the change
//!    of the gravity direction. If s = 1 misses by more than 10° (median) while s = π/180 or
//!    s = 180/π misses by less than a third of that, the gyro is in deg/s (or was declared
//!    deg/s wrongly). The accelerometer sees gravity only where the sensor is not
//!    accelerating; where no scale explains the data (a multirotor's accelerometer follows
//!    its thrust axis), the misfits are all small or all large, and the check is silent.

use crate::error::IoError;
use nalgebra::Vector3;
use preint::ImuSample;

/// Largest median gyro norm \[rad/s\] accepted while the accelerometer shows the sensor still.
pub const MAX_STILL_GYRO_RAD_S: f64 = 0.1;

/// Gravity magnitude used to recognise still and quasi-static windows \[m/s²\].
const G: f64 = 9.81;

/// Runs the checks of the module docs on `samples` (at least two, time-ordered); `source_name`
/// labels the error.
pub fn check_units(samples: &[ImuSample], source_name: &str) -> Result<(), IoError> {
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    if samples.len() < 2 {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    let dt_ns = median_interval_ns(samples);
    if !(20_000.0..=1e10).contains(&dt_ns) {
        return Err(units(format!(
            "the median sample interval is {dt_ns} ns ({:.4e} Hz); expected 20 µs to 10 s. If the \
             timestamps are not in the unit they were read as, set --time-unit (s, ms, us, ns)",
            1e9 / dt_ns
        )));
    }
    check_si_units(samples, source_name)?;
    let dt = dt_ns * 1e-9;
    if let Some(w) = still_gyro_norm(samples, dt)
        && w > MAX_STILL_GYRO_RAD_S
    {
        return Err(units(format!(
            "while the accelerometer is steady (no turn about a horizontal axis), the gyro \
             reads {w:.3} across the vertical (median), above {MAX_STILL_GYRO_RAD_S} rad/s \
             for a MEMS bias: is it in deg/s (--gyro-unit deg/s)? If this gyro's bias \
             really is that large, pass --no-unit-check"
        )));
    }
    if let Some(msg) = gyro_scale_fit(samples, dt).and_then(|fit| fit.verdict()) {
        return Err(units(msg));
    }
    Ok(())
}

/// Median interval between consecutive samples \[ns\].
pub fn median_interval_ns(samples: &[ImuSample]) -> f64 {
    let mut d: Vec<i64> = samples.windows(2).map(|w| w[1].t_ns - w[0].t_ns).collect();
    let mid = d.len() / 2;
    *d.select_nth_unstable(mid).1 as f64
}

/// Checks that IMU samples look like SI units for an IMU near the Earth's surface: the median
/// accelerometer norm must lie in [4, 20] m/s² (data in g reads ≈ 1) and the median gyro norm
/// below 20 rad/s (data in deg/s of a moving IMU reads tens to hundreds).
pub fn check_si_units(samples: &[ImuSample], source_name: &str) -> Result<(), IoError> {
    if samples.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    let acc = median(samples.iter().map(|s| s.acc.norm()).collect());
    let gyro = median(samples.iter().map(|s| s.gyro.norm()).collect());
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    if let Some(msg) = accel_norm_verdict(acc).or_else(|| gyro_norm_verdict(gyro)) {
        return Err(units(msg));
    }
    let first_acc = samples[0].acc;
    if samples.len() >= MIN_SAMPLES_FOR_ZERO_GYRO
        && samples.iter().all(|s| s.gyro == Vector3::zeros())
        && samples.iter().any(|s| s.acc != first_acc)
    {
        return Err(units(format!(
            "the gyro reads exactly 0 on all {} samples while the accelerometer varies: this \
             is not a gyroscope channel (an accelerometer-only topic, or the wrong --columns?)",
            samples.len()
        )));
    }
    Ok(())
}

/// The error message if a median accelerometer norm `acc` (as read) is not in [4, 20] m/s².
pub fn accel_norm_verdict(acc: f64) -> Option<String> {
    (!(4.0..=20.0).contains(&acc)).then(|| {
        format!(
            "median accelerometer norm is {acc:.4}; expected about 9.81 m/s² (specific force). \
             If the data is in g, set --accel-unit g"
        )
    })
}

/// The error message if a median gyro norm `gyro` (as read) exceeds 20 rad/s.
pub fn gyro_norm_verdict(gyro: f64) -> Option<String> {
    (gyro > 20.0).then(|| {
        format!(
            "median gyro norm is {gyro:.2}; expected rad/s. If the data is in deg/s, set \
             --gyro-unit deg/s"
        )
    })
}

/// Fewest samples for the zero-gyro check of [`check_si_units`] (and of a split recording's
/// gyro channel in the audit).
pub const MIN_SAMPLES_FOR_ZERO_GYRO: usize = 100;

fn median(mut v: Vec<f64>) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Mean and largest per-axis standard deviation of the accelerometer over `w`.
fn acc_stats(w: &[ImuSample]) -> (Vector3<f64>, f64) {
    let n = w.len() as f64;
    let mean = w.iter().map(|s| s.acc).sum::<Vector3<f64>>() / n;
    let var = w
        .iter()
        .map(|s| (s.acc - mean).component_mul(&(s.acc - mean)))
        .sum::<Vector3<f64>>()
        / n;
    (mean, var.max().sqrt())
}

/// Non-overlapping windows of about `seconds` (at least 5 samples) over `samples` sampled
/// every `dt` s.
fn windows(samples: &[ImuSample], dt: f64, seconds: f64) -> std::slice::Chunks<'_, ImuSample> {
    let n = ((seconds / dt).round() as usize).max(5);
    samples.chunks(n)
}

/// The windows of 0.5 s in which the sensor is still by its accelerometer: largest per-axis
/// standard deviation below 0.2 m/s² (a still MEMS accelerometer shows 0.01–0.05 m/s² per
/// sample at 100–200 Hz; any tilt of a few degrees or a push moves it by more) and mean norm
/// within 1 m/s² of g.
pub fn still_windows(samples: &[ImuSample], dt: f64) -> Vec<&[ImuSample]> {
    windows(samples, dt, 0.5)
        .filter(|w| {
            let (mean, sd) = acc_stats(w);
            sd < 0.2 && (mean.norm() - G).abs() < 1.0
        })
        .collect()
}

/// Fewest still windows (2 s) for a verdict on the gyro across the vertical: a few windows of
/// a moving recording can look steady while it turns.
const MIN_STILL_WINDOWS: usize = 4;

/// Median over the still windows of the gyro's mean reading across the gravity direction
/// (the part perpendicular to the accelerometer's mean), if there are at least
/// [`MIN_STILL_WINDOWS`].
fn still_gyro_norm(samples: &[ImuSample], dt: f64) -> Option<f64> {
    let still = still_windows(samples, dt);
    if still.len() < MIN_STILL_WINDOWS {
        return None;
    }
    let across = still
        .iter()
        .map(|w| {
            let n = w.len() as f64;
            let gyro = w.iter().map(|s| s.gyro).sum::<Vector3<f64>>() / n;
            let up = (w.iter().map(|s| s.acc).sum::<Vector3<f64>>() / n).normalize();
            (gyro - up * gyro.dot(&up)).norm()
        })
        .collect();
    Some(median(across))
}

/// How well each gyro scale explains the turning of the gravity direction (module docs,
/// check 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroScaleFit {
    /// Number of window pairs compared.
    pub pairs: usize,
    /// Median misfit \[rad\] of the gravity direction with the gyro scaled by π/180, 1 and
    /// 180/π (a constant bias fitted for each).
    pub median_error: [f64; 3],
}

/// The candidate gyro scales of [`GyroScaleFit::median_error`].
pub const GYRO_SCALES: [f64; 3] = [
    std::f64::consts::PI / 180.0,
    1.0,
    180.0 / std::f64::consts::PI,
];

impl GyroScaleFit {
    /// The error message if a scale other than 1 explains the data much better: the gyro as
    /// read misses by more than 10° (median) and another scale by less than a third of that.
    pub fn verdict(&self) -> Option<String> {
        let [deg, one, rad] = self.median_error;
        let best_other = deg.min(rad);
        if one < 10f64.to_radians() || best_other >= one / 3.0 {
            return None;
        }
        let (scale, fix) = if deg < rad {
            ("π/180", "the gyro looks like deg/s: set --gyro-unit deg/s")
        } else {
            (
                "180/π",
                "the gyro looks like rad/s, not deg/s: set --gyro-unit rad/s",
            )
        };
        Some(format!(
            "the gyro does not explain how the accelerometer's gravity direction turns: over {} \
             pairs of quasi-static moments 1 s apart it misses by {:.1}° (median), scaled by \
             {scale} by {:.1}°; {fix} (or --no-unit-check)",
            self.pairs,
            one.to_degrees(),
            best_other.to_degrees()
        ))
    }
}

/// One pair of quasi-static moments: gravity direction u at the first and its change Δu, the
/// gyro's integral Ω \[rad\] and the time T \[s\] between them.
struct TiltPair {
    u: Vector3<f64>,
    du: Vector3<f64>,
    omega: Vector3<f64>,
    t: f64,
}

/// Compares the gyro scales of [`GYRO_SCALES`] on pairs of quasi-static 0.25 s windows 1 s
/// apart (accelerometer mean norm within 0.6 m/s² of g, largest per-axis standard deviation
/// below 0.5 m/s²). The body turning by Ω over T moves the unit gravity direction seen in the
/// body frame by Δu ≈ u × (sΩ − T b) (gravity is fixed in the world); for each scale s the
/// constant bias b is fitted by least squares and the misfit is `|Δu − u × (sΩ − T b)|`.
/// `None` when fewer than 10 pairs exist.
pub fn gyro_scale_fit(samples: &[ImuSample], dt: f64) -> Option<GyroScaleFit> {
    let pairs = tilt_pairs(samples, dt);
    if pairs.len() < 10 {
        return None;
    }
    let median_error = GYRO_SCALES.map(|s| {
        let b = fitted_bias(&pairs, s);
        median(
            pairs
                .iter()
                .map(|p| (p.du - p.u.cross(&(p.omega * s - b * p.t))).norm())
                .collect(),
        )
    });
    Some(GyroScaleFit {
        pairs: pairs.len(),
        median_error,
    })
}

/// The pairs of [`gyro_scale_fit`].
fn tilt_pairs(samples: &[ImuSample], dt: f64) -> Vec<TiltPair> {
    let n = ((0.25 / dt).round() as usize).max(5);
    let quasi: Vec<(usize, Vector3<f64>)> = samples
        .chunks(n)
        .enumerate()
        .filter_map(|(k, w)| {
            let (mean, sd) = acc_stats(w);
            ((mean.norm() - G).abs() < 0.6 && sd < 0.5)
                .then(|| (k * n + w.len() / 2, mean.normalize()))
        })
        .collect();
    let mut pairs = Vec::new();
    for (a, &(i, u)) in quasi.iter().enumerate() {
        let Some(&(j, uj)) = quasi[a + 1..].iter().find(|(j, _)| *j == i + 4 * n) else {
            continue;
        };
        let omega = samples[i..j]
            .iter()
            .zip(&samples[i + 1..=j])
            .fold(Vector3::zeros(), |acc, (s0, s1)| {
                acc + s0.gyro * ((s1.t_ns - s0.t_ns) as f64 * 1e-9)
            });
        let t = (samples[j].t_ns - samples[i].t_ns) as f64 * 1e-9;
        pairs.push(TiltPair {
            u,
            du: uj - u,
            omega,
            t,
        });
    }
    pairs
}

/// The bias b minimising `Σ |Δu − u × (sΩ − T b)|²` (zero if unobservable).
fn fitted_bias(pairs: &[TiltPair], s: f64) -> Vector3<f64> {
    let (mut normal, mut rhs) = (nalgebra::Matrix3::zeros(), Vector3::zeros());
    for p in pairs {
        // Δu − s u×Ω = −T u×b = A b with A = −T [u]×.
        let a = -p.t * preint_lie::so3::hat(&p.u);
        normal += a.transpose() * a;
        rhs += a.transpose() * (p.du - p.u.cross(&p.omega) * s);
    }
    normal
        .try_inverse()
        .map_or(Vector3::zeros(), |inv| inv * rhs)
}
