//! The sections of the report page, each a heading, its prose, its charts (written into the
//! output directory and embedded) and its tables.

use super::failed;
use crate::analysis::accuracy::{Row, order};
use crate::analysis::report::{
    ADVISE_RECORDING, ADVISE_WINDOW_FRACTION, AdviceCheck, AllanCheck, NEES_RUNS, ReportData,
    SPEED_SAMPLES_RUNS, StaticCheck, front_runs, hz, nees_band_half, worst_ratio,
};
use crate::charts::figures;
use crate::html::Page;
use crate::{CliError, scheme};
use preint_analysis::advise::Candidate;
use preint_analysis::format::IMU_AXES;
use preint_calib::allan::ImuAllan;
use std::path::Path;

fn e3(x: f64) -> String {
    format!("{x:.3e}")
}

/// Accuracy against cost: per scene, the chart and the Pareto front as a table. Returns the
/// chart paths.
pub(super) fn accuracy_section(
    page: &mut Page,
    data: &ReportData,
    out: &Path,
) -> Result<Vec<String>, CliError> {
    page.h2("Accuracy against cost: the cheapest scheme for an error budget");
    page.p(
        "Noise-free samples of each scene at 25–3200 Hz, preintegrated over the window \
            [1 s, 2 s] and compared with the scene's exact deltas. Cost = measured ns per sample \
            (with covariance and bias Jacobians) × rate, i.e. the time to integrate one second of \
            IMU data. A point is on the Pareto front when no other scheme and rate is both \
            cheaper and more accurate: for a given error budget, the cheapest choice is the first \
            front point below it.",
    );
    let mut files = Vec::new();
    for (scene, rows) in &data.accuracy {
        let path = figures::accuracy_vs_cost(rows, scene, out)?;
        page.svg(&path, &format!("`{scene}`: position error of the 1 s window against the cost of integrating one second of IMU data, one line per scheme (a point per rate, 25 Hz at the left). The thin grey dashed line, drawn under the scheme lines, and the grey rings mark the Pareto front; hover over a point for its rate.")).map_err(failed)?;
        let table: Vec<Vec<String>> = front_runs(rows)
            .iter()
            .flat_map(|run| &run.rows)
            .map(|r: &Row| {
                vec![
                    scheme::label(r.scheme).into(),
                    hz(r.rate),
                    format!("{:.2}", r.cost_per_s() * 1e-3),
                    e3(r.err[2]),
                ]
            })
            .collect();
        page.p(&format!("Pareto front on `{scene}`, cheapest first:"));
        page.table(
            &[
                "scheme",
                "rate [Hz]",
                "cost [µs per s of data]",
                "position error [m]",
            ],
            &table,
        );
        files.push(path.display().to_string());
    }
    Ok(files)
}

/// Error against rate: per scene, the two-panel chart and the 200 Hz table. Returns the chart
/// paths.
pub(super) fn convergence_section(
    page: &mut Page,
    data: &ReportData,
    out: &Path,
) -> Result<Vec<String>, CliError> {
    page.h2("Error against rate: convergence order");
    let mut files = Vec::new();
    for (scene, rows) in &data.accuracy {
        let path = figures::convergence(rows, scene, out)?;
        page.svg(&path, &format!("`{scene}`: rotation and position error against rate; the legend gives each scheme's fitted log-log slope (its convergence order), over the points above the round-off floor (1e-13).")).map_err(failed)?;
        let table: Vec<Vec<String>> = rows
            .iter()
            .filter(|r| r.rate == 200.0)
            .map(|r| {
                vec![
                    scheme::label(r.scheme).into(),
                    e3(r.err[0]),
                    e3(r.err[1]),
                    e3(r.err[2]),
                    format!("{:.1}", r.ns_per_sample),
                    format!("{:.2}", order(rows, r.scheme, 2).unwrap_or(f64::NAN)),
                ]
            })
            .collect();
        page.p(&format!(
            "`{scene}` at 200 Hz, 1 s window, noise-free, against the exact deltas:"
        ));
        page.table(
            &[
                "scheme",
                "rotation [rad]",
                "velocity [m/s]",
                "position [m]",
                "ns/sample",
                "order (pos)",
            ],
            &table,
        );
        files.push(path.display().to_string());
    }
    Ok(files)
}

