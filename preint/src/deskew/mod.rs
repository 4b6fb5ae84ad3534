//! The state anywhere inside a keyframe window, from the stored samples: the deltas
//! (ΔR, Δv, Δp from `t_i`), the predicted [`NavState`] at any time between the keyframes, and
//! lidar points moved to the body frame of one keyframe (deskewing).
//!
//! # Exactly the window's deltas, in one pass
//!
//! The deltas at a query time `t` ∈ (t_i, t_j] are those [`preintegrate`](crate::preintegrate)
//! gives for the window `[t_i, t]`: the same boundary sample at `t` (linear for Euler and
//! midpoint, cubic for hermite4), the same context sample after `t` and close-sample rule
//! ([`preintegrate`](crate::preintegrate())), the same stencils, renormalisation and `body_p_sensor` map. That window's
//! node sequence (context before, boundary sample at `t_i`, the stream samples, boundary sample
//! at `t`, context after) agrees with the stream's (context before, boundary at `t_i`, every
//! later stream sample) up to a position `P` just before `t`, and every interval whose stencil
//! lies below `P` gives the same bits in both. So one running pass over the stream keeps the
//! deltas (and the scheme's carry) at its last few nodes, and a query takes the snapshot at the
//! last shared interval and integrates the window's remaining intervals on its own tail of
//! nodes: one for Euler and midpoint, two for hermite4 (its boundary sample replaces a stream
//! sample in the stencils of the two intervals before it; three next to the stream's first
//! sample, where the stencils are one-sided). The pass is in `deskew/pass.rs`. With
//! [`Level::Covariance`](crate::Level) or [`Level::Combined`](crate::Level) the deltas are
//! bit-for-bit those of [`preintegrate`](crate::preintegrate); with
//! [`Level::Deltas`](crate::Level) `preintegrate` takes its quaternion fast path, and the two
//! agree to round-off (`preint/tests/deskew.rs`). At `t = t_i` the deltas are the identity.
//!
//! The functions: [`deltas_at`] (the deltas, [`DeltasAt`], at a sorted list of times in
//! `[t_i, t_j]`), [`states_at`] (the predicted states, through [`predict`], so gravity and
//! `omega_coriolis` are handled as at the window's end) and [`deskew_points`]. Under them is
//! the cursor [`WindowDeltas`]: built once per window (the stream checked as `preintegrate`
//! checks it), then [`WindowDeltas::at`] for non-decreasing times. The pass keeps the deltas and
//! the scheme's carry at its last 16 nodes. On the command line `preint integrate --at
//! T1,T2,…` prints the deltas (with `--initial-state`, the states) at those times, JSON key
//! `at`.
//!
//! Cost: O(N + M) for N stream samples and M sorted queries, one step per stream interval plus
//! at most three per query; the public functions allocate their output vector and one box for
//! the pass, [`WindowDeltas::at`] nothing. Only deltas are computed (no covariance).
//!
//! # Frames and units
//!
//! Times are integer ns. Deltas are in body frame i (Forster et al. 2017, eq. 33): the body
//! is the sensor unless `PreintParams::body_p_sensor` is set, then the body map of
//! [`SensorPose`] is applied at every query with the end rate at `t` (its boundary
//! sample's). States follow [`predict`] (gravity, `omega_coriolis`). A lidar point `x` \[m\]
//! given in the body frame at its own time `t` is the world point `p(t) + R(t) x`; deskewing
//! expresses it in the body frame at `t_i` or `t_j`: `R_refᵀ (p(t) + R(t) x − p_ref)`. Points
//! measured in a lidar frame must first be mapped into the body frame with the lidar's
//! extrinsics.
//!
//! GTSAM 4.3's `PreintegrationBase::deskewPointsAtTimes` does not read the samples: it
//! interpolates the rotation at a constant rate, `Exp((t/Δt) Log ΔR_ij)`, and translates by
//! `v_i t` (no gravity, no acceleration). It agrees with this module where that model is exact
//! (a constant yaw rate at constant velocity) and otherwise errs by the motion it leaves out
//! (`docs/EVIDENCE.md`).

use crate::edges::EdgeNoise;
use crate::error::PreintError;
use crate::measurement::{BiasJacobians, Cov9, Cov15, PreintegratedImu};
use crate::navstate::{NavState, predict};
use crate::params::PreintParams;
use crate::params::SensorPose;
use crate::preintegrator::Maps;
use crate::preintegrator::Preintegrator;
use crate::sample::{ImuBias, ImuSample, span_s};
use crate::scheme::Scheme;
use crate::scheme::with_scheme;
use crate::window::{boundary, bracket, inner_samples};
use nalgebra::Vector3;
use preint_lie::SO3;

mod pass;
use pass::{Corr, Pass, Query, Runner, Stream};

