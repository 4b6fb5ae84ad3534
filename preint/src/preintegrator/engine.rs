//! The interval loop of one scheme: the window's samples as nodes in a ring, each interval
//! integrated once its stencil has arrived, its linearisation handed to the propagator, and
//! each sample's noise added (or, near the window's edges, its gain collected) once no later
//! interval reads it.
//!
//! Intervals are processed with a lag of one sample: a sample's noise needs its time cell,
//! which the next sample gives, and the last samples of a window are edge samples, which only
//! [`Core::measurement`] knows. That integrates the rest on a copy, so more samples may be
//! added afterwards.

use super::edges::{EdgeGains, EdgeLayout, WindowSpec, resolve};
use super::intrinsic::{IntrAcc, IntrMode, NoIntr, WithIntr};
use super::output::Chart;
use super::output::time_offset_jacobian;
use super::retire::{Retirer, edge_count};
use crate::choices::Level;
use crate::edges::EdgeNoise;
use crate::extrinsics::CentripetalArm;
use crate::fast::{Attached, SliceInput};
use crate::intrinsics::IntrinsicJacobian;
use crate::measurement::PreintegratedImu;
use crate::noise::walk_scale;
use crate::params::CovShape;
use crate::propagation::blocks::{Cols9, Gain96, PackedSym9};
use crate::propagation::linearisation::MAX_STENCIL;
use crate::propagation::transition::Origin;
use crate::propagation::{
    AnisotropicNoise, BiasWalk, Coupled, ErrorState, IsotropicNoise, NoiseCov, RateCoupling,
};
use crate::sample::{ImuBias, ImuSample, span_s};
use crate::scheme::{Deltas, IntervalScheme, Node, RENORM_EVERY, Stencil};
use nalgebra::{Matrix3, Vector3};

/// Nodes kept: enough for every stencil and for the slice path's write-back.
pub(super) const RING: usize = 8;

/// The white-noise covariance, in the shape decided once at construction.
#[derive(Clone, Copy, Debug)]
pub(crate) enum NoiseKind {
    Isotropic(IsotropicNoise),
    Anisotropic(AnisotropicNoise),
}

impl NoiseKind {
    /// `P += G Q Gᵀ` with `Q = diag(Σ_g, Σ_a)·s`.
    pub(crate) fn add_full(&self, p: &mut PackedSym9, g: &Gain96, s: f64) {
        match self {
            NoiseKind::Isotropic(q) => q.add_full(p, g, s),
            NoiseKind::Anisotropic(q) => q.add_full(p, g, s),
        }
    }
}

/// What the loop needs of the parameters, fixed at construction.
#[derive(Clone, Debug)]
pub(crate) struct Fixed {
    pub bias_hat: ImuBias,
    pub gravity: Vector3<f64>,
    pub omega_coriolis: Option<Vector3<f64>>,
    pub coriolis: crate::choices::CoriolisMode,
    pub bias_correction: crate::BiasCorrection,
    pub level: Level,
    pub gyro_cov: Matrix3<f64>,
    pub acc_cov: Matrix3<f64>,
    pub noise: NoiseKind,
    pub walk: BiasWalk,
    pub int_cov: Option<CovShape>,
    pub spec: WindowSpec,
    /// The rate coupling of samples transformed before the loop: a lever arm corrected per
    /// sample (GTSAM's model, [`crate::LeverArm::Centripetal`]; the preintegrator's front takes
    /// `ω × (ω × r)` off each specific force), whose `D(ω) = ∂a/∂ω` moves the gyro noise and
    /// bias into the specific force. The loop runs with the noise of such samples
    /// ([`Coupled`]), whose gains carry it.
    pub coupling: Option<CentripetalArm>,
}

