//! Allan analysis of a sample stream in bounded memory: block means at a base cluster time τ₀.
//!
//! # Method
//! [`AllanStream`] keeps the means of consecutive, non-overlapping blocks of `b` samples
//! (`b` a power of two, τ₀ = bΔt), at most [`MAX_BASE_BLOCKS`] = 2²⁰ of them (48 MB). It
//! starts with `b = 1` (the samples themselves); whenever the store is full, neighbouring
//! blocks are averaged in pairs (`b` doubles, the count halves), so memory does not depend on
//! the length of the recording: up to 2²⁰ samples (87 min at 200 Hz) τ₀ = Δt; a 15 M-sample
//! recording has `b = 16` (τ₀ = 80 ms at 200 Hz). The samples of a last, incomplete block
//! (fewer than `b`) are left out.
//!
//! The overlapping Allan deviation is then computed from the cumulative sums of the block means
//! ([`super::allan_deviation`] on the block means with period τ₀), at τ = mτ₀. The mean of `m`
//! consecutive block means is the mean of the `mb` samples they hold, so each term
//! `θ_{k+2m} − 2θ_{k+m} + θ_k` is exactly a term of the full overlapping estimator at τ = mτ₀;
//! with `b = 1` the estimate is the full one, otherwise it takes every `b`-th of its terms
//! (start times step by τ₀ instead of Δt). Same expectation and the same number of clusters
//! `N/(mb)`; the EDF of each point ([`super::edf`]) is computed from the block series, so it is
//! that of this estimator: for white noise 0.45 of the full estimator's at m = 1 (which has b
//! times as many terms), 0.99 at m = 10, equal beyond; for a random walk 0.96 at m = 1 and
//! equal from m = 2 (b = 64). τ below τ₀ is not available.
//!
//! # Timestamps
//! As [`super::ImuAllan::from_samples`]: the period is `(t_last − t_first)/(N − 1)` and every
//! interval must lie within ±10 % of it (checked at the end from the shortest and longest
//! interval, which are tracked with their indices).

use super::{AllanError, AllanPoint, ImuAllan, allan_deviation, log_spaced_cluster_sizes};
use preint::ImuSample;

/// Largest number of base blocks held (module docs): 2²⁰, 48 MB of `[f64; 6]`.
pub const MAX_BASE_BLOCKS: usize = 1 << 20;

/// One interval between consecutive samples: its length \[ns\] and the index of its first
/// sample.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Interval {
    ns: i64,
    index: u64,
}

/// Streaming Allan analysis of six channels `[ω_x, ω_y, ω_z, a_x, a_y, a_z]` (module docs).
///
/// ```
/// use preint::ImuSample;
/// use preint_calib::allan::AllanStream;
/// use nalgebra::Vector3;
///
/// // 100 s at 100 Hz, at most 64 blocks held: the blocks are 16 samples long at the end.
/// let mut s = AllanStream::with_max_blocks(64);
/// for k in 0..10_000i64 {
///     let x = ((k * 7919) % 101) as f64 * 1e-3; // a deterministic, wiggly signal
///     let v = Vector3::new(x, -x, 2.0 * x);
///     s.push(&ImuSample { t_ns: k * 10_000_000, gyro: v, acc: v }).unwrap();
/// }
/// assert_eq!(s.block_len(), 256);
/// let a = s.finish(10).unwrap();
/// assert!((a.dt - 0.01).abs() < 1e-12);
/// assert!((a.tau0 - 2.56).abs() < 1e-9);
/// assert_eq!(a.curves[0][0].tau, a.tau0);
/// ```
#[derive(Clone, Debug)]
pub struct AllanStream {
    max_blocks: usize,
    block_len: usize,
    reference: [f64; 6],
    sum: [f64; 6],
    in_block: usize,
    blocks: Vec<[f64; 6]>,
    samples: u64,
    first_t_ns: i64,
    last_t_ns: i64,
    shortest: Interval,
    longest: Interval,
}

impl Default for AllanStream {
    fn default() -> Self {
        Self::new()
    }
}

impl AllanStream {
    /// A stream holding at most [`MAX_BASE_BLOCKS`] blocks.
    pub fn new() -> Self {
        Self::with_max_blocks(MAX_BASE_BLOCKS)
    }

    /// A stream holding at most `max_blocks` blocks (rounded up to an even number ≥ 16).
    pub fn with_max_blocks(max_blocks: usize) -> Self {
        let max_blocks = (max_blocks.max(16) + 1) & !1;
        Self {
            max_blocks,
            block_len: 1,
            reference: [0.0; 6],
            sum: [0.0; 6],
            in_block: 0,
            blocks: Vec::with_capacity(max_blocks),
            samples: 0,
            first_t_ns: 0,
            last_t_ns: 0,
            shortest: Interval {
                ns: i64::MAX,
                index: 0,
            },
            longest: Interval { ns: 0, index: 0 },
        }
    }

