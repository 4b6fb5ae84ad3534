//! Split gyro / accelerometer streams (200 Hz gyro, 63 Hz accelerometer, as a RealSense
//! publishes them) merged by `preint_io::split` and preintegrated with the effective noise of
//! `preint_io::split::effective_noise`, against the baseline "accelerometer linearly
//! interpolated onto the gyro stamps, accelerometer density used as is" (computed here, not by
//! the code under test). See `docs/SPLIT_STREAMS.md` for the model.
//!
//! Setup. Gyro and accelerometer sampled from the scene's analytic state (ideal readings
//! `ω_b`, `R_wbᵀ(a − g)`) on their own grids, plus white noise with the EuRoC densities at each
//! stream's own rate (per-sample std `σ/√h`, drawn by the suite's seeded `evidence::Gauss`),
//! no bias. Window `[1 s, 2 s]` (gyro stamps at both ends), `Level::Covariance`. The error is
//! `e = [Log(ΔR_refᵀ ΔR), Δv − Δv_ref, Δp − Δp_ref]`, NEES `eᵀΣ⁻¹e` with each run's `cov`. The
//! reference is the exact deltas of the scene (`preint_sim::exact_deltas`) for hermite4; for
//! midpoint it is midpoint on the noise-free IMU at the gyro stamps (accelerometer known
//! there), so that midpoint's own O(h²) error, common to every way of merging (0.30 of NEES
//! on `aggressive` at 200 Hz), is not charged to the merge.
//!
//! Cases:
//! - RealSense: gyro `k·5 ms` (200 Hz), accelerometer `k·15 873 016 ns` (63 Hz); scenes
//!   `seed-ellipse` and `aggressive`; midpoint and hermite4. Asserted: (1) the RMS Δv error
//!   of the merge over the realisations is at most the baseline's (same noise draws), and its
//!   noise-free Δv error is at most the baseline's; (2) the mean NEES of the merge with the
//!   effective noise is within 9 ± 0.3 (N = 2 000: the std of the mean of χ²₉ draws is
//!   `√(18/N)` = 0.095, so ±0.3 is ±3.2σ; `PREINT_FULL=1`: N = 20 000, std 0.03).
//! - Accelerometer faster than the gyro: gyro 100 Hz, accelerometer 400 Hz with stamps 1.25 ms
//!   after the gyro's (λ = ½ at every gyro stamp); `seed-ellipse`, midpoint. Asserted: mean
//!   NEES of the merge with the effective noise within 9 ± 0.3 (ρ = 4·(2·(1/16)² + 2·(9/16)²)
//!   = 2.5625 here). The Δv errors are recorded, not asserted: at λ = ½ linear interpolation
//!   averages two samples (Σw² = ½) and the cubic one has Σw² = 0.64, so the baseline has the
//!   smaller noise (docs/SPLIT_STREAMS.md).
//!
//! The NEES of the baseline and of the merge with the accelerometer density as is (the
//! effective-noise ablation) are printed and recorded, not asserted.
//!
//! Output: `target/evidence/split_streams.json`.

use evidence::monte_carlo::{nees, realise};
use evidence::{Gauss, full_run, mean, write_json};
use nalgebra::{SVector, Vector3};
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, PreintParams, PreintegratedImu, Scheme, preintegrate,
};
use preint_io::split::{MergeReport, effective_noise, merge_with_report};
use preint_io::{ChannelSample, Format, Location, ReadOptions, SourceInfo, Units};
use preint_lie::SO3;
use preint_sim::{Scene, exact_deltas, scene_by_name, t_s};
use serde_json::Value;

const T_I: i64 = 1_000_000_000;
const T_J: i64 = 2_000_000_000;

fn realisations() -> usize {
    if full_run() { 20_000 } else { 2_000 }
}

fn g() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

/// Two sample grids and what is asserted on them.
struct Case {
    label: &'static str,
    gyro_period: i64,
    accel_period: i64,
    /// Accelerometer stamps are `k·accel_period + accel_offset`.
    accel_offset: i64,
    scenes: &'static [&'static str],
    schemes: &'static [Scheme],
    /// Assert that the merge's Δv errors are at most the baseline's.
    assert_dv: bool,
}

const CASES: [Case; 2] = [
    Case {
        label: "gyro 200 Hz, accel 63 Hz",
        gyro_period: 5_000_000,
        // round(1e9 / 63) ns.
        accel_period: 15_873_016,
        accel_offset: 0,
        scenes: &["seed-ellipse", "aggressive"],
        schemes: &[Scheme::Midpoint, Scheme::Hermite4],
        assert_dv: true,
    },
    Case {
        label: "gyro 100 Hz, accel 400 Hz",
        gyro_period: 10_000_000,
        accel_period: 2_500_000,
        accel_offset: 1_250_000,
        scenes: &["seed-ellipse"],
        schemes: &[Scheme::Midpoint],
        assert_dv: false,
    },
];

