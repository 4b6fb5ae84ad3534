//! The choices a preintegration is configured with besides its numbers: what to compute
//! ([`Level`]) and the model of each effect ([`BiasCorrection`], [`CoriolisMode`],
//! [`LeverArm`]). Kept apart from the mathematics that implements them, so that every data type
//! can name them.

/// What the preintegrator computes per sample. Ordered: `Deltas < Covariance < Combined`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Level {
    /// ΔR, Δv, Δp only (covariance and Jacobians are returned as zeros).
    Deltas,
    /// Deltas, the 9×9 covariance [δφ, δv, δp] and the five bias Jacobians.
    Covariance,
    /// Everything in `Covariance` plus the 15×15 combined covariance with bias random walk
    /// (GTSAM `CombinedImuFactor` semantics).
    Combined,
}

/// How [`PreintegratedImu::corrected`](crate::PreintegratedImu::corrected) applies the
/// first-order bias correction ([`BiasCorrection`](crate::BiasCorrection)). The default is the scheme's
/// ([`SchemeInfo::bias_correction`](crate::SchemeInfo::bias_correction)).
///
/// # The correction
///
/// With `δb = b − b̂` (`b̂ = bias_hat`) and the bias Jacobians of [`BiasJacobians`](crate::BiasJacobians) (Forster
/// et al. 2017, eq. 44), the first-order corrections in this crate's chart are
///
/// ```text
/// c_φ = ∂ΔR/∂b_g δb_g,   c_v = ∂Δv/∂b_g δb_g + ∂Δv/∂b_a δb_a,   c_p = ∂Δp/∂b_g δb_g + ∂Δp/∂b_a δb_a
/// ```
///
/// (`c_v`, `c_p` additive in frame i). Two ways of applying them:
///
/// - [`BiasCorrection::Additive`] (Forster eq. 44): `ΔR Exp(c_φ)`, `Δv + c_v`, `Δp + c_p`.
/// - [`BiasCorrection::Group`] (GTSAM 4.3's `GalileanPreintegration::biasCorrectedDelta` and
///   its SE₂(3) `LieGroupPreintegration`; Brossard et al., "Associating Uncertainty to Extended
///   Poses for on Lie Group IMU Preintegration With Rotating Earth", T-RO 2022): the deltas
///   as the group element `Γ = (ΔR, Δv, Δp)` composed on the right with the exponential of the
///   correction in the right-trivialised chart, `Γ(b) = Γ Exp(ξ)` with
///   `ξ = (c_φ, ΔRᵀc_v, ΔRᵀc_p)` (and a zero time component on Gal(3)):
///
/// ```text
/// ΔR(b) = ΔR Exp(c_φ),   Δv(b) = Δv + ΔR Jl(c_φ) ΔRᵀ c_v,   Δp(b) = Δp + ΔR Jl(c_φ) ΔRᵀ c_p
/// ```
///
/// (`Jl` the SO(3) left Jacobian). Both agree to first order in `δb`; they differ at second
/// order, where the group form keeps the coupling of the rotation correction into the
/// velocity and position corrections. On GTSAM 4.3's `PreintegratedImuMeasurementsG` fixtures
/// the group form equals GTSAM's `predict` at a shifted bias to round-off
/// (`preint/tests/galilean_gtsam.rs`). In GTSAM's bias-correction experiment at `‖δb‖ = 0.35`
/// (`tests/tests/group_bias.rs`, `docs/EVIDENCE.md`) it takes the galilean scheme's median
/// error against re-integration from 0.586 mm / 0.175 cm/s (additive) to 0.302 mm / 0.0131 cm/s,
/// GTSAM Galilean's 0.3035 mm / 0.0130 cm/s.
///
/// # Bias Jacobians of the corrected deltas
///
/// The factors differentiate the corrected deltas with respect to `δb`. For the group form,
/// with `ν = ΔRᵀc_k` (`k ∈ {v, p}`) and `∂(Jl(φ)ν)/∂φ = Q(ν, φ) − [Jl(φ)ν]× Jl(φ)` (Barfoot's
/// SE(3) block `Q`, [`preint_lie::se3::q_block`]):
///
/// ```text
/// ∂Δk(b)/∂δb_g = ΔR (Q(ν, c_φ) − [Jl(c_φ)ν]× Jl(c_φ)) ∂ΔR/∂b_g + ΔR Jl(c_φ) ΔRᵀ ∂Δk/∂b_g
/// ∂Δk(b)/∂δb_a = ΔR Jl(c_φ) ΔRᵀ ∂Δk/∂b_a
/// ```
///
/// The rotation is the same in both forms. Checked against central differences at `δb ≠ 0` in
/// `preint/tests/factor.rs` and `preint/tests/factor_logmap.rs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BiasCorrection {
    /// Forster eq. 44: `ΔR Exp(c_φ)`, `Δv + c_v`, `Δp + c_p`.
    Additive,
    /// On the group, as GTSAM 4.3's Galilean and SE₂(3) backends: `Γ Exp(c_φ, ΔRᵀc_v, ΔRᵀc_p)`.
    Group,
}