/// The loop of scheme `S` over one window.
#[derive(Clone, Debug)]
pub(crate) struct Core<S: IntervalScheme> {
    fixed: Fixed,
    ring: [Node; RING],
    /// Window samples pushed.
    n: usize,
    /// 1 if a context sample precedes the window (it is `ring[0]`, extended index 0).
    ctx_before: usize,
    ctx_after: Option<Node>,
    first_t_ns: i64,
    /// The first window node's rate [rad/s] (bias-corrected).
    first_w: Vector3<f64>,
    origin: Origin,
    /// Window intervals integrated.
    done: usize,
    d: Deltas,
    carry: S::Carry,
    /// The scheme's fast path at [`Level::Deltas`], if it has one ([`crate::fast`]).
    fast: Attached,
    e: ErrorState,
    edges: EdgeGains,
    /// With a rate coupling: `−Σ_j G_a,j D_j`, the bias Jacobian's share through the nodes'
    /// coupling (pulled back, gyro columns).
    coupled_j: Cols9,
    /// The intrinsics' Jacobian sums (when requested and linearising).
    intr: Option<Box<IntrAcc>>,
    /// A rate coupling or the intrinsics' Jacobians: the loop's variants other than the
    /// default.
    special: bool,
    /// The first window node's specific force [m/s²] (bias-corrected), for the time-offset
    /// column (last, away from the fields the interval loop reads).
    first_a: Vector3<f64>,
}

impl<S: IntervalScheme> Core<S> {
    /// The scheme's fast path ([`crate::fast::kind`], 0 for none).
    const FAST_KIND: u8 = crate::fast::kind(S::SCHEME);
    /// Whether the scheme has a fast path.
    const FAST: bool = Self::FAST_KIND != 0;

    /// An empty loop; the context samples of `fixed.spec` are used if `S`'s stencil reaches
    /// beyond the window.
    pub(crate) fn new(fixed: Fixed) -> Self {
        let wide = S::NODES_BEFORE + S::NODES_AFTER > 0;
        let bias = fixed.bias_hat;
        let corrected =
            |s: &Option<ImuSample>| s.filter(|_| wide).map(|s| Node::corrected(&s, &bias));
        let ctx_before = corrected(&fixed.spec.start.ctx);
        let ctx_after = corrected(&fixed.spec.end.ctx);
        let mut ring = [Node::default(); RING];
        if let Some(c) = ctx_before {
            ring[0] = c;
        }
        Self {
            ring,
            n: 0,
            ctx_before: usize::from(ctx_before.is_some()),
            ctx_after,
            first_t_ns: 0,
            first_w: Vector3::zeros(),
            origin: Origin::default(),
            done: 0,
            d: Deltas::default(),
            carry: S::Carry::default(),
            fast: if fixed.level == Level::Deltas {
                Attached::of(S::SCHEME)
            } else {
                Attached::None
            },
            e: ErrorState::default(),
            edges: EdgeGains::default(),
            coupled_j: [[0.0; 9]; 3],
            intr: None,
            special: fixed.coupling.is_some(),
            first_a: Vector3::zeros(),
            fixed,
        }
    }

    /// The same loop accumulating the Jacobians with respect to `model` (the samples reach it
    /// corrected, by the preintegrator's front, `front.rs`); nothing at `Level::Deltas`.
    pub(crate) fn with_intrinsics(
        mut self,
        model: Option<crate::intrinsics::ImuIntrinsics>,
    ) -> Self {
        if let Some(x) = model.filter(|_| self.linearise()) {
            self.intr = Some(Box::new(IntrAcc::new(x, self.fixed.bias_hat)));
            self.special = true;
        }
        self
    }

    fn linearise(&self) -> bool {
        self.fixed.level != Level::Deltas
    }

    /// Window samples pushed.
    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// Window sample `j`.
    #[inline(always)]
    fn node(&self, j: usize) -> &Node {
        &self.ring[(j + self.ctx_before) % RING]
    }

    /// The bias-corrected rates [rad/s] of the first and last window samples and the last
    /// interval \[s\] (`n ≥ 2`).
    pub(crate) fn end_rates(&self) -> (Vector3<f64>, Vector3<f64>, f64) {
        let (n, last) = (self.n, self.node(self.n - 1));
        let h_j = span_s(self.node(n - 2).t_ns, last.t_ns);
        (self.first_w, last.w, h_j)
    }

