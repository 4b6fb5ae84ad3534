//! The preintegrator: feeds samples one at a time (or a slice) through the chosen scheme and
//! returns a [`PreintegratedImu`].
//!
//! The window is `[first sample, last sample]` pushed; keyframe times between samples are
//! handled by [`crate::window::preintegrate`], which inserts interpolated boundary samples.
//! Intervals are processed with a small lag (midpoint: 1 sample, rk4: 3 samples) because a
//! sample's noise covariance depends on its time cell (see [`Preintegrator`]); the tail is
//! integrated by [`Preintegrator::finish`], which does not consume the preintegrator.

use crate::error::PreintError;
use crate::measurement::{BiasJacobians, Cov9, Cov15, PreintegratedImu};
use crate::params::{CovShape, Level, PreintParams, Scheme};
use crate::propagation::{BiasWalk, ErrorState, GenQ, Input, IsoQ, M3, NoiseQ, Transition};
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::{Deltas, Node, euler, midpoint, rk4, span_s};
use lie::SO3;

const RING: usize = 8;
/// ΔR is re-orthonormalised (`R ← ½R(3I − RᵀR)`) every this many intervals.
const RENORM_EVERY: usize = 1024;

#[derive(Clone, Copy, Debug)]
enum NoiseKind {
    Iso(IsoQ),
    Gen(GenQ),
}

#[derive(Clone, Debug)]
struct Core {
    ring: [Node; RING],
    n: usize,
    done: usize,
    d: Deltas,
    e: ErrorState,
}

/// Static configuration of the loop, fixed at construction.
#[derive(Clone, Copy, Debug)]
struct Cfg {
    scheme: Scheme,
    walk: BiasWalk,
    int_cov: Option<CovShape>,
}

impl Core {
    #[inline(always)]
    fn node(&self, i: usize) -> &Node {
        &self.ring[i % RING]
    }

    /// `1/cell` [1/s] of node `j`: the mean length of its adjacent intervals in the window
    /// (`total` nodes if known). Uniform sampling at Δt gives `1/Δt`, i.e. per-sample noise
    /// `Σ/Δt`.
    #[inline(always)]
    fn cell_scale(&self, j: usize, total: usize) -> f64 {
        let t = |i: usize| self.node(i).t_ns;
        let span_ns = match (j > 0, j + 1 < total) {
            (true, true) => span_s(t(j - 1), t(j + 1)) * 0.5,
            (false, true) => span_s(t(j), t(j + 1)),
            (true, false) => span_s(t(j - 1), t(j)),
            (false, false) => 1.0,
        };
        1.0 / span_ns
    }

    /// Integrates every interval that is ready; with `fin`, all remaining intervals (the
    /// window then has exactly `self.n` nodes).
    #[inline(always)]
    fn advance<N: NoiseQ, const LIN: bool>(&mut self, cfg: &Cfg, noise: &N, fin: bool) {
        let n = self.n;
        loop {
            let k = self.done;
            if k + 1 >= n {
                return;
            }
            let ready = fin
                || match cfg.scheme {
                    Scheme::Euler => true,
                    Scheme::Midpoint => k + 2 < n,
                    Scheme::Rk4 => k.max(1) + 3 < n,
                };
            if !ready {
                return;
            }
            // In streaming mode `n` is a lower bound of the window size that is large enough
            // for every cell and stencil used here; with `fin` it is exact.
            let total = if fin { n } else { usize::MAX };
            if k == 0 {
                self.d.u_last = self.node(0).a;
            }
            match cfg.scheme {
                Scheme::Euler => {
                    let n0 = *self.node(k);
                    let h = span_s(n0.t_ns, self.node(k + 1).t_ns);
                    let r0 = self.d.r;
                    if let Some((tr, inp)) = euler::step::<LIN>(&mut self.d, &n0, h, k) {
                        let cp = 0.5 * h * h;
                        self.e.step_euler(&tr, &inp, &r0, cp, noise, &cfg.walk);
                        self.int_cov(cfg, &tr);
                    }
                }
                Scheme::Midpoint => {
                    let (n0, n1) = (*self.node(k), *self.node(k + 1));
                    let h = span_s(n0.t_ns, n1.t_ns);
                    if let Some((tr, g)) = midpoint::step::<LIN>(&mut self.d, &n0, &n1, h) {
                        let s0 = self.cell_scale(k, total);
                        self.e.step_mid(&tr, &g, s0, noise, &cfg.walk);
                        self.int_cov(cfg, &tr);
                    }
                }
                Scheme::Rk4 => {
                    let m = n.min(4);
                    let s0 = if fin {
                        k.saturating_sub(1).min(n - m)
                    } else {
                        k.saturating_sub(1)
                    };
                    let mut st = [Node::default(); 4];
                    let mut scales = [0.0; 4];
                    for j in 0..m {
                        st[j] = *self.node(s0 + j);
                        if LIN {
                            scales[j] = self.cell_scale(s0 + j, total);
                        }
                    }
                    let mut out = [Input::default(); 4];
                    if let Some(tr) =
                        rk4::step::<LIN>(&mut self.d, &st[..m], k - s0, s0, &scales, &mut out)
                    {
                        self.propagate(cfg, noise, &tr, &out[..m]);
                    }
                }
            }
            self.done += 1;
            if self.done.is_multiple_of(RENORM_EVERY) {
                let r = self.d.r;
                self.d.r = r * (M3::identity() * 3.0 - r.transpose() * r) * 0.5;
            }
        }
    }