impl BiasCorrection {
    /// Every correction, in a fixed order.
    pub const ALL: [BiasCorrection; 2] = [BiasCorrection::Additive, BiasCorrection::Group];

    /// The name on the command line and in printed output: `additive` or `group`.
    pub fn name(self) -> &'static str {
        match self {
            BiasCorrection::Additive => "additive",
            BiasCorrection::Group => "group",
        }
    }

    /// The correction called `name` ([`BiasCorrection::name`]).
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// How a navigation-frame rotation rate enters prediction and the factors ([`crate::earth`] for the
/// equations). Default [`CoriolisMode::Exact`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CoriolisMode {
    /// The first-order Coriolis correction of Forster et al.'s factor as implemented by
    /// GTSAM ≤ 4.2 (`use2ndOrderCoriolis = false`): attitude `Exp(Log ΔR − T R_iᵀω)`, Coriolis
    /// terms `−T² ω×v_i` (position) and `−2T ω×v_i` (velocity); no centrifugal term.
    FirstOrder,
    /// [`CoriolisMode::FirstOrder`] plus the centrifugal terms `−½T² ω×(ω×p_i)` and
    /// `−T ω×(ω×p_i)` (GTSAM ≤ 4.2 `use2ndOrderCoriolis = true`).
    SecondOrder,
    /// The exact transition for a navigation frame rotating at a constant rate with gravity
    /// fixed in it (what GTSAM 4.3 does with `omegaCoriolis`; `use2ndOrderCoriolis` has no
    /// effect there).
    #[default]
    Exact,
}

/// How the lever arm of a [`SensorPose`](crate::SensorPose) is removed ([`SensorPose`](crate::SensorPose)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LeverArm {
    /// The closed form of [`SensorPose`](crate::SensorPose), from the window's end rates: exact whatever `ω̇`,
    /// no per-sample cost. The default.
    #[default]
    Exact,
    /// GTSAM's model (`PreintegrationBase::correctMeasurementsBySensorPose`): `ω × (ω × r)`
    /// subtracted from every sample's specific force, `ω̇ × r` ignored, the gyroscope noise
    /// and bias the centripetal term carries into the specific force propagated per sample.
    /// Exact only at a constant rate (there, with Euler, it also cancels Euler's error on the
    /// sensor's circular motion); otherwise it leaves out `∫ ΔR (ω̇ × r) dt`. For agreeing with
    /// GTSAM's numbers.
    Centripetal,
}

impl LeverArm {
    /// The model's name on the command line and in printed output: `exact` or `centripetal`.
    pub fn name(self) -> &'static str {
        match self {
            LeverArm::Exact => "exact",
            LeverArm::Centripetal => "centripetal",
        }
    }

    /// The model called `name` ([`LeverArm::name`]).
    pub fn parse(name: &str) -> Option<Self> {
        [LeverArm::Exact, LeverArm::Centripetal]
            .into_iter()
            .find(|m| m.name() == name)
    }
}
