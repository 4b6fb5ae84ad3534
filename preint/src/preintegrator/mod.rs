//! The preintegrator: feeds samples one at a time (or a slice) through the chosen scheme and
//! returns a [`PreintegratedImu`].
//!
//! The window is `[first sample, last sample]` pushed; keyframe times between samples are
//! handled by [`crate::window::preintegrate`], which inserts interpolated boundary samples.
//!
//! | file | what it holds |
//! |---|---|
//! | `mod.rs` | the public API: construction, validation of every sample, bias update |
//! | `engine.rs` | the interval loop of one scheme (ring of nodes, stencils, noise cells) |
//! | `retire.rs` | a sample's noise once no interval reads it (or its gain, near an edge) |
//! | `edges.rs` | the samples near the window's edges, collected for exact merges |
//! | `output.rs` | the measurement in the documented chart |
//! | `intrinsic.rs` | IMU intrinsics: the samples corrected in front of the loop, the Jacobians |

mod edges;
mod engine;
mod front;
mod intrinsic;
mod output;
mod retire;

pub(crate) use edges::{Side, Src, WindowSpec};
pub use output::time_offset_jacobian;

use crate::choices::Level;
use crate::error::PreintError;
use crate::extrinsics::{EndRates, EndSource};
use crate::measurement::PreintegratedImu;
use crate::params::{CovShape, PreintParams};
use crate::propagation::{AnisotropicNoise, BiasWalk, IsotropicNoise};
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::{IntervalScheme, with_scheme};
use crate::validation::{check_sample, common_case};
use engine::{Core, Fixed, NoiseKind};
use front::Front;
pub(crate) use front::Maps;

/// What the preintegrator needs of a scheme's interval loop ([`Core`]), behind one pointer so
/// that the public type does not depend on the scheme.
trait Engine: std::fmt::Debug + Send + Sync {
    fn push(&mut self, s: &ImuSample);
    fn run_slice(&mut self, samples: &[ImuSample], last_t_ns: i64, gap_limit: u64) -> usize;
    /// Whether `run_slice` can take samples now (a fast path in its steady state).
    fn slice_ready(&self) -> bool;
    fn len(&self) -> usize;
    fn measurement(&self) -> PreintegratedImu;
    /// The measurement and the intrinsics' Jacobians, when they are accumulated.
    fn measurement_and_intrinsics(
        &self,
    ) -> (
        PreintegratedImu,
        Option<crate::intrinsics::IntrinsicJacobian>,
    ) {
        (self.measurement(), None)
    }
    fn end_rates(&self) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>, f64);
    fn boxed_clone(&self) -> Box<dyn Engine>;
}

impl<S: IntervalScheme + Send + Sync> Engine for Core<S>
where
    S::Carry: Send + Sync,
{
    #[inline(always)]
    fn push(&mut self, s: &ImuSample) {
        Core::push(self, s);
    }
    fn run_slice(&mut self, samples: &[ImuSample], last_t_ns: i64, gap_limit: u64) -> usize {
        Core::run_slice(self, samples, last_t_ns, gap_limit)
    }
    fn slice_ready(&self) -> bool {
        Core::slice_ready(self)
    }
    fn len(&self) -> usize {
        Core::len(self)
    }
    fn measurement(&self) -> PreintegratedImu {
        Core::measurement(self)
    }
    fn measurement_and_intrinsics(
        &self,
    ) -> (
        PreintegratedImu,
        Option<crate::intrinsics::IntrinsicJacobian>,
    ) {
        Core::measurement_and_intrinsics(self)
    }
    fn end_rates(&self) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>, f64) {
        Core::end_rates(self)
    }
    fn boxed_clone(&self) -> Box<dyn Engine> {
        Box::new(self.clone())
    }
}

