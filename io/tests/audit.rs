//! `preint audit`'s library: each defect of a hand-made recording is found at the index and
//! line where it was put, and the real EuRoC recording is clean, with its rate and jitter equal
//! to the values computed here from the file by other means.

use nalgebra::Vector3;
use preint::ImuSample;
use preint_io::audit::{Audit, AuditOptions, Severity, audit_channels, audit_stream};
use preint_io::plausibility::{median_interval_ns, still_windows};
use preint_io::{ChannelSample, ChannelStream, ImuReader, Located, Location, ReadOptions};
use preint_io::{audit_reader, euroc_imu_string};
use std::path::PathBuf;

const DT: i64 = 5_000_000;
const T0: i64 = 1_403_715_273_262_142_976;

/// A deterministic value in [−1, 1] for sample `k`, axis `a` (a hash, not a sequence).
fn noise(k: usize, a: usize) -> f64 {
    let mut x = (k as u64 * 6 + a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// `n` samples at 200 Hz of a still IMU: gyro bias (0.01, −0.02, 0.005) rad/s, gravity on z,
/// with small noise.
fn still(n: usize) -> Vec<ImuSample> {
    (0..n)
        .map(|k| {
            let w = Vector3::new(0.01, -0.02, 0.005) + Vector3::from_fn(|a, _| 2e-3 * noise(k, a));
            let f = Vector3::new(0.1, 0.2, 9.8) + Vector3::from_fn(|a, _| 0.02 * noise(k, a + 3));
            ImuSample::new(T0 + k as i64 * DT, w, f)
        })
        .collect()
}

/// Audits `samples` written as EuRoC text (header on line 1, sample `k` on line `k + 2`).
fn audit_text(samples: &[ImuSample]) -> Audit {
    let text = euroc_imu_string(samples);
    let reader = ImuReader::from_text(&text, "rec.csv", &ReadOptions::euroc()).unwrap();
    audit_reader(reader, AuditOptions::default())
}

fn kinds(a: &Audit, s: Severity) -> Vec<&'static str> {
    a.findings
        .iter()
        .filter(|f| f.severity == s)
        .map(|f| f.kind)
        .collect()
}

fn message<'a>(a: &'a Audit, kind: &str) -> &'a str {
    &a.findings.iter().find(|f| f.kind == kind).unwrap().message
}

#[test]
fn a_clean_recording_has_no_defect_and_its_exact_rate() {
    let a = audit_text(&still(4000));
    assert!(a.is_clean(), "{:#?}", a.findings);
    assert!(kinds(&a, Severity::Warning).is_empty(), "{:#?}", a.findings);
    assert_eq!(a.timing.samples, 4000);
    assert_eq!(a.timing.median_ns, Some(5e6));
    assert_eq!(a.timing.rate_hz(), Some(200.0));
    assert_eq!(a.timing.span_s(), Some(3999.0 * 0.005));
    assert_eq!(
        (a.timing.sd_ns, a.timing.robust_sd_ns),
        (Some(0.0), Some(0.0))
    );
    assert_eq!(a.timing.histogram[4], 3999, "all in (0.999, 1.001]");
    assert_eq!(a.still.fraction(), 1.0);
    assert!(message(&a, "units").starts_with("units plausible"));
}

#[test]
fn a_duplicate_row_is_reported_at_its_index_and_line() {
    let mut s = still(1000);
    let k = 300;
    s.insert(k + 1, s[k]); // row k written twice: the copy is sample k + 1, line k + 3
    let mut moved = s[701];
    moved.acc.x += 0.01;
    s[700] = ImuSample {
        t_ns: s[701].t_ns,
        ..moved
    }; // another stamp repeated, readings differ
    let a = audit_text(&s);
    assert!(!a.is_clean());
    assert_eq!(kinds(&a, Severity::Defect), ["duplicates"]);
    let d = &a.timing.duplicates;
    assert_eq!(d.count, 2);
    assert_eq!(
        (d.first[0].index, d.first[0].at),
        (k as u64 + 1, Location::Line(k as u64 + 3))
    );
    assert_eq!(d.first[0].prev_at, Location::Line(k as u64 + 2));
    assert_eq!(a.identical_duplicates, 1);
    let m = message(&a, "duplicates");
    assert!(m.contains("index 301 (line 303) repeats"), "{m}");
    assert!(m.contains("1 of them repeat the readings"), "{m}");
}

