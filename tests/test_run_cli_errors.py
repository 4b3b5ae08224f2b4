"""``tcbench run`` and ``tcbench leaderboard``: a bad tracking store is one line, quickly, before
any job; Hydra's information flags work after overrides; a leaderboard creates no store."""

from __future__ import annotations

import socket
import subprocess
import time
from pathlib import Path

import pytest
from cli_here import tcbench as here


def tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` run in this process (:mod:`cli_here`) without a tracking URI set."""
    return here(*args, cwd=cwd, env={"MLFLOW_TRACKING_URI": None})


def one_line_error(out: subprocess.CompletedProcess[str], *words: str) -> None:
    assert out.returncode == 2, out.stdout + out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.startswith("tcbench: error:")]
    assert len(lines) == 1 and "Traceback" not in out.stderr, out.stderr
    assert all(w in lines[0] for w in words), lines[0]


def closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_empty_experiment_name_is_refused_before_a_store_is_made(tmp_path: Path) -> None:
    one_line_error(tcbench("run", "budget=20", "tracking.experiment=", cwd=tmp_path), "tracking.experiment")
    assert not (tmp_path / "mlflow.db").exists()


@pytest.mark.parametrize("command", ["run", "leaderboard"])
def test_unknown_store_scheme_is_one_line(tmp_path: Path, command: str) -> None:
    args = ["run", "budget=20", "tracking.uri=foo://bar"] if command == "run" else \
        ["leaderboard", "--tracking-uri", "foo://bar"]
    one_line_error(tcbench(*args, cwd=tmp_path), "foo://bar")


def test_a_server_that_is_not_there_is_named_within_seconds(tmp_path: Path) -> None:
    """A closed port took 4 min 10 s of MLflow's retries and ended in a 107-line traceback."""
    port = closed_port()
    t0 = time.monotonic()
    out = tcbench("run", "budget=20", f"tracking.uri=http://127.0.0.1:{port}", cwd=tmp_path)
    one_line_error(out, f"127.0.0.1:{port}", "nothing answers")
    assert time.monotonic() - t0 < 60
    assert "job" not in out.stderr.split("tcbench: error:")[0]  # refused before any job was announced


def test_leaderboard_in_an_empty_folder_makes_no_store(tmp_path: Path) -> None:
    one_line_error(tcbench("leaderboard", cwd=tmp_path), "no tracking store")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("flags", [["--hydra-help"], ["task=sphere", "--help"], ["task=sphere", "-h"],
                                   ["task=sphere", "--cfg", "job"], ["task=sphere", "--info", "defaults"]])
def test_hydra_information_flags_after_overrides(tmp_path: Path, flags: list[str]) -> None:
    """``--hydra-help`` was a traceback, and every flag after an override was refused with
    "unrecognized arguments: tracking.sweep_id=..." (arguments tcbench had added itself)."""
    out = tcbench("run", *flags, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "unrecognized" not in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "mlflow.db").exists()
    if "--cfg" in flags:
        assert "name: sphere" in out.stdout or "name: fa" in out.stdout


def test_hydra_usage_error_is_one_line(tmp_path: Path) -> None:
    one_line_error(tcbench("run", "-m", "optimiser=fa,ifa", "--cfg", "job", cwd=tmp_path), "Only one of")


def test_run_help_lists_plugin_optimisers(tmp_path: Path) -> None:
    """The optimiser group in ``run --help`` left out the installed plugins' optimisers."""
    from importlib.metadata import entry_points

    if not any(ep.name == "tcbench_peers" for ep in entry_points(group="tcbench.configs")):
        pytest.skip("plugins/tcbench-peers is not installed")
    out = tcbench("run", "--help", cwd=tmp_path)
    group = next(ln for ln in out.stdout.splitlines() if ln.startswith("optimiser:"))
    assert "cmaes" in group and "ifa" in group


SIM = ["simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=200",
       "protocol_params.sample_rate_hz=1"]


def test_simulate_and_metrics_check_the_store_before_any_work(tmp_path: Path) -> None:
    """simulate and metrics log to MLflow too: a bad store is refused before anything is written."""
    port = closed_port()
    one_line_error(tcbench(*SIM, "tracking.uri=foo://bar", "out=o", cwd=tmp_path), "foo://bar")
    one_line_error(tcbench(*SIM, "tracking.experiment=", "out=o", cwd=tmp_path), "tracking.experiment")
    assert not (tmp_path / "o").exists() and not (tmp_path / "mlflow.db").exists()
    assert tcbench(*SIM, "tracking.enabled=false", "metrics=false", "name=r", "out=o", cwd=tmp_path).returncode == 0
    out = tcbench("metrics", "o/r.csv", f"tracking.uri=http://127.0.0.1:{port}", cwd=tmp_path)
    one_line_error(out, "nothing answers")
    assert not (tmp_path / "o" / "r_metrics").exists()