/// Incremental on-manifold preintegrator (Forster 2017 chart, see [`PreintegratedImu`](crate::PreintegratedImu)).
///
/// ```
/// use preint::{ImuBias, ImuSample, PreintParams, Preintegrator, Scheme};
/// use nalgebra::Vector3;
/// let params = PreintParams::default().with_scheme(Scheme::Midpoint);
/// let mut pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
/// for k in 0..201i64 {
///     let s = ImuSample::new(k * 5_000_000, Vector3::new(0.0, 0.0, 0.1), Vector3::new(0.0, 0.0, 9.81));
///     pi.integrate(&s).unwrap();
/// }
/// let m = pi.finish().unwrap();
/// assert!((m.delta_t - 1.0).abs() < 1e-15);
/// assert!((m.delta_r.log().z - 0.1).abs() < 1e-12);
/// ```
///
/// Noise model ([`ImuNoise`](crate::ImuNoise)): sample j carries independent white noise of covariance
/// `diag(Σ_g, Σ_a)·white_scale(c_j)`, where the cell `c_j` follows from the intervals to its
/// neighbours by the scheme's [`CellRule`](crate::noise::CellRule): the interval held by the
/// sample for Euler (GTSAM), the mean length of its adjacent intervals for midpoint and
/// Hermite (`Δt` for uniform sampling, matching [`ImuNoise`](crate::ImuNoise)'s per-sample
/// `σ/√Δt`). The pushed samples are the stream: the first sample has no left neighbour and the
/// last no right one. Each sample's noise is added exactly once, with the sum of its gains over
/// every interval that reads it.
///
/// Memory: with `keep_samples` (the default) every pushed sample is also stored for
/// re-integration. [`Preintegrator::new`] starts with an empty `Vec`, which then grows
/// geometrically (amortised O(1), about log₂ N reallocations for N samples);
/// [`Preintegrator::with_capacity`] reserves the room up front, and with `keep_samples = false`
/// nothing is stored. In those two cases [`Preintegrator::integrate`] never allocates
/// (`preint/tests/no_alloc.rs`).
#[derive(Debug)]
pub struct Preintegrator {
    params: PreintParams,
    bias_hat: ImuBias,
    engine: Box<dyn Engine>,
    spec: WindowSpec,
    check_gaps: bool,
    /// Largest accepted gap \[ns\] (`u64::MAX` without the gap check).
    gap_limit: u64,
    samples: Vec<ImuSample>,
    last_t_ns: i64,
}

impl Clone for Preintegrator {
    fn clone(&self) -> Self {
        Self {
            params: self.params.clone(),
            bias_hat: self.bias_hat,
            engine: self.engine.boxed_clone(),
            spec: self.spec,
            check_gaps: self.check_gaps,
            gap_limit: self.gap_limit,
            samples: self.samples.clone(),
            last_t_ns: self.last_t_ns,
        }
    }
}

impl Preintegrator {
    /// A preintegrator with bias estimate `bias_hat` ([b_g rad/s, b_a m/s²]); validates
    /// `params` and decides the noise path (isotropic closed form or general) once. With
    /// `keep_samples`, the stored samples live in a `Vec` that grows as samples arrive (see
    /// the type docs; use [`Preintegrator::with_capacity`] to avoid reallocations).
    pub fn new(params: PreintParams, bias_hat: ImuBias) -> Result<Self, PreintError> {
        Self::with_capacity(params, bias_hat, 0)
    }

    /// As [`Preintegrator::new`], reserving room for `capacity` stored samples so that
    /// `integrate` never allocates for the first `capacity` samples (when `keep_samples` is
    /// set; without it nothing is stored and nothing allocated).
    pub fn with_capacity(
        params: PreintParams,
        bias_hat: ImuBias,
        capacity: usize,
    ) -> Result<Self, PreintError> {
        Self::build(params, bias_hat, capacity, WindowSpec::default(), true)
    }

