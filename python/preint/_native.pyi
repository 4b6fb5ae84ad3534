"""Type stubs of the extension module preint._native (re-exported by the package preint).

Units and frames: timestamps int64 nanoseconds; gyro rad/s, accelerometer m/s² (sensor frame);
tangent order [dphi, dv, dp] (9) and [dphi, dv, dp, dbg, dba] (15); bias order [b_g, b_a].
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_I64 = npt.NDArray[np.int64]

# --- core: parameters, preintegration, measurement ---

from collections.abc import Sequence
from typing import ClassVar, Literal, final

_Vec3Like = Sequence[float] | npt.NDArray[np.floating]
"""Three numbers: a list, tuple or numpy array."""
_Mat3Like = Sequence[Sequence[float]] | npt.NDArray[np.floating]
"""A 3×3 matrix: nested sequences (rows) or a 2-D numpy array."""
_Cov3Like = float | _Mat3Like
"""A 3×3 covariance, or a number s meaning s·I."""
_RotationLike = Sequence[float] | _Mat3Like
"""A 3×3 rotation matrix or a unit quaternion (w, x, y, z)."""
_SchemeName = Literal["euler", "midpoint", "hermite4", "galilean"]
_LevelName = Literal["deltas", "covariance", "combined"]
_CoriolisName = Literal["exact", "first", "second"]

# The other sections extend it with `__all__ += [...]` (the module's runtime __all__ lists
# every class and function it registers).
__all__ = [
    "SCHEMES",
    "ImuBias",
    "Noise",
    "Params",
    "PreintegratedImu",
    "Preintegrator",
    "merge",
    "preintegrate",
    "preintegrate_windows",
]

SCHEMES: list[str]
"""The scheme names: ["euler", "midpoint", "hermite4", "galilean"]."""

@final
class Noise:
    """Kalibr-style continuous-time IMU noise densities. White-noise densities and the rate
    must be finite and > 0 (a zero white-noise density cannot weight a factor), random walks
    finite and ≥ 0 (0: a constant bias); otherwise PreintError (kind "InvalidParameter")
    naming the field."""

    def __new__(
        cls,
        gyro_noise_density: float,
        gyro_random_walk: float,
        acc_noise_density: float,
        acc_random_walk: float,
        update_rate_hz: float = 200.0,
    ) -> Noise: ...
    @staticmethod
    def euroc() -> Noise:
        """The EuRoC MAV dataset's ADIS16448 densities."""
    @property
    def gyro_noise_density(self) -> float:
        """Gyro white-noise density [rad/s/√Hz]."""
    @property
    def gyro_random_walk(self) -> float:
        """Gyro bias random walk [rad/s²/√Hz]."""
    @property
    def acc_noise_density(self) -> float:
        """Accelerometer white-noise density [m/s²/√Hz]."""
    @property
    def acc_random_walk(self) -> float:
        """Accelerometer bias random walk [m/s³/√Hz]."""
    @property
    def update_rate_hz(self) -> float:
        """Sample rate [Hz]."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[float, float, float, float, float]]: ...

@final
class ImuBias:
    """A bias estimate: gyro [rad/s], accelerometer [m/s²], sensor frame; order [b_g, b_a].
    Non-finite components raise PreintError (kind "InvalidParameter")."""

    def __new__(cls, gyro: _Vec3Like | None = None, acc: _Vec3Like | None = None) -> ImuBias: ...
    @property
    def gyro(self) -> _F64:
        """Gyro bias [rad/s], shape (3,)."""
    @property
    def acc(self) -> _F64:
        """Accelerometer bias [m/s²], shape (3,)."""
    def vector(self) -> _F64:
        """[b_g, b_a], shape (6,)."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[list[float], list[float]]]: ...

