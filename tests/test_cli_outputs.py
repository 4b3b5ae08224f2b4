"""What a command writes lands where it says: a sweep's Hydra record under the folder of its jobs'
``out=``, MLflow's artifacts and lock beside the store's database, nothing else in the working
folder; and Hydra's log lines go to stderr, never between the results on stdout."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.sensors.recording import make_recording, write_recording


def _gyro(path: Path, seed: int, rows: int = 600) -> Path:
    """A small gyro recording with its sidecar: warming, then cooling (two temperature branches)."""
    temp_c = 20.0 + 10.0 * np.sin(np.linspace(0.0, np.pi, rows))
    output = 0.01 * temp_c + np.random.default_rng(seed).normal(0.0, 0.01, rows)
    rec = make_recording(np.arange(rows, dtype=np.float64), temp_c, np.zeros(rows), output, sensor="gyro",
                         sample_rate_hz=1.0, device_id=f"d{seed}")
    write_recording(rec, path)
    return path


def _files(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()}


def test_a_calibrate_sweep_writes_under_out_and_beside_the_store(workdir: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """Before: ``multirun/<date>/...`` and ``mlartifacts/`` in the working folder whatever out= and
    tracking.uri said, and Hydra's ``[HYDRA]`` lines on stdout between calibrate's tables."""
    (workdir / "rec").mkdir()
    (workdir / "store").mkdir()  # a store's folder is never made for it
    for seed in (1, 2):
        _gyro(workdir / "rec" / f"unit{seed}.csv", seed)
    before = _files(workdir)
    uri = f"sqlite:///{workdir / 'store' / 'mlflow.db'}"
    code = main(["calibrate", "-m", "recording=rec/unit1.csv,rec/unit2.csv", "out=cal/${stem:recording}",
                 "methods=[raw,poly3]", f"tracking.uri={uri}"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    new = _files(workdir) - before
    assert {p.split("/")[0] for p in new} == {"cal", "store"}, sorted(new)  # no multirun/, no mlartifacts/ here
    assert {"cal/unit1/calibration.json", "cal/unit2/calibration.json", "store/mlflow.db",
            "store/mlflow.db.lock"} <= new
    assert any(p.startswith("store/mlartifacts/calibrations/") for p in new)
    records = sorted(p for p in new if p.startswith("cal/multirun/"))
    assert [p.rsplit("/", 3)[-3:] for p in records if p.endswith("config.yaml")] == \
        [["0", ".hydra", "config.yaml"], ["1", ".hydra", "config.yaml"]]
    assert "[HYDRA]" not in captured.out and captured.out.count("best held out:") == 2
    assert "[HYDRA] Launching 2 jobs" in captured.err and "sweep: 2/2 jobs done" in captured.err


def test_a_sweep_whose_outputs_share_no_folder_keeps_hydra_s_default(workdir: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """``tcbench run`` has no out=: its record stays in ./multirun/, as its --help says; its log
    lines go to stderr as every command's."""
    assert main(["run", "-m", "task=sphere", "budget=20", "seed=0,1", "tracking.enabled=false"]) == 0
    captured = capsys.readouterr()
    assert (workdir / "multirun").is_dir()
    assert "[HYDRA]" not in captured.out and "[HYDRA] Launching 2 jobs" in captured.err


def test_the_user_s_own_sweep_dir_and_logging_win(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _gyro(workdir / "a.csv", 1)
    assert main(["calibrate", "-m", "recording=a.csv", "out=cal/${stem:recording}", "methods=[raw]",
                 "tracking.enabled=false", "hydra.sweep.dir=mine", "hydra/hydra_logging=default"]) == 0
    captured = capsys.readouterr()
    assert (workdir / "mine" / "multirun.yaml").is_file() and not (workdir / "cal" / "multirun").exists()
    assert "[HYDRA] Launching 1 jobs" in captured.out


def test_a_failed_job_is_not_counted_against_the_next_command(workdir: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """main() run twice in one process: the first command's failed job is not the sweep's after it."""
    from tcbench.tracking import store as tracking

    uri = f"sqlite:///{workdir / 'mlflow.db'}"
    tracking.prepare_store(uri, "calibrations")
    assert main(["leaderboard", "experiments=[calibrations,diagnosis]", f"tracking.uri={uri}", "out=lb"]) != 0
    _gyro(workdir / "a.csv", 1)
    assert main(["calibrate", "-m", "recording=a.csv", "out=cal/${stem:recording}", "methods=[raw]",
                 "tracking.enabled=false"]) == 0
    assert "failed" not in capsys.readouterr().out.split("calibrate a.csv")[-1]
