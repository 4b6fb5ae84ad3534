"""preint's IMU factors as GTSAM factors, on GTSAM's own keys and types (optional: needs ``gtsam``).

Drop-in for GTSAM's constructors::

    preint.gtsam.ImuFactor(pose_i, vel_i, pose_j, vel_j, bias, measurement)
    preint.gtsam.CombinedImuFactor(pose_i, vel_i, pose_j, vel_j, bias_i, bias_j, measurement)

keys as in GTSAM (integers / ``gtsam.symbol``), values ``gtsam.Pose3``, a 3-vector velocity
(``Vector3``), ``gtsam.imuBias.ConstantBias``; ``measurement`` a :class:`preint.PreintegratedImu`
(any scheme, lever arm, Earth rate, ...). Residual and Jacobians are those of
:class:`preint.ImuFactor` / :class:`preint.CombinedImuFactor`, mapped to GTSAM's charts:

- Pose3 ``retract([ω, v])`` is ``(R Exp(ω), p + R v)`` to first order (the wheel's Expmap chart:
  ``p + R V(ω) v``, whose derivative at 0 is the same), our NavState.retract perturbs
  ``(R Exp(δφ), p + R δp, v + δv)``: the pose columns are our [δφ, δp] columns unchanged, the
  velocity (additive, world frame, as GTSAM's Vector3) our δv columns unchanged;
- bias: ours [b_g, b_a], ConstantBias's vector [acc, gyro]: the bias columns are swapped;
- the residual stays in our order [r_φ, r_v, r_p(, r_bg, r_ba)] (the order of a factor's own
  residual is free in GTSAM; only its whitened norm matters).

Noise model: the raw residual with ``gtsam.noiseModel.Gaussian.SqrtInformation(U)``, U our
factor's ``sqrt_information``. GTSAM then whitens (``U r``, ``U J``) in C++ and its error is
``½‖U r‖² = ½χ²`` of our factor; chosen (over whitened residual + unit model) so that the factor's
``noiseModel()`` carries the measurement's information as gtsam.ImuFactor's does, and a robust
kernel wraps it the same way (``gtsam.noiseModel.Robust.Create(kernel, factor.noiseModel())``).

ROUTE = "custom": a ``gtsam.CustomFactor`` calling our factor. The native route (a
``gtsam.ImuFactor`` on a ``gtsam.PreintegratedImuMeasurements`` filled with our values) is not
available in the gtsam 4.3.0 wheel: ``PreintegratedImuMeasurements`` / ``...Combined...`` only
wrap the constructors ``(params)`` and ``(params, bias)`` -- the C++ constructor from a base
preintegration and a covariance is not wrapped, and there are no setters for the deltas,
covariance or bias Jacobians; the wheel's ``ImuFactor`` takes only its *tangent* preintegration,
whose state (preintegrated ξ and its bias Jacobians) is not ours (we hold ΔR, Δv, Δp), so a
``deserialize`` of a filled archive would need converting our deltas to its tangent chart and its
Jacobians, undocumented and version-dependent (not attempted). The native factor would also
recompute the residual with GTSAM's formula, dropping what our factor adds (schemes, lever arm,
Earth rate model, in-window drift weight).

Conversions: :func:`to_gtsam` / :func:`from_gtsam` for NavState (↔ ``gtsam.NavState``, or
``(Pose3, velocity)`` with :func:`navstate_to_pose_velocity` / :func:`navstate_from_pose_velocity`),
ImuBias (↔ ConstantBias) and Params (↔ PreintegrationParams / PreintegrationCombinedParams;
see :func:`params_to_gtsam` for what does not map).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

import gtsam  # type: ignore[import-untyped,unused-ignore]  # the 4.3.0 wheel ships stubs

from ._native import CombinedImuFactor as _OurCombined
from ._native import ImuBias, NavState, Params, PreintegratedImu
from ._native import ImuFactor as _OurImuFactor

__all__ = [
    "ROUTE",
    "ImuFactor",
    "CombinedImuFactor",
    "to_gtsam",
    "from_gtsam",
    "navstate_to_pose_velocity",
    "navstate_from_pose_velocity",
    "bias_to_gtsam",
    "bias_from_gtsam",
    "params_to_gtsam",
    "params_from_gtsam",
]

ROUTE = "custom"
"""How the factors are built: "custom" (gtsam.CustomFactor); see the module docstring."""

_F64 = npt.NDArray[np.float64]
_SWAP = [3, 4, 5, 0, 1, 2]  # our bias [b_g, b_a] <-> GTSAM's [acc, gyro] (its own inverse)


# ----------------------------------------------------------------------------- conversions
def navstate_to_pose_velocity(x: NavState) -> tuple[Any, _F64]:
    """Our NavState → (gtsam.Pose3, velocity [m/s] world frame)."""
    return gtsam.Pose3(gtsam.Rot3(x.rotation), x.position), np.array(x.velocity, dtype=float)


def navstate_from_pose_velocity(pose: Any, velocity: npt.ArrayLike) -> NavState:
    """(gtsam.Pose3, velocity world frame) → our NavState."""
    return NavState(pose.rotation().matrix(), pose.translation(), np.asarray(velocity, dtype=float))


def bias_to_gtsam(b: ImuBias) -> Any:
    """Our ImuBias → gtsam.imuBias.ConstantBias(acc, gyro)."""
    return gtsam.imuBias.ConstantBias(b.acc, b.gyro)


def bias_from_gtsam(b: Any) -> ImuBias:
    """gtsam.imuBias.ConstantBias → our ImuBias."""
    return ImuBias(b.gyroscope(), b.accelerometer())


def params_to_gtsam(p: Params, combined: bool | None = None) -> Any:
    """Our Params → gtsam.PreintegrationParams, or PreintegrationCombinedParams when
    ``combined`` (default: ``p.level == "combined"``).

    Mapped: gravity (n_gravity), gyro/accelerometer white-noise covariances, integration
    covariance (None → 0), body_p_sensor, omega_coriolis; combined: bias random-walk
    covariances (biasOmega = our bias_gyro, biasAcc = our bias_acc).
    Not mapped (GTSAM has no equivalent): scheme (GTSAM's wheel integrates with its tangent
    preintegration; the Manifold backend ≡ our "euler"), level, lever_arm mode, bias_correction,
    coriolis order ("exact"/"first"/"second"; GTSAM's 4.3 params have no 2nd-order switch in
    Python), reintegration thresholds, max_gap_ns, keep_samples; the error mode is GTSAM-only
    (our factor takes ``residual=``).
    """
    if combined is None:
        combined = p.level == "combined"
    cls = gtsam.PreintegrationCombinedParams if combined else gtsam.PreintegrationParams
    g: Any = cls(np.asarray(p.gravity, dtype=float))
    g.setGyroscopeCovariance(np.asarray(p.gyroscope_covariance, dtype=float))
    g.setAccelerometerCovariance(np.asarray(p.accelerometer_covariance, dtype=float))
    ic = p.integration_covariance
    g.setIntegrationCovariance(np.zeros((3, 3)) if ic is None else np.asarray(ic, dtype=float))
    bps = p.body_p_sensor
    if bps is not None:
        g.setBodyPSensor(gtsam.Pose3(gtsam.Rot3(bps[0]), bps[1]))
    w = p.omega_coriolis
    if w is not None:
        g.setOmegaCoriolis(np.asarray(w, dtype=float))
    if combined:
        g.setBiasOmegaCovariance(np.asarray(p.bias_gyro_covariance, dtype=float))
        g.setBiasAccCovariance(np.asarray(p.bias_acc_covariance, dtype=float))
    return g


def params_from_gtsam(g: Any, scheme: str = "euler") -> Params:
    """gtsam.PreintegrationParams / PreintegrationCombinedParams → our Params (level "combined"
    for combined params, else "covariance"; scheme "euler" = GTSAM's Manifold discretisation).
    The bias random walks of non-combined params are left at our defaults."""
    combined = isinstance(g, gtsam.PreintegrationCombinedParams)
    p = Params(scheme=scheme, level="combined" if combined else "covariance")
    p.gravity = np.asarray(g.n_gravity, dtype=float).reshape(3)
    p.gyroscope_covariance = np.asarray(g.getGyroscopeCovariance(), dtype=float)
    p.accelerometer_covariance = np.asarray(g.getAccelerometerCovariance(), dtype=float)
    ic = np.asarray(g.getIntegrationCovariance(), dtype=float)
    p.integration_covariance = None if not ic.any() else ic
    bps = g.getBodyPSensor()
    if bps is not None:
        p.set_body_p_sensor(bps.rotation().matrix(), bps.translation())
    w = g.getOmegaCoriolis()
    if w is not None:
        p.omega_coriolis = np.asarray(w, dtype=float).reshape(3)
    if combined:
        p.bias_gyro_covariance = np.asarray(g.getBiasOmegaCovariance(), dtype=float)
        p.bias_acc_covariance = np.asarray(g.getBiasAccCovariance(), dtype=float)
    return p


def to_gtsam(x: Any, combined: bool | None = None) -> Any:
    """NavState → gtsam.NavState, ImuBias → ConstantBias, Params → PreintegrationParams
    (combined per :func:`params_to_gtsam`)."""
    if isinstance(x, NavState):
        return gtsam.NavState(gtsam.Rot3(x.rotation), x.position, x.velocity)
    if isinstance(x, ImuBias):
        return bias_to_gtsam(x)
    if isinstance(x, Params):
        return params_to_gtsam(x, combined)
    raise TypeError(f"to_gtsam: no conversion for {type(x).__name__}")


def from_gtsam(x: Any) -> Any:
    """gtsam.NavState → NavState, ConstantBias → ImuBias, PreintegrationParams → Params."""
    if isinstance(x, gtsam.NavState):
        return NavState(x.attitude().matrix(), x.position(), x.velocity())
    if isinstance(x, gtsam.imuBias.ConstantBias):
        return bias_from_gtsam(x)
    if isinstance(x, gtsam.PreintegrationParams):  # combined params derive from it
        return params_from_gtsam(x)
    raise TypeError(f"from_gtsam: no conversion for {type(x).__name__}")


# ----------------------------------------------------------------------------- factors
def _state(values: Any, kp: int, kv: int) -> NavState:
    pose = values.atPose3(kp)
    return NavState(pose.rotation().matrix(), pose.translation(), values.atVector(kv))


def _bias(values: Any, k: int) -> ImuBias:
    b = values.atConstantBias(k)
    return ImuBias(b.gyroscope(), b.accelerometer())


def _fill(H: Any, jac: dict[str, _F64], names: tuple[str, ...]) -> None:
    # state_i → (pose_i, vel_i), state_j → (pose_j, vel_j), bias_* columns swapped.
    out: list[_F64] = []
    for n in names:
        j = jac[n]
        if n.startswith("state"):
            out += [j[:, 0:6], j[:, 6:9]]
        else:
            out.append(j[:, _SWAP])
    for k, m in enumerate(out):
        H[k] = np.ascontiguousarray(m)


def ImuFactor(
    pose_i: int,
    vel_i: int,
    pose_j: int,
    vel_j: int,
    bias: int,
    measurement: PreintegratedImu,
    residual: str = "logmap",
    *,
    in_window_drift: bool = False,
) -> Any:
    """GTSAM ImuFactor signature on our measurement: a gtsam.CustomFactor on keys
    (pose_i, vel_i, pose_j, vel_j, bias) whose error is ½χ² of ``preint.ImuFactor(measurement,
    residual, in_window_drift=...)`` (captured by the error function)."""
    f = _OurImuFactor(measurement, residual, in_window_drift=in_window_drift)
    names = ("state_i", "state_j", "bias_i")

    def error(this: Any, values: Any, H: Any) -> _F64:
        xi = _state(values, pose_i, vel_i)
        xj = _state(values, pose_j, vel_j)
        bi = _bias(values, bias)
        if H is None:
            return f.residual(xi, xj, bi)
        r, jac = f.evaluate(xi, xj, bi)
        _fill(H, jac, names)
        return r

    model = gtsam.noiseModel.Gaussian.SqrtInformation(f.sqrt_information)
    return gtsam.CustomFactor(model, [pose_i, vel_i, pose_j, vel_j, bias], error)


def CombinedImuFactor(
    pose_i: int,
    vel_i: int,
    pose_j: int,
    vel_j: int,
    bias_i: int,
    bias_j: int,
    measurement: PreintegratedImu,
    residual: str = "logmap",
) -> Any:
    """GTSAM CombinedImuFactor signature on our measurement (level "combined"): a
    gtsam.CustomFactor on (pose_i, vel_i, pose_j, vel_j, bias_i, bias_j), error ½χ² of
    ``preint.CombinedImuFactor(measurement, residual)`` (15-dim, bias rows b_j − b_i)."""
    f = _OurCombined(measurement, residual)
    names = ("state_i", "state_j", "bias_i", "bias_j")

    def error(this: Any, values: Any, H: Any) -> _F64:
        xi = _state(values, pose_i, vel_i)
        xj = _state(values, pose_j, vel_j)
        bi, bj = _bias(values, bias_i), _bias(values, bias_j)
        if H is None:
            return f.residual(xi, xj, bi, bj)
        r, jac = f.evaluate(xi, xj, bi, bj)
        _fill(H, jac, names)
        return r

    model = gtsam.noiseModel.Gaussian.SqrtInformation(f.sqrt_information)
    return gtsam.CustomFactor(model, [pose_i, vel_i, pose_j, vel_j, bias_i, bias_j], error)
