"""Exceptions raised by preint.

Every exception derives from :class:`Error` and from the built-in class a Python user would
catch (``ValueError`` for bad input, ``OSError`` for unreadable files). Its ``kind`` attribute is
the Rust error variant's name (e.g. ``"DecreasingTimestamp"``) and its message the Rust message,
which names the sample, line, file or parameter at fault.
"""


class Error(Exception):
    """Base class of every error preint raises. ``kind``: the Rust variant's name."""

    kind: str = ""


class PreintError(Error, ValueError):
    """Invalid samples or parameters of a preintegration (non-finite values, duplicate or
    decreasing timestamps, gaps, keyframes outside the samples, invalid parameters)."""


class MergeError(Error, ValueError):
    """Two measurements that cannot be merged (not consecutive, different parameters)."""


class FactorError(Error, ValueError):
    """A measurement that cannot weight a factor (covariance not positive definite, level too
    low)."""


class ShapeError(Error, ValueError):
    """An array argument of the wrong shape, length or dtype, or an unknown name."""


class InputError(Error, OSError):
    """A file that cannot be read as IMU data (unreadable, malformed rows, wrong units); the
    message names the file and line or message."""


class CalibrationError(Error, ValueError):
    """A calibration or noise analysis that cannot answer (moving data for a static method, an
    unobservable parameter, too short a recording)."""