    /// Adds the node of a valid sample and integrates the intervals that became ready.
    #[inline(always)]
    pub(crate) fn push(&mut self, s: &ImuSample) {
        let node = Node::corrected(s, &self.fixed.bias_hat);
        if self.n == 0 {
            self.first_t_ns = s.t_ns;
            self.first_w = node.w;
            self.first_a = node.a;
            S::start(&mut self.carry, &node);
            self.fast.start(&node);
        }
        self.ring[(self.n + self.ctx_before) % RING] = node;
        self.n += 1;
        self.advance(false);
    }

    #[inline(always)]
    fn advance(&mut self, at_end: bool) {
        let special = || self.special;
        match (self.linearise(), self.fixed.noise) {
            (false, _) => self.advance_with::<IsotropicNoise, false, NoIntr>(
                &IsotropicNoise { g: 0.0, a: 0.0 },
                at_end,
            ),
            (true, NoiseKind::Isotropic(q)) if special() => self.advance_special(q, at_end),
            (true, NoiseKind::Anisotropic(q)) if special() => self.advance_special(q, at_end),
            (true, NoiseKind::Isotropic(q)) => self.advance_with::<_, true, NoIntr>(&q, at_end),
            (true, NoiseKind::Anisotropic(q)) => self.advance_with::<_, true, NoIntr>(&q, at_end),
        }
    }

    /// [`Core::advance`] for samples with a rate coupling, whose noise is then [`Coupled`], or
    /// accumulating the intrinsics' Jacobians (never both: [`crate::PreintParams::validate`]).
    #[inline(never)]
    fn advance_special<N: NoiseCov>(&mut self, noise: N, at_end: bool) {
        match self.fixed.coupling {
            Some(map) => self.advance_with::<_, true, NoIntr>(&Coupled { noise, map }, at_end),
            None => self.advance_with::<N, true, WithIntr>(&noise, at_end),
        }
    }

    /// Whether interval `k` can be integrated while samples are still arriving: its stencil
    /// has arrived, and the samples it retires cannot be the window's last.
    #[inline(always)]
    fn ready(&self, k: usize) -> bool {
        let start = (k + self.ctx_before).saturating_sub(S::NODES_BEFORE);
        k + 2 < self.n && start + S::STENCIL <= self.ctx_before + self.n
    }

    /// Integrates every interval that is ready; with `at_end`, all remaining intervals and
    /// the remaining noise (the window then has exactly `self.n` samples).
    #[inline(always)]
    fn advance_with<N: NoiseCov, const LINEARISE: bool, I: IntrMode>(
        &mut self,
        noise: &N,
        at_end: bool,
    ) {
        let n = self.n;
        while self.done + 1 < n && (at_end || self.ready(self.done)) {
            if at_end {
                self.interval::<N, LINEARISE, true, I>(noise, self.done);
            } else {
                self.interval::<N, LINEARISE, false, I>(noise, self.done);
            }
            self.done += 1;
            if self.done.is_multiple_of(RENORM_EVERY) {
                self.renormalize();
            }
        }
        if at_end && LINEARISE && n >= 2 {
            let last = self.ctx_before + n - 1;
            let r_last = self.d.r;
            let (e, mut r) = self.split::<N, I>(noise, true);
            if S::NODES_BEFORE + S::NODES_AFTER == 0 {
                e.retire_last::<S>(last, &r_last, |p, id, g| r.retire::<S>(p, id, g));
            } else {
                e.retire_below(usize::MAX, |p, id, g| r.retire::<S>(p, id, g));
            }
        }
    }

    fn renormalize(&mut self) {
        if Self::FAST && self.fast.is_some() {
            self.fast.renormalize();
        } else {
            self.d.renormalize();
        }
    }

