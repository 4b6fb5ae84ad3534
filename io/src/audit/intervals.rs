//! The timing of a stream in bounded memory: intervals between consecutive stamps, their
//! median, spread and drift, gaps, duplicates and samples that go back in time.
//!
//! Every interval is measured from the latest stamp seen so far (the running maximum), so one
//! late sample is reported once, as out of order, and does not make the samples after it look
//! out of order too. A swapped pair `a, c, b, d` shows as a gap `c − a` of two intervals, `b`
//! out of order, then `d − c`.

use crate::error::Location;

/// An interval above this multiple of the reference interval is a gap (a sample or more is
/// missing).
pub const GAP_FACTOR: f64 = 1.5;

/// A gap longer than this is refused by the integrator (`preint::DEFAULT_MAX_GAP_NS`,
/// 0.25 s) and is a defect; shorter gaps are warnings.
pub const LONG_GAP_NS: i64 = preint::DEFAULT_MAX_GAP_NS;

/// Upper edges of the Δt histogram in multiples of the reference interval: bin `k` counts the
/// intervals with Δt/reference in `(EDGES[k-1], EDGES[k]]` (`(0, 0.5]` for the first); the
/// last is unbounded.
pub const HISTOGRAM_EDGES: [f64; 12] = [
    0.5,
    0.9,
    0.99,
    0.999,
    1.001,
    1.01,
    1.1,
    GAP_FACTOR,
    2.0,
    5.0,
    10.0,
    f64::INFINITY,
];

/// The fine histogram that gives the median and the MAD spans ± this fraction of the
/// reference interval, in `2 FINE_HALF_BINS + 1` bins.
const FINE_HALF_WIDTH: f64 = 0.05;
const FINE_HALF_BINS: i64 = 2048;

/// Number of blocks kept for the drift (merged pairwise when full).
const MAX_BLOCKS: usize = 128;

/// One sample of interest: the sample at `index` (0-based, in stream order) and the latest
/// sample before it (largest stamp so far).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// 0-based index of the sample in stream order.
    pub index: u64,
    /// Where the sample is in the source.
    pub at: Location,
    /// Its stamp \[ns\].
    pub t_ns: i64,
    /// Stamp of the latest sample before it \[ns\].
    pub prev_t_ns: i64,
    /// Where that sample is.
    pub prev_at: Location,
}

impl Event {
    /// `t_ns − prev_t_ns` \[ns\] (saturated to the `i64` range): the gap, 0 for a
    /// duplicate, negative out of order.
    pub fn dt_ns(&self) -> i64 {
        self.t_ns.saturating_sub(self.prev_t_ns)
    }
}

/// A count and the first few of them.
#[derive(Clone, Debug, PartialEq)]
pub struct EventList<T> {
    /// How many there are.
    pub count: u64,
    /// The first ones, in stream order (at most the audit's `max_listed`).
    pub first: Vec<T>,
}

impl<T> Default for EventList<T> {
    fn default() -> Self {
        Self {
            count: 0,
            first: Vec::new(),
        }
    }
}

impl<T> EventList<T> {
    /// Counts `e` and keeps it if fewer than `limit` are kept.
    pub fn push(&mut self, e: T, limit: usize) {
        self.count += 1;
        if self.first.len() < limit {
            self.first.push(e);
        }
    }
}

/// What one interval was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The first sample.
    First,
    /// A regular interval (0 < Δt ≤ [`GAP_FACTOR`] × reference).
    Regular,
    /// A gap.
    Gap,
    /// The same stamp as the latest sample.
    Duplicate,
    /// A stamp before the latest sample's.
    OutOfOrder,
}

/// The timing of a stream (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// Number of samples.
    pub samples: u64,
    /// Stamp of the first sample \[ns\].
    pub first_t_ns: Option<i64>,
    /// Largest stamp \[ns\].
    pub last_t_ns: Option<i64>,
    /// The interval the histogram and the gap threshold are relative to \[ns\]: the median of
    /// the positive intervals of the stream's first samples (the audit's prefix).
    pub reference_ns: Option<i64>,
    /// Median of the positive intervals \[ns\] (mean of the fine-histogram bin holding it).
    pub median_ns: Option<f64>,
    /// Width of the fine-histogram bins \[ns\]: the resolution of the median and the MAD.
    pub resolution_ns: i64,
    /// Mean of the positive intervals \[ns\].
    pub mean_ns: Option<f64>,
    /// Standard deviation of the regular intervals (gaps left out) \[ns\].
    pub sd_ns: Option<f64>,
    /// 1.4826 × the median absolute deviation of the positive intervals from their median
    /// \[ns\] (a robust standard deviation); `None` when more than half of them are more than
    /// 5 % away from the median.
    pub robust_sd_ns: Option<f64>,
    /// Rate over the first and the last tenth of the stream \[Hz\], from the mean regular
    /// interval of each (tenths rounded to the blocks of the bounded summary).
    pub tenth_rates_hz: Option<(f64, f64)>,
    /// Counts of positive intervals in the bins of [`HISTOGRAM_EDGES`].
    pub histogram: [u64; 12],
    /// Positive intervals outside ± 5 % of the reference: below, above.
    pub outside_fine: (u64, u64),
    /// Gaps (Δt > [`GAP_FACTOR`] × reference).
    pub gaps: EventList<Event>,
    /// Samples missing in the gaps: Σ (round(Δt / reference) − 1).
    pub missing_samples: u64,
    /// Gaps longer than [`LONG_GAP_NS`].
    pub long_gaps: EventList<Event>,
    /// The largest gap.
    pub largest_gap: Option<Event>,
    /// Samples with the stamp of the latest sample before them.
    pub duplicates: EventList<Event>,
    /// Samples with a stamp before the latest sample's.
    pub out_of_order: EventList<Event>,
}

