"""Output folders are checked before any work: one line, exit 2, nothing written."""

from __future__ import annotations

import errno
import os
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from cli_here import tcbench as here

from tcbench.outputs import folder_problem, name_problem, overwritten_input
from tcbench.sensors.recording import make_recording, write_recording
from tcbench.staging import InputOverwriteError, staged_dir


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
    """``tcbench ARGS`` run in this process (:mod:`cli_here`)."""
    return here(*args, cwd=cwd)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "task=sphere", "budget=40", "tracking.enabled=false", "tracking.ioh_dir=blocker"],
         "tracking.ioh_dir=blocker: is not a folder"),
        (["run", "task=sphere", "budget=40", "tracking.uri=sqlite:///blocker/mlflow.db"],
         "tracking store blocker/mlflow.db: its folder blocker is not a folder"),
        (["simulate", "sensor=gyro", "protocol=static", "out=blocker/recs"],
         "out=blocker/recs: cannot be made: blocker is not a folder"),
        (["import", "csv=in.csv", "sensor=gyro", "time=t:s", "temperature=T:degC", "output=w:deg/s", "out=blocker"],
         "out=blocker: is not a folder"),
        (["diagnose", "recording=in.csv", "out=blocker/d"], "out=blocker/d: cannot be made: blocker is not a folder"),
        (["leaderboard", "--out", "blocker"], "out=blocker: is not a folder"),
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


# -- names, inputs and staging ----------------------------------------------------------------------
@pytest.mark.parametrize("name", ["", ".", "..", "a/b", "../x", "/tmp/x", "a\\b", "a\0b"])
def test_names_that_leave_the_folder_are_refused(name: str) -> None:
    assert name_problem(name) is not None


@pytest.mark.parametrize("name", ["run1", "gyro-static-dev0-seed0", ".hidden", "a b", "x.y"])
def test_plain_names_pass(name: str) -> None:
    assert name_problem(name) is None


def test_an_input_is_found_through_another_spelling(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    src = tmp_path / "src.csv"
    src.write_text("x\n")
    (tmp_path / "link.csv").symlink_to(src)
    assert overwritten_input([tmp_path / "sub" / ".." / "src.csv"], [src]) is not None
    assert overwritten_input([tmp_path / "link.csv"], [src]) is not None
    assert overwritten_input([tmp_path / "new.csv", tmp_path / "sub"], [src, tmp_path / "missing"]) is None


def test_staging_keeps_inputs_and_leaves_no_folder_it_made(tmp_path: Path) -> None:
    src = tmp_path / "out" / "a.txt"
    src.parent.mkdir()
    src.write_text("input")
    with pytest.raises(InputOverwriteError), staged_dir(tmp_path / "out", [src]) as tmp:
        (tmp / "b.txt").write_text("new")
        (tmp / "a.txt").write_text("new")
    assert listing(tmp_path) == ["out", "out/a.txt"] and src.read_text() == "input"  # not even b.txt moved
    with pytest.raises(OSError), staged_dir(tmp_path / "x" / "y" / "out") as tmp:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert listing(tmp_path) == ["out", "out/a.txt"]  # x/ and x/y/ made for the staging are gone


def test_staging_merges_folders(tmp_path: Path) -> None:
    with staged_dir(tmp_path / "out") as tmp:
        (tmp / "m").mkdir()
        (tmp / "m" / "old.png").write_text("1")
        (tmp / "m" / "same.json").write_text("1")
    with staged_dir(tmp_path / "out", overwrite=True) as tmp:  # a file of the same name: replaced only when asked
        (tmp / "m").mkdir()
        (tmp / "m" / "same.json").write_text("2")
    assert listing(tmp_path) == ["out", "out/m", "out/m/old.png", "out/m/same.json"]
    assert (tmp_path / "out" / "m" / "same.json").read_text() == "2"


@pytest.fixture
def small_tmpfs(tmp_path: Path) -> Iterator[Path]:
    """A 2 MB tmpfs, nearly full (skipped where mounting is not allowed)."""
    mount = tmp_path / "full"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mount)], capture_output=True,
                          check=False)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        (mount / "filler").write_bytes(b"\0" * (2 * 1024 * 1024 - 64 * 1024))
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], check=False)


@pytest.mark.figures
def test_a_real_full_disk(workdir: Path, small_tmpfs: Path) -> None:
    """Simulate, metrics and diagnose into a full tmpfs: one line, exit 2, nothing left there."""
    t_s = np.arange(2000.0)
    temp_c = np.linspace(20.0, 30.0, t_s.size)
    rate_dps = 0.01 * temp_c + np.random.default_rng(0).normal(0.0, 0.01, t_s.size)
    write_recording(make_recording(t_s, temp_c, 0.0 * t_s, rate_dps, sensor="gyro", sample_rate_hz=1.0,
                                   device_id="d"), workdir / "rec.csv")
    before = listing(small_tmpfs)
    for args in (["simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=2000",
                  "protocol_params.sample_rate_hz=1", "tracking.enabled=false", f"out={small_tmpfs}/o"],
                 ["metrics", "rec.csv", f"out={small_tmpfs}/m", "tracking.enabled=false"],
                 ["diagnose", "recording=rec.csv", f"out={small_tmpfs}/d"]):
        out = tcbench(*args, cwd=workdir)
        lines = out.stderr.strip().splitlines()
        assert out.returncode == 2 and len(lines) == 1, out.stderr
        assert lines[0].startswith("tcbench: error: out=") and "(No space left on device)" in lines[0], lines
        assert listing(small_tmpfs) == before