/// Ideal readings of `scene` at stamps `k·period + offset` covering `[T_I − 60 ms, T_J + 60 ms]`.
fn ideal(scene: &dyn Scene, period: i64, offset: i64) -> Vec<ImuSample> {
    let (k0, k1) = ((T_I - 60_000_000) / period, (T_J + 60_000_000) / period + 1);
    (k0..=k1)
        .map(|k| {
            let t = k * period + offset;
            scene.state(t_s(t)).ideal_sample(t, &g())
        })
        .collect()
}

fn channel(v: Vec<(i64, Vector3<f64>)>) -> preint_io::ChannelStream {
    Box::new(v.into_iter().enumerate().map(|(k, (t_ns, value))| {
        Ok(ChannelSample {
            at: Location::Line(k as u64 + 1),
            t_ns,
            value,
        })
    }))
}

/// The merge under test: samples and report.
fn merged(
    gyro: &[(i64, Vector3<f64>)],
    acc: &[(i64, Vector3<f64>)],
) -> (Vec<ImuSample>, MergeReport) {
    let info = SourceInfo {
        source_name: "sim-gyro + sim-accel".into(),
        format: Format::Delimited,
        layout: None,
        units: Units::SI_NS,
        notes: vec![],
        warnings: Vec::new(),
    };
    let (reader, handle) = merge_with_report(
        channel(gyro.to_vec()),
        channel(acc.to_vec()),
        info,
        &ReadOptions::default(),
    )
    .unwrap();
    let s = reader.read_all().unwrap();
    (s, handle.report())
}

/// The baseline: accelerometer linearly interpolated between the bracketing samples.
fn linear(gyro: &[(i64, Vector3<f64>)], acc: &[(i64, Vector3<f64>)]) -> Vec<ImuSample> {
    let mut j = 0;
    gyro.iter()
        .filter(|(t, _)| *t >= acc[0].0 && *t < acc[acc.len() - 1].0)
        .map(|&(t, w)| {
            while acc[j + 1].0 <= t {
                j += 1;
            }
            let l = (t - acc[j].0) as f64 / (acc[j + 1].0 - acc[j].0) as f64;
            ImuSample::new(t, w, acc[j].1 * (1.0 - l) + acc[j + 1].1 * l)
        })
        .collect()
}

fn error(m: &PreintegratedImu, truth: &(SO3, Vector3<f64>, Vector3<f64>)) -> SVector<f64, 9> {
    let r = m.delta_r.minus(&truth.0);
    let (v, p) = (m.delta_v - truth.1, m.delta_p - truth.2);
    SVector::<f64, 9>::from_column_slice(&[r.x, r.y, r.z, v.x, v.y, v.z, p.x, p.y, p.z])
}

fn params(noise: &ImuNoise, scheme: Scheme) -> PreintParams {
    PreintParams::from_noise(noise)
        .with_scheme(scheme)
        .with_level(Level::Covariance)
        .with_gravity(g())
}

fn pairs(s: &[ImuSample], gyro: bool) -> Vec<(i64, Vector3<f64>)> {
    s.iter()
        .map(|x| (x.t_ns, if gyro { x.gyro } else { x.acc }))
        .collect()
}

/// The NEES and the squared Δv error of `m` against `reference`.
fn figures(m: &PreintegratedImu, reference: &Deltas) -> [f64; 2] {
    let e = error(m, reference);
    [nees(&e, &m.cov), e.fixed_rows::<3>(3).norm_squared()]
}

/// The draws of [`figures`] of one way of merging.
struct Stats<'a> {
    nees: &'a [f64],
    dv_sq: &'a [f64],
}

impl Stats<'_> {
    fn rms_dv(&self) -> f64 {
        mean(self.dv_sq).sqrt()
    }
}

type Deltas = (SO3, Vector3<f64>, Vector3<f64>);

/// The reference deltas (see the module docs).
fn reference(scene: &dyn Scene, scheme: Scheme, p: &PreintParams, gyro_period: i64) -> Deltas {
    match scheme {
        Scheme::Midpoint => {
            let s = ideal(scene, gyro_period, 0);
            let m = preintegrate(p, &ImuBias::zero(), &s, T_I, T_J).unwrap();
            (m.delta_r, m.delta_v, m.delta_p)
        }
        _ => exact_deltas(scene, T_I, T_J, g()),
    }
}