@final
class Params:
    """Preintegration parameters (Rust PreintParams); covariances continuous-time.

    Every setter checks its value and keeps the old one on error (PreintError, kind
    "InvalidParameter", naming the property): gravity finite with |g| ≤ 100 m/s²,
    omega_coriolis finite with |ω| < 100 rad/s, covariances finite and symmetric with a
    non-negative diagonal, thresholds > 0, max_gap_ns > 0, body_p_sensor a rotation (within
    1e-6) and a finite translation."""

    def __new__(cls, noise: Noise | None = None, *, scheme: str = "midpoint", level: str = "combined") -> Params: ...
    @property
    def gravity(self) -> _F64:
        """Gravity in the world frame [m/s²], shape (3,)."""
    @gravity.setter
    def gravity(self, v: _Vec3Like) -> None: ...
    @property
    def gyroscope_covariance(self) -> _F64:
        """Gyro white-noise covariance [rad²/s], 3×3."""
    @gyroscope_covariance.setter
    def gyroscope_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def accelerometer_covariance(self) -> _F64:
        """Accelerometer white-noise covariance [m²/s³], 3×3."""
    @accelerometer_covariance.setter
    def accelerometer_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def bias_gyro_covariance(self) -> _F64:
        """Gyro bias random-walk covariance [rad²/s³], 3×3."""
    @bias_gyro_covariance.setter
    def bias_gyro_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def bias_acc_covariance(self) -> _F64:
        """Accelerometer bias random-walk covariance [m²/s⁵], 3×3."""
    @bias_acc_covariance.setter
    def bias_acc_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def integration_covariance(self) -> _F64 | None:
        """Integration covariance [m²/s³] added to Δp per unit time, 3×3, or None."""
    @integration_covariance.setter
    def integration_covariance(self, v: _Cov3Like | None) -> None: ...
    @property
    def scheme(self) -> _SchemeName:
        """"euler" (GTSAM Manifold), "midpoint", "hermite4" or "galilean" (GTSAM PreintegratedImuMeasurementsG)."""
    @scheme.setter
    def scheme(self, v: str) -> None: ...
    @property
    def level(self) -> _LevelName:
        """"deltas", "covariance" or "combined"."""
    @level.setter
    def level(self, v: str) -> None: ...
    @property
    def reintegrate_gyro_threshold(self) -> float:
        """Gyro-bias change [rad/s] above which measurement_for_bias re-integrates."""
    @reintegrate_gyro_threshold.setter
    def reintegrate_gyro_threshold(self, v: float) -> None: ...
    @property
    def reintegrate_acc_threshold(self) -> float:
        """Accelerometer-bias change [m/s²] above which measurement_for_bias re-integrates."""
    @reintegrate_acc_threshold.setter
    def reintegrate_acc_threshold(self, v: float) -> None: ...
    @property
    def max_gap_ns(self) -> int:
        """Largest allowed gap between samples [ns]."""
    @max_gap_ns.setter
    def max_gap_ns(self, v: int) -> None: ...
    @property
    def keep_samples(self) -> bool:
        """Whether a Preintegrator stores its samples (needed to re-integrate)."""
    @keep_samples.setter
    def keep_samples(self, v: bool) -> None: ...
    @property
    def body_p_sensor(self) -> tuple[_F64, _F64] | None:
        """(R_bs 3×3, t_bs [m] in the body frame), or None."""
    def set_body_p_sensor(self, rotation: _RotationLike | None, translation: _Vec3Like | None = None) -> None:
        """Sets (or with None clears) the IMU's pose in the body frame."""
    @property
    def lever_arm(self) -> Literal["exact", "centripetal"]:
        """"exact" or "centripetal" (GTSAM's)."""
    @lever_arm.setter
    def lever_arm(self, v: str) -> None: ...
    @property
    def bias_correction(self) -> Literal["additive", "group"] | None:
        """"additive", "group" or None (the scheme's: group for galilean, additive otherwise)."""
    @bias_correction.setter
    def bias_correction(self, v: str | None) -> None: ...
    @property
    def omega_coriolis(self) -> _F64 | None:
        """Navigation-frame rotation rate [rad/s], shape (3,), or None."""
    @omega_coriolis.setter
    def omega_coriolis(self, v: _Vec3Like | None) -> None: ...
    @property
    def coriolis(self) -> _CoriolisName:
        """"exact", "first" or "second"."""
    @coriolis.setter
    def coriolis(self, v: str) -> None: ...
    def validate(self) -> None:
        """Raises PreintError if a parameter is invalid."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[list[int]]]: ...
    @staticmethod
    def _from_state(state: bytes) -> Params: ...

@final
class PreintegratedImu:
    """A preintegrated measurement between keyframes i and j; tangent order [dphi, dv, dp]."""

    TANGENT_ORDER: ClassVar[tuple[str, str, str]]
    TANGENT_ORDER_15: ClassVar[tuple[str, str, str, str, str]]
    @property
    def t_i_ns(self) -> int:
        """Keyframe i time [ns]."""
    @property
    def t_j_ns(self) -> int:
        """Keyframe j time [ns]."""
    @property
    def delta_t(self) -> float:
        """t_j − t_i [s]."""
    @property
    def delta_R(self) -> _F64:
        """ΔR_ij, 3×3 rotation (body j → body i)."""
    @property
    def delta_rotvec(self) -> _F64:
        """Log(ΔR_ij) [rad], shape (3,)."""
    @property
    def delta_v(self) -> _F64:
        """Δv_ij [m/s] in body frame i, gravity excluded, shape (3,)."""
    @property
    def delta_p(self) -> _F64:
        """Δp_ij [m] in body frame i, gravity excluded, shape (3,)."""
    @property
    def cov(self) -> _F64:
        """9×9 covariance of [dphi, dv, dp]."""
    @property
    def cov15(self) -> _F64:
        """15×15 covariance of [dphi, dv, dp, dbg, dba]."""
    def residual_cov15(self) -> _F64:
        """15×15 covariance of the combined factor's residual (cov15, delta–bias blocks negated)."""
    @property
    def bias_jacobians(self) -> _F64:
        """9×6: rows [dphi, dv, dp], columns [b_g, b_a]."""
    @property
    def bias_hat(self) -> ImuBias:
        """The bias estimate the samples were integrated with."""
    @property
    def gravity(self) -> _F64:
        """Gravity [m/s²] in the world frame, shape (3,)."""
    @property
    def omega_coriolis(self) -> _F64 | None:
        """Navigation-frame rotation rate [rad/s], or None."""
    @property
    def coriolis(self) -> _CoriolisName:
        """"exact", "first" or "second"."""
    @property
    def level(self) -> _LevelName:
        """"deltas", "covariance" or "combined"."""
    @property
    def bias_correction(self) -> Literal["additive", "group"]:
        """How corrected/predict/the factors apply a new bias: "additive" (Forster eq. 44) or
        "group" (right-applied on SE₂(3), GTSAM's Galilean backend; galilean's default)."""
    def corrected(self, bias: ImuBias) -> tuple[_F64, _F64, _F64]:
        """First-order bias-corrected (ΔR 3×3, Δv [m/s], Δp [m]), additively or on the group
        (bias_correction). At level "deltas" (no bias Jacobians) a bias other than bias_hat
        raises PreintError (kind "NoBiasJacobians")."""
    def delta_error(self, reference: PreintegratedImu) -> _F64:
        """[Log(ΔR_refᵀ ΔR), Δv − Δv_ref, Δp − Δp_ref], shape (9,)."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[bytes]]: ...
    @staticmethod
    def _from_state(state: bytes) -> PreintegratedImu: ...

@final
class Preintegrator:
    """Accumulates samples (one at a time or from arrays) into a PreintegratedImu.
    ``capacity`` (samples stored without reallocating) is at most 50 million."""

    def __new__(cls, params: Params, bias: ImuBias | None = None, capacity: int = 0) -> Preintegrator: ...
    def integrate(self, t_ns: int, gyro: _Vec3Like, acc: _Vec3Like) -> None:
        """Adds one sample: time [ns], gyro [rad/s], accelerometer [m/s²]."""
    def integrate_arrays(self, t_ns: _I64, gyro: _F64, acc: _F64) -> None:
        """Adds int64[N] times [ns], float64[N, 3] gyro [rad/s] and accelerometer [m/s²]."""
    def finish(self) -> PreintegratedImu:
        """The measurement over [first sample, last sample]."""
    def measurement_for_bias(self, bias: ImuBias) -> tuple[PreintegratedImu, bool]:
        """(measurement for `bias`, whether it was re-integrated). At level "deltas" any
        change re-integrates, and without keep_samples raises PreintError (kind
        "NoBiasJacobians")."""
    def reintegrate(self, bias: ImuBias) -> None:
        """Re-integrates the stored samples with `bias`."""
    @property
    def params(self) -> Params:
        """The parameters (a copy)."""
    @property
    def bias_hat(self) -> ImuBias:
        """The bias estimate samples are integrated with."""
    def __len__(self) -> int: ...

def preintegrate(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    t_i_ns: int,
    t_j_ns: int,
    bias: ImuBias | None = None,
) -> PreintegratedImu:
    """The measurement over the keyframe window [t_i_ns, t_j_ns] of a time-ordered stream."""

def preintegrate_windows(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    keyframes_ns: _I64,
    bias: ImuBias | None = None,
) -> list[PreintegratedImu]:
    """One measurement per pair of consecutive keyframes (int64[K]): K − 1 results."""

def merge(a: PreintegratedImu, b: PreintegratedImu) -> PreintegratedImu:
    """The measurement over [a.t_i, b.t_j] from two consecutive measurements."""


# --- inside a window: deltas and states at query times, deskewing, truncation error ---

__all__ += [
    "add_covariance",
    "deltas_at",
    "deskew_points",
    "inflate",
    "second_order_covariance",
    "states_at",
    "truncation_estimate",
]

def deltas_at(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    t_i_ns: int,
    t_j_ns: int,
    times_ns: _I64,
    bias: ImuBias | None = None,
) -> dict[str, npt.NDArray[Any]]:
    """Deltas from t_i_ns to each query time (int64[K], non-decreasing, inside the window):
    keys t_ns, delta_t [s], delta_R [K,3,3], delta_v [m/s] and delta_p [m] [K,3] (frame i,
    gravity excluded). Raises PreintError (QueryNotSorted, QueryOutsideWindow, …)."""

def states_at(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    t_i_ns: int,
    t_j_ns: int,
    state_i: NavState,
    times_ns: _I64,
    bias: ImuBias | None = None,
) -> dict[str, npt.NDArray[Any]]:
    """deltas_at's arrays plus the predicted body state at each query time, world frame:
    rotation [K,3,3] (body → world), position [m] and velocity [m/s] [K,3]."""

def deskew_points(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    t_i_ns: int,
    t_j_ns: int,
    state_i: NavState,
    points_t_ns: _I64,
    points: _F64,
    target: Literal["start", "end"] = "start",
    bias: ImuBias | None = None,
) -> _F64:
    """Lidar points [M,3] [m], each in the body frame at its own time, expressed in the body
    frame at t_i_ns ("start") or t_j_ns ("end")."""

def truncation_estimate(
    params: Params,
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    pim: PreintegratedImu,
    bias: ImuBias | None = None,
) -> tuple[_F64, str, _F64]:
    """(error float64[9] = scheme ⊖ exact deltas in [dphi rad, dv m/s, dp m], method,
    companion_cov float64[9, 9] the companion's covariance, which inflate weights with).
    ``bias`` defaults to pim.bias_hat; another bias raises PreintError."""

def inflate(
    pim: PreintegratedImu,
    error: _Vec3Like | Sequence[float] | _F64,
    residual: str = "logmap",
    companion_cov: _F64 | Sequence[Sequence[float]] | None = None,
) -> PreintegratedImu:
    """pim with cov = companion_cov + u uᵀ (the 9×9 block of cov15 changed by the same amount),
    u the estimate `error` (nine numbers [dphi, dv, dp]) as a factor of mode `residual` sees it
    ("logmap" or "component"); companion_cov defaults to pim.cov."""

def second_order_covariance(
    params: Params, t_ns: _I64, gyro: _F64, acc: _F64, pim: PreintegratedImu
) -> _F64:
    """The second-order covariance term of pim's SE₂(3) error, float64[9, 9] in
    [dphi rad, dv m/s, dp m]."""

def add_covariance(pim: PreintegratedImu, term: _F64 | Sequence[Sequence[float]]) -> PreintegratedImu:
    """pim with the symmetric 9×9 `term` added to cov and to the 9×9 block of cov15."""

# --- factor: NavState, prediction, factors ---

__all__ += ["CombinedImuFactor", "ImuFactor", "NavState", "predict"]

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
        """`rotation`: 3×3 rotation matrix or unit quaternion (w, x, y, z), within 1e-6
        (ShapeError otherwise); `position` [m], `velocity` [m/s], world frame, finite
        (PreintError otherwise). Defaults: identity, zeros."""
    @staticmethod
    def identity() -> NavState:
        """Identity attitude, zero position and velocity."""
    @property
    def rotation(self) -> _F64:
        """Attitude R_wb (3×3, body → world)."""
    @property
    def position(self) -> _F64:
        """Position [m], world frame."""
    @property
    def velocity(self) -> _F64:
        """Velocity [m/s], world frame."""
    def retract(self, delta: npt.ArrayLike) -> NavState:
        """self ⊕ [δφ, δp, δv] = (R Exp(δφ), p + R δp, v + δv); `delta` finite."""
    def local(self, other: NavState) -> _F64:
        """other ⊖ self = [Log(Rᵀ R_o), Rᵀ(p_o − p), v_o − v] (9), inverse of retract."""
    def __eq__(self, value: object, /) -> bool: ...

def predict(pim: PreintegratedImu, state_i: NavState, bias_i: ImuBias | None = None) -> NavState:
    """State at keyframe j from the state at i (Forster 2017 eq. 33 with the eq. 44 bias
    correction; rotating frame when `pim.omega_coriolis` is set). `bias_i` [b_g, b_a] defaults
    to `pim.bias_hat`. GTSAM's `pim.predict(state_i, bias_i)`. A level "deltas" measurement
    has no bias Jacobians: a `bias_i` other than its bias_hat raises PreintError (kind
    "NoBiasJacobians") instead of being ignored."""

@final
class ImuFactor:
    """Forster's IMU factor between (state_i, state_j, bias_i), 9-dim residual
    [r_φ, r_v, r_p] (rad, m/s, m). `residual`: "logmap" (SE₂(3), GTSAM 4.3 `Logmap`, default)
    or "component" (Forster eq. 45, GTSAM `ComponentWise`). Weighted by pim.cov (GTSAM's
    weight) or, with `in_window_drift=True`, by the [δφ, δv, δp] block of pim.cov15, which
    adds the bias random walk within the window (needs level "combined"). Raises FactorError
    for a measurement below the level its weight needs or with a covariance that is not
    positive definite.

    Jacobians: dict {"state_i": 9×9, "state_j": 9×9, "bias_i": 9×6}; state columns
    [δφ, δp, δv] (NavState.retract), bias columns [δb_g, δb_a]. GTSAM's error is −Q r in its
    order [rot, pos, vel] (Logmap mode). `bias_i=None` means `pim.bias_hat`. Pickles exactly.
    """

    RESIDUAL_ORDER: tuple[str, str, str]
    def __new__(
        cls, pim: PreintegratedImu, residual: str = "logmap", *, in_window_drift: bool = False
    ) -> ImuFactor: ...
    @property
    def residual_mode(self) -> str:
        """ "logmap" or "component"."""
    @property
    def in_window_drift(self) -> bool:
        """Whether the weight includes the bias random walk within the window."""
    @property
    def pim(self) -> PreintegratedImu:
        """The measurement (a copy)."""
    @property
    def sqrt_information(self) -> _F64:
        """U (9×9 upper triangular), Σ⁻¹ = UᵀU, order [r_φ, r_v, r_p]."""
    @property
    def residual_covariance(self) -> _F64:
        """Σ (9×9): pim.cov (component) or T cov Tᵀ, T = diag(I, ΔRᵀ, ΔRᵀ) (logmap)."""
    def predict(self, state_i: NavState, bias_i: ImuBias | None = None) -> NavState: ...
    def residual(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> _F64:
        """[r_φ, r_v, r_p] (9)."""
    def evaluate(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> tuple[_F64, dict[str, _F64]]:
        """(residual, {"state_i", "state_j", "bias_i"} Jacobians)."""
    def evaluate_whitened(
        self, state_i: NavState, state_j: NavState, bias_i: ImuBias | None = None
    ) -> tuple[_F64, dict[str, _F64]]:
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
    def __new__(
        cls, pim: PreintegratedImu, residual: str = "logmap", *, in_window_drift: bool = False
    ) -> CombinedImuFactor:
        """`in_window_drift=True` raises FactorError: this weight always includes it."""
    @property
    def residual_mode(self) -> str: ...
    @property
    def in_window_drift(self) -> bool:
        """True: the weight includes the bias random walk within the window."""
    @property
    def pim(self) -> PreintegratedImu: ...
    @property
    def sqrt_information(self) -> _F64:
        """U (15×15 upper triangular), Σ⁻¹ = UᵀU."""
    @property
    def residual_covariance(self) -> _F64:
        """Σ (15×15), order [r_φ, r_v, r_p, r_bg, r_ba]."""
    def predict(self, state_i: NavState, bias_i: ImuBias | None = None) -> NavState: ...
    def residual(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> _F64: ...
    def evaluate(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> tuple[_F64, dict[str, _F64]]: ...
    def evaluate_whitened(
        self,
        state_i: NavState,
        state_j: NavState,
        bias_i: ImuBias | None = None,
        bias_j: ImuBias | None = None,
    ) -> tuple[_F64, dict[str, _F64]]: ...
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


__all__ += [
    "advise",
    "advise_file",
    "allan_variance",
    "allan_variance_file",
    "audit",
    "apply_intrinsics",
    "calibrate_file",
    "calibrate_multi_pose",
    "calibrate_static",
    "detect_still_intervals",
    "initialise_file",
    "read_calibration",
    "read_groundtruth",
    "read_imu",
    "read_kalibr_yaml",
    "write_euroc_imu",
    "write_kalibr_yaml",
]

import os
from typing import Any

from numpy.typing import ArrayLike

from typing_extensions import TypedDict, Unpack

class _ReaderOptions(TypedDict, total=False):
    """The reader options (keyword arguments) of every function that reads a recording."""

    format: str | None
    columns: str | None
    delimiter: str | None
    time_unit: str | None
    gyro_unit: str | None
    accel_unit: str | None
    topic: str | None
    gyro_topic: str | None
    accel_topic: str | None
    stamp: str | None
    check_units: bool

# Reader options shared by read_imu, audit, allan_variance_file, calibrate_file, advise_file
# (the command line's --imu / --gyro --accel, --format, --columns, ... flags): ``path`` one
# recording, or ``gyro`` and ``accel`` the two files of a split recording; ``format`` one of
# euroc, tum-vi, uzh-fpv, kitti, delimited, bag, mcap, db3 (default: detected from the
# extension and the first lines); ``columns`` e.g. "t,ax,ay,az,wx,wy,wz" (skip for unused
# columns; default: from the header's names); ``delimiter`` comma, semicolon, tab or whitespace;
# ``time_unit`` s, ms, us or ns (decimals converted to integer ns exactly); ``gyro_unit`` rad/s or
# deg/s; ``accel_unit`` m/s2 or g (9.80665 m/s²); ``topic`` the sensor_msgs/Imu topic of a bag,
# MCAP or db3 file (default: its only one); ``gyro_topic`` + ``accel_topic`` a split recording in
# a container; ``stamp`` "header" (header.stamp, default) or "record" (receive time);
# ``check_units`` the check that the values look like rad/s, m/s² and the stated time unit.
# An unknown option value raises ShapeError (kind "Usage"); a file that cannot be read raises
# InputError naming the file and the line (text) or message (containers).

def read_imu(
    path: str | os.PathLike[str] | None = None,
    *,
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """Reads an IMU recording (EuRoC/TUM-VI CSV, UZH-FPV imu.txt, KITTI text, any delimited
    text in any units, ROS 1 bag, MCAP, ROS 2 db3; options above) with the Rust readers.

    Returns a dict: ``t_ns`` int64[N] (nanoseconds, strictly increasing), ``gyro`` float64[N, 3]
    [rad/s], ``acc`` float64[N, 3] [m/s², specific force], sensor frame, converted from the
    file's units; and what was detected: ``source``, ``format``, ``read_as`` (one line),
    ``units`` {``time``, ``gyro``, ``accel``} (the file's units), ``columns`` and ``delimiter``
    (text files, else None), ``notes`` (how format, topic, columns and units were decided),
    ``split`` (two streams merged onto the gyro stamps) and ``accel_white_ratio`` (the merged
    accelerometer's white-noise variance factor ρ, or None).

    Memory: at most 50 million samples (the Rust reader's bound, refused before allocating;
    ~112 bytes per sample at the peak). Raises InputError (bad file, duplicate or decreasing
    timestamp, non-finite value, implausible units: the message names file and line).
    """

def read_groundtruth(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Reads an EuRoC ground-truth CSV (17 columns: t [ns], p, q w,x,y,z, v, b_g, b_a).

    Returns a dict: ``t_ns`` int64[M]; ``p`` float64[M, 3] body position in the world frame
    [m]; ``q_wxyz`` float64[M, 4] body→world attitude, Hamilton, order **(w, x, y, z)**
    (``v_world = q v_body q*``; scipy's ``Rotation.from_quat`` wants (x, y, z, w)); ``v``
    float64[M, 3] world velocity [m/s]; ``bias_gyro`` [rad/s] and ``bias_acc`` [m/s²] float64[M, 3];
    ``source``. Raises InputError naming file, line and column.
    """

def read_kalibr_yaml(path: str | os.PathLike[str]) -> Noise:
    """The noise densities of a Kalibr imu.yaml (gyroscope_noise_density [rad/s/√Hz],
    gyroscope_random_walk [rad/s²/√Hz], accelerometer_noise_density [m/s²/√Hz],
    accelerometer_random_walk [m/s³/√Hz], update_rate [Hz]; continuous-time densities).
    Raises InputError naming the file and the missing key or bad line, or a density a Noise
    refuses (a zero white-noise density)."""

def write_kalibr_yaml(path: str | os.PathLike[str], noise: Noise) -> None:
    """Writes ``noise`` as a Kalibr imu.yaml (shortest round-trip floats: reading it back gives
    the same numbers). A noise a Noise could not be built from (e.g. an allan_variance fit
    that found no white noise) raises PreintError before the file is opened; InputError when
    the file cannot be written."""

def write_euroc_imu(path: str | os.PathLike[str], t_ns: _I64, gyro: _F64, acc: _F64) -> None:
    """Writes arrays (t_ns int64[N] ns, gyro float64[N, 3] rad/s, acc float64[N, 3] m/s²) as a
    EuRoC imu0 CSV with shortest round-trip floats, so that :func:`read_imu` gives back the
    same arrays bit for bit. ShapeError for wrong shapes or dtypes; PreintError (NonFinite,
    DuplicateTimestamp, DecreasingTimestamp, naming the sample) before the file is opened;
    InputError when the file cannot be written."""

def audit(
    path: str | os.PathLike[str] | None = None,
    *,
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    calibration: str | os.PathLike[str] | None = None,
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """What is wrong with a recording (timing, gaps, duplicates, clipping, units, stillness), in
    one streaming pass in bounded memory: the ``preint audit --json`` report as a dict (keys
    ``clean``, ``defects``, ``warnings``, ``findings`` [{severity, kind, message}], ``rate``,
    ``jitter``, ``gaps``, ``axes``, ...; see the command's documentation). ``calibration``: an
    IMU calibration file whose intrinsics correct the unit checks' samples and which is checked
    against the recording (``preint audit --calibration``)."""

def allan_variance(
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    *,
    per_decade: int = 10,
    check_still: bool = True,
) -> dict[str, Any]:
    """Overlapping Allan deviation (IEEE Std 952-1997, Annex C) of the six channels
    [ω_x, ω_y, ω_z, a_x, a_y, a_z] of a static recording (t_ns int64[N], gyro float64[N, 3]
    rad/s, acc float64[N, 3] m/s²; uniform sampling within ±10 %), with the Kalibr noise fits.

    Bounded memory as ``preint allan``: up to 2²⁰ samples the curves use every sample
    (τ₀ = Δt); longer recordings are reduced to 2²⁰ block means (τ₀ = bΔt, b a power of two).

    Returns a dict (channel axis last, order ``channels``): ``tau`` float64[M] [s], ``clusters``
    float64[M] (N/m), ``adev`` and ``adev_err`` float64[M, 6] (σ(τ) and its 1-σ error,
    rad/s resp. m/s²); per channel float64[6]: ``white_density`` N (slope −½ line read at τ = 1 s)
    [rad/s/√Hz | m/s²/√Hz] and its 1-σ ``white_density_err``, ``random_walk`` K (slope +½ line read
    at τ = 3 s) [rad/s²/√Hz | m/s³/√Hz] and ``random_walk_err``, ``bias_instability`` B
    (floor / 0.664) [rad/s | m/s²] at ``bias_instability_tau`` [s]; bool[6]
    ``white_density_is_bound`` / ``random_walk_is_bound`` (no region of that slope: the value
    is an upper bound, its error NaN); ``white_tau_range`` / ``random_walk_tau_range``
    float64[6, 2]; ``noise``: a Noise with the Kalibr imu.yaml figures (maximum over the three
    axes of each sensor, update rate 1/Δt); ``dt``, ``tau0`` [s], ``block_len``, ``samples``;
    ``stillness`` {windows, still_windows, still_fraction, first_motion_s, max_tilt_deg,
    max_tilt_at_s}; ``units``.

    Raises CalibrationError: kind ``NotStatic`` for a moving recording (fewer than 90 % of the
    1 s windows still, or gravity turning by more than 2°; ``check_still=False`` skips the
    check), ``Timestamps`` for gaps or irregular sampling, ``TooFewSamples``; ShapeError for
    arrays of the wrong shape or dtype.
    """

def allan_variance_file(
    path: str | os.PathLike[str] | None = None,
    *,
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    check_still: bool = True,
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """``preint allan`` on a recording, streamed in bounded memory (the file is read once; the
    units are checked on its first 60 s): the dict of :func:`allan_variance` plus ``source`` and
    ``units_checked``. A moving recording raises CalibrationError (kind ``Failed``, the
    command's message); a bad file InputError."""

def detect_still_intervals(
    t_ns: _I64, gyro: _F64, acc: _F64, noise: Noise | str | os.PathLike[str] | None = None
) -> list[dict[str, Any]]:
    """The still intervals of a recording (moving variances of gyro and accelerometer within
    4× the white-noise variances of ``noise``, at least 1 s; ``noise`` a Noise, a Kalibr
    imu.yaml path, or None for the EuRoC ADIS16448 figures): [{``start``, ``end`` (sample
    indices, end exclusive), ``t_start_ns``, ``t_end_ns``, ``duration_s``}]."""

def calibrate_static(
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    noise: Noise | str | os.PathLike[str] | None = None,
    *,
    gravity: float = 9.81,
    acc_bias_prior: tuple[ArrayLike, ArrayLike] | None = None,
    latitude: float | None = None,
    heading: float | None = None,
    still_check: bool = True,
) -> dict[str, Any]:
    """Single-attitude static calibration (Gauss-Newton, as ``preint calibrate`` without
    --poses at one attitude): gyro bias and roll/pitch on the longest still interval (the whole
    input with ``still_check=False``). World z up, gravity (0, 0, −gravity) m/s².

    Returns a dict: ``gyro_bias``, ``gyro_bias_std`` float64[3] [rad/s, sensor frame];
    ``acc_bias``, ``acc_bias_std`` float64[3] [m/s²] only with ``acc_bias_prior=(mean, std)``,
    else None (not separable from tilt; ``acc_bias_note`` says so); ``roll``, ``pitch``,
    ``roll_std``, ``pitch_std`` [rad], ``roll_pitch_cov`` 2×2, ``up_body`` float64[3] (unit up
    in sensor axes), ``R_wb`` 3×3 (yaw 0), ``unobservable``; ``measured_gyro_density`` /
    ``measured_acc_density`` float64[3] [rad/s/√Hz, m/s²/√Hz]; ``chi2``, ``dof``,
    ``iterations``; ``interval`` (the still interval used), ``still_s``, ``recording_s``.
    ``latitude`` [deg] removes the Earth rate's vertical part from b_g (the whole of it with
    ``heading`` [deg, body x clockwise from north]). Standard deviations are predicted from
    ``noise`` (default EuRoC ADIS16448); chi2/dof ≈ 1 when the densities are right.

    Raises CalibrationError: kind ``NotStatic`` when no still interval exists (moving data),
    ``TooFew``, ``NonFinite``, ``NotIncreasing``, ``Solver``; PreintError for a ``gravity``
    outside [0, 100] m/s² (also in calibrate_multi_pose and calibrate_file).
    """

def calibrate_multi_pose(
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    noise: Noise | str | os.PathLike[str] | None = None,
    *,
    gravity: float = 9.81,
) -> dict[str, Any]:
    """Multi-position calibration (Tedaldi, Pretto, Menegatti, ICRA 2014): still intervals at
    ≥ 3 attitudes linked by gyro preintegration → both biases, the attitudes, and scale factors
    and misalignments when BIC supports them (the bias random walk marginalised).

    Returns a dict: ``model`` (``multi-pose/<name>``), ``reason``, ``gyro_bias``,
    ``gyro_bias_std`` [rad/s], ``acc_bias``, ``acc_bias_std`` [m/s²] float64[3] (sensor frame, at
    ``bias_reference_time_ns``); ``acc_scale``, ``acc_misalignment``, ``gyro_scale`` float64[3]
    and ``gyro_misalignment`` float64[6] with their ``_std`` (None when the model lacks them),
    ``acc_scale_matrix`` / ``gyro_scale_matrix`` 3×3; ``intervals``, ``R_wb`` float64[K, 3, 3];
    ``model_selection`` [{model, chi2, params, residuals, bic, identifiable, converged}],
    ``dof``, ``iterations``, ``random_walk_marginalised``.

    Raises CalibrationError (kind ``TooFew`` with fewer than 3 still intervals, ...).
    """

def initialise_file(
    path: str | os.PathLike[str] | None = None,
    *,
    poses: str | os.PathLike[str],
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    scale: str = "unknown",
    noise: str | os.PathLike[str] | None = None,
    gravity: float = 9.81,
    from_ns: int | None = None,
    to_ns: int | None = None,
    pose_rot_std: float = 0.0,
    pose_pos_std: float = 0.0,
    pose_spacing: float = 0.1,
    body_p_sensor: Sequence[float] | None = None,
    bias_prior_std: tuple[float, float] | None = None,
    scheme: str = "midpoint",
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """``preint initialise --json`` on a recording and a front end's keyframe poses
    (``t,x,y,z,qw,qx,qy,qz`` or EuRoC ground truth, positions in their own unit), as a dict:
    ``scale`` [m per unit of the poses] and ``scale_std`` (``scale="known"``: metric poses,
    scale 1), ``gravity`` [m/s², world frame of the poses] with ``gravity_std``,
    ``bias_gyro`` [rad/s], ``bias_acc`` [m/s²] with their σ, ``velocities`` [{t_ns, v, std}],
    the 10×10 ``covariance`` in ``covariance_order`` (s, g, b_g, b_a), ``fit``,
    ``std_factor`` (every σ is multiplied by max(1, √(χ²/dof))), ``linear_start``, and
    ``ready`` with its ``reason`` (a window that is not ready is a result, not an error).
    ``pose_rot_std`` [rad] and ``pose_pos_std`` [unit of the poses]: the keyframes' noise;
    ``pose_spacing`` [s]; ``body_p_sensor`` (x, y, z, qw, qx, qy, qz): the IMU's pose in the
    frame of the poses; ``bias_prior_std`` (gyro rad/s, accelerometer m/s²; None: 0.05 and
    0.2): the zero-mean prior of the maximum-a-posteriori refinement.

    Raises CalibrationError (kind ``Failed``) for a file without positions or fewer than three
    keyframes; InputError for a bad file or value."""

def calibrate_file(
    path: str | os.PathLike[str] | None = None,
    *,
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    noise: str | os.PathLike[str] | None = None,
    poses: str | os.PathLike[str] | None = None,
    gravity: float = 9.81,
    from_ns: int | None = None,
    to_ns: int | None = None,
    pose_rot_std: float | None = None,
    pose_pos_std: float | None = None,
    latitude: float | None = None,
    heading: float | None = None,
    estimate: str | Sequence[str] | None = None,
    pose_spacing: float = 0.5,
    calibration: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    scheme: str = "midpoint",
    window: Sequence[float] | None = None,
    vel_std: float | None = None,
    bias_gyro_std: float | None = None,
    bias_acc_std: float | None = None,
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """``preint calibrate --json`` on a recording, as a dict: the model is chosen as the
    command does (known poses with ``poses``: a EuRoC ground-truth, ``t,x,y,z,qw,qx,qy,qz`` or
    attitudes-only ``t,qw,qx,qy,qz`` file; multi-position with ≥ 3 distinct still attitudes;
    otherwise single-attitude static on the longest still interval), ``model`` names it.
    ``noise``: a Kalibr imu.yaml (default EuRoC figures). With ``poses``: ``estimate``, a
    comma-separated string or a list of ``time-offset``, ``gyro-intrinsics``, ``g-sensitivity``,
    ``accel-intrinsics`` (``parameters`` [{name, unit, excited, value, kept, std}] in the
    result; a parameter the motion does not excite is withheld: ``value`` None, ``kept`` its
    initial value), ``pose_spacing`` [s], ``calibration`` (a
    calibration file applied and used as the starting point). ``out``: write the calibration
    file (OpenVINS kalibr_imu_chain.yaml). ``scheme``: the scheme the known-pose windows are
    preintegrated with, and recorded in ``out`` (estimate for the scheme that will use the
    result: euler and galilean lag midpoint and hermite4 by half a sample interval). The
    result's ``fit`` (``chi2``, ``dof``, ``chi2_dof``, ``credible``, ``why``, …) says whether
    the residuals are what the noise model predicts, and every ``*_std`` has its
    ``*_std_scaled`` by √(χ²/dof). ``pose_rot_std`` [rad], ``pose_pos_std`` [m]: the poses'
    standard deviations (None: 0, exact).

    ``estimate="noise"`` (alone, with a EuRoC ground truth as ``poses``): ``preint calibrate
    --estimate noise --json``, the maximum-likelihood noise densities, bias random walks and
    the ground truth's own errors from ImuFactors over back-to-back windows of each length of
    ``window`` [s] (default [0.5, 1, 2, 4]); result ``noise``, ``ground_truth_error``,
    ``withheld``, ``per_length``, ``gravity`` (the world gravity vector that fits, its tilt and
    whether the information criterion supports it), ``fit``. ``noise`` is the starting point (else a moment
    estimate); a ground-truth error given (``pose_rot_std`` [rad], ``pose_pos_std`` [m],
    ``vel_std`` [m/s], ``bias_gyro_std`` [rad/s], ``bias_acc_std`` [m/s²]) is held at that
    value, the others are fitted; ``out`` writes the fitted model as a Kalibr imu.yaml.
    ``window``, ``vel_std``, ``bias_gyro_std`` and ``bias_acc_std`` are refused without it.

    Raises CalibrationError (kind ``Failed``) when nothing can be answered, e.g. no still
    interval; InputError for a bad file or list; ShapeError (kind ``Usage``) for a bad
    value."""

def read_calibration(path: str | os.PathLike[str]) -> dict[str, Any]:
    """An IMU calibration file (``calibrate_file(out=...)``, ``preint calibrate --out``;
    OpenVINS kalibr_imu_chain.yaml or Kalibr imu.yaml): ``model`` (``kalibr`` or ``rpng``),
    ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` (3×3 float64; OpenVINS' model
    ``ω_m = Tw R_IMUtoGYRO ω + Tg a + b_g``, ``a_m = Ta R_IMUtoACC a + b_a``; Tg in
    (rad/s)/(m/s²)), ``time_offset_s`` (``t_imu = t_keyframe + time_offset_s``, or None) and
    ``noise`` (a Noise, or None). Raises InputError naming the file, line and field."""

def apply_intrinsics(
    calibration: str | os.PathLike[str],
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The samples corrected by a calibration file's intrinsics, bias not removed:
    ``a' = R_ACCtoIMU Ta⁻¹ a_m``, ``ω' = R_GYROtoIMU Tw⁻¹ (ω_m − Tg a')`` (gyro', acc', float64
    [N, 3]; the same bits as the Rust preintegrator's correction). Preintegrating them with
    keyframes moved by ``time_offset_s`` is ``preint integrate --calibration`` (to rounding: the
    command interpolates boundary samples before correcting them). Raises InputError for the
    file, ShapeError for the arrays, PreintError for a non-finite sample or timestamps out of
    order (naming the sample)."""

def advise(
    t_ns: _I64,
    gyro: _F64,
    acc: _F64,
    noise: Noise | str | os.PathLike[str],
    *,
    window: float = 1.0,
    fraction: float = 0.1,
    input: Literal["smooth", "held"] = "smooth",
) -> dict[str, Any]:
    """``preint advise`` on arrays: the cheapest scheme and lowest rate whose discretisation
    error stays below ``fraction`` × the noise σ on ``window``-second preintegrations, with the
    noise separated from the motion by a zero-phase low-pass (gravity 9.81 m/s²). ``input``:
    "smooth" (point samples of a smooth signal; reference hermite4) or "held" (rate and specific
    force constant over each interval; reference galilean, exact for it; not low-passed).

    Returns the command's JSON as a dict: ``recommended_scheme`` (euler, midpoint, hermite4, galilean)
    and ``recommended_rate`` [Hz] (None when no candidate is acceptable), ``candidates``
    [{scheme, rate, decimation, disc_err {rot_rad, vel_m_s, pos_m}, noise_sigma {...},
    cost_ns_per_s (measured on this machine), acceptable}], ``denoise_cutoff_hz`` {gyro, acc},
    ``fraction``, ``window_s``, ``samples``, ``method``. Raises CalibrationError (gap, too short
    a recording), ShapeError (``window`` or ``fraction`` not a finite number > 0).
    """

def advise_file(
    path: str | os.PathLike[str] | None = None,
    *,
    noise: str | os.PathLike[str],
    gyro: str | os.PathLike[str] | None = None,
    accel: str | os.PathLike[str] | None = None,
    window: float = 1.0,
    fraction: float = 0.1,
    from_ns: int | None = None,
    to_ns: int | None = None,
    input: Literal["smooth", "held"] = "smooth",
    **options: Unpack[_ReaderOptions],
) -> dict[str, Any]:
    """``preint advise --json`` on a recording (samples with ``from_ns ≤ t ≤ to_ns``), as a
    dict (keys as :func:`advise`); ``noise`` a Kalibr imu.yaml."""