/// The deltas from `t_i` to a time inside the window, body frame i.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltasAt {
    /// Query time \[ns\].
    pub t_ns: i64,
    /// `t − t_i` \[s\].
    pub delta_t: f64,
    /// ΔR (rotation from body at `t` to body at `t_i`).
    pub delta_r: SO3,
    /// Δv [m/s], frame i, gravity excluded.
    pub delta_v: Vector3<f64>,
    /// Δp \[m\], frame i, gravity excluded.
    pub delta_p: Vector3<f64>,
}

/// The deltas and the predicted state at a time inside the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateAt {
    /// The deltas from `t_i`.
    pub deltas: DeltasAt,
    /// The body's state at the query time, world frame ([`predict`]).
    pub state: NavState,
}

/// The body frame deskewed points are expressed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeskewTarget {
    /// The body frame at `t_i`.
    Start,
    /// The body frame at `t_j`.
    End,
}

/// The deltas at non-decreasing times inside one keyframe window, one pass over the stream
/// (module docs). Built once per window; [`WindowDeltas::at`] allocates nothing.
#[derive(Debug)]
pub struct WindowDeltas<'a> {
    scheme: Scheme,
    stream: Stream<'a>,
    pass: Box<dyn Pass + 'a>,
    t_i_ns: i64,
    t_j_ns: i64,
    bi: Result<usize, usize>,
    /// Body map: the pose (rotation only with the per-sample lever-arm model).
    body: Option<SensorPose>,
    /// First sample at or after the last query.
    m: usize,
    queries: usize,
    last_t_ns: i64,
}

impl<'a> WindowDeltas<'a> {
    /// The window `[t_i_ns, t_j_ns]` of `samples` with bias estimate `bias`. Errors as
    /// [`preintegrate`](crate::preintegrate) for the same window (the stream is checked around
    /// and inside it).
    pub fn new(
        params: &PreintParams,
        bias: &ImuBias,
        samples: &'a [ImuSample],
        t_i_ns: i64,
        t_j_ns: i64,
    ) -> Result<Self, PreintError> {
        params.validate()?;
        let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !finite(&bias.gyro) || !finite(&bias.acc) {
            return Err(PreintError::InvalidParameter {
                name: "bias_hat",
                reason: "non-finite component",
            });
        }
        let scheme = params.scheme;
        let reach = scheme.stencil_reach();
        let (lo, hi) = bracket(samples, t_i_ns, t_j_ns, reach, params.max_gap_ns)?;
        let mj = if samples[hi - 1].t_ns == t_j_ns {
            hi - 1
        } else {
            hi
        };
        let (bi, node_i, _) = boundary(scheme, samples, t_i_ns, lo);
        let (bj, _, _) = boundary(scheme, samples, t_j_ns, mj);
        let inner = inner_samples(scheme, samples, (t_i_ns, bi), (t_j_ns, bj));
        let (arm, body) = crate::extrinsics::plan(params.body_p_sensor.as_ref(), params.lever_arm);
        let corr = Corr {
            bias: *bias,
            maps: Maps::new(
                params
                    .intrinsics
                    .filter(|x| !x.model.is_identity())
                    .map(|x| x.model.correction()),
                arm.map(|a| (a, bias.gyro)),
            ),
        };
        let ctx = inner.ctx_before.map(|k| corr.node(&samples[k]));
        let c = usize::from(ctx.is_some());
        let first = corr.node(&node_i);
        let stream = Stream {
            samples,
            corr,
            ctx,
            first,
            c,
            lo: inner.lo,
            len: c + 1 + samples.len().saturating_sub(inner.lo),
        };
        let pass: Box<dyn Pass + 'a> =
            with_scheme!(scheme, S => Box::new(Runner::<S>::new(&first)));
        Ok(Self {
            scheme,
            stream,
            pass,
            t_i_ns,
            t_j_ns,
            bi,
            body,
            m: lo,
            queries: 0,
            last_t_ns: t_i_ns,
        })
    }

    /// The window of a [`Preintegrator`] that kept its samples (`PreintParams::keep_samples`,
    /// the default): from its first to its last sample, with its parameters and bias estimate;
    /// the deltas at its last sample are then those of [`Preintegrator::finish`]. Errors:
    /// [`PreintError::SamplesNotKept`], [`PreintError::TooFewSamples`].
    pub fn of_preintegrator(pi: &'a Preintegrator) -> Result<Self, PreintError> {
        let samples = pi.samples();
        if !pi.params().keep_samples {
            return Err(PreintError::SamplesNotKept { count: pi.len() });
        }
        match (samples.first(), samples.last()) {
            (Some(a), Some(b)) if samples.len() >= 2 => {
                Self::new(pi.params(), pi.bias_hat(), samples, a.t_ns, b.t_ns)
            }
            _ => Err(PreintError::TooFewSamples {
                count: samples.len(),
            }),
        }
    }