#[test]
fn an_out_of_order_pair_is_reported_once_at_the_late_sample() {
    let mut s = still(1000);
    let k = 400;
    s.swap(k, k + 1); // stamps k+1 then k
    let a = audit_text(&s);
    assert_eq!(kinds(&a, Severity::Defect), ["out_of_order"]);
    let o = &a.timing.out_of_order;
    assert_eq!(o.count, 1);
    assert_eq!(o.first[0].index, k as u64 + 1);
    assert_eq!(o.first[0].at, Location::Line(k as u64 + 3));
    assert_eq!(o.first[0].dt_ns(), -DT);
    assert!(message(&a, "out_of_order").contains("index 401 (line 403)"));
    // The swap also opens a gap of two intervals before it (documented).
    assert_eq!(a.timing.gaps.count, 1);
    assert_eq!(a.timing.gaps.first[0].index, k as u64);
}

#[test]
fn a_one_second_gap_is_a_defect_at_the_sample_after_it() {
    let mut s = still(2000);
    let k = 1234;
    for x in &mut s[k..] {
        x.t_ns += 1_000_000_000;
    }
    let a = audit_text(&s);
    assert_eq!(kinds(&a, Severity::Defect), ["long_gaps"]);
    assert_eq!(kinds(&a, Severity::Warning), ["gaps"]);
    let g = a.timing.largest_gap.unwrap();
    assert_eq!(
        (g.index, g.at, g.dt_ns()),
        (k as u64, Location::Line(k as u64 + 2), 1_005_000_000)
    );
    assert_eq!(a.timing.long_gaps.count, 1);
    assert_eq!(a.timing.missing_samples, 200);
    assert!(message(&a, "long_gaps").contains("1.005000 s before index 1234 (line 1236"));
    // The gap is not in the jitter, and the nominal rate is unchanged.
    assert_eq!(
        (a.timing.rate_hz(), a.timing.sd_ns),
        (Some(200.0), Some(0.0))
    );
}

#[test]
fn a_clipped_axis_is_found_with_its_first_flat_top() {
    // acc x swings ±12 m/s² at 0.5 Hz and is clipped at ±10: flat tops at both extremes.
    let mut s = still(2000);
    for (k, x) in s.iter_mut().enumerate() {
        let raw = 12.0 * (std::f64::consts::PI * k as f64 * 0.005).sin() + 0.02 * noise(k, 9);
        x.acc.x = raw.clamp(-10.0, 10.0);
    }
    let first_run = |v: f64| (0..s.len() - 2).find(|&k| (0..3).all(|j| s[k + j].acc.x == v));
    let (top, bottom) = (first_run(10.0).unwrap(), first_run(-10.0).unwrap());
    let a = audit_text(&s);
    assert_eq!(kinds(&a, Severity::Defect), ["clipping"]);
    let ax = &a.axes.unwrap()[3];
    assert_eq!((ax.name, ax.max, ax.min), ("acc x", 10.0, -10.0));
    assert_eq!(
        ax.at_max.first,
        Some((top as u64, Location::Line(top as u64 + 2)))
    );
    assert_eq!(ax.at_min.first.unwrap().0, bottom as u64);
    let at_limit = s.iter().filter(|x| x.acc.x.abs() == 10.0).count() as u64;
    assert!(ax.at_max.samples + ax.at_min.samples <= at_limit);
    assert!(ax.at_max.samples + ax.at_min.samples > at_limit * 9 / 10);
    let m = message(&a, "clipping");
    assert!(
        m.contains(&format!("first at index {top} (line {})", top + 2)),
        "{m}"
    );
    // The other axes are noisy: no flat top.
    assert!(
        a.axes
            .unwrap()
            .iter()
            .filter(|x| x.name != "acc x")
            .all(|x| x.at_max.runs == 0)
    );
}

