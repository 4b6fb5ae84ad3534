//! Real data: KITTI raw drive as shipped with GTSAM (`tests/data/kitti`, README there): the
//! yaw obtained by chaining our preintegrated ΔR over the 1 s GPS intervals follows the GPS
//! heading.
//!
//! Method. IMU rows `Time dt accel… omega…` (seconds of day, OXTS frame x forward, y left,
//! z up, 100 Hz) become `ImuSample`s with exact integer-ns stamps parsed from the decimal text.
//! The initial roll/pitch come from the mean specific force of the first second (levelling);
//! then each GPS interval `[t_k, t_k+1]` is preintegrated (`preint::preintegrate`, midpoint and
//! hermite4, zero bias, `Level::Deltas`) and `R ← R·ΔR`. The GPS heading of an interval is
//! `atan2(ΔY, ΔX)` of the local-level displacement, used only when the speed exceeds 2 m/s
//! (below that, GPS noise dominates the direction). It is compared with the circular mean of
//! the integrated yaw `atan2(R₁₀, R₀₀)` at both ends; the constant offset (unknown initial
//! heading, GPS-vs-body mounting) is removed as the circular mean of the residuals.
//!
//! Asserted: median |residual| ≤ 3° (measured: 0.61° for both schemes on these 120 s). The
//! dataset's curators (`tests/data/README.md`, KITTI) got 1.5° median (95 %: 6.6°) with
//! a plain integral of omegaZ over the full 470 s drive; the residual also contains the car's
//! side-slip and GPS direction noise (≈ 0.1 m over ≥ 2 m → up to ≈ 3°), so 3° is the allowance
//! for the reference, not the integration's accuracy. Power of
//! the test: the drive must turn (GPS heading range > 45°, asserted) and a constant-yaw
//! "integrator" must fail the same bound (asserted), so the pass is not vacuous. ≥ 60 usable
//! intervals are required.

use evidence::{data_dir, median, wrap_pi};
use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuSample, Level, PreintParams, Scheme, preintegrate};

/// Decimal seconds text → integer ns (exact for ≤ 9 decimals; rounds further digits).
fn secs_to_ns(text: &str) -> i64 {
    let (int, frac) = text.split_once('.').unwrap_or((text, ""));
    let mut digits: String = frac.chars().take(10).collect();
    while digits.len() < 10 {
        digits.push('0');
    }
    let f: i64 = digits.parse().expect("fraction digits");
    int.parse::<i64>().expect("integer seconds") * 1_000_000_000 + (f + 5) / 10
}

fn read_imu() -> Vec<ImuSample> {
    let text = std::fs::read_to_string(data_dir().join("kitti/KittiEquivBiasedImu_first120s.txt"))
        .expect("read KITTI IMU");
    let mut out = Vec::new();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(c.len(), 8, "KITTI IMU row: {line}");
        let f = |i: usize| c[i].parse::<f64>().expect("number");
        out.push(ImuSample::new(
            secs_to_ns(c[0]),
            Vector3::new(f(5), f(6), f(7)),
            Vector3::new(f(2), f(3), f(4)),
        ));
    }
    out
}

fn read_gps() -> Vec<(i64, f64, f64)> {
    let text = std::fs::read_to_string(data_dir().join("kitti/KittiGps_converted_first120s.txt"))
        .expect("read KITTI GPS");
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                secs_to_ns(c[0]),
                c[1].parse().unwrap(),
                c[2].parse().unwrap(),
            )
        })
        .collect()
}

/// Roll/pitch from a specific-force vector `f ≈ Rᵀ(0, 0, g)` (yaw 0).
fn level(f: &Vector3<f64>) -> Matrix3<f64> {
    let roll = f.y.atan2(f.z);
    let pitch = (-f.x).atan2((f.y * f.y + f.z * f.z).sqrt());
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    ry * rx
}

fn circ_mean(a: &[f64]) -> f64 {
    let (s, c) = a
        .iter()
        .fold((0.0, 0.0), |(s, c), x| (s + x.sin(), c + x.cos()));
    s.atan2(c)
}

#[test]
fn integrated_yaw_follows_gps_heading() {
    let imu = read_imu();
    let gps = read_gps();
    assert!(imu.len() > 11_000 && gps.len() > 100);
    let t0 = imu[0].t_ns;
    let f0 = imu
        .iter()
        .take_while(|s| s.t_ns < t0 + 1_000_000_000)
        .map(|s| s.acc)
        .sum::<Vector3<f64>>();
    let r0 = level(&f0.normalize());
    let gps: Vec<_> = gps
        .into_iter()
        .filter(|g| g.0 >= imu[0].t_ns && g.0 <= imu[imu.len() - 1].t_ns)
        .collect();

    for scheme in [Scheme::Midpoint, Scheme::Hermite4] {
        let params = PreintParams::default()
            .with_scheme(scheme)
            .with_level(Level::Deltas);
        let mut r = preint_lie::SO3::from_matrix(&r0);
        let mut yaw = vec![r.matrix()[(1, 0)].atan2(r.matrix()[(0, 0)])];
        for w in gps.windows(2) {
            let pim = preintegrate(&params, &ImuBias::zero(), &imu, w[0].0, w[1].0)
                .expect("preintegrate a GPS interval");
            r = r.compose(&pim.delta_r);
            yaw.push(r.matrix()[(1, 0)].atan2(r.matrix()[(0, 0)]));
        }
        let mut heading = vec![];
        let mut res = vec![];
        let mut res_const = vec![];
        for k in 0..gps.len() - 1 {
            let (dx, dy) = (gps[k + 1].1 - gps[k].1, gps[k + 1].2 - gps[k].2);
            let dt = (gps[k + 1].0 - gps[k].0) as f64 * 1e-9;
            if (dx * dx + dy * dy).sqrt() / dt <= 2.0 {
                continue;
            }
            let h = dy.atan2(dx);
            let y_mid = yaw[k] + 0.5 * wrap_pi(yaw[k + 1] - yaw[k]);
            heading.push(h);
            res.push(wrap_pi(h - y_mid));
            res_const.push(wrap_pi(h - yaw[0]));
        }
        let n = res.len();
        assert!(n >= 60, "{scheme:?}: only {n} GPS intervals above 2 m/s");
        let centred = |v: &[f64]| {
            let off = circ_mean(v);
            v.iter()
                .map(|x| wrap_pi(x - off).abs().to_degrees())
                .collect::<Vec<_>>()
        };
        let med = median(&centred(&res));
        let med_const = median(&centred(&res_const));
        let h_range = {
            let c = circ_mean(&heading);
            let d: Vec<f64> = heading.iter().map(|h| wrap_pi(h - c)).collect();
            (d.iter().cloned().fold(f64::MIN, f64::max)
                - d.iter().cloned().fold(f64::MAX, f64::min))
            .to_degrees()
        };
        println!(
            "{scheme:?}: {n} intervals, GPS heading range {h_range:.0}°, median |yaw residual| \
             {med:.2}° (constant-yaw null model {med_const:.1}°)"
        );
        assert!(h_range > 45.0, "the drive does not turn ({h_range}°)");
        assert!(med_const > 3.0, "null model passes: the test has no power");
        assert!(med <= 3.0, "{scheme:?}: median yaw residual {med}° > 3°");
    }
}