    /// The deltas at `t_ns` ∈ `[t_i, t_j]`; successive calls must not go back in time.
    /// Errors: [`PreintError::QueryOutsideWindow`], [`PreintError::QueryNotSorted`] (the index
    /// counts the calls), [`PreintError::NonFiniteResult`].
    pub fn at(&mut self, t_ns: i64) -> Result<DeltasAt, PreintError> {
        let index = self.queries;
        if t_ns < self.t_i_ns || t_ns > self.t_j_ns {
            return Err(PreintError::QueryOutsideWindow {
                index,
                t_ns,
                t_i_ns: self.t_i_ns,
                t_j_ns: self.t_j_ns,
            });
        }
        if t_ns < self.last_t_ns {
            return Err(PreintError::QueryNotSorted {
                index,
                t_ns,
                prev_t_ns: self.last_t_ns,
            });
        }
        self.queries += 1;
        self.last_t_ns = t_ns;
        if t_ns == self.t_i_ns {
            return Ok(DeltasAt {
                t_ns,
                delta_t: 0.0,
                delta_r: SO3::identity(),
                delta_v: Vector3::zeros(),
                delta_p: Vector3::zeros(),
            });
        }
        let samples = self.stream.samples;
        while samples[self.m].t_ns < t_ns {
            self.m += 1;
        }
        let (bj, end, _) = boundary(self.scheme, samples, t_ns, self.m);
        let inner = inner_samples(self.scheme, samples, (self.t_i_ns, self.bi), (t_ns, bj));
        let s = &self.stream;
        let end_pos = s.c + 1 + (inner.hi - inner.lo);
        let after = inner.ctx_after.map(|k| s.corr.node(&samples[k]));
        let q = Query {
            end_pos,
            end: s.corr.node(&end),
            after,
            len: end_pos + 1 + usize::from(after.is_some()),
        };
        let d = self.pass.deltas(s, &q);
        let mut out = DeltasAt {
            t_ns,
            delta_t: span_s(self.t_i_ns, t_ns),
            delta_r: SO3::from_matrix_unchecked(d.r),
            delta_v: d.v,
            delta_p: d.p,
        };
        if let Some(pose) = &self.body {
            let sensor = (&out.delta_r, &out.delta_v, &out.delta_p);
            (out.delta_r, out.delta_v, out.delta_p) =
                crate::extrinsics::body_deltas(pose, sensor, out.delta_t, (&s.first.w, &q.end.w));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !(finite(out.delta_r.matrix().as_slice())
            && finite(out.delta_v.as_slice())
            && finite(out.delta_p.as_slice()))
        {
            return Err(PreintError::NonFiniteResult { what: "deltas" });
        }
        Ok(out)
    }
}

/// The deltas at each of `times_ns` (non-decreasing, inside `[t_i_ns, t_j_ns]`): exactly those
/// of [`preintegrate`](crate::preintegrate) over `[t_i_ns, t]`, in one pass (module docs).
///
/// ```
/// use preint::nalgebra::Vector3;
/// use preint::{ImuBias, ImuSample, PreintParams, Scheme, deskew, preintegrate};
/// let s: Vec<ImuSample> = (0..201i64)
///     .map(|k| ImuSample::new(k * 5_000_000, Vector3::new(0.1, 0.0, 0.2), Vector3::new(0.3, 0.0, 9.81)))
///     .collect();
/// let p = PreintParams::default().with_scheme(Scheme::Hermite4);
/// let b = ImuBias::zero();
/// let at = deskew::deltas_at(&p, &b, &s, (2_500_000, 900_000_000), &[12_345_678, 500_000_000]).unwrap();
/// let w = preintegrate(&p, &b, &s, 2_500_000, 12_345_678).unwrap();
/// assert_eq!((at[0].delta_v, at[0].delta_p), (w.delta_v, w.delta_p));
/// ```
pub fn deltas_at(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
    times_ns: &[i64],
) -> Result<Vec<DeltasAt>, PreintError> {
    let mut w = WindowDeltas::new(params, bias, samples, t_i_ns, t_j_ns)?;
    let mut out = Vec::with_capacity(times_ns.len());
    for &t in times_ns {
        out.push(w.at(t)?);
    }
    Ok(out)
}

/// A template measurement for [`predict`] at a query: the window's parameters, zero covariance.
fn template(params: &PreintParams, bias: &ImuBias, t_i_ns: i64) -> PreintegratedImu {
    PreintegratedImu {
        t_i_ns,
        t_j_ns: t_i_ns,
        delta_t: 0.0,
        delta_r: SO3::identity(),
        delta_v: Vector3::zeros(),
        delta_p: Vector3::zeros(),
        cov: Cov9::zeros(),
        cov15: Cov15::zeros(),
        jac: BiasJacobians::default(),
        jac_td: Default::default(),
        bias_hat: *bias,
        gravity: params.gravity,
        omega_coriolis: params.omega_coriolis,
        coriolis: params.coriolis,
        level: params.level,
        edge_noise: EdgeNoise::default(),
        bias_correction: params.resolved_bias_correction(),
    }
}

/// The deltas and the predicted state ([`predict`], with gravity and `omega_coriolis`) at each
/// of `times_ns`, from the state at `t_i` (`state_i`, world frame). Errors as [`deltas_at`], and
/// [`PreintError::InvalidParameter`] for a non-finite `state_i`.
pub fn states_at(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
    state_i: &NavState,
    times_ns: &[i64],
) -> Result<Vec<StateAt>, PreintError> {
    check_state(state_i)?;
    let mut w = WindowDeltas::new(params, bias, samples, t_i_ns, t_j_ns)?;
    let mut pim = template(params, bias, t_i_ns);
    let mut out = Vec::with_capacity(times_ns.len());
    for &t in times_ns {
        let deltas = w.at(t)?;
        out.push(StateAt {
            deltas,
            state: state_from(&mut pim, &deltas, state_i, bias),
        });
    }
    Ok(out)
}

/// [`PreintError::InvalidParameter`] for a non-finite state.
fn check_state(state_i: &NavState) -> Result<(), PreintError> {
    if state_i.is_finite() {
        Ok(())
    } else {
        Err(PreintError::InvalidParameter {
            name: "state_i",
            reason: "non-finite component",
        })
    }
}

/// The state at `d.t_ns`: `state_i` itself at `t_i`, else [`predict`] with `pim` carrying `d`.
fn state_from(
    pim: &mut PreintegratedImu,
    d: &DeltasAt,
    state_i: &NavState,
    bias: &ImuBias,
) -> NavState {
    if d.t_ns == pim.t_i_ns {
        return *state_i;
    }
    pim.t_j_ns = d.t_ns;
    pim.delta_t = d.delta_t;
    pim.delta_r = d.delta_r;
    pim.delta_v = d.delta_v;
    pim.delta_p = d.delta_p;
    predict(pim, state_i, bias)
}

/// Deskews a lidar sweep: each point `(t_ns, x)` — `x` \[m\] in the body frame at its own time
/// `t_ns` (non-decreasing, inside `[t_i_ns, t_j_ns]`) — expressed in the body frame at `t_i`
/// or `t_j` (`target`), `R_refᵀ (p(t) + R(t) x − p_ref)` with the states of [`states_at`]
/// from `state_i` (world frame at `t_i`; its attitude and velocity matter, its position does
/// not). Errors as [`states_at`], and [`PreintError::NonFinitePoint`].
pub fn deskew_points(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
    state_i: &NavState,
    points: &[(i64, Vector3<f64>)],
    target: DeskewTarget,
) -> Result<Vec<Vector3<f64>>, PreintError> {
    check_state(state_i)?;
    let mut w = WindowDeltas::new(params, bias, samples, t_i_ns, t_j_ns)?;
    let mut pim = template(params, bias, t_i_ns);
    let mut out = Vec::with_capacity(points.len());
    for (index, (t_ns, x)) in points.iter().enumerate() {
        if !x.iter().all(|c| c.is_finite()) {
            return Err(PreintError::NonFinitePoint { index, t_ns: *t_ns });
        }
        let d = w.at(*t_ns).map_err(|e| point_error(e, index))?;
        let s = state_from(&mut pim, &d, state_i, bias);
        // World frame (relative to p_i, which keeps the numbers small).
        out.push(s.p - state_i.p + s.r.act(x));
    }
    let reference = match target {
        DeskewTarget::Start => *state_i,
        DeskewTarget::End => {
            let d = w.at(t_j_ns).map_err(|e| point_error(e, points.len()))?;
            state_from(&mut pim, &d, state_i, bias)
        }
    };
    let (r_t, p_ref) = (reference.r.inverse(), reference.p - state_i.p);
    for x in &mut out {
        *x = r_t.act(&(*x - p_ref));
    }
    Ok(out)
}

/// A query error renumbered by point.
fn point_error(e: PreintError, index: usize) -> PreintError {
    match e {
        PreintError::QueryOutsideWindow {
            t_ns,
            t_i_ns,
            t_j_ns,
            ..
        } => PreintError::QueryOutsideWindow {
            index,
            t_ns,
            t_i_ns,
            t_j_ns,
        },
        PreintError::QueryNotSorted {
            t_ns, prev_t_ns, ..
        } => PreintError::QueryNotSorted {
            index,
            t_ns,
            prev_t_ns,
        },
        other => other,
    }
}