/// What `advise` recommends on each scene: the chart, the recommendation and, per scheme, its
/// lowest acceptable rate. Returns the chart's path.
pub(super) fn advice_section(
    page: &mut Page,
    advice: &[AdviceCheck],
    out: &Path,
) -> Result<String, CliError> {
    let ((rate, duration), (window, fraction)) = (ADVISE_RECORDING, ADVISE_WINDOW_FRACTION);
    page.h2("What `preint advise` recommends for a noisy recording");
    page.p(&format!("`preint advise` on a simulated {duration} s recording of each scene at {rate} Hz with \
        EuRoC noise (bias random walk on): the white noise is removed by a zero-phase low-pass, \
        each scheme's discretisation error over {window} s windows is measured at the recording's \
        rate and at decimated rates against `hermite4` at the full rate, and compared with the \
        noise-induced σ of the preintegrated deltas. Acceptable: all three errors (rotation, \
        velocity, position) below {fraction}·σ. Recommended: the cheapest acceptable (scheme, rate); \
        costs within 15 % of the cheapest count as equal and the simplest scheme among them wins."));
    let path = out.join("advise.svg");
    let scenes: Vec<Advised> = advice
        .iter()
        .map(|a| (a.scene, a.candidates.as_slice(), a.recommended))
        .collect();
    figures::advice(&scenes, fraction, &path)?;
    page.svg(&path, &format!("Worst ratio of discretisation error to noise σ (over rotation, velocity and position) against rate; below the grey dashed line ({fraction}·σ) a (scheme, rate) is acceptable; the black ring marks the recommendation.")).map_err(failed)?;
    let rows = advice_rows(&scenes, rate);
    page.p("Per scheme, its lowest acceptable rate:");
    page.table(
        &[
            "scene",
            "scheme",
            "rate [Hz]",
            "worst error / σ",
            "cost [µs per s of data]",
            "",
        ],
        &rows,
    );
    let cut = |c: Option<f64>| c.map_or("none".into(), |c| format!("{c:.2} Hz"));
    let cuts: Vec<String> = advice
        .iter()
        .map(|a| {
            format!(
                "`{}` gyro {}, accelerometer {}",
                a.scene,
                cut(a.cutoffs[0]),
                cut(a.cutoffs[1])
            )
        })
        .collect();
    page.p(&format!("Low-pass cutoffs found: {}.", cuts.join("; ")));
    Ok(path.display().to_string())
}

/// One recording `advise` ran on: its name, every (scheme, rate) evaluated and the index of
/// the recommendation.
pub(super) type Advised<'a> = (&'a str, &'a [Candidate], Option<usize>);

/// The advice table's rows: per recording and scheme its lowest acceptable rate, its worst
/// error over σ, its cost and whether it is the recommendation (`none up to` the recording's
/// `rate` \[Hz\] when no rate is acceptable).
pub(super) fn advice_rows(advice: &[Advised], rate: f64) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for &(scene, candidates, recommended) in advice {
        let rec = recommended.map(|i| &candidates[i]);
        for s in scheme::ALL {
            let ok = candidates
                .iter()
                .filter(|c| c.scheme == s && c.acceptable)
                .min_by(|x, y| x.rate_hz.total_cmp(&y.rate_hz));
            rows.push(match ok {
                Some(c) => vec![
                    format!("`{scene}`"),
                    scheme::label(s).into(),
                    hz(c.rate_hz),
                    format!("{:.3}", worst_ratio(c)),
                    format!("{:.1}", c.cost_ns_per_s * 1e-3),
                    if rec.is_some_and(|r| std::ptr::eq(r, c)) {
                        "recommended"
                    } else {
                        ""
                    }
                    .into(),
                ],
                None => vec![
                    format!("`{scene}`"),
                    scheme::label(s).into(),
                    format!("none up to {} Hz", hz(rate)),
                    "".into(),
                    "".into(),
                    "".into(),
                ],
            });
        }
    }
    rows
}

