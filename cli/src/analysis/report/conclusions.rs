//! The conclusions at the top of the report, each computed from the report's numbers.

use super::{
    ADVISE_RECORDING, ADVISE_WINDOW_FRACTION, Curve, FrontRun, NEES_RUNS, ReportData, front_runs,
    hz, nees_band_half,
};
use crate::analysis::accuracy::{Row, order};
use crate::scheme;
use preint::Scheme;
use preint_analysis::speed::Throughput;

/// `[a, b]` as `a Hz` or `a–b Hz`.
fn rate_range(a: f64, b: f64) -> String {
    if a == b {
        format!("{} Hz", hz(a))
    } else {
        format!("{}–{} Hz", hz(a), hz(b))
    }
}

/// `scheme (rates)` of a run of the front.
fn run_label(run: &FrontRun) -> String {
    let (first, last) = (&run.rows[0], &run.rows[run.rows.len() - 1]);
    format!(
        "{} ({})",
        scheme::label(run.scheme),
        rate_range(first.rate, last.rate)
    )
}

/// Which scheme is cheapest for which position-error budget on `scene`, from the runs of the
/// Pareto front ([`front_runs`]): first the scheme that is cheapest for every budget below
/// some error, then the budgets above it; schemes on the front only at their cheapest point,
/// or never, are named.
fn budget_statement(scene: &str, rows: &[Row]) -> String {
    let runs = front_runs(rows);
    let Some((last, above)) = runs.split_last() else {
        return format!("On `{scene}` no error was measured.");
    };
    let lead = match above.last() {
        None => format!(
            "the cheapest for every position-error budget is {}",
            run_label(last)
        ),
        Some(prev) => format!(
            "for any position-error budget below {:.1e} m the cheapest is {}, down to {:.1e} m",
            prev.min_err(),
            run_label(last),
            last.min_err()
        ),
    };
    let parts: Vec<String> = above
        .iter()
        .enumerate()
        .map(|(j, run)| match j {
            0 => format!("≥ {:.1e} m {}", run.min_err(), run_label(run)),
            _ => format!(
                "{:.1e} to {:.1e} m {}",
                run.min_err(),
                above[j - 1].min_err(),
                run_label(run)
            ),
        })
        .collect();
    let above = if parts.is_empty() {
        String::new()
    } else {
        format!("; for larger budgets: {}", parts.join("; "))
    };
    format!(
        "On `{scene}` (1 s window, noise-free), {lead}{above}.{}",
        front_notes(rows, &runs)
    )
}

/// The schemes on the front only at their cheapest point, or never.
fn front_notes(rows: &[Row], runs: &[FrontRun]) -> String {
    let mut notes = Vec::new();
    for s in scheme::ALL {
        let on: Vec<&Row> = runs
            .iter()
            .filter(|r| r.scheme == s)
            .flat_map(|r| &r.rows)
            .collect();
        let lowest = rows
            .iter()
            .filter(|r| r.scheme == s)
            .map(|r| r.rate)
            .fold(f64::INFINITY, f64::min);
        match on.as_slice() {
            [] => notes.push(format!("{} is never the cheapest", scheme::label(s))),
            [only] if only.rate == lowest => notes.push(format!(
                "{} is on the front only at its cheapest point ({} Hz)",
                scheme::label(s),
                hz(only.rate)
            )),
            _ => {}
        }
    }
    if notes.is_empty() {
        String::new()
    } else {
        format!(" {}.", capitalise(&notes.join("; ")))
    }
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map_or(String::new(), |f| f.to_uppercase().chain(c).collect())
}

/// The fitted convergence orders of the position error per scheme, over the scenes.
fn orders_statement(d: &ReportData) -> String {
    let scenes: Vec<String> = d.accuracy.iter().map(|(s, _)| format!("`{s}`")).collect();
    let per: Vec<String> = scheme::ALL
        .iter()
        .map(|&s| {
            let o: Vec<String> = d
                .accuracy
                .iter()
                .map(|(_, rows)| order(rows, s, 2).map_or("–".into(), |o| format!("{o:.2}")))
                .collect();
            format!("{} {}", scheme::label(s), o.join(", "))
        })
        .collect();
    format!(
        "Fitted convergence orders of the position error ({}): {}.",
        scenes.join(", "),
        per.join("; ")
    )
}

/// What `advise` recommends on each scene, and why.
fn advice_statement(d: &ReportData) -> String {
    let (rate, duration) = ADVISE_RECORDING;
    let (_, fraction) = ADVISE_WINDOW_FRACTION;
    let per: Vec<String> = d
        .advice
        .iter()
        .map(|a| match a.recommendation() {
            Some(c) => format!(
                "{} at {} Hz on `{}` ({:.1} µs per second of data)",
                scheme::label(c.scheme),
                hz(c.rate_hz),
                a.scene,
                c.cost_ns_per_s * 1e-3
            ),
            None => format!("nothing on `{}` (no scheme meets the threshold)", a.scene),
        })
        .collect();
    format!(
        "`preint advise` on simulated {duration} s recordings at {rate} Hz with EuRoC noise \
         recommends {}: the cheapest scheme and rate whose discretisation error stays below \
         {fraction}·σ of the noise on rotation, velocity and position.",
        per.join(" and ")
    )
}

