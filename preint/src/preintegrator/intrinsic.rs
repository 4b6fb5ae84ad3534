//! IMU intrinsics in the preintegrator ([`crate::intrinsics`]; the samples reach the loop
//! corrected, `front.rs`): the accumulator of the deltas' Jacobians with respect to the
//! intrinsics' parameters.
//!
//! # Jacobians
//!
//! Sample j enters the deltas only through its corrected values `u_j = (ω'_j, a'_j)`, so
//! `∂e/∂θ = Σ_j G_j ∂u_j/∂θ`, `G_j` the sample's total gain (the 9×6 matrix its noise is
//! retired with, pulled back to the window's origin). `∂u/∂θ` is linear in `u`
//! ([`ImuIntrinsics::sample_jacobian`]): `∂u/∂θ = Σ_c ω'_c B_ω,c + a'_c B_a,c` with `B` the
//! sample Jacobian of the unit vectors, and `∂a'/∂θ` does not depend on `ω'`. The loop therefore
//! accumulates, at each retirement, the 216 products `S_gω[c] += G_g ω'_c`,
//! `S_ga[c] += G_g a'_c`, `S_aa[c] += G_a a'_c`, and the window's end contracts them,
//! `Σ_c [S_gω[c], 0] B_ω,c + [S_ga[c], S_aa[c]] B_a,c`, pushes the result forward (`Φ_N`) and
//! takes its rotation rows into the chart (`δφ = ΔRᵀ ψ`), as for the bias Jacobians.

use super::{Preintegrator, checked};
use crate::error::PreintError;
use crate::intrinsics::{ImuIntrinsics, IntrinsicJacobian};
use crate::measurement::PreintegratedImu;
use crate::propagation::SampleGain;
use crate::propagation::blocks::{Cols6, Cols9, Gain96, M3};
use crate::propagation::transition::Transition;
use crate::sample::ImuBias;
use crate::scheme::Node;
use nalgebra::{SMatrix, Vector3};

/// Where the loop's retirements send each sample's total gain: nowhere (`()`, zero-sized: the
/// default loop is unchanged) or the intrinsics' sums.
pub(super) trait Sink {
    /// Whether gains are collected.
    const ON: bool;
    /// Adds the total gain `g` of the sample whose node is `node`.
    fn add(&mut self, g: &SampleGain, node: &Node);
}

impl Sink for () {
    const ON: bool = false;
    #[inline(always)]
    fn add(&mut self, _: &SampleGain, _: &Node) {}
}

impl Sink for &mut IntrAcc {
    const ON: bool = true;
    #[inline(always)]
    fn add(&mut self, g: &SampleGain, node: &Node) {
        IntrAcc::add(self, &g.full(), node);
    }
}

/// The loop's variant, chosen at compile time: with or without the intrinsics' sums.
pub(super) trait IntrMode {
    type Sink<'a>: Sink;
    /// The sink borrowing the core's sums.
    fn sink(acc: &mut Option<Box<IntrAcc>>) -> Self::Sink<'_>;
}

/// The default loop.
pub(super) struct NoIntr;

impl IntrMode for NoIntr {
    type Sink<'a> = ();
    #[inline(always)]
    fn sink(_: &mut Option<Box<IntrAcc>>) {}
}

/// The loop that accumulates the intrinsics' sums (the core holds them whenever it runs).
pub(super) struct WithIntr;

impl IntrMode for WithIntr {
    type Sink<'a> = &'a mut IntrAcc;
    #[inline(always)]
    fn sink(acc: &mut Option<Box<IntrAcc>>) -> &mut IntrAcc {
        acc.as_deref_mut()
            .expect("the intrinsics' sums exist whenever their loop runs")
    }
}

/// The sums of the module docs, pulled back to the window's origin.
#[derive(Clone, Debug)]
pub(crate) struct IntrAcc {
    /// The intrinsics the samples were corrected with.
    model: ImuIntrinsics,
    /// The bias estimate the nodes were corrected with (`u = node + b̂`).
    bias: ImuBias,
    s_gw: [Cols9; 3],
    s_ga: [Cols9; 3],
    s_aa: [Cols6; 3],
}

impl IntrAcc {
    pub(crate) fn new(model: ImuIntrinsics, bias: ImuBias) -> Self {
        Self {
            model,
            bias,
            s_gw: [[[0.0; 9]; 3]; 3],
            s_ga: [[[0.0; 9]; 3]; 3],
            s_aa: [[[0.0; 6]; 3]; 3],
        }
    }