    /// Samples per base block (a power of two).
    pub fn block_len(&self) -> usize {
        self.block_len
    }

    /// Samples pushed so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Adds the next sample. Errors: a non-finite reading ([`AllanError::NonFinite`]) or a
    /// timestamp not after the previous one ([`AllanError::Timestamps`]), with the sample index.
    pub fn push(&mut self, s: &ImuSample) -> Result<(), AllanError> {
        let v = [s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z];
        if let Some(c) = v.iter().position(|x| !x.is_finite()) {
            return Err(AllanError::NonFinite {
                channel: c,
                index: self.samples as usize,
            });
        }
        if self.samples == 0 {
            self.reference = v;
            self.first_t_ns = s.t_ns;
        } else {
            let d = Interval {
                ns: s.t_ns.saturating_sub(self.last_t_ns),
                index: self.samples - 1,
            };
            if d.ns <= 0 {
                return Err(AllanError::Timestamps(format!(
                    "sample {} (t = {} ns) is not after the previous one (t = {} ns)",
                    self.samples, s.t_ns, self.last_t_ns
                )));
            }
            if d.ns < self.shortest.ns {
                self.shortest = d;
            }
            if d.ns > self.longest.ns {
                self.longest = d;
            }
        }
        self.last_t_ns = s.t_ns;
        self.samples += 1;
        for (c, x) in v.iter().enumerate() {
            self.sum[c] += x - self.reference[c];
        }
        self.in_block += 1;
        if self.in_block == self.block_len {
            let n = self.block_len as f64;
            self.blocks.push(self.sum.map(|x| x / n));
            self.sum = [0.0; 6];
            self.in_block = 0;
            if self.blocks.len() == self.max_blocks {
                self.merge_pairs();
            }
        }
        Ok(())
    }

    /// Averages neighbouring blocks in pairs: the block length doubles, the count halves.
    fn merge_pairs(&mut self) {
        let half = self.blocks.len() / 2;
        for i in 0..half {
            let (a, b) = (self.blocks[2 * i], self.blocks[2 * i + 1]);
            self.blocks[i] = std::array::from_fn(|c| 0.5 * (a[c] + b[c]));
        }
        self.blocks.truncate(half);
        self.block_len *= 2;
    }

    /// The mean sample period \[s\], after checking that every interval is within ±10 % of it.
    fn period(&self) -> Result<f64, AllanError> {
        let dt = (self.last_t_ns - self.first_t_ns) as f64 * 1e-9 / (self.samples - 1) as f64;
        let off = |iv: &Interval| (iv.ns as f64 * 1e-9 - dt).abs();
        // The interval farthest from the mean (the longest one for a gap).
        let iv = if off(&self.longest) >= off(&self.shortest) {
            self.longest
        } else {
            self.shortest
        };
        let d = iv.ns as f64 * 1e-9;
        if (d - dt).abs() > 0.1 * dt {
            return Err(AllanError::Timestamps(format!(
                "interval {} (samples {} and {}) is {d} s, mean period {dt} s (gap or \
                 irregular sampling)",
                iv.index,
                iv.index,
                iv.index + 1
            )));
        }
        Ok(dt)
    }

    /// The curves (`per_decade` log-spaced τ per decade from τ₀) and fits of the six channels.
    /// Errors: fewer than 8 blocks ([`AllanError::TooFewSamples`]), irregular timestamps, and
    /// those of the fits.
    pub fn finish(self, per_decade: usize) -> Result<ImuAllan, AllanError> {
        if self.blocks.len() < 8 {
            return Err(AllanError::TooFewSamples(self.samples as usize));
        }
        let dt = self.period()?;
        let tau0 = dt * self.block_len as f64;
        let ms = log_spaced_cluster_sizes(self.blocks.len() / 2, per_decade);
        let mut curves: [Vec<AllanPoint>; 6] = Default::default();
        let mut channel = Vec::with_capacity(self.blocks.len());
        for (c, curve) in curves.iter_mut().enumerate() {
            channel.clear();
            channel.extend(self.blocks.iter().map(|b| b[c]));
            *curve = allan_deviation(&channel, tau0, &ms).map_err(|e| match e {
                AllanError::NonFinite { index, .. } => AllanError::NonFinite { channel: c, index },
                e => e,
            })?;
        }
        ImuAllan::from_curves(dt, tau0, curves)
    }
}
