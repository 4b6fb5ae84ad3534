"""Type stubs of the extension module preint._native (re-exported by the package preint).

Units and frames: timestamps int64 nanoseconds; gyro rad/s, accelerometer m/s² (sensor frame);
tangent order [dphi, dv, dp] (9) and [dphi, dv, dp, dbg, dba] (15); bias order [b_g, b_a].
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]

# --- core: parameters, preintegration, measurement ---

# --- factor: NavState, prediction, factors, deskew ---

from typing import final

@final
class NavState:
    """Navigation state: attitude R_wb (body → world), position [m] and velocity [m/s] of the
    body origin in the world frame (z up).

    Tangent order [δφ, δp, δv] (rad, m, m/s): R ← R·Exp(δφ) (right, body frame),
    p ← p + R·δp (body frame), v ← v + δv (world frame) — GTSAM's NavState order, not the
    [δφ, δv, δp] order of residuals and covariances. Pickles exactly.
    """

    TANGENT_ORDER: tuple[str, str, str]
    def __new__(
        cls,
        rotation: npt.ArrayLike | None = None,
        position: npt.ArrayLike | None = None,
        velocity: npt.ArrayLike | None = None,
    ) -> NavState:
        """`rotation`: 3×3 rotation matrix or unit quaternion (w, x, y, z); `position` [m],
        `velocity` [m/s], world frame. Defaults: identity, zeros."""
    @staticmethod
    def identity() -> NavState:
        """Identity attitude, zero position and velocity."""
    @property
    def rotation(self) -> F64:
        """Attitude R_wb (3×3, body → world)."""
    @property
    def position(self) -> F64:
        """Position [m], world frame."""
    @property
    def velocity(self) -> F64:
        """Velocity [m/s], world frame."""
    def retract(self, delta: npt.ArrayLike) -> NavState:
        """self ⊕ [δφ, δp, δv] = (R Exp(δφ), p + R δp, v + δv)."""
    def local(self, other: NavState) -> F64:
        """other ⊖ self = [Log(Rᵀ R_o), Rᵀ(p_o − p), v_o − v] (9), inverse of retract."""
    def __eq__(self, value: object, /) -> bool: ...

def predict(pim: PreintegratedImu, state_i: NavState, bias_i: ImuBias | None = None) -> NavState:
    """State at keyframe j from the state at i (Forster 2017 eq. 33 with the eq. 44 bias
    correction; rotating frame when `pim.omega_coriolis` is set). `bias_i` [b_g, b_a] defaults
    to `pim.bias_hat`. GTSAM's `pim.predict(state_i, bias_i)`."""

@final
class ImuFactor:
    """Forster's IMU factor between (state_i, state_j, bias_i), 9-dim residual
    [r_φ, r_v, r_p] (rad, m/s, m). `residual`: "logmap" (SE₂(3), GTSAM 4.3 `Logmap`, default)
    or "component" (Forster eq. 45, GTSAM `ComponentWise`). Raises FactorError for a
    measurement below level "covariance" or with a covariance that is not positive definite.

    Jacobians: dict {"state_i": 9×9, "state_j": 9×9, "bias_i": 9×6}; state columns
    [δφ, δp, δv] (NavState.retract), bias columns [δb_g, δb_a]. GTSAM's error is −Q r in its
    order [rot, pos, vel] (Logmap mode). `bias_i=None` means `pim.bias_hat`. Pickles exactly.
    """

    RESIDUAL_ORDER: tuple[str, str, str]
    def __new__(cls, pim: PreintegratedImu, residual: str = "logmap") -> ImuFactor: ...
    @property
    def residual_mode(self) -> str:
        """ "logmap" or "component"."""
    @property
    def pim(self) -> PreintegratedImu:
        """The measurement (a copy)."""
    @property
    def sqrt_information(self) -> F64:
        """U (9×9 upper triangular), Σ⁻¹ = UᵀU, order [r_φ, r_v, r_p]."""
    @property
    def residual_covariance(self) -> F64:
        """Σ (9×9): pim.cov (component) or T cov Tᵀ, T = diag(I, ΔRᵀ, ΔRᵀ) (logmap)."""
    def predict(self, state_i: NavState, bias_i: ImuBias | None = None) -> NavState: ...
    def residual(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> F64:
        """[r_φ, r_v, r_p] (9)."""
    def evaluate(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> tuple[F64, dict[str, F64]]:
        """(residual, {"state_i", "state_j", "bias_i"} Jacobians)."""
    def evaluate_whitened(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> tuple[F64, dict[str, F64]]:
        """(U r, {name: U J})."""
    def chi2(self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None) -> float:
        """rᵀ Σ⁻¹ r (9 dof)."""
    def cost(self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None) -> float:
        """½ chi2 (GTSAM's factor error)."""
    def __eq__(self, value: object, /) -> bool: ...

@final
class CombinedImuFactor:
    """Combined IMU factor between (state_i, state_j, bias_i, bias_j), 15-dim residual
    [r_φ, r_v, r_p, r_bg, r_ba] (rad, m/s, m, rad/s, m/s²; bias rows b_j − b_i), weighted by
    pim.residual_cov15() (component) or diag(T, I₆)·it·diag(T, I₆)ᵀ (logmap). Needs level
    "combined" and a non-zero bias random walk (else FactorError).

    Jacobians: dict {"state_i": 15×9, "state_j": 15×9, "bias_i": 15×6, "bias_j": 15×6};
    columns as ImuFactor. `bias_i=None` means `pim.bias_hat`, `bias_j=None` means `bias_i`.
    """

    RESIDUAL_ORDER: tuple[str, str, str, str, str]
    def __new__(cls, pim: PreintegratedImu, residual: str = "logmap") -> CombinedImuFactor: ...
    @property
    def residual_mode(self) -> str: ...
    @property
    def pim(self) -> PreintegratedImu: ...
    @property
    def sqrt_information(self) -> F64:
        """U (15×15 upper triangular), Σ⁻¹ = UᵀU."""
    @property
    def residual_covariance(self) -> F64:
        """Σ (15×15), order [r_φ, r_v, r_p, r_bg, r_ba]."""
    def predict(self, state_i: NavState, bias_i: ImuBias | None = None) -> NavState: ...
    def residual(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> F64: ...
    def evaluate(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> tuple[F64, dict[str, F64]]: ...
    def evaluate_whitened(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> tuple[F64, dict[str, F64]]: ...
    def chi2(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> float: ...
    def cost(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> float: ...
    def __eq__(self, value: object, /) -> bool: ...


# --- io and calibration: readers, Allan variance, calibration, advise ---