    /// Adds sample `node`'s total gain `g`.
    #[inline(always)]
    pub(crate) fn add(&mut self, g: &Gain96, node: &Node) {
        let w = node.w + self.bias.gyro;
        let a = node.a + self.bias.acc;
        for c in 0..3 {
            let (wc, ac) = (w[c], a[c]);
            for m in 0..3 {
                for i in 0..9 {
                    let x = g.g[m][i];
                    self.s_gw[c][m][i] += x * wc;
                    self.s_ga[c][m][i] += x * ac;
                }
                for i in 0..6 {
                    self.s_aa[c][m][i] += g.a[m][i] * ac;
                }
            }
        }
    }

    /// `∂(ΔR, Δv, Δp)/∂θ` in the chart, from the window's push-forward `tr` (`Φ_N`) and its
    /// `ΔR` (`r`).
    pub(crate) fn jacobian(&self, tr: &Transition, r: &M3) -> IntrinsicJacobian {
        let model = &self.model;
        let i3 = M3::identity();
        let zero = Vector3::zeros();
        let mut jp = IntrinsicJacobian::zeros();
        for c in 0..3 {
            let e = Vector3::ith(c, 1.0);
            let nw = Gain96 {
                g: self.s_gw[c],
                a: [[0.0; 6]; 3],
            }
            .chart(&i3);
            let na = Gain96 {
                g: self.s_ga[c],
                a: self.s_aa[c],
            }
            .chart(&i3);
            jp += nw * model.sample_jacobian(&e, &zero) + na * model.sample_jacobian(&zero, &e);
        }
        let rt = r.transpose();
        let mut out = IntrinsicJacobian::zeros();
        for k in 0..ImuIntrinsics::PARAMS / 3 {
            let mut g = Gain96::default();
            for (j, col) in g.g.iter_mut().enumerate() {
                for (i, x) in col.iter_mut().enumerate() {
                    *x = jp[(i, 3 * k + j)];
                }
            }
            let f = tr.apply(&g);
            let block: SMatrix<f64, 9, 3> = SMatrix::from_fn(|i, j| f.g[j][i]);
            let mut view = out.fixed_view_mut::<9, 3>(0, 3 * k);
            view.copy_from(&block);
            let psi = rt * block.fixed_view::<3, 3>(0, 0);
            view.fixed_view_mut::<3, 3>(0, 0).copy_from(&psi);
        }
        out
    }
}

impl Preintegrator {
    /// [`Preintegrator::finish`] with the Jacobians of `[δφ, δv, δp]` with respect to the
    /// intrinsics' parameters ([`crate::intrinsics`], columns in
    /// [`ImuIntrinsics::PARAMS`](crate::intrinsics::ImuIntrinsics::PARAMS) order) at the
    /// frame-I bias estimate. Errors: those of `finish`, and
    /// [`PreintError::InvalidParameter`] when `params.intrinsics` does not ask for them or the
    /// level is [`Level::Deltas`](crate::Level::Deltas).
    ///
    /// ```
    /// use preint::intrinsics::{AppliedIntrinsics, ImuIntrinsics, IntrinsicsModel};
    /// use preint::nalgebra::Vector3;
    /// use preint::{ImuBias, ImuSample, PreintParams, Preintegrator};
    /// let mut x = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    /// x.t_w[(0, 0)] = 1.01; // the gyro x axis reads 1 % high
    /// let mut params = PreintParams::default();
    /// params.intrinsics = Some(AppliedIntrinsics::new(x).with_jacobians());
    /// let mut pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
    /// for k in 0..201i64 {
    ///     let s = ImuSample::new(k * 5_000_000, Vector3::new(0.101, 0.0, 0.0), Vector3::new(0.0, 0.0, 9.81));
    ///     pi.integrate(&s).unwrap();
    /// }
    /// let (m, jac) = pi.finish_with_intrinsic_jacobian().unwrap();
    /// assert!((m.delta_r.log().x - 0.1).abs() < 1e-12); // the true 0.1 rad/s over 1 s
    /// assert!((jac[(0, 0)] + 0.1 / 1.01).abs() < 1e-12); // ∂φ_x/∂Tw(0,0) = −ω_m T/Tw² ≈ −0.099
    /// ```
    pub fn finish_with_intrinsic_jacobian(
        &self,
    ) -> Result<(PreintegratedImu, crate::intrinsics::IntrinsicJacobian), PreintError> {
        let count = self.engine.len();
        if count < 2 {
            return Err(PreintError::TooFewSamples { count });
        }
        let (m, jac) = self.engine.measurement_and_intrinsics();
        let Some(jac) = jac else {
            return Err(PreintError::InvalidParameter {
                name: "intrinsics",
                reason: "Jacobians not requested (AppliedIntrinsics::jacobians) or level Deltas",
            });
        };
        if !jac.iter().all(|x| x.is_finite()) {
            return Err(PreintError::NonFiniteResult {
                what: "intrinsic Jacobians",
            });
        }
        Ok((checked(m)?, jac))
    }
}
