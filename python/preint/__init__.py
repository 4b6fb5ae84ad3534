"""preint: on-manifold IMU preintegration (Rust) from numpy.

Conventions (as in the Rust library):

- timestamps are integer nanoseconds (``int64``); gyro [rad/s], accelerometer [m/s²], sensor
  frame; world frame z up, gravity ``(0, 0, -9.81)`` m/s² by default;
- rotations are perturbed on the right (``R <- R Exp(dphi)``); tangent order of a
  preintegrated measurement **[dphi, dv, dp]** (``PreintegratedImu.TANGENT_ORDER``), of the
  combined one **[dphi, dv, dp, dbg, dba]``; bias order **[b_g, b_a]**;
- noise densities continuous-time (Kalibr's ``gyroscope_noise_density`` etc.; covariances are
  their squares, GTSAM's ``gyroscopeCovariance`` semantics).

Arrays in: ``t_ns`` int64[N], ``gyro`` float64[N, 3], ``acc`` float64[N, 3]; one call integrates
them all in Rust (no per-sample Python loop). Errors raise the typed exceptions of
:mod:`preint._errors` (all derive from :class:`preint.Error`) with the Rust message.
"""

from ._errors import (
    CalibrationError,
    Error,
    FactorError,
    InputError,
    MergeError,
    PreintError,
    ShapeError,
)
from ._native import (
    SCHEMES,
    CombinedImuFactor,
    ImuBias,
    ImuFactor,
    NavState,
    Noise,
    Params,
    PreintegratedImu,
    Preintegrator,
    deltas_at,
    deskew_points,
    inflate,
    merge,
    predict,
    preintegrate,
    preintegrate_windows,
    second_order_covariance,
    states_at,
    truncation_estimate,
    add_covariance,
)
from ._native import (  # io and calibration
    advise,
    advise_file,
    allan_variance,
    allan_variance_file,
    audit,
    apply_intrinsics,
    calibrate_file,
    calibrate_multi_pose,
    calibrate_static,
    detect_still_intervals,
    initialise_file,
    read_calibration,
    read_groundtruth,
    read_imu,
    read_kalibr_yaml,
    write_euroc_imu,
    write_kalibr_yaml,
)

__all__ = [
    "SCHEMES",
    "CalibrationError",
    "CombinedImuFactor",
    "Error",
    "FactorError",
    "ImuBias",
    "ImuFactor",
    "InputError",
    "MergeError",
    "NavState",
    "Noise",
    "Params",
    "PreintError",
    "PreintegratedImu",
    "Preintegrator",
    "ShapeError",
    "deltas_at",
    "deskew_points",
    "inflate",
    "merge",
    "predict",
    "preintegrate",
    "preintegrate_windows",
    "states_at",
    "truncation_estimate",
    "second_order_covariance",
    "add_covariance",
    # io and calibration
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