#[test]
fn a_gyro_in_deg_per_s_is_a_units_defect_and_in_rad_per_s_is_not() {
    // A still IMU whose gyro bias is (0.4, −0.3, 0.2) deg/s, written without conversion.
    let mut s = still(12_000);
    for x in &mut s {
        x.gyro = Vector3::new(0.4, -0.3, 0.2) + x.gyro * 0.1;
    }
    let a = audit_text(&s);
    assert_eq!(kinds(&a, Severity::Defect), ["units"]);
    assert!(message(&a, "units").contains("--gyro-unit deg/s"));
    let u = a.units.as_ref().unwrap();
    assert_eq!(u.samples, 12_000);
    assert!((u.gravity_median_m_s2 - Vector3::new(0.1_f64, 0.2, 9.8).norm()).abs() < 0.02);
    for x in &mut s {
        x.gyro *= std::f64::consts::PI / 180.0;
    }
    assert!(audit_text(&s).is_clean());
}

#[test]
fn non_finite_readings_and_unreadable_rows_are_counted_not_fatal() {
    let mut s = still(600);
    s[50].acc.y = f64::NAN;
    let located: Vec<_> = s
        .iter()
        .enumerate()
        .map(|(k, x)| {
            Ok(Located {
                at: Location::Line(k as u64 + 2),
                sample: *x,
            })
        })
        .collect();
    let a = audit_stream(located.into_iter(), "rec", AuditOptions::default());
    assert_eq!(kinds(&a, Severity::Defect), ["non_finite"]);
    assert_eq!(a.non_finite.first, [(50, Location::Line(52))]);
    // The text reader refuses a `nan` field: the row is listed with its line, reading goes on.
    let text = euroc_imu_string(&still(600));
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let stamp = lines[101].split(',').next().unwrap().to_string();
    lines[101] = format!("{stamp},nan,0,0,0,0,9.8"); // line 102
    let text = lines.join("\n");
    let reader = ImuReader::from_text(&text, "rec.csv", &ReadOptions::euroc()).unwrap();
    let a = audit_reader(reader, AuditOptions::default());
    assert_eq!(a.bad_rows.count, 1);
    assert_eq!(a.bad_rows.first[0].at, Location::Line(102));
    assert!(a.bad_rows.first[0].message.starts_with("rec.csv:102:"));
    assert_eq!(a.timing.samples, 599);
    assert_eq!(kinds(&a, Severity::Defect), ["bad_rows"]);
    // One missing row leaves a gap of two intervals (a warning, not a defect).
    assert_eq!(a.timing.gaps.count, 1);
}

