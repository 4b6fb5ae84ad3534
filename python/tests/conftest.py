"""Shared helpers of the preint Python tests: the repository's paths, an exact reader of EuRoC
IMU CSV files, the Rust command line, and the rule that turns skipped tests into failures.

``PREINT_REQUIRE_GTSAM=1`` (set by ``tools/test``, the project's test command) makes every
skipped test a failure: a missing ``gtsam`` wheel, Rust command line or data file must not let
the suite pass with checks left out.
"""

from __future__ import annotations

import csv
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
"""The repository root (``python/tests`` → root)."""

EUROC = REPO / "tests" / "data" / "euroc"
GTSAM_FIXTURES = REPO / "tests" / "fixtures" / "gtsam"


def skips_fail() -> bool:
    """Whether skips must fail (``PREINT_REQUIRE_GTSAM`` set to anything but ``""``/``0``)."""
    return os.environ.get("PREINT_REQUIRE_GTSAM", "") not in ("", "0")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    if skips_fail() and rep.skipped and not hasattr(rep, "wasxfail"):
        rep.outcome = "failed"
        reason = rep.longrepr[2] if isinstance(rep.longrepr, tuple) else str(rep.longrepr)
        rep.longrepr = f"skipped under PREINT_REQUIRE_GTSAM=1 (must run): {reason}"


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    outcome = yield
    rep = outcome.get_result()
    if skips_fail() and rep.skipped:
        reason = rep.longrepr[2] if isinstance(rep.longrepr, tuple) else str(rep.longrepr)
        rep.outcome = "failed"
        rep.longrepr = f"module skipped under PREINT_REQUIRE_GTSAM=1 (must run): {reason}"


def read_euroc_imu(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A EuRoC ``imu0/data.csv`` as ``(t_ns int64[N], gyro float64[N, 3] rad/s, acc
    float64[N, 3] m/s²)``. Timestamps are parsed as integers and values by ``float`` (correctly
    rounded, as Rust's ``str::parse::<f64>``), so the arrays hold the exact values the Rust
    reader produces."""
    t, w, a = [], [], []
    with open(path, newline="") as f:
        for row in csv.reader(f):
            if not row or row[0].lstrip().startswith("#"):
                continue
            t.append(int(row[0]))
            w.append([float(x) for x in row[1:4]])
            a.append([float(x) for x in row[4:7]])
    return np.array(t, dtype=np.int64), np.array(w, dtype=np.float64), np.array(a, dtype=np.float64)


@pytest.fixture(scope="session")
def euroc_imu() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EuRoC V1_01_easy's IMU (29 120 samples at 200 Hz)."""
    return read_euroc_imu(EUROC / "V1_01_easy_imu0.csv")


def cli_command() -> list[str] | None:
    """The Rust command line ``preint`` as an argv prefix: ``$PREINT_CLI`` (``tools/test`` sets
    it to the binary ``cargo test --workspace`` built), else ``cargo run -q -p preint-cli --``
    (builds it if needed, so never a stale binary); None without either."""
    env = os.environ.get("PREINT_CLI")
    if env:
        return [env]
    if shutil.which("cargo"):
        manifest = str(REPO / "Cargo.toml")
        return ["cargo", "run", "-q", "--manifest-path", manifest, "-p", "preint-cli", "--"]
    return None


@pytest.fixture(scope="session")
def preint_cli() -> list[str]:
    """The Rust command line (see :func:`cli_command`); skips (a failure under
    ``PREINT_REQUIRE_GTSAM=1``) when there is none."""
    cmd = cli_command()
    if cmd is None:
        pytest.skip("no Rust command line: set PREINT_CLI or build it with cargo")
    return cmd