    /// The error state and a [`Retirer`] borrowing the ring and the edge store.
    #[inline(always)]
    fn split<'a, N, I: IntrMode>(
        &'a mut self,
        noise: &'a N,
        at_end: bool,
    ) -> (&'a mut ErrorState, Retirer<'a, N, I::Sink<'a>>) {
        let Self {
            ring,
            ctx_after,
            edges,
            e,
            ctx_before,
            n,
            coupled_j,
            intr,
            ..
        } = self;
        let window = (*ctx_before, *n, at_end);
        let intr = I::sink(intr);
        (
            e,
            Retirer::new(
                ring,
                ctx_after.as_ref(),
                edges,
                noise,
                window,
                coupled_j,
                intr,
            ),
        )
    }

    /// Interval `k` (out of line: it keeps the per-interval code small enough for the
    /// compiler to inline the fixed-size matrix operations).
    #[inline(never)]
    fn interval<N: NoiseCov, const LINEARISE: bool, const AT_END: bool, I: IntrMode>(
        &mut self,
        noise: &N,
        k: usize,
    ) {
        let at_end = AT_END;
        let Self {
            fixed,
            ring,
            n,
            ctx_before,
            ctx_after,
            origin,
            d,
            carry,
            fast,
            e,
            edges,
            coupled_j,
            intr,
            ..
        } = self;
        let (first_id, st) = stencil::<S>(ring, ctx_after.as_ref(), *ctx_before, *n, k, at_end);
        if !LINEARISE && Self::FAST && fast.step(Self::FAST_KIND, &st) {
            return;
        }
        let intr = I::sink(intr);
        let mut r = Retirer::<N, _>::new(
            ring,
            ctx_after.as_ref(),
            edges,
            noise,
            (*ctx_before, *n, at_end),
            coupled_j,
            intr,
        );
        if LINEARISE && S::NODES_BEFORE + S::NODES_AFTER > 0 {
            e.retire_below(first_id, |p, id, g| r.retire::<S>(p, id, g));
        }
        let step = S::step(d, carry, &st);
        if !LINEARISE {
            return;
        }
        let lin = S::linearise(&step, &st);
        let pb = origin.pull_back(st.n1().t_ns, &d.v, &d.p);
        let rates = (N::COUPLED && fixed.walk.combined).then(|| stencil_coupling(noise, &st));
        e.interval::<S>(
            &lin,
            &pb,
            first_id,
            st.k,
            st.len,
            &fixed.walk,
            rates.as_ref(),
            |p, id, g| r.retire::<S>(p, id, g),
        );
        int_cov(fixed, e, d, lin.tr.h);
    }

    /// Whether [`Core::run_slice`] can take samples: a fast path, in its steady state.
    #[inline]
    pub(crate) fn slice_ready(&self) -> bool {
        let n = self.n;
        Self::FAST && self.fast.is_some() && n >= self.fast.slice_from() && self.done + 2 == n
    }

    /// The slice path of [`crate::Level::Deltas`] (the `fast` module), when the loop is in its
    /// steady state: integrates the leading samples of `samples` that pass the common-case
    /// test and returns how many; 0 when not applicable.
    pub(crate) fn run_slice(
        &mut self,
        samples: &[ImuSample],
        last_t_ns: i64,
        gap_limit: u64,
    ) -> usize {
        if !self.slice_ready() {
            return 0;
        }
        let n = self.n;
        let last = [*self.node(n - 2), *self.node(n - 1)];
        let bias = self.fixed.bias_hat;
        let input = SliceInput {
            samples,
            bias: &bias,
            last_t_ns,
            gap_limit,
        };
        let used = self.fast.run_slice(&last, &input, &mut self.done);
        // The ring as pushing the samples one by one would have left it.
        self.n += used;
        let keep = used.min(RING);
        for (i, s) in samples[used - keep..used].iter().enumerate() {
            let j = self.n - keep + i;
            self.ring[(j + self.ctx_before) % RING] = Node::corrected(s, &bias);
        }
        used
    }

    /// The measurement over the samples pushed so far (integrated on a copy).
    pub(crate) fn measurement(&self) -> PreintegratedImu {
        let mut core = self.clone();
        core.advance(true);
        if core.fixed.coupling.is_some() {
            let extra = core.coupled_j;
            crate::propagation::blocks::add_cols(&mut core.e.j.g, &extra);
        }
        core.output()
    }

    /// The measurement and, when they are accumulated, the intrinsics' Jacobians
    /// ([`super::intrinsic`]).
    pub(crate) fn measurement_and_intrinsics(
        &self,
    ) -> (PreintegratedImu, Option<IntrinsicJacobian>) {
        let mut core = self.clone();
        core.advance(true);
        let jac = core.intr.as_ref().map(|acc| {
            let last_t_ns = core.node(core.n - 1).t_ns;
            let tr = core.origin.push_to(last_t_ns, &core.d.v, &core.d.p);
            acc.jacobian(&tr, &core.d.r)
        });
        (core.output(), jac)
    }

    fn output(&self) -> PreintegratedImu {
        let fixed = &self.fixed;
        let (r, v, p) = if Self::FAST && self.fast.is_some() {
            self.fast.deltas()
        } else {
            (self.d.r, self.d.v, self.d.p)
        };
        let last_t_ns = self.node(self.n - 1).t_ns;
        let mut chart = Chart::zeros();
        let mut edge_noise = EdgeNoise::default();
        let mut jac_td = nalgebra::SVector::<f64, 9>::zeros();
        if self.linearise() {
            let last = self.node(self.n - 1);
            jac_td = time_offset_jacobian(
                (&self.first_w, &self.first_a),
                (&last.w, &last.a),
                (&r, &v, &p),
                span_s(self.first_t_ns, last_t_ns),
            );
            // Pulled back to the origin → pushed forward to the end (rotated coordinates) →
            // the documented chart.
            let tr = self.origin.push_to(last_t_ns, &v, &p);
            let mut pw = self.e.p;
            let layout = EdgeLayout {
                ctx_before: self.ctx_before,
                n: self.n,
                first: edge_count::<S>(),
                last: edge_count::<S>(),
            };
            let noise = fixed.noise;
            edge_noise = resolve(
                &self.edges,
                layout,
                &fixed.spec,
                S::CELL_RULE,
                (fixed.gyro_cov, fixed.acc_cov),
                &mut pw,
                &tr,
                &r.transpose(),
                |p, g, s| noise.add_full(p, g, s),
            );
            chart = Chart::of(&self.e, &pw, &tr, &r, &fixed.walk);
        }
        PreintegratedImu {
            t_i_ns: self.first_t_ns,
            t_j_ns: last_t_ns,
            delta_t: span_s(self.first_t_ns, last_t_ns),
            delta_r: preint_lie::SO3::from_matrix_unchecked(r),
            delta_v: v,
            delta_p: p,
            cov: chart.cov,
            cov15: chart.cov15,
            jac: chart.jac,
            jac_td,
            bias_hat: fixed.bias_hat,
            gravity: fixed.gravity,
            omega_coriolis: fixed.omega_coriolis,
            coriolis: fixed.coriolis,
            level: fixed.level,
            edge_noise,
            bias_correction: fixed.bias_correction,
        }
    }
}

