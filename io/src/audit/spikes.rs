//! Single-sample spikes: a reading far from both of its neighbours while the neighbours agree
//! with each other. A sensor sampling a band-limited signal cannot produce one; a corrupt or
//! mis-parsed row, a bit flip or an electrical glitch does.
//!
//! The scale is the axis' own: σ = 1.4826 × the median absolute deviation of its
//! sample-to-sample changes over the audit's prefix (noise, vibration and motion included),
//! at least its resolution (the smallest non-zero change). Sample k is a spike on an axis when
//! it lies on the same side of both neighbours, at least [`SPIKE_SIGMAS`] σ from each, and
//! the neighbours differ from each other by at most a quarter of that distance. Its size is
//! that distance in σ. For Gaussian noise the change over one sample has σ√2 of the noise
//! level, and a reading 20 such σ from both neighbours is a 28σ event: never. (EuRoC, KITTI,
//! the ADIS16405 hour and the BROAD excerpt in `tests/data` have none.)

use super::intervals::EventList;
use crate::error::Location;

/// Distance from both neighbours, in robust σ of the sample-to-sample change, from which a
/// reading is a spike.
pub const SPIKE_SIGMAS: f64 = 20.0;

/// One spike: where, on which axis (0–5 in the order of [`super::AXES`]), how far from its
/// neighbours (in robust σ of the axis' change) and the reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spike {
    /// 0-based sample index.
    pub index: u64,
    /// Where it is in the source.
    pub at: Location,
    /// Axis, in the order of [`super::AXES`] (the axis with the largest spike).
    pub axis: usize,
    /// Distance from the nearer neighbour, in robust σ.
    pub sigmas: f64,
    /// The reading (rad/s or m/s²).
    pub value: f64,
}

/// Finds spikes in a stream of readings, three at a time.
#[derive(Clone, Debug)]
pub(crate) struct Spikes {
    sigma: [f64; 6],
    window: [Option<(u64, Location, [f64; 6])>; 2],
    pub(crate) found: EventList<Spike>,
    limit: usize,
}

impl Spikes {
    /// A detector whose scales come from `prefix` (the readings of the prefix, in order);
    /// `limit` spikes are listed.
    pub(crate) fn new(prefix: &[[f64; 6]], limit: usize) -> Self {
        Self {
            sigma: std::array::from_fn(|c| robust_change_sigma(prefix.iter().map(|v| v[c]))),
            window: [None, None],
            found: EventList::default(),
            limit,
        }
    }

    /// Adds the next readings; the sample before them is judged.
    pub(crate) fn push(&mut self, index: u64, at: Location, v: [f64; 6]) {
        if let [Some((_, _, a)), Some((i, where_, m))] = self.window {
            let mut best: Option<Spike> = None;
            for c in 0..6 {
                let s = self.sigma[c];
                let (d1, d2) = (m[c] - a[c], m[c] - v[c]);
                let near = d1.abs().min(d2.abs());
                if s > 0.0
                    && d1 * d2 > 0.0
                    && near >= SPIKE_SIGMAS * s
                    && (v[c] - a[c]).abs() <= 0.25 * near
                    && best.is_none_or(|b| near / s > b.sigmas)
                {
                    best = Some(Spike {
                        index: i,
                        at: where_,
                        axis: c,
                        sigmas: near / s,
                        value: m[c],
                    });
                }
            }
            if let Some(b) = best {
                self.found.push(b, self.limit);
            }
        }
        self.window = [self.window[1], Some((index, at, v))];
    }

    /// Forgets the neighbours (a sample that is not judged breaks the sequence).
    pub(crate) fn gap(&mut self) {
        self.window = [None, None];
    }
}

/// 1.4826 × the median absolute deviation of the changes between consecutive values, at
/// least the smallest non-zero change; 0 when the values never change.
fn robust_change_sigma(values: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = values.collect();
    let mut d: Vec<f64> = v.windows(2).map(|w| w[1] - w[0]).collect();
    let resolution = d
        .iter()
        .map(|x| x.abs())
        .filter(|&x| x > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !resolution.is_finite() {
        return 0.0;
    }
    let median = |x: &mut Vec<f64>| {
        let mid = x.len() / 2;
        *x.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let m = median(&mut d);
    let mut dev: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    (1.4826 * median(&mut dev)).max(resolution)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lone_reading_far_from_agreeing_neighbours_is_a_spike_and_a_step_is_not() {
        let noise = |k: usize| ((k * 7919) % 13) as f64 * 0.01 - 0.06;
        let mut x: Vec<[f64; 6]> = (0..200).map(|k| [noise(k); 6]).collect();
        let sigma = robust_change_sigma(x.iter().map(|v| v[0]));
        assert!(sigma > 0.0);
        let mut s = Spikes::new(&x, 5);
        x[50][3] += 100.0 * sigma; // a spike on acc x
        for v in &mut x[120..] {
            v[1] += 100.0 * sigma; // a step on gyro y: the neighbours do not agree
        }
        for (k, v) in x.iter().enumerate() {
            s.push(k as u64, Location::Line(k as u64 + 2), *v);
        }
        assert_eq!(s.found.count, 1, "{:?}", s.found.first);
        let f = s.found.first[0];
        assert_eq!((f.index, f.at, f.axis), (50, Location::Line(52), 3));
        assert!(f.sigmas > 90.0 && f.sigmas < 101.0, "{f:?}");
    }
}
