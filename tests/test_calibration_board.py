"""Calibrations are runs the ordinary ``tcbench leaderboard`` reads: one board per recording's
content, so two files of one name never merge and no calibration config hides another."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from tcbench.cli import main
from tcbench.datasets.real import TOFUPILOT_CSV


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


def test_the_leaderboard_reads_calibrations_keyed_by_content(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.x:rad/s,imu.gyro.y:rad/s", "out=rec",
                       "name=imu", "tracking.enabled=false")
    assert code == 0, err
    # two different recordings under one name, in two folders
    for axis, folder in (("x", "a"), ("y", "b")):
        (workdir / folder).mkdir()
        for ext in ("csv", "json"):
            shutil.copy(workdir / "rec" / f"imu-imu.gyro.{axis}.{ext}", workdir / folder / f"gyro.{ext}")
        code, _, err = run(capsys, "calibrate", f"recording={folder}/gyro.csv", f"out=cal-{folder}",
                           "methods=[raw,poly3]")
        assert code == 0, err
    # the same recording calibrated twice with different configs: both stay
    code, _, err = run(capsys, "calibrate", "recording=a/gyro.csv", "out=cal-a2", "methods=[raw,poly3]",
                       "train_branches=[0,1]")
    assert code == 0, err
    code, out, err = run(capsys, "leaderboard", "experiments=calibrations", "out=boards")
    assert code == 0, err
    files = sorted(p.name for p in (workdir / "boards").glob("calibration-*.csv"))
    assert len(files) == 2 and all(f.startswith("calibration-gyro-") for f in files), files
    tables = {f: pd.read_csv(workdir / "boards" / f) for f in files}
    sizes = sorted(len(t) for t in tables.values())
    assert sizes == [2, 4], tables  # b: raw and poly3 once; a: raw and poly3 under two configs
    two = next(t for t in tables.values() if len(t) == 4)
    assert two["config"].nunique() == 2 and set(two["split"]) == {"fit 1 -> score 0,2", "fit 0,1 -> score 2"}
    assert two.loc[0, "method"] == "poly3" and (two["x_best"] >= 1).all()


def test_testing_on_the_training_data_warns(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.x:rad/s", "out=rec", "name=x",
                       "tracking.enabled=false")
    assert code == 0, err
    for ext in ("csv", "json"):
        shutil.copy(workdir / "rec" / f"x.{ext}", workdir / "rec" / f"copy.{ext}")
    code, _, err = run(capsys, "calibrate", "recording=rec/x.csv", "out=cal", "methods=[raw,poly3]",
                       "test_recordings=[rec/copy.csv]", "tracking.enabled=false")
    assert code == 0 and err == ["tcbench: warning: test_recordings: rec/copy.csv holds the same data as rec/x.csv: "
                                 "its scores are in-sample"], err
