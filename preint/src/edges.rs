//! What a measurement records about the white-noise sources near its window's edges
//! ([`PreintegratedImu::edge_noise`](crate::PreintegratedImu::edge_noise)): the stream samples
//! two consecutive windows share and each one's gain on a window's error, so that
//! [`merge`](crate::merge()) adds the covariance between the windows exactly.

use crate::noise::{CellRule, white_scale};
use nalgebra::{Matrix3, SMatrix};

/// Most noise sources an [`EdgeNoise`] holds: at most 5 per window edge (hermite4's cubic
/// boundary stencil of 4 stream samples plus one neighbour; 2 for Euler and midpoint).
pub const MAX_EDGE_SOURCES: usize = 10;

/// One white-noise source near an edge of a window: a stream sample whose noise may also
/// enter the neighbouring window, and its first-order effect on this window's error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeSource {
    /// Timestamp of the stream sample \[ns\]; identifies the sample across windows of the same
    /// stream.
    pub t_ns: i64,
    /// `∂[δφ, δv, δp]/∂[n_g, n_a]` (9×6): rows in the chart of [`PreintegratedImu`](crate::PreintegratedImu) (error at `t_j`,
    /// order [δφ, δv, δp]), columns the sample's gyro [rad/s] and accelerometer [m/s²] noise.
    pub gain: SMatrix<f64, 9, 6>,
    /// Interval to the previous stream sample \[s\], `0.0` if unknown to this window.
    pub left_s: f64,
    /// Interval to the next stream sample \[s\], `0.0` if unknown to this window.
    pub right_s: f64,
    /// The sample is near the start of the window (it may be shared with the window before).
    pub start: bool,
    /// The sample is near the end of the window (it may be shared with the window after).
    pub end: bool,
}

impl Default for EdgeSource {
    fn default() -> Self {
        Self {
            t_ns: 0,
            gain: SMatrix::zeros(),
            left_s: 0.0,
            right_s: 0.0,
            start: false,
            end: false,
        }
    }
}

/// The white-noise sources near the edges of a window: what [`merge`](crate::merge()) needs
/// to add the covariance between two consecutive windows that share stream samples.
///
/// Noise model ([`ImuNoise`](crate::ImuNoise)): every stream sample carries independent white noise
/// `n = [n_g, n_a]` of covariance `diag(Σ_g, Σ_a)·white_scale(c)` with `c = cell_rule.cell_s(left,
/// right)`; the window's error is, to first order, `Σ_samples gain·n`. Consecutive windows
/// share the samples around their common keyframe (the sample at the keyframe, or the samples
/// an interpolated boundary sample is made of, and for hermite4 the stencil neighbours), so their
/// errors are correlated by `Σ_shared gain_a Q gain_bᵀ`. Empty for [`Level::Deltas`](crate::Level::Deltas) and for
/// hand-made measurements (then a merge treats the windows as independent).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeNoise {
    /// Gyro white-noise density Σ_g [rad²/s] the sources were integrated with.
    pub gyro_cov: Matrix3<f64>,
    /// Accelerometer white-noise density Σ_a [m²/s³].
    pub acc_cov: Matrix3<f64>,
    /// How a source's cell follows from `left_s`, `right_s` (the scheme's rule).
    pub cell_rule: CellRule,
    sources: [EdgeSource; MAX_EDGE_SOURCES],
    len: usize,
}

impl Default for EdgeNoise {
    /// No sources.
    fn default() -> Self {
        Self::new(Matrix3::zeros(), Matrix3::zeros(), CellRule::Centered)
    }
}

impl EdgeNoise {
    /// An empty set for noise densities `gyro_cov`, `acc_cov` and a cell rule.
    pub fn new(gyro_cov: Matrix3<f64>, acc_cov: Matrix3<f64>, cell_rule: CellRule) -> Self {
        Self {
            gyro_cov,
            acc_cov,
            cell_rule,
            sources: [EdgeSource::default(); MAX_EDGE_SOURCES],
            len: 0,
        }
    }

    /// The sources, sorted by time.
    pub fn sources(&self) -> &[EdgeSource] {
        &self.sources[..self.len]
    }

    /// Adds a source, keeping the order by time; `false` (and nothing added) if
    /// [`MAX_EDGE_SOURCES`] are held already or a source with that time exists.
    pub fn push(&mut self, s: EdgeSource) -> bool {
        if self.len == MAX_EDGE_SOURCES || self.find(s.t_ns).is_some() {
            return false;
        }
        let at = self.sources[..self.len].partition_point(|x| x.t_ns < s.t_ns);
        self.sources.copy_within(at..self.len, at + 1);
        self.sources[at] = s;
        self.len += 1;
        true
    }

    /// The source at time `t_ns`, if held.
    pub fn find(&self, t_ns: i64) -> Option<&EdgeSource> {
        self.sources().iter().find(|s| s.t_ns == t_ns)
    }

    /// Number of sources.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if there are no sources.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether `other` describes the same noise model (densities and cell rule, compared
    /// exactly), so that sources with equal times can be identified.
    pub fn same_model(&self, other: &EdgeNoise) -> bool {
        self.gyro_cov == other.gyro_cov
            && self.acc_cov == other.acc_cov
            && self.cell_rule == other.cell_rule
    }

    /// Noise covariance of a source whose intervals to its neighbours are `left_s`, `right_s`
    /// \[s\]: `diag(Σ_g, Σ_a)·white_scale(cell_rule.cell_s(left_s, right_s))` (6×6, order
    /// [n_g, n_a]).
    pub fn sample_cov(&self, left_s: f64, right_s: f64) -> SMatrix<f64, 6, 6> {
        let s = white_scale(self.cell_rule.cell_s(left_s, right_s));
        let mut q = SMatrix::<f64, 6, 6>::zeros();
        q.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(self.gyro_cov * s));
        q.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(self.acc_cov * s));
        q
    }
}