/// Monte Carlo of one scene and scheme of `case`; returns its JSON record and appends
/// failures.
fn run(case: &Case, si: usize, name: &str, scheme: Scheme, failures: &mut Vec<String>) -> Value {
    let n_real = realisations();
    let noise = ImuNoise::euroc();
    let (hg, ha) = (
        case.gyro_period as f64 * 1e-9,
        case.accel_period as f64 * 1e-9,
    );
    let (sg, sa) = (noise.gyro_sample_std(hg), noise.acc_sample_std(ha));
    let bias = ImuBias::zero();
    let scene = scene_by_name(name).unwrap();
    let gyro0 = pairs(&ideal(scene.as_ref(), case.gyro_period, 0), true);
    let acc0 = pairs(
        &ideal(scene.as_ref(), case.accel_period, case.accel_offset),
        false,
    );
    let p0 = params(&noise, scheme);
    let truth = reference(scene.as_ref(), scheme, &p0, case.gyro_period);
    let dv0 = |s: &[ImuSample]| {
        let m = preintegrate(&p0, &bias, s, T_I, T_J).unwrap();
        error(&m, &truth).fixed_rows::<3>(3).norm()
    };
    let (dv0_ours, dv0_base) = (dv0(&merged(&gyro0, &acc0).0), dv0(&linear(&gyro0, &acc0)));
    let draw = |rng: &mut Gauss| {
        let gyro: Vec<_> = gyro0
            .iter()
            .map(|&(t, w)| (t, w + rng.normal3(sg)))
            .collect();
        let acc: Vec<_> = acc0
            .iter()
            .map(|&(t, a)| (t, a + rng.normal3(sa)))
            .collect();
        (gyro, acc)
    };
    // Per realisation: the merge with the effective noise, with the density as is, the
    // baseline (NEES and squared Δv error of each), then ρ and the effective σ_a.
    let f = realise(n_real, (si as u64) << 40, draw, |_, (gyro, acc)| {
        let (s, report) = merged(gyro, acc);
        let eff = effective_noise(&noise, &report);
        let m = preintegrate(&params(&eff, scheme), &bias, &s, T_I, T_J).unwrap();
        let [ours, as_is, base] = [
            m,
            preintegrate(&p0, &bias, &s, T_I, T_J).unwrap(),
            preintegrate(&p0, &bias, &linear(gyro, acc), T_I, T_J).unwrap(),
        ]
        .map(|m| figures(&m, &truth));
        [
            ours,
            as_is,
            base,
            [report.white_ratio(), eff.acc_noise_density],
        ]
        .concat()
    });
    let stats = |k: usize| Stats {
        nees: &f[2 * k],
        dv_sq: &f[2 * k + 1],
    };
    let (ours, as_is, base) = (stats(0), stats(1), stats(2));
    let (rho, eff_a) = (&f[6], &f[7]);
    let (n_ours, n_base, n_as_is) = (mean(ours.nees), mean(base.nees), mean(as_is.nees));
    let sname = format!("{scheme:?}").to_lowercase();
    println!(
        "{}: {name:<13} {sname:<9} N = {n_real}: mean NEES9 merge {n_ours:.3} (density as is \
         {n_as_is:.3}), linear + σ_a {n_base:.3}; RMS |Δv error| merge {:.4e}, linear {:.4e} \
         m/s; noise-free |Δv error| merge {dv0_ours:.3e}, linear {dv0_base:.3e} m/s; mean ρ \
         {:.5}, mean σ_a,eff {:.5e}",
        case.label,
        ours.rms_dv(),
        base.rms_dv(),
        mean(rho),
        mean(eff_a)
    );
    let tag = format!("{}: {name} {sname}", case.label);
    if (n_ours - 9.0).abs() > 0.3 {
        failures.push(format!("{tag}: mean NEES9 {n_ours:.3} ∉ 9 ± 0.3"));
    }
    if case.assert_dv && ours.rms_dv() > base.rms_dv() {
        failures.push(format!(
            "{tag}: RMS Δv error {:.4e} > linear {:.4e}",
            ours.rms_dv(),
            base.rms_dv()
        ));
    }
    if case.assert_dv && dv0_ours > dv0_base {
        failures.push(format!(
            "{tag}: noise-free Δv error above linear interpolation's"
        ));
    }
    serde_json::json!({
        "case": case.label, "scene": name, "scheme": sname, "realisations": n_real,
        "mean_nees_9_merge": n_ours, "mean_nees_9_merge_density_as_is": n_as_is,
        "mean_nees_9_linear_baseline": n_base,
        "rms_dv_error_merge": ours.rms_dv(), "rms_dv_error_linear": base.rms_dv(),
        "noise_free_dv_error_merge": dv0_ours, "noise_free_dv_error_linear": dv0_base,
        "mean_white_ratio": mean(rho), "mean_acc_noise_density_eff": mean(eff_a),
    })
}

#[test]
fn merged_split_streams_are_consistent_and_no_worse_than_linear_interpolation() {
    let mut records = vec![];
    let mut failures = vec![];
    for case in &CASES {
        for (si, name) in case.scenes.iter().enumerate() {
            for &scheme in case.schemes {
                records.push(run(case, si, name, scheme, &mut failures));
            }
        }
    }
    write_json(
        "split_streams.json",
        &serde_json::json!({
            "description": "split gyro/accelerometer streams merged (cubic Hermite, effective noise) vs linear interpolation with the accelerometer density as is; window [1 s, 2 s], EuRoC densities",
            "tangent_order": "[dphi, dv, dp]",
            "results": records,
        }),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
