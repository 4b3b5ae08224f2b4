"""The tutorials run as written.

Convention: every block fenced ```` ```bash ```` in ``docs/tutorials/*.md`` runs, in the page's
order, with ``bash -euo pipefail`` in one fresh working directory per page that holds the
repository's ``data/`` (a link) and a copy of its ``examples/``, with ``tcbench``, ``python`` and
``pip`` of this interpreter's environment first on the path. A block fenced
```` ```{.bash .no-run} ```` (a cluster, a database server, an hour-long study) is shown and not
run. ``pip install`` installs into a throwaway folder on ``PYTHONPATH`` rather than the
environment, so a plugin a page installs is gone after its test. Each page must exit 0 block by
block; a few outputs of each are checked where that is cheap."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"
FENCE = re.compile(r"^```([^\n]*)\n(.*?)^```\s*$", re.M | re.S)
PIP_SHIM = """#!/usr/bin/env bash
# pip as the tutorials call it: installs go to a throwaway folder on PYTHONPATH
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


@dataclass(frozen=True)
class Expect:
    """What a page's run must leave: substrings of its output and files (with their first line)."""

    output: tuple[str, ...] = ()
    files: dict[str, str] = field(default_factory=dict)


EXPECT = {
    "own-imu.md": Expect(
        output=("best held out: model, drift 0.111 deg/s", "6247 samples in 25 segments at 50 Hz",
                "allan_min_is_interior         0", "calibration-pan-x-"),
        files={"my-imu/params/px4_tc_params.txt": "param set TC_G0_ID 2293768",
               "my-imu/params/ardupilot_tcal.parm": "INS_TCAL1_ENABLE 1",
               "my-imu/diagnosis-y/report.json": "{",
               "my-imu/calibration/gyro-y-both/calibration.json": "{"}),
    "add-optimiser.md": Expect(
        output=("(from tcbench-de; single-objective)", "3 passed"),
        files={"de-boards/rastrigin-2d.md": ""}),
    "add-term.md": Expect(
        output=("(from tcbench-rate2)", "missing: temperature_rate_squared", "2 passed"),
        files={"diag/model.yaml": "# tcbench fitted model"}),
    "reproduce-papers.md": Expect(
        files={"boards/paper-fa-ifa/rastrigin-2d.md": "", "boards/ifa-bp/msra_zerobias-dev0.md": "",
               "boards/movmd/gyro_driftnoise-dev0.md": ""}),
    "cluster-sweeps.md": Expect(
        output=("already FINISHED", "(experiment 'rehearsal', sweep rehearsal-1): 4 finished, 0 failed")),
}
PAGES = sorted(p.name for p in TUTORIALS.glob("*.md"))


def test_every_tutorial_has_runnable_blocks_and_only_local_ones() -> None:
    assert set(PAGES) == set(EXPECT), "a tutorial without its expectations here, or the other way round"
    for name in PAGES:
        page = TUTORIALS / name
        assert runnable(page), f"{name} runs nothing"
        infos = {info for info, _ in blocks(page)}
        assert infos <= {"bash", "{.bash .no-run}", "text", "python", "toml", "yaml"}, infos
        for body in runnable(page):
            assert "submitit_slurm" not in body and "postgresql" not in body, f"{name}: a cluster block runs"
            assert "run.sh" not in body, f"{name}: a full study runs (it rewrites the committed boards)"


def _environment(work: Path) -> dict[str, str]:
    bin_dir = work / ".bin"
    bin_dir.mkdir()
    site = work / ".site"
    site.mkdir()
    shim = bin_dir / "pip"
    shim.write_text(PIP_SHIM.format(python=sys.executable, site=site))
    shim.chmod(0o755)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": str(site), "MPLBACKEND": "Agg", "MLFLOW_DISABLE_TELEMETRY": "true"}
    env.pop("MLFLOW_TRACKING_URI", None)  # the pages' runs go to ./mlflow.db, as they say
    return env


@pytest.mark.slow
@pytest.mark.parametrize("name", PAGES)
def test_tutorial_runs_as_written(name: str, tmp_path: Path) -> None:
    work = tmp_path / "work"
    work.mkdir()
    (work / "data").symlink_to(ROOT / "data")
    shutil.copytree(ROOT / "examples", work / "examples",
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    env = _environment(work)
    output, start = [], time.monotonic()
    for i, body in enumerate(runnable(TUTORIALS / name)):
        run = subprocess.run(["bash", "-euo", "pipefail", "-c", body], cwd=work, env=env, capture_output=True,
                             text=True, timeout=1800)
        output.append(run.stdout + run.stderr)
        assert run.returncode == 0, f"{name}, block {i + 1} exited {run.returncode}:\n{body}\n{output[-1][-4000:]}"
    text = "\n".join(output)
    expect = EXPECT[name]
    for piece in expect.output:
        assert piece in text, f"{name}: {piece!r} not in its output"
    for path, first in expect.files.items():
        assert (work / path).is_file(), f"{name}: {path} not written"
        assert (work / path).read_text(encoding="utf-8").startswith(first), f"{name}: {path}"
    print(f"{name}: {len(output)} blocks in {time.monotonic() - start:.0f} s")