#[test]
fn drift_is_the_rate_change_from_the_first_to_the_last_tenth() {
    // The interval grows linearly by 0.2 % over the recording: the rate of the last tenth is
    // (1 + 0.05 ε) / (1 + 0.95 ε) − 1 ≈ −1796 ppm of the first's, ε = 2e-3.
    let n = 12_800;
    let eps = 2e-3;
    let mut t = T0;
    let mut s = still(n);
    for (k, x) in s.iter_mut().enumerate() {
        x.t_ns = t;
        t += (DT as f64 * (1.0 + eps * k as f64 / n as f64)).round() as i64;
    }
    let a = audit_text(&s);
    let expected = ((1.0 + 0.05 * eps) / (1.0 + 0.95 * eps) - 1.0) * 1e6;
    let drift = a.timing.drift_ppm().unwrap();
    assert!((drift - expected).abs() < 10.0, "{drift} vs {expected}");
    assert_eq!(kinds(&a, Severity::Warning), ["drift"]);
}

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// EuRoC V1_01: no defect; rate and jitter equal to what the file gives when read here with
/// `str::parse` (the stamps exceed an f64's 53 bits, so they are read as integers).
#[test]
fn euroc_is_clean_with_the_rate_and_jitter_of_the_file() {
    let path = repo("tests/data/euroc/V1_01_easy_imu0.csv");
    let a = audit_reader(
        ImuReader::open(&path, &ReadOptions::default()).unwrap(),
        AuditOptions::default(),
    );
    assert!(a.is_clean(), "{:#?}", a.findings);
    let text = std::fs::read_to_string(&path).unwrap();
    let t: Vec<i64> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let n = t.len();
    assert_eq!(a.timing.samples, n as u64);
    let mean = (t[n - 1] - t[0]) as f64 / (n - 1) as f64;
    assert!((a.timing.mean_ns.unwrap() / mean - 1.0).abs() < 1e-12);
    let rate = a.timing.rate_hz().unwrap();
    assert!(
        (rate * mean * 1e-9 - 1.0).abs() < 2e-5,
        "{rate} Hz vs 1/{mean} ns"
    );
    let mut d: Vec<i64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let sd = {
        let m = d.iter().sum::<i64>() as f64 / d.len() as f64;
        (d.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / d.len() as f64).sqrt()
    };
    assert!(
        (a.timing.sd_ns.unwrap() / sd - 1.0).abs() < 1e-9,
        "{:?} vs {sd}",
        a.timing.sd_ns
    );
    d.sort_unstable();
    assert_eq!(a.timing.median_ns, Some(d[d.len() / 2] as f64));
    let mad = {
        let m = d[d.len() / 2];
        let mut dev: Vec<i64> = d.iter().map(|x| (x - m).abs()).collect();
        dev.sort_unstable();
        dev[dev.len() / 2] as f64
    };
    assert_eq!(a.timing.robust_sd_ns, Some(1.4826 * mad));
    assert_eq!(a.timing.histogram.iter().sum::<u64>(), n as u64 - 1);
    // The still fraction is plausibility's still windows over the same 0.5 s windows.
    let samples = ImuReader::open(&path, &ReadOptions::default())
        .unwrap()
        .read_all()
        .unwrap();
    let dt = median_interval_ns(&samples) * 1e-9;
    let still = still_windows(&samples, dt).len() as u64;
    assert_eq!(
        (a.still.still, a.still.windows),
        (still, (n as u64).div_ceil(100))
    );
    assert!(
        a.axes
            .unwrap()
            .iter()
            .all(|x| x.at_max.runs + x.at_min.runs == 0)
    );
}

