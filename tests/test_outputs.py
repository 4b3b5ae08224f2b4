"""Output folders are checked before any work: one line, exit 2, nothing written."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from tcbench.outputs import folder_problem


def listing(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def test_usable_folders_pass_and_nothing_is_left(tmp_path: Path) -> None:
    (tmp_path / "there").mkdir()
    before = listing(tmp_path)
    assert folder_problem(tmp_path / "there") is None
    assert folder_problem(tmp_path / "new" / "deeper") is None  # made later, by the command
    assert listing(tmp_path) == before  # the probe folder is gone and nothing was made


def test_a_file_is_not_a_folder(tmp_path: Path) -> None:
    (tmp_path / "f.txt").write_text("x")
    assert folder_problem(tmp_path / "f.txt") == "is not a folder"
    assert folder_problem(tmp_path / "f.txt" / "sub") == f"cannot be made: {tmp_path / 'f.txt'} is not a folder"


def test_an_unwritable_folder_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Permission bits do not stop the superuser, so the refusal of the file system is simulated.
    def refuse(*args: object, **kwargs: object) -> str:
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    assert folder_problem(tmp_path) == "cannot be written (Permission denied)"
    assert folder_problem(tmp_path / "a" / "b") == f"cannot be made in {tmp_path} (Permission denied)"


def tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tcbench", *args], check=False, cwd=cwd, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "task=sphere", "budget=40", "tracking.enabled=false", "tracking.ioh_dir=blocker"],
         "tracking.ioh_dir=blocker: is not a folder"),
        (["run", "task=sphere", "budget=40", "tracking.uri=sqlite:///blocker/mlflow.db"],
         "tracking store blocker/mlflow.db: its folder blocker is not a folder"),
        (["simulate", "sensor=gyro", "protocol=static", "out=blocker/recs"],
         "out=blocker/recs: cannot be made: blocker is not a folder"),
        (["import", "csv=in.csv", "sensor=gyro", "time=t", "temperature=T", "output=w", "out=blocker"],
         "out=blocker: is not a folder"),
        (["diagnose", "recording=in.csv", "out=blocker/d"], "out=blocker/d: cannot be made: blocker is not a folder"),
        (["leaderboard", "--out", "blocker"], "--out blocker: is not a folder"),
    ],
)
def test_commands_refuse_an_unusable_output_folder(workdir: Path, args: list[str], message: str) -> None:
    (workdir / "blocker").write_text("a file where a folder should be\n")
    (workdir / "in.csv").write_text("t,T,w\n0,20,0.1\n1,20,0.2\n")
    before = listing(workdir)
    out = tcbench(*args, cwd=workdir)
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2, out.stderr
    assert lines and message in lines[-1], out.stderr
    assert "Traceback" not in out.stderr + out.stdout
    assert listing(workdir) == before  # no store, no recording, no report was started


def test_metrics_refuses_an_unusable_output_folder(workdir: Path) -> None:
    made = tcbench("simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=120",
                   "metrics=false", "tracking.enabled=false", "out=recs", cwd=workdir)
    assert made.returncode == 0, made.stderr
    (recording,) = (workdir / "recs").glob("*.csv")
    (workdir / "blocker").write_text("x")
    before = listing(workdir)
    out = tcbench("metrics", str(recording), "out=blocker/m", "tracking.enabled=false", cwd=workdir)
    assert out.returncode == 2 and "out=blocker/m: cannot be made: blocker is not a folder" in out.stderr
    assert "Traceback" not in out.stderr and listing(workdir) == before
