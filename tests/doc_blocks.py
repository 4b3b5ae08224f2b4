"""Running a page's shell blocks as a reader would, shared by the tests of the tutorials
(``test_docs_tutorials.py``) and of the README (``test_docs_readme.py``).

Every block fenced ```` ```bash ```` runs with ``bash -euo pipefail`` in one fresh working
directory per page that holds the repository's ``data/`` (a link) and a copy of its
``examples/``, with ``tcbench``, ``python`` and ``pip`` of this interpreter's environment first
on the path (the environment a reader has activated; the test's own ``PYTHONPATH`` kept, so a
checkout on it is the ``tcbench`` the blocks run). ``pip install`` installs into a throwaway folder
put first on ``PYTHONPATH`` rather than into the environment."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^```([^\n]*)\n(.*?)^```\s*$", re.M | re.S)
PIP_SHIM = """#!/usr/bin/env bash
# pip as the pages call it: installs go to a throwaway folder on PYTHONPATH
if [ "$1" = install ]; then
  shift
  exec "{python}" -m pip install -q --no-deps --no-build-isolation --target "{site}" "$@"
fi
exec "{python}" -m pip "$@"
"""


def blocks(page: Path) -> list[tuple[str, str]]:
    """``(info string, body)`` of every fenced block of ``page``, in order."""
    return [(info.strip(), body) for info, body in FENCE.findall(page.read_text(encoding="utf-8"))]


def runnable(page: Path) -> list[str]:
    """The bodies of the page's blocks fenced exactly ```` ```bash ````."""
    return [body for info, body in blocks(page) if info == "bash"]


def fresh_folder(work: Path) -> Path:
    """``work`` made a reader's working folder: the repository's ``data/`` linked, ``examples/`` copied."""
    work.mkdir(parents=True)
    (work / "data").symlink_to(ROOT / "data")
    shutil.copytree(ROOT / "examples", work / "examples",
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    return work


def environment(work: Path) -> dict[str, str]:
    """The environment of a shell with this interpreter's environment active, ``pip`` shimmed."""
    bin_dir = work / ".bin"
    bin_dir.mkdir()
    site = work / ".site"
    site.mkdir()
    shim = bin_dir / "pip"
    shim.write_text(PIP_SHIM.format(python=sys.executable, site=site))
    shim.chmod(0o755)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": os.pathsep.join(filter(None, (str(site), os.environ.get("PYTHONPATH")))),
           "MPLBACKEND": "Agg", "MLFLOW_DISABLE_TELEMETRY": "true"}
    env.pop("MLFLOW_TRACKING_URI", None)  # the pages' runs go to ./mlflow.db, as they say
    return env


def run_blocks(name: str, bodies: list[str], work: Path, env: dict[str, str]) -> list[str]:
    """Run ``bodies`` in ``work`` one after another; each block's output. AssertionError naming the
    page, the block and its output's end at the first block that exits non-zero."""
    output = []
    for i, body in enumerate(bodies):
        run = subprocess.run(["bash", "-euo", "pipefail", "-c", body], cwd=work, env=env, capture_output=True,
                             text=True, timeout=1800)
        output.append(run.stdout + run.stderr)
        assert run.returncode == 0, f"{name}, block {i + 1} exited {run.returncode}:\n{body}\n{output[-1][-4000:]}"
    return output
