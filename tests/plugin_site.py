"""Plugin packages for the plugin tests: an example installed (not editable) into a folder put on
PYTHONPATH, fake distributions beside it, and ``tcbench`` run with that folder on the path."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def tcbench(*args: str, cwd: Path, path: Path, timeout_s: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m tcbench ARGS`` in ``cwd`` with ``path`` on PYTHONPATH and no tracking server."""
    env = {**os.environ, "PYTHONPATH": str(path), "MLFLOW_DISABLE_TELEMETRY": "true", "MPLBACKEND": "Agg"}
    env.pop("MLFLOW_TRACKING_URI", None)
    return subprocess.run([sys.executable, "-m", "tcbench", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout_s)


def install_example(name: str, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``examples/NAME`` installed into a new folder, returned. Built from a copy: the build's
    build/ and *.egg-info stay out of the clone, and test workers that each install it (pytest -n)
    do not build in the same folder at once."""
    target = tmp_path_factory.mktemp("site")
    src = tmp_path_factory.mktemp("example") / name
    shutil.copytree(EXAMPLES / name, src, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation",
         "--target", str(target), str(src)],
        check=True, capture_output=True, text=True, timeout=300,
    )
    return target


def fake_distribution(site: Path, name: str, entry_points: str, module: str = "", code: str = "") -> None:
    """A distribution ``name`` in ``site`` declaring ``entry_points`` (and a module ``module.py``)."""
    info = site / f"{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(entry_points)
    if module:
        (site / f"{module}.py").write_text(code)