    /// The window path's constructor: `spec` describes the window edges, `check_gaps = false`
    /// skips the gap check (the stream was checked instead).
    pub(crate) fn build(
        params: PreintParams,
        bias_hat: ImuBias,
        capacity: usize,
        spec: WindowSpec,
        check_gaps: bool,
    ) -> Result<Self, PreintError> {
        params.validate()?;
        let finite = |v: &nalgebra::Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !finite(&bias_hat.gyro) || !finite(&bias_hat.acc) {
            return Err(PreintError::InvalidParameter {
                name: "bias_hat",
                reason: "non-finite component",
            });
        }
        let mut fixed = fixed(&params, bias_hat, spec);
        // The samples' transforms before the loop (the context samples too): the intrinsics'
        // correction (identity: nothing to do), then a lever arm taken off per sample.
        let maps = Maps::new(
            params
                .intrinsics
                .filter(|x| !x.model.is_identity())
                .map(|x| x.model.correction()),
            fixed.coupling.map(|arm| (arm, bias_hat.gyro)),
        );
        for side in [&mut fixed.spec.start, &mut fixed.spec.end] {
            side.ctx = side.ctx.map(|s| maps.map(&s));
        }
        let jac_model = params.intrinsics.filter(|x| x.jacobians).map(|x| x.model);
        let engine: Box<dyn Engine> = with_scheme!(params.scheme, S => {
            let core = Core::<S>::new(fixed).with_intrinsics(jac_model);
            if maps.is_identity() {
                Box::new(core)
            } else {
                Box::new(Front::new(core, maps))
            }
        });
        let samples = if params.keep_samples {
            Vec::with_capacity(capacity)
        } else {
            Vec::new()
        };
        let gap_limit = if check_gaps {
            params.max_gap_ns as u64
        } else {
            u64::MAX
        };
        Ok(Self {
            params,
            bias_hat,
            engine,
            spec,
            check_gaps,
            gap_limit,
            samples,
            last_t_ns: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PreintParams {
        &self.params
    }

    /// The bias estimate used for integration.
    pub fn bias_hat(&self) -> &ImuBias {
        &self.bias_hat
    }

    /// Number of samples integrated so far.
    pub fn len(&self) -> usize {
        self.engine.len()
    }

    /// True if no sample was integrated yet.
    pub fn is_empty(&self) -> bool {
        self.engine.len() == 0
    }

    /// The stored samples (empty unless `keep_samples`).
    pub fn samples(&self) -> &[ImuSample] {
        &self.samples
    }

    /// Adds one sample. Rejects non-finite readings, duplicate or decreasing timestamps and
    /// gaps above `max_gap_ns`, naming the sample index (count of samples accepted so far) and
    /// timestamp; a rejected sample leaves the preintegrator unchanged.
    #[inline]
    pub fn integrate(&mut self, s: &ImuSample) -> Result<(), PreintError> {
        if self.engine.len() > 0 && common_case(s, self.last_t_ns, self.gap_limit) {
            self.push(s);
            Ok(())
        } else {
            self.integrate_checked(s)
        }
    }

    /// [`Preintegrator::integrate`] for the first sample and for samples that may be invalid.
    #[cold]
    #[inline(never)]
    fn integrate_checked(&mut self, s: &ImuSample) -> Result<(), PreintError> {
        let index = self.engine.len();
        let prev = (index > 0).then_some(self.last_t_ns);
        let max_gap = self.check_gaps.then_some(self.params.max_gap_ns);
        check_sample(s, index, prev, max_gap)?;
        self.push(s);
        Ok(())
    }

    /// Stores a valid sample and integrates the intervals that became ready.
    #[inline(always)]
    fn push(&mut self, s: &ImuSample) {
        self.last_t_ns = s.t_ns;
        if self.params.keep_samples {
            self.samples.push(*s);
        }
        self.engine.push(s);
    }

    /// Adds the samples in order; stops at the first invalid one (see [`Self::integrate`]),
    /// leaving the samples before it integrated. With [`Level::Deltas`], runs of valid
    /// samples go straight from the slice through the scheme's deltas step where the scheme
    /// has a fast path (same result, bit for bit, as pushing them one by one).
    pub fn integrate_slice(&mut self, samples: &[ImuSample]) -> Result<(), PreintError> {
        let fast = self.params.level == Level::Deltas;
        let mut i = 0;
        while i < samples.len() {
            if fast {
                let rest = &samples[i..];
                let used = self.engine.run_slice(rest, self.last_t_ns, self.gap_limit);
                if used > 0 {
                    self.last_t_ns = rest[used - 1].t_ns;
                    if self.params.keep_samples {
                        self.samples.extend_from_slice(&rest[..used]);
                    }
                    i += used;
                    continue;
                }
            }
            self.integrate(&samples[i])?;
            i += 1;
        }
        Ok(())
    }

    /// The measurement over `[first sample, last sample]`: deltas, 9×9 covariance
    /// [δφ, δv, δp] and bias Jacobians in the Forster chart, and the 15×15 combined covariance
    /// [δφ, δv, δp, δb_g, δb_a] (with [`Level::Covariance`] its delta–bias cross blocks are
    /// zero and its 9×9 block is `cov`; with [`Level::Deltas`] covariances and Jacobians are
    /// zero). Integrates the remaining intervals on a copy, so more samples may be added
    /// afterwards.
    pub fn finish(&self) -> Result<PreintegratedImu, PreintError> {
        let count = self.engine.len();
        if count < 2 {
            return Err(PreintError::TooFewSamples { count });
        }
        let mut m = self.engine.measurement();
        let p = &self.params;
        if let (_, Some(pose)) = crate::extrinsics::plan(p.body_p_sensor.as_ref(), p.lever_arm) {
            let ends = self.end_rates(m.t_i_ns);
            crate::extrinsics::to_body(&mut m, &pose, &ends);
            m.jac_td = crate::extrinsics::time_offset_to_body(&m.jac_td, &pose);
        }
        checked(m)
    }

    /// The end rates of the window and the stream samples each is made of (for the lever arm):
    /// the interpolation weights of a boundary sample, or the first or last pushed sample.
    fn end_rates(&self, t_i_ns: i64) -> EndRates {
        // The first sample is always an edge source when there is noise to carry (its own
        // intervals are recorded there); the last may not be (Euler reads it in no interval),
        // so its interval to the previous sample is given.
        let (w_i, w_j, h_j) = self.engine.end_rates();
        let side = |sd: &Side, t_ns: i64, (left_s, right_s): (f64, f64)| {
            let mut src = [EndSource::default(); 4];
            if sd.nw == 0 {
                src[0] = EndSource {
                    t_ns,
                    w: 1.0,
                    left_s,
                    right_s,
                };
                return (src, 1);
            }
            for (i, x) in src.iter_mut().enumerate().take(sd.nw) {
                let s = &sd.src[i];
                *x = EndSource {
                    t_ns: s.t_ns,
                    w: sd.w[i],
                    left_s: s.left_s,
                    right_s: s.right_s,
                };
            }
            (src, sd.nw)
        };
        let (src_i, n_i) = side(&self.spec.start, t_i_ns, (0.0, 0.0));
        let (src_j, n_j) = side(&self.spec.end, self.last_t_ns, (h_j, 0.0));
        EndRates {
            w_i,
            w_j,
            src_i,
            n_i,
            src_j,
            n_j,
        }
    }

    /// The measurement for a new bias estimate `bias`: if `‖δb_g‖ ≤ reintegrate_gyro_threshold`
    /// and `‖δb_a‖ ≤ reintegrate_acc_threshold` (δb = bias − bias_hat), the first-order
    /// correction [`PreintegratedImu::corrected`] (Forster eq. 44; covariance and Jacobians
    /// kept, `bias_hat` set to `bias`); otherwise the stored samples are re-integrated with
    /// `bias`.
    ///
    /// Without `keep_samples` there is nothing to re-integrate: the first-order correction is
    /// returned whatever the size of δb, with `reintegrated: false` (callers that need the
    /// accuracy of re-integration above the thresholds must keep the samples; the size of the
    /// first-order error is documented at [`crate::params::DEFAULT_REINTEGRATE_GYRO`]).
    ///
    /// At [`Level::Deltas`] there are no bias Jacobians, so no first-order correction: any
    /// `bias ≠ bias_hat` re-integrates the stored samples, and without `keep_samples` it is
    /// [`PreintError::NoBiasJacobians`] ([`PreintegratedImu::check_bias`]). `bias == bias_hat`
    /// returns the measurement unchanged at every level.
    ///
    /// ```
    /// use preint::nalgebra::Vector3;
    /// use preint::{ImuBias, ImuSample, PreintParams, Preintegrator};
    /// let mut pi = Preintegrator::new(PreintParams::default(), ImuBias::zero()).unwrap();
    /// for k in 0..201i64 {
    ///     let t = k as f64 * 5e-3;
    ///     let w = Vector3::new(t.sin(), 0.5, 0.2);
    ///     pi.integrate(&ImuSample::new(k * 5_000_000, w, Vector3::new(0.3, 0.0, 9.81))).unwrap();
    /// }
    /// let small = ImuBias::new(Vector3::new(1e-3, 0.0, 0.0), Vector3::zeros());
    /// assert!(!pi.measurement_for_bias(&small).unwrap().reintegrated); // first order
    /// let large = ImuBias::new(Vector3::new(0.05, 0.0, 0.0), Vector3::zeros());
    /// assert!(pi.measurement_for_bias(&large).unwrap().reintegrated); // from the samples
    /// ```
    pub fn measurement_for_bias(&self, bias: &ImuBias) -> Result<BiasUpdate, PreintError> {
        let dbg = (bias.gyro - self.bias_hat.gyro).norm();
        let dba = (bias.acc - self.bias_hat.acc).norm();
        let small = dbg <= self.params.reintegrate_gyro_threshold
            && dba <= self.params.reintegrate_acc_threshold;
        let first_order = self.params.level != Level::Deltas || *bias == self.bias_hat;
        if first_order && (small || !self.params.keep_samples) {
            let mut m = self.finish()?;
            let (r, v, p) = m.corrected(bias);
            m.delta_r = r;
            m.delta_v = v;
            m.delta_p = p;
            m.bias_hat = *bias;
            return Ok(BiasUpdate {
                measurement: m,
                reintegrated: false,
            });
        }
        if !self.params.keep_samples {
            return Err(PreintError::NoBiasJacobians {
                bias: *bias,
                bias_hat: self.bias_hat,
            });
        }
        let mut other = self.clone();
        other.reintegrate(bias)?;
        Ok(BiasUpdate {
            measurement: other.finish()?,
            reintegrated: true,
        })
    }

    /// Replaces the bias estimate by `bias` and re-integrates the stored samples.
    ///
    /// Errors: [`PreintError::SamplesNotKept`] if `keep_samples` is off and samples were
    /// integrated (nothing to re-integrate; the preintegrator is left unchanged), and the
    /// errors of [`Preintegrator::new`] for a non-finite `bias`.
    pub fn reintegrate(&mut self, bias: &ImuBias) -> Result<(), PreintError> {
        if !self.params.keep_samples && !self.is_empty() {
            return Err(PreintError::SamplesNotKept { count: self.len() });
        }
        let mut fresh = Preintegrator::build(
            self.params.clone(),
            *bias,
            self.samples.len(),
            self.spec,
            self.check_gaps,
        )?;
        fresh.integrate_slice(&self.samples)?;
        *self = fresh;
        Ok(())
    }
}

/// `m` if every delta, covariance and bias Jacobian is finite.
fn checked(m: PreintegratedImu) -> Result<PreintegratedImu, PreintError> {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let deltas = finite(m.delta_r.matrix().as_slice())
        && finite(m.delta_v.as_slice())
        && finite(m.delta_p.as_slice());
    let what = if !deltas {
        "deltas"
    } else if !finite(m.cov15.as_slice()) {
        "covariance"
    } else if !m.jac.is_finite() {
        "bias Jacobians"
    } else {
        return Ok(m);
    };
    Err(PreintError::NonFiniteResult { what })
}

/// What the interval loop needs of the parameters: the noise shapes (isotropic closed form
/// or general, decided once) and the bias random walk.
fn fixed(params: &PreintParams, bias_hat: ImuBias, spec: WindowSpec) -> Fixed {
    let noise = match (
        CovShape::of(&params.gyro_cov),
        CovShape::of(&params.acc_cov),
    ) {
        (CovShape::Isotropic(g), CovShape::Isotropic(a)) => {
            NoiseKind::Isotropic(IsotropicNoise { g, a })
        }
        _ => NoiseKind::Anisotropic(AnisotropicNoise {
            g: params.gyro_cov,
            a: params.acc_cov,
        }),
    };
    let iso = match (
        CovShape::of(&params.gyro_bias_rw_cov),
        CovShape::of(&params.acc_bias_rw_cov),
    ) {
        (CovShape::Isotropic(g), CovShape::Isotropic(a)) => Some((g, a)),
        _ => None,
    };
    Fixed {
        bias_hat,
        gravity: params.gravity,
        omega_coriolis: params.omega_coriolis,
        coriolis: params.coriolis,
        bias_correction: params.resolved_bias_correction(),
        level: params.level,
        gyro_cov: params.gyro_cov,
        acc_cov: params.acc_cov,
        noise,
        walk: BiasWalk {
            combined: params.level == Level::Combined,
            g: params.gyro_bias_rw_cov,
            a: params.acc_bias_rw_cov,
            iso,
        },
        int_cov: params
            .integration_cov
            .as_ref()
            .map(CovShape::of)
            .filter(|c| *c != CovShape::Isotropic(0.0)),
        spec,
        coupling: crate::extrinsics::plan(params.body_p_sensor.as_ref(), params.lever_arm).0,
    }
}

/// Result of [`Preintegrator::measurement_for_bias`].
#[derive(Clone, Debug, PartialEq)]
pub struct BiasUpdate {
    /// The measurement at the new bias.
    pub measurement: PreintegratedImu,
    /// True if the samples were re-integrated, false for the first-order correction.
    pub reintegrated: bool,
}