impl Timing {
    /// Nominal rate \[Hz\]: 1 / median interval.
    pub fn rate_hz(&self) -> Option<f64> {
        self.median_ns.map(|m| 1e9 / m)
    }

    /// Span from the first to the latest stamp \[s\].
    pub fn span_s(&self) -> Option<f64> {
        Some((self.last_t_ns? as i128 - self.first_t_ns? as i128) as f64 * 1e-9)
    }

    /// Rate change from the first to the last tenth \[ppm\] (positive: faster at the end).
    pub fn drift_ppm(&self) -> Option<f64> {
        self.tenth_rates_hz.map(|(a, b)| (b / a - 1.0) * 1e6)
    }
}

/// The median of the positive consecutive differences of `stamps` \[ns\] (upper median), if
/// any.
pub fn reference_interval(stamps: impl Iterator<Item = i64>) -> Option<i64> {
    let mut prev = None;
    let mut d: Vec<i64> = Vec::new();
    for t in stamps {
        if let Some(p) = prev
            && t > p
        {
            d.push(t.saturating_sub(p));
        }
        prev = Some(prev.map_or(t, |p: i64| p.max(t)));
    }
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    Some(*d.select_nth_unstable(mid).1)
}

/// Accumulates [`Timing`] sample by sample in fixed memory (plus the first `limit` events of
/// each kind).
#[derive(Clone, Debug)]
pub struct TimingStats {
    limit: usize,
    reference: Option<i64>,
    width: i64,
    counts: Vec<u64>,
    sums: Vec<i128>,
    out: Timing,
    latest: Option<(i64, Location)>,
    positive: u64,
    positive_sum: i128,
    welford: (u64, f64, f64),
    blocks: Vec<(u64, i128)>,
    block_len: u64,
}

impl TimingStats {
    /// Statistics relative to `reference` \[ns\] (from [`reference_interval`]; `None`: the
    /// first positive interval), keeping the first `limit` events of each kind.
    pub fn new(reference: Option<i64>, limit: usize) -> Self {
        let mut s = Self {
            limit,
            reference: None,
            width: 1,
            counts: Vec::new(),
            sums: Vec::new(),
            out: Timing {
                samples: 0,
                first_t_ns: None,
                last_t_ns: None,
                reference_ns: None,
                median_ns: None,
                resolution_ns: 1,
                mean_ns: None,
                sd_ns: None,
                robust_sd_ns: None,
                tenth_rates_hz: None,
                histogram: [0; 12],
                outside_fine: (0, 0),
                gaps: EventList::default(),
                missing_samples: 0,
                long_gaps: EventList::default(),
                largest_gap: None,
                duplicates: EventList::default(),
                out_of_order: EventList::default(),
            },
            latest: None,
            positive: 0,
            positive_sum: 0,
            welford: (0, 0.0, 0.0),
            blocks: Vec::with_capacity(MAX_BLOCKS),
            block_len: 1,
        };
        if let Some(r) = reference.filter(|&r| r > 0) {
            s.set_reference(r);
        }
        s
    }

    fn set_reference(&mut self, r: i64) {
        self.reference = Some(r);
        self.width = ((r as f64 * FINE_HALF_WIDTH / FINE_HALF_BINS as f64).round() as i64).max(1);
        let bins = (2 * FINE_HALF_BINS + 1) as usize;
        self.counts = vec![0; bins];
        self.sums = vec![0; bins];
    }

    /// Adds the sample at `index` with stamp `t_ns` found at `at`; says what its interval was.
    pub fn push(&mut self, index: u64, at: Location, t_ns: i64) -> Step {
        self.out.samples += 1;
        let Some((prev, prev_at)) = self.latest else {
            self.out.first_t_ns = Some(t_ns);
            self.latest = Some((t_ns, at));
            return Step::First;
        };
        let event = Event {
            index,
            at,
            t_ns,
            prev_t_ns: prev,
            prev_at,
        };
        if t_ns == prev {
            self.out.duplicates.push(event, self.limit);
            return Step::Duplicate;
        }
        if t_ns < prev {
            self.out.out_of_order.push(event, self.limit);
            return Step::OutOfOrder;
        }
        self.latest = Some((t_ns, at));
        self.positive_interval(index, event)
    }