/// A split stream: gyro at 200 Hz, accelerometer at 62.5 Hz starting 3 ms later, a duplicate
/// gyro stamp; offsets equal to the nearest-stamp offsets found here by brute force.
#[test]
fn split_streams_report_each_channel_and_the_stamp_offsets() {
    let gyro_t: Vec<i64> = (0..400)
        .map(|k| T0 + k * DT)
        .chain([T0 + 399 * DT])
        .collect();
    let accel_t: Vec<i64> = (0..120).map(|k| T0 + 3_000_000 + k * 16_000_000).collect();
    let channel = |t: &[i64], v: f64| -> ChannelStream {
        let samples: Vec<_> = (t.iter().enumerate())
            .map(|(k, &t_ns)| {
                let value = Vector3::new(v, 0.0, 0.0) + Vector3::from_fn(|a, _| 1e-3 * noise(k, a));
                Ok(ChannelSample {
                    at: Location::Line(k as u64 + 1),
                    t_ns,
                    value,
                })
            })
            .collect();
        Box::new(samples.into_iter())
    };
    let a = audit_channels(
        channel(&gyro_t, 0.01),
        channel(&accel_t, 9.81),
        "g+a",
        AuditOptions::default(),
    );
    assert!(!a.is_clean());
    let dup = &a.gyro.timing.duplicates;
    assert_eq!((dup.count, dup.first[0].index), (1, 400));
    assert!(
        a.findings[0]
            .message
            .starts_with("gyro: 1 duplicate timestamp: index 400 (line 401)")
    );
    assert_eq!(a.accel.timing.rate_hz(), Some(62.5));
    assert_eq!(a.gyro.timing.rate_hz(), Some(200.0));
    let nearest: Vec<i64> = (accel_t.iter())
        .filter(|&&t| t <= gyro_t[399])
        .map(|&t| {
            let g = gyro_t
                .iter()
                .min_by_key(|&&g| ((t - g).abs(), -(t - g)))
                .unwrap();
            t - g
        })
        .collect();
    let o = &a.offsets;
    assert_eq!(o.count, nearest.len() as u64);
    assert_eq!(
        (o.min_ns, o.max_ns),
        (
            *nearest.iter().min().unwrap(),
            *nearest.iter().max().unwrap()
        )
    );
    let mean = nearest.iter().sum::<i64>() as f64 / nearest.len() as f64;
    assert!((o.mean_ns - mean).abs() < 1e-6);
    assert_eq!(
        o.coincident,
        nearest.iter().filter(|&&d| d == 0).count() as u64
    );
    let after = gyro_t
        .iter()
        .filter(|&&g| g > *accel_t.last().unwrap())
        .count() as u64;
    assert_eq!(
        (o.gyro_before, o.gyro_after, o.accel_before, o.accel_after),
        (1, after, 0, 0)
    );
}

#[test]
fn a_signal_below_its_resolution_is_not_clipped() {
    // gyro z in steps of 1 mrad/s with noise below a step: it reads 0 mostly and ±1 mrad/s in
    // 8 % of the samples, sometimes three in a row, but mostly alone.
    let mut s = still(4000);
    for (k, x) in s.iter_mut().enumerate() {
        x.gyro.z = 1e-3 * (0.6 * noise(k, 2)).round();
    }
    let runs = (0..s.len() - 2)
        .filter(|&k| (0..3).all(|j| s[k + j].gyro.z == 1e-3))
        .count();
    assert!(runs > 0, "the data has runs of three at its maximum");
    let a = audit_text(&s);
    assert!(a.is_clean(), "{:#?}", a.findings);
    let z = &a.axes.unwrap()[2];
    assert!(z.at_max.runs > 0 && !z.at_max.clipped());
    let at_max = s.iter().filter(|x| x.gyro.z == 1e-3).count() as u64;
    assert_eq!(z.at_max.total, at_max);
}

#[test]
fn the_prefix_size_changes_nothing_but_the_unit_check_when_the_reference_is_the_same() {
    let mut s = still(5000);
    s.swap(4000, 4001);
    s[4500].t_ns = s[4499].t_ns;
    let audit = |prefix_samples| {
        let located = (s.iter().enumerate()).map(|(k, x)| {
            Ok(Located {
                at: Location::Line(k as u64 + 2),
                sample: *x,
            })
        });
        let opts = AuditOptions {
            prefix_samples,
            max_listed: 20,
            ..AuditOptions::default()
        };
        audit_stream(located, "rec", opts)
    };
    let (small, whole) = (audit(100), audit(1 << 15));
    assert_eq!(small.timing, whole.timing);
    let timing = |a: &Audit| {
        a.findings
            .iter()
            .filter(|f| f.kind != "units")
            .cloned()
            .collect::<Vec<_>>()
    };
    assert_eq!(timing(&small), timing(&whole));
    assert_eq!(small.still, whole.still);
}

#[test]
fn no_samples_and_one_stamp_are_reported_not_fatal() {
    let a = audit_stream(std::iter::empty(), "none", AuditOptions::default());
    assert_eq!(kinds(&a, Severity::Defect), ["empty"]);
    let one = still(1)[0];
    let same = (0..10).map(|k| {
        Ok(Located {
            at: Location::Message(k + 1),
            sample: one,
        })
    });
    let a = audit_stream(same, "bag", AuditOptions::default());
    assert_eq!(a.timing.duplicates.count, 9);
    assert_eq!(a.timing.duplicates.first[8].at, Location::Message(10));
    assert!(message(&a, "rate").contains("no two samples have different stamps"));
}

