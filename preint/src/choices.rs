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
/// first-order bias correction ([`crate::bias_correction`]). The default is the scheme's
/// ([`SchemeInfo::bias_correction`](crate::SchemeInfo::bias_correction)).
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

/// How the lever arm of a [`SensorPose`](crate::SensorPose) is removed ([`crate::extrinsics`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LeverArm {
    /// The closed form of [`crate::extrinsics`], from the window's end rates: exact whatever `ω̇`,
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