    fn positive_interval(&mut self, index: u64, event: Event) -> Step {
        let dt = event.dt_ns();
        let r = *self.reference.get_or_insert(dt);
        if self.counts.is_empty() {
            self.set_reference(r);
        }
        self.positive += 1;
        self.positive_sum += dt as i128;
        let ratio = dt as f64 / r as f64;
        let bin = HISTOGRAM_EDGES
            .iter()
            .position(|&e| ratio <= e)
            .unwrap_or(11);
        self.out.histogram[bin] += 1;
        let k = ((dt - r) as f64 / self.width as f64).round();
        if k < -(FINE_HALF_BINS as f64) {
            self.out.outside_fine.0 += 1;
        } else if k > FINE_HALF_BINS as f64 {
            self.out.outside_fine.1 += 1;
        } else {
            let k = (k as i64 + FINE_HALF_BINS) as usize;
            self.counts[k] += 1;
            self.sums[k] += dt as i128;
        }
        if ratio <= GAP_FACTOR {
            self.regular(index, dt);
            return Step::Regular;
        }
        self.gap(event, ratio);
        Step::Gap
    }

    fn regular(&mut self, index: u64, dt: i64) {
        let (n, mean, m2) = &mut self.welford;
        *n += 1;
        let d = dt as f64 - *mean;
        *mean += d / *n as f64;
        *m2 += d * (dt as f64 - *mean);
        let block = self.block_for(index);
        self.blocks[block].0 += 1;
        self.blocks[block].1 += dt as i128;
    }

    /// The block of sample `index`, merging blocks pairwise (in place) while there would be
    /// more than [`MAX_BLOCKS`].
    fn block_for(&mut self, index: u64) -> usize {
        while index / self.block_len >= MAX_BLOCKS as u64 {
            let half = self.blocks.len().div_ceil(2);
            for j in 0..half {
                let (a, b) = (
                    self.blocks[2 * j],
                    *self.blocks.get(2 * j + 1).unwrap_or(&(0, 0)),
                );
                self.blocks[j] = (a.0 + b.0, a.1 + b.1);
            }
            self.blocks.truncate(half);
            self.block_len *= 2;
        }
        let block = (index / self.block_len) as usize;
        if self.blocks.len() <= block {
            self.blocks.resize(block + 1, (0, 0));
        }
        block
    }

    fn gap(&mut self, event: Event, ratio: f64) {
        let missing = (ratio.round() as u64).saturating_sub(1);
        self.out.missing_samples = self.out.missing_samples.saturating_add(missing);
        if self
            .out
            .largest_gap
            .is_none_or(|g| event.dt_ns() > g.dt_ns())
        {
            self.out.largest_gap = Some(event);
        }
        if event.dt_ns() > LONG_GAP_NS {
            self.out.long_gaps.push(event, self.limit);
        }
        self.out.gaps.push(event, self.limit);
    }

    /// The statistics of everything pushed.
    pub fn finish(self) -> Timing {
        let median = self.median();
        let robust_sd = median.and_then(|m| self.robust_sd(m));
        let tenth_rates = self.tenth_rates();
        let (n, _, m2) = self.welford;
        let mut out = self.out;
        out.last_t_ns = self.latest.map(|(t, _)| t);
        out.reference_ns = self.reference;
        out.resolution_ns = self.width;
        out.mean_ns = (self.positive > 0).then(|| self.positive_sum as f64 / self.positive as f64);
        out.sd_ns = (n > 0).then(|| (m2 / n as f64).sqrt());
        out.median_ns = median;
        out.robust_sd_ns = robust_sd;
        out.tenth_rates_hz = tenth_rates;
        out
    }

    /// Mean of the values in the fine bin holding rank `positive / 2`, if it is in the fine
    /// range.
    fn median(&self) -> Option<f64> {
        let rank = self.positive / 2;
        let mut seen = self.out.outside_fine.0;
        if rank < seen {
            return None;
        }
        for (c, s) in self.counts.iter().zip(&self.sums) {
            seen += c;
            if rank < seen {
                return Some(*s as f64 / *c as f64);
            }
        }
        None
    }

    fn robust_sd(&self, median: f64) -> Option<f64> {
        let mut dev: Vec<(f64, u64)> = (self.counts.iter().zip(&self.sums))
            .filter(|(c, _)| **c > 0)
            .map(|(c, s)| ((*s as f64 / *c as f64 - median).abs(), *c))
            .collect();
        dev.sort_by(|a, b| a.0.total_cmp(&b.0));
        let rank = self.positive / 2;
        let mut seen = 0;
        for (d, c) in dev {
            seen += c;
            if rank < seen {
                return Some(1.4826 * d);
            }
        }
        None
    }

    fn tenth_rates(&self) -> Option<(f64, f64)> {
        let b = &self.blocks;
        if b.len() < 10 {
            return None;
        }
        let k = b.len() / 10;
        let rate = |s: &[(u64, i128)]| {
            let (n, sum) = s.iter().fold((0, 0), |a, x| (a.0 + x.0, a.1 + x.1));
            (n > 0).then(|| 1e9 * n as f64 / sum as f64)
        };
        Some((rate(&b[..k])?, rate(&b[b.len() - k..])?))
    }
}
