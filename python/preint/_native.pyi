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
_SchemeName = Literal["euler", "midpoint", "hermite4"]
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
"""The scheme names: ["euler", "midpoint", "hermite4"]."""

@final
class Noise:
    """Kalibr-style continuous-time IMU noise densities."""

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
    """A bias estimate: gyro [rad/s], accelerometer [m/s²], sensor frame; order [b_g, b_a]."""

    def __new__(cls, gyro: _Vec3Like | None = None, acc: _Vec3Like | None = None) -> ImuBias: ...
    @property
    def gyro(self) -> F64:
        """Gyro bias [rad/s], shape (3,)."""
    @property
    def acc(self) -> F64:
        """Accelerometer bias [m/s²], shape (3,)."""
    def vector(self) -> F64:
        """[b_g, b_a], shape (6,)."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[list[float], list[float]]]: ...

@final
class Params:
    """Preintegration parameters (Rust PreintParams); covariances continuous-time."""

    def __new__(cls, noise: Noise | None = None, *, scheme: str = "midpoint", level: str = "combined") -> Params: ...
    @property
    def gravity(self) -> F64:
        """Gravity in the world frame [m/s²], shape (3,)."""
    @gravity.setter
    def gravity(self, v: _Vec3Like) -> None: ...
    @property
    def gyroscope_covariance(self) -> F64:
        """Gyro white-noise covariance [rad²/s], 3×3."""
    @gyroscope_covariance.setter
    def gyroscope_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def accelerometer_covariance(self) -> F64:
        """Accelerometer white-noise covariance [m²/s³], 3×3."""
    @accelerometer_covariance.setter
    def accelerometer_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def bias_gyro_covariance(self) -> F64:
        """Gyro bias random-walk covariance [rad²/s³], 3×3."""
    @bias_gyro_covariance.setter
    def bias_gyro_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def bias_acc_covariance(self) -> F64:
        """Accelerometer bias random-walk covariance [m²/s⁵], 3×3."""
    @bias_acc_covariance.setter
    def bias_acc_covariance(self, v: _Cov3Like) -> None: ...
    @property
    def integration_covariance(self) -> F64 | None:
        """Integration covariance [m²/s³] added to Δp per unit time, 3×3, or None."""
    @integration_covariance.setter
    def integration_covariance(self, v: _Cov3Like | None) -> None: ...
    @property
    def scheme(self) -> _SchemeName:
        """"euler", "midpoint" or "hermite4"."""
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
    def body_p_sensor(self) -> tuple[F64, F64] | None:
        """(R_bs 3×3, t_bs [m] in the body frame), or None."""
    def set_body_p_sensor(self, rotation: _RotationLike | None, translation: _Vec3Like | None = None) -> None:
        """Sets (or with None clears) the IMU's pose in the body frame."""
    @property
    def lever_arm(self) -> Literal["exact", "centripetal"]:
        """"exact" or "centripetal" (GTSAM's)."""
    @lever_arm.setter
    def lever_arm(self, v: str) -> None: ...
    @property
    def omega_coriolis(self) -> F64 | None:
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
    def delta_R(self) -> F64:
        """ΔR_ij, 3×3 rotation (body j → body i)."""
    @property
    def delta_rotvec(self) -> F64:
        """Log(ΔR_ij) [rad], shape (3,)."""
    @property
    def delta_v(self) -> F64:
        """Δv_ij [m/s] in body frame i, gravity excluded, shape (3,)."""
    @property
    def delta_p(self) -> F64:
        """Δp_ij [m] in body frame i, gravity excluded, shape (3,)."""
    @property
    def cov(self) -> F64:
        """9×9 covariance of [dphi, dv, dp]."""
    @property
    def cov15(self) -> F64:
        """15×15 covariance of [dphi, dv, dp, dbg, dba]."""
    def residual_cov15(self) -> F64:
        """15×15 covariance of the combined factor's residual (cov15, delta–bias blocks negated)."""
    @property
    def bias_jacobians(self) -> F64:
        """9×6: rows [dphi, dv, dp], columns [b_g, b_a]."""
    @property
    def bias_hat(self) -> ImuBias:
        """The bias estimate the samples were integrated with."""
    @property
    def gravity(self) -> F64:
        """Gravity [m/s²] in the world frame, shape (3,)."""
    @property
    def omega_coriolis(self) -> F64 | None:
        """Navigation-frame rotation rate [rad/s], or None."""
    @property
    def coriolis(self) -> _CoriolisName:
        """"exact", "first" or "second"."""
    @property
    def level(self) -> _LevelName:
        """"deltas", "covariance" or "combined"."""
    def corrected(self, bias: ImuBias) -> tuple[F64, F64, F64]:
        """First-order bias-corrected (ΔR 3×3, Δv [m/s], Δp [m])."""
    def delta_error(self, reference: PreintegratedImu) -> F64:
        """[Log(ΔR_refᵀ ΔR), Δv − Δv_ref, Δp − Δp_ref], shape (9,)."""
    def __eq__(self, value: object, /) -> bool: ...
    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __reduce__(self) -> tuple[object, tuple[bytes]]: ...
    @staticmethod
    def _from_state(state: bytes) -> PreintegratedImu: ...

@final
class Preintegrator:
    """Accumulates samples (one at a time or from arrays) into a PreintegratedImu."""

    def __new__(cls, params: Params, bias: ImuBias | None = None, capacity: int = 0) -> Preintegrator: ...
    def integrate(self, t_ns: int, gyro: _Vec3Like, acc: _Vec3Like) -> None:
        """Adds one sample: time [ns], gyro [rad/s], accelerometer [m/s²]."""
    def integrate_arrays(self, t_ns: I64, gyro: F64, acc: F64) -> None:
        """Adds int64[N] times [ns], float64[N, 3] gyro [rad/s] and accelerometer [m/s²]."""
    def finish(self) -> PreintegratedImu:
        """The measurement over [first sample, last sample]."""
    def measurement_for_bias(self, bias: ImuBias) -> tuple[PreintegratedImu, bool]:
        """(measurement for `bias`, whether it was re-integrated)."""
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
    t_ns: I64,
    gyro: F64,
    acc: F64,
    t_i_ns: int,
    t_j_ns: int,
    bias: ImuBias | None = None,
) -> PreintegratedImu:
    """The measurement over the keyframe window [t_i_ns, t_j_ns] of a time-ordered stream."""

def preintegrate_windows(
    params: Params,
    t_ns: I64,
    gyro: F64,
    acc: F64,
    keyframes_ns: I64,
    bias: ImuBias | None = None,
) -> list[PreintegratedImu]:
    """One measurement per pair of consecutive keyframes (int64[K]): K − 1 results."""

def merge(a: PreintegratedImu, b: PreintegratedImu) -> PreintegratedImu:
    """The measurement over [a.t_i, b.t_j] from two consecutive measurements."""


# --- factor: NavState, prediction, factors, deskew ---

# --- io and calibration: readers, Allan variance, calibration, advise ---