proptest::proptest! {
    /// Whatever the stamps and readings, every interval is counted once: duplicates,
    /// out-of-order samples and positive intervals (binned in the histogram) add up to n − 1.
    #[test]
    fn every_interval_is_counted_once(
        rows in proptest::collection::vec((0i64..50, -3.0f64..3.0, 0u8..8), 0..400),
        prefix in 1usize..64,
    ) {
        let mut t = 0;
        let located = rows.iter().enumerate().map(|(k, &(step, v, special))| {
            t += step * 1_000_000 - 5_000_000;
            let x = match special { 0 => f64::NAN, 1 => f64::INFINITY, _ => v };
            let sample = ImuSample::new(t, Vector3::new(x, v, 0.0), Vector3::new(v, 0.0, 9.8));
            Ok(Located { at: Location::Line(k as u64 + 1), sample })
        });
        let opts = AuditOptions { prefix_samples: prefix, max_listed: 5, ..AuditOptions::default() };
        let a = audit_stream(located, "p", opts);
        let n = rows.len() as u64;
        let tm = &a.timing;
        let positive: u64 = tm.histogram.iter().sum();
        proptest::prop_assert_eq!(tm.samples, n);
        proptest::prop_assert_eq!(
            positive + tm.duplicates.count + tm.out_of_order.count,
            n.saturating_sub(1)
        );
        let special = rows.iter().filter(|r| r.2 < 2).count() as u64;
        proptest::prop_assert_eq!(a.non_finite.count, special);
        proptest::prop_assert!(tm.duplicates.first.len() <= 5);
        proptest::prop_assert_eq!(a.is_clean(), a.findings.iter().all(|f| f.severity != Severity::Defect));
    }
}

#[test]
fn stamps_at_the_ends_of_the_i64_range_do_not_overflow() {
    let stamps = [i64::MAX, i64::MIN, 0, i64::MAX, i64::MIN + 1, -1, i64::MAX];
    let one = still(1)[0];
    let located = (stamps.iter().enumerate()).map(|(k, &t_ns)| {
        Ok(Located {
            at: Location::Line(k as u64 + 1),
            sample: ImuSample { t_ns, ..one },
        })
    });
    let a = audit_stream(located, "edge", AuditOptions::default());
    assert_eq!(
        (a.timing.out_of_order.count, a.timing.duplicates.count),
        (4, 2)
    );
    assert_eq!(a.timing.out_of_order.first[0].dt_ns(), i64::MIN);
    assert!(
        message(&a, "out_of_order")
            .contains(&format!("{} ns before line 1", i64::MIN.unsigned_abs()))
    );
    let gyro: ChannelStream = Box::new(
        stamps
            .map(|t_ns| {
                Ok(ChannelSample {
                    at: Location::Line(1),
                    t_ns,
                    value: one.gyro,
                })
            })
            .into_iter(),
    );
    let accel: ChannelStream = Box::new(
        [i64::MIN, 0, i64::MAX]
            .map(|t_ns| {
                Ok(ChannelSample {
                    at: Location::Line(1),
                    t_ns,
                    value: one.acc,
                })
            })
            .into_iter(),
    );
    let s = audit_channels(gyro, accel, "edge", AuditOptions::default());
    assert_eq!(s.gyro.timing.samples, 7);
}