    /// Midpoint, end of the window (`fin`, exactly `self.n` nodes): the last sample's noise.
    #[inline]
    fn finish_tail<N: NoiseQ>(&mut self, cfg: &Cfg, noise: &N) {
        if cfg.scheme == Scheme::Midpoint && self.n >= 2 {
            let s = self.cell_scale(self.n - 1, self.n);
            self.e.finish_mid(noise, s);
        }
    }

    #[inline(always)]
    fn propagate<N: NoiseQ>(&mut self, cfg: &Cfg, noise: &N, tr: &Transition, inp: &[Input]) {
        self.e.step(tr, inp, noise, &cfg.walk);
        self.int_cov(cfg, tr);
    }

    #[inline(always)]
    fn int_cov(&mut self, cfg: &Cfg, tr: &Transition) {
        if let Some(ic) = &cfg.int_cov {
            // GTSAM: integration noise added to δp in the body-(k+1) chart, i.e.
            // ΔR_k+1 Σ_int ΔR_k+1ᵀ h in frame i.
            match ic {
                CovShape::Isotropic(s) => {
                    let add = s * tr.h;
                    for i in 0..3 {
                        self.e.p.pp[(i, i)] += add;
                    }
                }
                CovShape::General(m) => {
                    let r = &self.d.r;
                    self.e.p.pp += r * m * r.transpose() * tr.h;
                }
            }
        }
    }
}

/// Incremental on-manifold preintegrator (Forster 2017 chart, see [`crate::measurement`]).
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
/// Noise model: sample j carries white noise of covariance `diag(Σ_g, Σ_a)/c_j`, where the cell
/// `c_j` is the interval held by the sample for Euler (GTSAM), and the mean length of the
/// sample's adjacent intervals for midpoint and rk4 (`Δt` for uniform sampling, matching
/// [`ImuNoise`](crate::ImuNoise)'s per-sample `σ/√Δt`).
#[derive(Clone, Debug)]
pub struct Preintegrator {
    params: PreintParams,
    bias_hat: ImuBias,
    noise: NoiseKind,
    cfg: Cfg,
    lin: bool,
    samples: Vec<ImuSample>,
    first_t_ns: i64,
    last_t_ns: i64,
    core: Core,
}

impl Preintegrator {
    /// A preintegrator with bias estimate `bias_hat` ([b_g rad/s, b_a m/s²]); validates
    /// `params` and decides the noise path (isotropic closed form or general) once.
    pub fn new(params: PreintParams, bias_hat: ImuBias) -> Result<Self, PreintError> {
        Self::with_capacity(params, bias_hat, 0)
    }