/// Interval `k` of a window with `before` context samples before it and `n` samples: its
/// stencil's first extended index, and the stencil (node k at `st.k`).
#[inline(always)]
fn stencil<'a, S: IntervalScheme>(
    ring: &'a [Node; RING],
    ctx_after: Option<&'a Node>,
    before: usize,
    n: usize,
    k: usize,
    at_end: bool,
) -> (usize, Stencil<'a>) {
    let k_ext = k + before;
    let with_ctx = at_end && ctx_after.is_some();
    let len = before + n + usize::from(with_ctx);
    let m = len.min(S::STENCIL);
    let first_id = if at_end {
        k_ext.saturating_sub(S::NODES_BEFORE).min(len - m)
    } else {
        k_ext.saturating_sub(S::NODES_BEFORE)
    };
    let at = |i: usize| &ring[i % RING];
    let mut nodes = [
        at(first_id),
        at(first_id + 1),
        at(first_id + 2),
        at(first_id + 3),
    ];
    if with_ctx {
        // The context sample after the window, at extended index `before + n`.
        let c = ctx_after.expect("with_ctx");
        for (j, x) in nodes.iter_mut().enumerate() {
            if first_id + j == before + n {
                *x = c;
            }
        }
    }
    let st = Stencil {
        nodes,
        len: m,
        k: k_ext - first_id,
        first: k == 0,
    };
    (first_id, st)
}