/// The cost per sample of each scheme, and the rate ratio at which hermite4 costs as much as
/// midpoint.
fn speed_statement(d: &ReportData) -> String {
    let ns = |f: fn(&Throughput) -> f64| -> Vec<String> {
        d.speed.iter().map(|t| format!("{:.0}", f(t))).collect()
    };
    let cov: Vec<String> = d
        .speed
        .iter()
        .map(|t| format!("{} {:.0} ns", scheme::label(t.scheme), t.covariance))
        .collect();
    let get = |s: Scheme| d.speed.iter().find(|t| t.scheme == s).map(|t| t.covariance);
    let ratio = match (get(Scheme::Hermite4), get(Scheme::Midpoint)) {
        (Some(h), Some(m)) => format!(
            ", so hermite4 is cheaper than midpoint when it allows a rate more than {:.1}× lower",
            h / m
        ),
        _ => String::new(),
    };
    format!(
        "Cost per sample with covariance and bias Jacobians: {} (deltas only: {} ns; with the \
         15×15 covariance: {} ns){ratio}.",
        cov.join(", "),
        ns(|t| t.deltas).join(", "),
        ns(|t| t.combined).join(", ")
    )
}

/// Whether every mean NEES lies in the 3σ band around 9, with the mean over the rows.
fn nees_statement(d: &ReportData) -> String {
    let v: Vec<f64> = d.nees.iter().map(|r| r.2).collect();
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let h = nees_band_half(NEES_RUNS);
    let outside: Vec<String> = d
        .nees
        .iter()
        .filter(|r| (r.2 - 9.0).abs() > h)
        .map(|(scene, s, n)| format!("{} on `{scene}` ({n:.2})", scheme::label(*s)))
        .collect();
    let verdict = if outside.is_empty() {
        format!(
            "The covariance is consistent for every scheme on {} scenes",
            d.accuracy.len()
        )
    } else {
        format!(
            "The covariance is not consistent for {}",
            outside.join(", ")
        )
    };
    format!(
        "{verdict}: mean NEES {mean:.2} over the rows (each {lo:.2}–{hi:.2}; a consistent 9×9 \
         covariance gives 9 ± {h:.2} at 3σ with {NEES_RUNS} runs)."
    )
}

/// The largest attitude error of each representation through the gimbal-lock scene.
fn gimbal_statement(d: &ReportData) -> String {
    let worst = |pts: &[(f64, f64)]| {
        if pts.iter().any(|p| !p.1.is_finite()) {
            f64::INFINITY
        } else {
            pts.iter().map(|p| p.1).fold(0.0, f64::max)
        }
    };
    let (euler, others): (Vec<&Curve>, Vec<&Curve>) =
        d.gimbal_lock.iter().partition(|c| c.0.contains("Euler"));
    let e = euler.first().map_or(f64::NAN, |c| worst(&c.1));
    let o = others.iter().map(|c| worst(&c.1)).fold(0.0, f64::max);
    let e = if e.is_finite() {
        format!("reaches {e:.1e} rad")
    } else {
        "becomes non-finite".into()
    };
    format!(
        "Never integrate Euler angles through pitch ±90°: on `gimbal-lock` their attitude error \
         {e}, against at most {o:.1e} rad with quaternions or rotation matrices (same samples, \
         200 Hz midpoint)."
    )
}

/// How close the static calibration and the Allan fits (per axis) come to the simulated truth.
fn calibration_statement(d: &ReportData) -> String {
    let c = &d.calibration;
    let k = (0..3)
        .map(|i| ((c.cal.gyro_bias[i] - c.truth.gyro[i]) / c.cal.gyro_bias_std[i]).abs())
        .fold(0.0, f64::max);
    let s = &d.allan.simulated;
    let worst = |get: fn(&preint_calib::allan::NoiseFit) -> f64, truth: [f64; 2]| {
        (0..6)
            .map(|ch| 100.0 * (get(&d.allan.allan.fits[ch]) / truth[ch / 3] - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let dens = worst(
        |f| f.white_density,
        [s.gyro_noise_density, s.acc_noise_density],
    );
    let walk = worst(|f| f.random_walk, [s.gyro_random_walk, s.acc_random_walk]);
    format!(
        "The static calibration recovers the gyro bias within {k:.1}σ on every axis; the Allan \
         fits of a simulated hour recover each axis' noise density within {dens:.1} % and its \
         random walk within {walk:.0} % (read from the few long clusters of one hour)."
    )
}

/// The conclusions at the top of the page, each from the numbers of `d`: which scheme is the
/// cheapest for which error budget, the convergence orders, `advise`'s recommendations, the
/// cost per sample, covariance consistency, gimbal lock, calibration and noise fits. Plain
/// text; code is between backticks.
pub fn conclusions(d: &ReportData) -> Vec<String> {
    let mut out: Vec<String> = d
        .accuracy
        .iter()
        .rev()
        .map(|(scene, rows)| budget_statement(scene, rows))
        .collect();
    out.extend([
        orders_statement(d),
        advice_statement(d),
        speed_statement(d),
        nees_statement(d),
        gimbal_statement(d),
        calibration_statement(d),
    ]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::report::tests::rows;

    /// The budgets between the runs of the front; a scheme on the front only at its cheapest
    /// point, and one never on it, are named.
    #[test]
    fn budgets_between_the_runs_of_the_front() {
        let rows = rows();
        let s = budget_statement("x", &rows);
        assert!(
            s.contains(
                "for any position-error budget below 2.5e-3 m the cheapest is hermite4 (25–50 \
                 Hz), down to 6.0e-6 m; for larger budgets: ≥ 1.0e-1 m euler (25 Hz); 2.5e-3 \
                 to 1.0e-1 m midpoint (25–50 Hz)."
            ),
            "{s}"
        );
        assert!(
            s.contains("Euler is on the front only at its cheapest point (25 Hz)"),
            "{s}"
        );
        assert!(s.contains("galilean is never the cheapest"), "{s}");
        let s = budget_statement("x", &rows[2..]);
        assert!(s.contains("Euler is never the cheapest"), "{s}");
    }
}
