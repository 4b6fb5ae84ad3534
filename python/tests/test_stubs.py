"""The type stubs (``preint/_native.pyi``) describe the extension module as it is at runtime, and
type-check code that uses the package.

- ``python -m mypy.stubtest preint._native``: every class, method, property and function of the
  compiled module is in the stubs with the runtime's parameter names, kinds and defaults, and
  nothing in the stubs is missing at runtime (no allowlist).
- ``mypy --strict`` accepts a program using the core API and the example script, and rejects
  a program that misuses the types (so the stubs are read, not ``Any``).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from conftest import REPO

pytest.importorskip("mypy")


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    # From an empty directory, so that the installed package is checked (not a source tree).
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, capture_output=True, text=True, timeout=600)


def test_stubtest_finds_the_stubs_consistent_with_the_module(tmp_path):
    out = run(["mypy.stubtest", "preint._native"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr


GOOD = """
import pickle
import numpy as np
import numpy.typing as npt
import preint

t: npt.NDArray[np.int64] = np.arange(201, dtype=np.int64) * 5_000_000
g = np.zeros((201, 3))
a = np.tile([0.0, 0.0, 9.81], (201, 1))
p = preint.Params(preint.Noise.euroc(), scheme="euler", level="covariance")
p.gravity = [0.0, 0.0, -9.80665]
p.gyroscope_covariance = 1e-8
p.integration_covariance = None
p.set_body_p_sensor([1.0, 0.0, 0.0, 0.0], [0.1, 0.0, 0.0])
b = preint.ImuBias([0.0, 0.0, 0.001])
m: preint.PreintegratedImu = preint.preintegrate(p, t, g, a, 0, 1_000_000_000, bias=b)
ws: list[preint.PreintegratedImu] = preint.preintegrate_windows(p, t, g, a, t[::100])
m2 = preint.merge(ws[0], ws[1])
dt: float = m.delta_t + m2.delta_t
cov: npt.NDArray[np.float64] = m.cov @ m.bias_jacobians
r, v, q = m.corrected(b)
pi = preint.Preintegrator(p, b, capacity=201)
pi.integrate(0, g[0], a[0])
pi.integrate_arrays(t[1:], g[1:], a[1:])
n: int = len(pi) + m.t_j_ns
u, again = pi.measurement_for_bias(preint.ImuBias(acc=[0.01, 0.0, 0.0]))
ok: bool = again and m == pickle.loads(pickle.dumps(m))
scheme: str = p.scheme
rs: list[str] = preint.SCHEMES
try:
    p.validate()
except preint.PreintError as e:
    kind: str = e.kind
"""

BAD = """
import preint
m = preint.preintegrate(preint.Params(), 0, 0, 0, 0, 1)
s: str = m.delta_t
preint.Preintegrator(preint.Params()).integrate("0", [0.0, 0.0, 0.0], [0.0, 0.0, 9.81])
preint.merge(m)
"""


def test_mypy_strict_accepts_correct_use_and_rejects_misuse(tmp_path):
    (tmp_path / "good.py").write_text(textwrap.dedent(GOOD))
    out = run(["mypy", "--strict", "--no-incremental", "good.py"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr

    (tmp_path / "bad.py").write_text(textwrap.dedent(BAD))
    out = run(["mypy", "--strict", "--no-incremental", "bad.py"], tmp_path)
    assert out.returncode == 1
    # One error per misuse, on its line.
    for line, what in ((3, "arg-type"), (4, "assignment"), (5, "arg-type"), (6, "call-arg")):
        assert f"bad.py:{line}:" in out.stdout and f"[{what}]" in out.stdout, out.stdout


def test_mypy_accepts_the_example_script(tmp_path):
    out = run(["mypy", "--no-incremental", str(REPO / "python" / "examples" / "euroc.py")], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