/// The rate coupling `D_j` of each node of the stencil `st` (zero beyond its length).
#[inline(never)]
fn stencil_coupling<N: NoiseCov>(noise: &N, st: &Stencil) -> RateCoupling {
    let mut d = [nalgebra::Matrix3::zeros(); MAX_STENCIL];
    for (x, node) in d.iter_mut().zip(&st.nodes).take(st.len) {
        *x = noise.coupling(&node.w);
    }
    d
}

/// Integration noise of an interval of length `h` \[s\]. GTSAM adds it to δp in the
/// body-(k+1) chart, i.e. `ΔR_k+1 Σ_int ΔR_k+1ᵀ h` in frame i; its pulled-back gain is the
/// same (it has no ψ row).
#[inline(always)]
fn int_cov(fixed: &Fixed, e: &mut ErrorState, d: &Deltas, h: f64) {
    if let Some(ic) = &fixed.int_cov {
        let ws = walk_scale(h);
        match ic {
            CovShape::Isotropic(s) => e.p.add_pp_diag(s * ws),
            CovShape::General(m) => {
                let r = &d.r;
                e.p.add_pp(&(r * m * r.transpose() * ws));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preintegrator::fixed;
    use crate::scheme::midpoint::Midpoint;
    use crate::{ImuNoise, PreintParams};

    /// `n` samples of a smooth 200 Hz stream.
    fn stream(n: usize) -> Vec<ImuSample> {
        (0..n)
            .map(|k| {
                let t = k as f64 * 0.005;
                ImuSample::new(
                    k as i64 * 5_000_000,
                    Vector3::new(0.3 * (1.1 * t).sin(), 0.2 * (0.7 * t).cos(), 0.1),
                    Vector3::new(0.5 * (0.9 * t).sin(), 0.3, 9.81),
                )
            })
            .collect()
    }

    /// Midpoint's loop at `level`; `attached = false` detaches its fast path (what a scheme
    /// without one runs).
    fn run(level: Level, attached: bool) -> PreintegratedImu {
        let p = PreintParams::from_noise(&ImuNoise::euroc())
            .with_scheme(crate::Scheme::Midpoint)
            .with_level(level);
        let mut core = Core::<Midpoint>::new(fixed(&p, ImuBias::zero(), WindowSpec::default()));
        assert_eq!(core.fast.is_some(), level == Level::Deltas);
        if !attached {
            core.fast = Attached::None;
        }
        for s in stream(3000) {
            core.push(&s);
        }
        core.measurement()
    }

    /// A scheme without a fast path integrates its deltas with its plain step at
    /// `Level::Deltas`: the same bits as the deltas at `Level::Covariance` (the same step), and
    /// the fast quaternion path's deltas to round-off.
    #[test]
    fn a_scheme_without_a_fast_path_runs_its_plain_step_at_every_level() {
        let plain = run(Level::Deltas, false);
        let cov = run(Level::Covariance, true);
        let fast = run(Level::Deltas, true);
        assert_eq!(plain.delta_r, cov.delta_r);
        assert_eq!((plain.delta_v, plain.delta_p), (cov.delta_v, cov.delta_p));
        assert_eq!(plain.cov, crate::Cov9::zeros());
        let dr = (plain.delta_r.matrix() - fast.delta_r.matrix()).amax();
        assert!(dr > 0.0 && dr < 1e-13, "{dr}");
        assert!((plain.delta_v - fast.delta_v).amax() < 1e-12 * fast.delta_v.amax());
    }
}
