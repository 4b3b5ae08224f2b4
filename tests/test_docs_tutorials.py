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

import importlib.util
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from doc_blocks import ROOT, blocks, environment, fresh_folder, run_blocks, runnable

TUTORIALS = ROOT / "docs" / "tutorials"


@dataclass(frozen=True)
class Expect:
    """What a page's run must leave: substrings of its output and files (with their first line, past
    any comment lines unless the line expected is one)."""

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
# tutorials whose blocks are not all shell (a C source, Python run in-process) have a test of their own
OWN_TEST = {"device-c.md": "tests/test_device_tutorial.py"}
PAGES = sorted(p.name for p in TUTORIALS.glob("*.md") if p.name not in OWN_TEST)


def test_every_tutorial_has_runnable_blocks_and_only_local_ones() -> None:
    assert set(PAGES) == set(EXPECT), "a tutorial without its expectations here, or the other way round"
    here = Path(__file__).resolve().parents[1]
    assert all((TUTORIALS / page).is_file() and (here / test).is_file() for page, test in OWN_TEST.items())
    for name in PAGES:
        page = TUTORIALS / name
        assert runnable(page), f"{name} runs nothing"
        infos = {info for info, _ in blocks(page)}
        assert infos <= {"bash", "{.bash .no-run}", "text", "python", "toml", "yaml"}, infos
        for body in runnable(page):
            assert "submitit_slurm" not in body and "postgresql" not in body, f"{name}: a cluster block runs"
            assert "run.sh" not in body, f"{name}: a full study runs (it rewrites the committed boards)"
            assert "hydra/launcher=ray" not in body, f"{name}: a Ray block runs without the ray extra"


@pytest.mark.slow
@pytest.mark.parametrize("name", PAGES)
def test_tutorial_runs_as_written(name: str, tmp_path: Path) -> None:
    work = fresh_folder(tmp_path / "work")
    start = time.monotonic()
    output = run_blocks(name, runnable(TUTORIALS / name), work, environment(work))
    text = "\n".join(output)
    expect = EXPECT[name]
    for piece in expect.output:
        assert piece in text, f"{name}: {piece!r} not in its output"
    for path, first in expect.files.items():
        assert (work / path).is_file(), f"{name}: {path} not written"
        lines = (work / path).read_text(encoding="utf-8").splitlines(keepends=True)
        body = "".join(line for line in lines if first.startswith("#") or not line.startswith("#"))
        assert body.startswith(first), f"{name}: {path}"  # past the comments an autopilot file opens with
    print(f"{name}: {len(output)} blocks in {time.monotonic() - start:.0f} s")


@pytest.mark.slow
def test_cluster_page_ray_rehearsal_runs(tmp_path: Path) -> None:
    """The cluster page's Ray block (shown, not run, by the test above: it needs the ``ray``
    extra) runs a two-job sweep on a local Ray instance where Ray is installed."""
    if not (importlib.util.find_spec("ray") and importlib.util.find_spec("hydra_plugins.hydra_ray_launcher")):
        pytest.skip("ray and hydra-ray-launcher are not installed (pip install -e '.[ray]')")
    (body,) = [body for info, body in blocks(TUTORIALS / "cluster-sweeps.md") if "hydra/launcher=ray" in body]
    work = fresh_folder(tmp_path / "work")
    env = {**environment(work), "RAY_USAGE_STATS_ENABLED": "0"}
    start = time.monotonic()
    (output,) = run_blocks("cluster-sweeps.md (Ray)", [body], work, env)
    assert "Ray Launcher is launching 2 jobs" in output, output[-4000:]
    assert "(experiment 'ray-rehearsal', sweep ray-1): 2 finished, 0 failed" in output, output[-4000:]
    print(f"cluster-sweeps.md, Ray rehearsal: {time.monotonic() - start:.0f} s")