/// The speed table: median ns per sample per scheme and level.
pub(super) fn speed_section(page: &mut Page, data: &ReportData) {
    let (samples, runs) = SPEED_SAMPLES_RUNS;
    page.h2("Speed: cost per sample");
    page.p(&format!("Median of {runs} runs of `Preintegrator::integrate_slice` over a synthetic smooth \
        200 Hz stream of {samples} samples, nothing stored, on this machine (`preint speed` measures the \
        same with more samples and runs). Multiply by the rate for the cost per second of data."));
    let rows: Vec<Vec<String>> = data
        .speed
        .iter()
        .map(|t| {
            vec![
                scheme::label(t.scheme).into(),
                format!("{:.1}", t.deltas),
                format!("{:.1}", t.covariance),
                format!("{:.1}", t.combined),
            ]
        })
        .collect();
    page.table(
        &[
            "scheme",
            "deltas only [ns]",
            "+ 9×9 covariance and bias Jacobians [ns]",
            "+ 15×15 covariance [ns]",
        ],
        &rows,
    );
}

/// The NEES table.
pub(super) fn nees_section(page: &mut Page, data: &ReportData) {
    page.h2("Covariance consistency (Monte Carlo NEES)");
    let rows: Vec<Vec<String>> = data
        .nees
        .iter()
        .map(|(scene, s, n)| {
            vec![
                format!("`{scene}`"),
                scheme::label(*s).into(),
                format!("{n:.3}"),
            ]
        })
        .collect();
    let runs = NEES_RUNS;
    let half = nees_band_half(runs);
    page.p(&format!("{runs} noise realisations per row (EuRoC densities, 200 Hz, 1 s window); mean of eᵀΣ⁻¹e with \
        e = [Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀] against the noise-free run. A consistent 9×9 covariance gives 9; \
        with {runs} runs the 3σ band is [{:.2}, {:.2}]. (The test suite, `cargo test -p evidence --test nees`, runs 2 000 per row; `PREINT_FULL=1` runs 20 000.)", 9.0 - half, 9.0 + half));
    page.table(&["scene", "scheme", "mean NEES"], &rows);
}

/// The gimbal-lock chart. Returns its path.
pub(super) fn gimbal_lock_section(
    page: &mut Page,
    data: &ReportData,
    out: &Path,
) -> Result<String, CliError> {
    page.h2("Where methods fail: Euler angles at gimbal lock");
    let path = out.join("gimbal_lock.svg");
    figures::attitude_error(
        &data.gimbal_lock,
        "gimbal-lock scene, 200 Hz midpoint dead reckoning",
        &path,
    )?;
    page.svg(&path, "Attitude error against time; the scene passes exactly through pitch ±90° at t = 2, 6, 10 s. At the first pass the Euler-angle integration's error jumps by orders of magnitude and stays there: the body-rate→Euler-rate matrix has 1/cos(pitch) terms, so steps near ±90° move roll and yaw by large, grid-dependent amounts, and the error no longer shrinks with the rate as the scheme's order says (a run that starts at the lock is off by O(1) rad at every rate). Quaternion and SO(3) integration stay at their discretisation error.").map_err(failed)?;
    Ok(path.display().to_string())
}

