//! An axis' scale: data values to fractions of the axis, with decade ticks on a log axis
//! (labelled every few decades, minor ticks at 2…9 when few decades show) and 1-2-5 steps on a
//! linear one.

/// A mapping from data values to `[0, 1]` with its ticks.
pub(super) struct Scale {
    pub(super) log: bool,
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// (position in the axis' space, label if labelled).
    pub(super) ticks: Vec<(f64, Option<String>)>,
}

impl Scale {
    pub(super) fn new(vals: &[f64], log: bool) -> Self {
        let t: Vec<f64> = vals
            .iter()
            .filter(|v| v.is_finite() && (!log || **v > 0.0))
            .map(|&v| if log { v.log10() } else { v })
            .collect();
        let (mut lo, mut hi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if log {
            log_scale(lo, hi)
        } else {
            linear_scale(lo, hi)
        }
    }

    /// The fraction of the axis at which `v` lies (`None` for a value the axis cannot show).
    pub(super) fn frac(&self, v: f64) -> Option<f64> {
        if !v.is_finite() || (self.log && v <= 0.0) {
            return None;
        }
        let t = if self.log { v.log10() } else { v };
        Some((t - self.lo) / (self.hi - self.lo))
    }
}

fn log_scale(lo: f64, hi: f64) -> Scale {
    let (mut a, mut b) = (lo, hi);
    if b - a < 1.0 {
        let m = 0.5 * (a + b);
        (a, b) = (m - 0.5, m + 0.5);
    }
    let pad = 0.04 * (b - a);
    (a, b) = (a - pad, b + pad);
    let decades: Vec<i32> = (a.ceil() as i32..=b.floor() as i32).collect();
    let step = ((decades.len() as i32 + 6) / 7).max(1);
    let labelled: Vec<i32> = decades.iter().copied().filter(|k| k % step == 0).collect();
    let plain = labelled.iter().all(|k| (-2..=4).contains(k));
    let mut ticks: Vec<(f64, Option<String>)> = decades
        .iter()
        .map(|&k| {
            (
                k as f64,
                labelled.contains(&k).then(|| decade_label(k, plain)),
            )
        })
        .collect();
    if b - a <= 6.5 {
        for k in a.floor() as i32..=b.ceil() as i32 {
            for m in 2..=9 {
                let t = k as f64 + (m as f64).log10();
                if t > a && t < b {
                    let label =
                        (decades.len() <= 1 && (m == 2 || m == 5)).then(|| fmt_num(10f64.powf(t)));
                    ticks.push((t, label));
                }
            }
        }
    }
    Scale {
        log: true,
        lo: a,
        hi: b,
        ticks,
    }
}

fn linear_scale(lo: f64, hi: f64) -> Scale {
    let (lo, hi) = if hi - lo > 0.0 {
        (lo, hi)
    } else {
        (lo - 1.0, hi + 1.0)
    };
    let raw = (hi - lo) / 6.0;
    let p = 10f64.powf(raw.log10().floor());
    let step = p * [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|&f| f * p >= raw)
        .unwrap_or(10.0);
    let (a, b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    let n = ((b - a) / step).round() as i64;
    let ticks = (0..=n)
        .map(|i| {
            let v = a + i as f64 * step;
            (v, Some(fmt_num(v)))
        })
        .collect();
    Scale {
        log: false,
        lo: a,
        hi: b,
        ticks,
    }
}

/// `10^k`: plain (`0.01`, `1000`) or with a superscript exponent.
fn decade_label(k: i32, plain: bool) -> String {
    if plain {
        return fmt_num(10f64.powi(k));
    }
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let digits: String = k
        .unsigned_abs()
        .to_string()
        .chars()
        .map(|c| SUP[c.to_digit(10).unwrap_or(0) as usize])
        .collect();
    format!("10{}{digits}", if k < 0 { "⁻" } else { "" })
}

/// A tick value: up to four decimals without trailing zeros, or one significant digit with
/// an exponent outside `[1e-3, 1e5)`.
fn fmt_num(v: f64) -> String {
    let a = v.abs();
    if a < 1e-12 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_label_decades_and_linear_ticks_nice_steps() {
        let s = Scale::new(&[25.0, 3200.0], true);
        let labels: Vec<&str> = s.ticks.iter().filter_map(|t| t.1.as_deref()).collect();
        assert_eq!(labels, ["100", "1000"]);
        let s = Scale::new(&[1e-14, 1.0], true);
        let labels: Vec<&str> = s.ticks.iter().filter_map(|t| t.1.as_deref()).collect();
        // Fifteen decades: every third one labelled, all as powers of ten.
        assert_eq!(labels, ["10⁻¹²", "10⁻⁹", "10⁻⁶", "10⁻³", "10⁰"]);
        let s = Scale::new(&[0.0, 12.0], false);
        let labels: Vec<&str> = s.ticks.iter().filter_map(|t| t.1.as_deref()).collect();
        assert_eq!(labels, ["0", "2", "4", "6", "8", "10", "12"]);
        assert_eq!(s.frac(6.0), Some(0.5));
        assert_eq!(Scale::new(&[1.0, 2.0], true).frac(-1.0), None);
    }
}
