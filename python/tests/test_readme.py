"""The Python code blocks of python/README.md run, in order, in one namespace (from the
repository root, where the README's paths point)."""

import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_readme_python_blocks_run():
    text = (ROOT / "python" / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 4
    ns: dict = {}
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        for code in blocks:
            exec(compile(code, "python/README.md", "exec"), ns)
    finally:
        os.chdir(cwd)
    # What the blocks claim: x_j is the prediction, so the residual is zero.
    assert abs(ns["r"]).max() < 1e-12
    assert ns["rec"]["gyro"].shape[1] == 3 and ns["d"]["delta_R"].shape == (2, 3, 3)
