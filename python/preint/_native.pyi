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

# --- io and calibration: readers, Allan variance, calibration, advise ---