/// The static calibration against the true biases.
pub(super) fn calibration_section(page: &mut Page, c: &StaticCheck) {
    page.h2("Bias calibration from a simulated static recording");
    let (truth, cal) = (&c.truth, &c.cal);
    let rows: Vec<Vec<String>> = (0..3)
        .map(|k| {
            vec![
                ["x", "y", "z"][k].into(),
                format!("{:.6}", truth.gyro[k]),
                format!("{:.6}", cal.gyro_bias[k]),
                format!("{:.1e}", cal.gyro_bias_std[k]),
                format!(
                    "{:.2}",
                    (cal.gyro_bias[k] - truth.gyro[k]) / cal.gyro_bias_std[k]
                ),
            ]
        })
        .collect();
    page.p("60 s at 200 Hz, one attitude, EuRoC noise, constant biases. Gauss-Newton estimate of the gyro bias [rad/s] with its standard deviation; the accelerometer bias is reported unobservable at one attitude (it cannot be separated from tilt):");
    page.table(&["axis", "true b_g", "estimate", "σ", "error / σ"], &rows);
    page.p(&format!("`acc_bias`: {}", cal.acc_bias_note));
}

/// The Allan charts of both sensors (`allan_gyro.svg`, `allan_acc.svg` in `out`), embedded
/// with their captions. Returns their paths.
pub(super) fn allan_charts(
    page: &mut Page,
    allan: &ImuAllan,
    out: &Path,
) -> Result<Vec<String>, CliError> {
    let mut files = Vec::new();
    for (sensor, name, unit) in [(0, "gyro", "rad/s"), (1, "acc", "m/s²")] {
        let path = out.join(format!("allan_{name}.svg"));
        figures::allan(allan, sensor, &path)?;
        let what = if sensor == 0 {
            "gyroscope"
        } else {
            "accelerometer"
        };
        page.svg(&path, &format!("Overlapping Allan deviation of the three {what} axes [{unit}], with the fitted white-noise (dashed) and random-walk (dotted) lines in each axis' colour; the diamonds mark N at τ = 1 s and the squares K at τ = 3 s.")).map_err(failed)?;
        files.push(path.display().to_string());
    }
    Ok(files)
}

/// The Allan charts of both sensors and the fitted densities per axis. Returns the charts'
/// paths.
pub(super) fn allan_section(
    page: &mut Page,
    a: &AllanCheck,
    out: &Path,
) -> Result<Vec<String>, CliError> {
    page.h2("Allan deviation of a simulated static hour");
    let sim = &a.simulated;
    page.p(&format!("One hour at rest at {} Hz with EuRoC densities and bias random walk. The fitted white-noise \
        line (slope −½) read at τ = 1 s gives the noise density N, the random-walk line (slope +½) read at \
        τ = 3 s gives K; the Kalibr `imu.yaml` that `preint allan` writes takes the maximum over the axes.", sim.update_rate_hz));
    let files = allan_charts(page, &a.allan, out)?;
    let (sn, sk) = (
        [sim.gyro_noise_density, sim.acc_noise_density],
        [sim.gyro_random_walk, sim.acc_random_walk],
    );
    let rows: Vec<Vec<String>> = (0..6)
        .map(|c| {
            let f = &a.allan.fits[c];
            let bound = |b: bool| if b { "≤ " } else { "" };
            vec![
                format!("`{}`", IMU_AXES[c]),
                format!("{}{}", bound(f.white_density_is_bound), e3(f.white_density)),
                e3(sn[c / 3]),
                format!("{}{}", bound(f.random_walk_is_bound), e3(f.random_walk)),
                e3(sk[c / 3]),
            ]
        })
        .collect();
    page.p("Fitted and simulated densities per axis (gyro: N in rad/s/√Hz, K in rad/s²/√Hz; accelerometer: N in m/s²/√Hz, K in m/s³/√Hz; ≤: an upper bound, no region of that slope in the data):");
    page.table(
        &["axis", "N fitted", "N simulated", "K fitted", "K simulated"],
        &rows,
    );
    Ok(files)
}