    /// As [`Preintegrator::new`], reserving room for `capacity` stored samples so that
    /// `integrate` never allocates (when `keep_samples` is set).
    pub fn with_capacity(
        params: PreintParams,
        bias_hat: ImuBias,
        capacity: usize,
    ) -> Result<Self, PreintError> {
        params.validate()?;
        let finite = |v: &nalgebra::Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !finite(&bias_hat.gyro) || !finite(&bias_hat.acc) {
            return Err(PreintError::InvalidParameter {
                name: "bias_hat",
                reason: "non-finite component",
            });
        }
        let noise = match (
            CovShape::of(&params.gyro_cov),
            CovShape::of(&params.acc_cov),
        ) {
            (CovShape::Isotropic(g), CovShape::Isotropic(a)) => NoiseKind::Iso(IsoQ { g, a }),
            _ => NoiseKind::Gen(GenQ {
                g: params.gyro_cov,
                a: params.acc_cov,
            }),
        };
        let cfg = Cfg {
            scheme: params.scheme,
            walk: BiasWalk {
                combined: params.level == Level::Combined,
                g: params.gyro_bias_rw_cov,
                a: params.acc_bias_rw_cov,
            },
            int_cov: params
                .integration_cov
                .as_ref()
                .map(CovShape::of)
                .filter(|c| *c != CovShape::Isotropic(0.0)),
        };
        let samples = if params.keep_samples {
            Vec::with_capacity(capacity)
        } else {
            Vec::new()
        };
        Ok(Self {
            lin: params.level != Level::Deltas,
            params,
            bias_hat,
            noise,
            cfg,
            samples,
            first_t_ns: 0,
            last_t_ns: 0,
            core: Core {
                ring: [Node::default(); RING],
                n: 0,
                done: 0,
                d: Deltas::default(),
                e: ErrorState::default(),
            },
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
        self.core.n
    }

    /// True if no sample was integrated yet.
    pub fn is_empty(&self) -> bool {
        self.core.n == 0
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
        let index = self.core.n;
        for (v, field) in [(&s.gyro, "gyro"), (&s.acc, "acc")] {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(PreintError::NonFinite {
                    index,
                    t_ns: s.t_ns,
                    field,
                });
            }
        }
        if index > 0 {
            let prev = self.last_t_ns;
            if s.t_ns == prev {
                return Err(PreintError::DuplicateTimestamp {
                    index,
                    t_ns: s.t_ns,
                });
            }
            if s.t_ns < prev {
                return Err(PreintError::DecreasingTimestamp {
                    index,
                    t_ns: s.t_ns,
                    prev_t_ns: prev,
                });
            }
            // i128: a gap that overflows i64 is reported as i64::MAX.
            let gap = s.t_ns as i128 - prev as i128;
            if gap > self.params.max_gap_ns as i128 {
                let gap = i64::try_from(gap).unwrap_or(i64::MAX);
                return Err(PreintError::GapTooLarge {
                    index,
                    t_ns: s.t_ns,
                    gap_ns: gap,
                    max_gap_ns: self.params.max_gap_ns,
                });
            }
        } else {
            self.first_t_ns = s.t_ns;
        }
        self.last_t_ns = s.t_ns;
        if self.params.keep_samples {
            self.samples.push(*s);
        }
        self.core.ring[index % RING] = Node {
            t_ns: s.t_ns,
            w: s.gyro - self.bias_hat.gyro,
            a: s.acc - self.bias_hat.acc,
        };
        self.core.n += 1;
        Self::run(&mut self.core, &self.cfg, &self.noise, self.lin, false);
        Ok(())
    }

    /// Adds the samples in order; stops at the first invalid one (see [`Self::integrate`]).
    pub fn integrate_slice(&mut self, samples: &[ImuSample]) -> Result<(), PreintError> {
        samples.iter().try_for_each(|s| self.integrate(s))
    }

    #[inline(always)]
    fn run(core: &mut Core, cfg: &Cfg, noise: &NoiseKind, lin: bool, fin: bool) {
        match (lin, noise) {
            (false, _) => core.advance::<IsoQ, false>(cfg, &IsoQ { g: 0.0, a: 0.0 }, fin),
            (true, NoiseKind::Iso(q)) => {
                core.advance::<IsoQ, true>(cfg, q, fin);
                if fin {
                    core.finish_tail(cfg, q);
                }
            }
            (true, NoiseKind::Gen(q)) => {
                core.advance::<GenQ, true>(cfg, q, fin);
                if fin {
                    core.finish_tail(cfg, q);
                }
            }
        }
    }

    /// The measurement over `[first sample, last sample]`: deltas, 9×9 covariance
    /// [δφ, δv, δp] and bias Jacobians in the Forster chart, and the 15×15 combined covariance
    /// [δφ, δv, δp, δb_g, δb_a] (with [`Level::Covariance`] its delta–bias cross blocks are
    /// zero; with [`Level::Deltas`] covariances and Jacobians are zero). Integrates the
    /// remaining intervals on a copy, so more samples may be added afterwards.
    pub fn finish(&self) -> Result<PreintegratedImu, PreintError> {
        if self.core.n < 2 {
            return Err(PreintError::TooFewSamples { count: self.core.n });
        }
        let mut core = self.core.clone();
        Self::run(&mut core, &self.cfg, &self.noise, self.lin, true);
        Ok(self.output(&core))
    }

    fn output(&self, core: &Core) -> PreintegratedImu {
        let r = core.d.r;
        let rt = r.transpose();
        let e = &core.e;
        let mut cov = Cov9::zeros();
        let mut cov15 = Cov15::zeros();
        let mut jac = BiasJacobians::default();
        if self.lin {
            // Rotated error coordinates → the documented chart.
            let to_chart = |p: &crate::propagation::Sym9| {
                let mut m = Cov9::zeros();
                let blocks = [
                    (0, 0, rt * p.rr * r),
                    (0, 3, rt * p.rv),
                    (0, 6, rt * p.rp),
                    (3, 3, p.vv),
                    (3, 6, p.vp),
                    (6, 6, p.pp),
                ];
                for (i, j, b) in blocks {
                    m.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
                    if i != j {
                        m.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
                    }
                }
                (m + m.transpose()) * 0.5
            };
            cov = to_chart(&e.p);
            let cov_walk = to_chart(&e.p_walk);
            jac = BiasJacobians {
                d_r_d_bg: rt * e.j.rg,
                d_v_d_bg: e.j.vg,
                d_v_d_ba: e.j.va,
                d_p_d_bg: e.j.pg,
                d_p_d_ba: e.j.pa,
            };
            cov15
                .fixed_view_mut::<9, 9>(0, 0)
                .copy_from(&(cov + cov_walk));
            let c = &e.c;
            let cross = [
                (0, 9, rt * c.rg),
                (3, 9, c.vg),
                (3, 12, c.va),
                (6, 9, c.pg),
                (6, 12, c.pa),
            ];
            for (i, j, b) in cross {
                cov15.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
                cov15.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
            }
            cov15.fixed_view_mut::<3, 3>(9, 9).copy_from(&e.pbb_g);
            cov15.fixed_view_mut::<3, 3>(12, 12).copy_from(&e.pbb_a);
        }
        PreintegratedImu {
            t_i_ns: self.first_t_ns,
            t_j_ns: self.last_t_ns,
            delta_t: span_s(self.first_t_ns, self.last_t_ns),
            delta_r: SO3::from_matrix_unchecked(r),
            delta_v: core.d.v,
            delta_p: core.d.p,
            cov,
            cov15,
            jac,
            bias_hat: self.bias_hat,
            gravity: self.params.gravity,
        }
    }

    /// The measurement for a new bias estimate `bias`: if `‖δb_g‖ ≤ reintegrate_gyro_threshold`
    /// and `‖δb_a‖ ≤ reintegrate_acc_threshold` (δb = bias − bias_hat), the first-order
    /// correction [`PreintegratedImu::corrected`] (Forster eq. 44; covariance and Jacobians
    /// kept, `bias_hat` set to `bias`); otherwise the stored samples are re-integrated with
    /// `bias` (if `keep_samples` is off, the first-order correction is returned regardless).
    pub fn measurement_for_bias(&self, bias: &ImuBias) -> Result<BiasUpdate, PreintError> {
        let dbg = (bias.gyro - self.bias_hat.gyro).norm();
        let dba = (bias.acc - self.bias_hat.acc).norm();
        let small = dbg <= self.params.reintegrate_gyro_threshold
            && dba <= self.params.reintegrate_acc_threshold;
        if small || !self.params.keep_samples {
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
        let mut other = self.clone();
        other.reintegrate(bias)?;
        Ok(BiasUpdate {
            measurement: other.finish()?,
            reintegrated: true,
        })
    }

    /// Replaces the bias estimate by `bias` and re-integrates the stored samples (a no-op on
    /// the deltas if `keep_samples` is off and nothing is stored: the window restarts empty).
    pub fn reintegrate(&mut self, bias: &ImuBias) -> Result<(), PreintError> {
        let samples = std::mem::take(&mut self.samples);
        let mut fresh = Preintegrator::with_capacity(self.params.clone(), *bias, samples.len())?;
        fresh.integrate_slice(&samples)?;
        *self = fresh;
        Ok(())
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
