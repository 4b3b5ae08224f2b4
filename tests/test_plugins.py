"""Optimiser plugins from other packages: the example package, a broken one, a rogue one."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from cli_here import install_here
from cli_here import tcbench as here
from plugin_site import fake_distribution, install_example, tcbench

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plugin-optimiser"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example plugin installed (not editable) into a directory put on PYTHONPATH."""
    return install_example("plugin-optimiser", tmp_path_factory)


def in_here(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` in this process (the plugins installed by :func:`cli_here.install_here`),
    with no tracking URI set, as :func:`plugin_site.tcbench` runs it."""
    return here(*args, cwd=cwd, env={"MLFLOW_TRACKING_URI": None})


def test_example_plugin_on_a_leaderboard(site: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Listed, swept and on a board, in this process with the plugin installed here (``tcbench
    list`` with plugins in a process of its own: the broken plugin's test below)."""
    install_here(monkeypatch, site)
    listed = in_here("list", cwd=tmp_path)
    assert "de         tcbench_de.de.DifferentialEvolution  (from tcbench-de; single-objective)" in listed.stdout
    run = in_here("run", "-m", "optimiser=de,ifa", "task=sphere", "seed=range(2)", "budget=200",
                  "tracking.experiment=plugins", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "4 finished, 0 failed" in run.stdout
    board = in_here("leaderboard", "--experiment", "plugins", "--out", "lb", cwd=tmp_path)
    assert board.returncode == 0, board.stderr
    table = pd.read_csv(tmp_path / "lb" / "sphere-2d.csv")
    assert sorted(table["method"]) == ["de", "ifa"] and table["seeds"].tolist() == [2, 2]


def test_example_plugin_own_tests(site: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(site)}
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(EXAMPLE / "tests")],
                         env=env, capture_output=True, text=True, timeout=300, cwd=site)
    assert out.returncode == 0, out.stdout + out.stderr


def test_broken_plugin_is_reported_and_skipped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    site = tmp_path / "site"
    site.mkdir()
    fake_distribution(site, "broken_plugin", "[tcbench.optimisers]\nbroken = no_such_module:Nope\n")
    listed = tcbench("list", cwd=tmp_path, path=site)
    assert listed.returncode == 0
    assert "broken     BROKEN: ModuleNotFoundError: No module named 'no_such_module'" in listed.stdout
    assert "ifa" in listed.stdout
    install_here(monkeypatch, site)
    run = in_here("run", "task=sphere", "optimiser=fa", "budget=50", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "1 finished, 0 failed" in run.stdout


def test_protocol_breaking_plugin_is_stopped_and_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    site = tmp_path / "site"
    site.mkdir()
    code = (
        "from tcbench.optimisers.fa import FireflyAlgorithm\n"
        "class Rogue(FireflyAlgorithm):\n"
        "    name = 'rogue'\n"
        "    def ask(self):\n"
        "        return super().ask() * 1000.0\n"
    )
    fake_distribution(site, "rogue_plugin", "[tcbench.optimisers]\nrogue = rogue_mod:Rogue\n", "rogue_mod", code)
    install_here(monkeypatch, site)
    run = in_here("run", "-m", "task=sphere", "optimiser=fa", "optimiser.name=rogue,fa", "budget=50", cwd=tmp_path)
    assert run.returncode == 1
    assert "1 finished, 1 failed" in run.stdout
    assert "ProtocolError: optimiser 'rogue' broke the protocol: asked points outside the bounds" in run.stdout