/// Each channel of a split recording gets the unit checks it allows on its own: an accelerometer
/// in g and a gyro of exact zeros are defects, the same streams in SI are not.
#[test]
fn split_channels_are_checked_for_units() {
    let t: Vec<i64> = (0..300).map(|k| T0 + k * DT).collect();
    let channel = |v: Vector3<f64>, jitter: f64| -> ChannelStream {
        let samples: Vec<_> = (t.iter().enumerate())
            .map(|(k, &t_ns)| {
                Ok(ChannelSample {
                    at: Location::Line(k as u64 + 1),
                    t_ns,
                    value: v + Vector3::from_fn(|a, _| jitter * noise(k, a)),
                })
            })
            .collect();
        Box::new(samples.into_iter())
    };
    let (gyro, up) = (Vector3::new(0.01, 0.0, 0.0), Vector3::new(0.0, 0.0, 9.81));
    let units = |a: &preint_io::audit::SplitAudit| {
        (a.findings.iter())
            .filter(|f| f.kind == "units" && f.severity == Severity::Defect)
            .map(|f| f.message.clone())
            .collect::<Vec<_>>()
    };
    let si = audit_channels(
        channel(gyro, 1e-3),
        channel(up, 1e-2),
        "si",
        AuditOptions::default(),
    );
    assert!(units(&si).is_empty(), "{:?}", units(&si));
    let in_g = audit_channels(
        channel(gyro, 1e-3),
        channel(up / 9.80665, 1e-3),
        "g",
        AuditOptions::default(),
    );
    let m = units(&in_g);
    assert!(
        m.len() == 1 && m[0].starts_with("accel: ") && m[0].contains("--accel-unit g"),
        "{m:?}"
    );
    let zero = audit_channels(
        channel(Vector3::zeros(), 0.0),
        channel(up, 1e-2),
        "zero",
        AuditOptions::default(),
    );
    let m = units(&zero);
    assert!(m.len() == 1 && m[0].contains("exactly 0"), "{m:?}");
}

#[test]
fn an_impossible_reading_is_a_defect_and_a_spike_a_warning_at_their_index_and_line() {
    let mut s = still(4000);
    s[1200].acc.y = 1e308;
    s[3000].gyro.x += 0.5; // 0.5 rad/s for one sample, the neighbours at the bias
    let a = audit_text(&s);
    assert_eq!(kinds(&a, Severity::Defect), ["impossible"]);
    assert_eq!(kinds(&a, Severity::Warning), ["spikes"]);
    let i = &a.impossible.first[0];
    assert_eq!(
        (a.impossible.count, i.index, i.at),
        (1, 1200, Location::Line(1202))
    );
    let p = &a.spikes.first[0];
    assert_eq!(
        (a.spikes.count, p.index, p.at, p.axis),
        (1, 3000, Location::Line(3002), 0)
    );
    // The hash noise is uniform in ±2e-3 rad/s: the robust σ of its changes is ≈ 2.3e-3.
    assert!(p.sigmas > 100.0 && p.sigmas < 400.0, "{p:?}");
    assert!(message(&a, "spikes").contains("index 3000 (line 3002) gyro x"));
    // The impossible sample is left out of the spikes and the unit checks.
    assert!(a.units.as_ref().unwrap().error.is_none());
}

#[test]
fn a_recording_too_short_to_judge_is_not_clean_and_units_that_cannot_be_told_warn() {
    use preint_io::audit::Verdict;
    for n in [1, 99, 150] {
        // 150 samples span 0.745 s.
        let a = audit_text(&still(n));
        assert_eq!(a.verdict(), Verdict::TooShort, "{n}: {:#?}", a.findings);
        assert!(a.is_clean(), "no defect");
        assert!(!message(&a, "too_short").is_empty());
    }
    let one = audit_text(&still(1));
    assert!(one.still.windows == 0, "one sample is no 0.5 s window");
    // 300 samples (1.5 s): judged; its units cannot be told (fewer than 4 still windows).
    let a = audit_text(&still(300));
    assert_eq!(a.verdict(), Verdict::Clean);
    assert_eq!(kinds(&a, Severity::Warning), ["units"]);
    assert!(message(&a, "units").starts_with("unit check inconclusive: gyro unit"));
}
