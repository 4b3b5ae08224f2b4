"""``tcbench calibrate`` on the real tofupilot chamber cycle as a user imports it: fitted on the
first cooling branch, scored on the heating and the second cooling branch, tracked in MLflow."""

from __future__ import annotations

from pathlib import Path

import mlflow
import pandas as pd
import pytest

from tcbench.cli import main
from tcbench.diagnose.real_records import TOFUPILOT_CSV


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


@pytest.fixture()
def gyro_y(workdir: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature", "output=imu.gyro.y:rad/s", "out=rec", "name=gyro-y",
                       "tracking.enabled=false")
    assert code == 0, err
    return workdir / "rec" / "gyro-y.csv"


def test_calibrate_the_tofupilot_gyro(gyro_y: Path, workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "calibrate", f"recording={gyro_y}", "out=cal")
    assert code == 0, err
    table = pd.read_csv(workdir / "cal" / "calibration.csv")
    assert sorted(set(table["method"])) == ["bp", "elman", "poly3", "poly3_rate", "raw"]
    assert table.groupby("method")["direction"].apply(list).to_dict()["raw"] == ["cooling", "heating", "cooling"]
    drift = table.pivot(index="branch", columns="method", values="drift_rms_deg_per_s")
    assert (table.loc[table["branch"] == 0, "role"] == "train").all()
    assert (drift.loc[[1, 2], "poly3"] < 0.7 * drift.loc[[1, 2], "raw"]).all()  # held out: the cubic still helps
    assert (drift.loc[0, "poly3"] < 0.05 * drift.loc[0, "raw"])  # in sample: it fits
    assert (drift.loc[[1, 2], "bp"] < drift.loc[[1, 2], "raw"]).all()
    params = (workdir / "cal" / "px4_tc_params.txt").read_text().splitlines()
    assert params[0] == "param set TC_G0_ID 0" and "param set TC_G0_X3_0" in " ".join(params)
    assert (workdir / "cal" / "residuals.png").stat().st_size > 10_000
    assert "| poly3 | 1 | heating |" in out

    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (r,) = client.search_runs([client.get_experiment_by_name("calibrations").experiment_id])
    assert r.data.tags["tcbench.kind"] == "calibration" and r.data.tags["tcbench.sensor"] == "gyro"
    assert r.data.metrics["poly3.b1.drift_rms"] == pytest.approx(drift.loc[1, "poly3"])
    assert {"calibration.md", "residuals.png", "px4_tc_params.txt"} <= {a.path for a in client.list_artifacts(r.info.run_id)}


@pytest.mark.parametrize(("args", "words"), [
    (("train_branches=[5]",), "the recording has 3 temperature branches"),
    (("methods=[elman_magic]",), "methods: unknown 'elman_magic'"),
    (("min_swing_c=0",), "must be > 0"),
    (("seed=-1",), "seed must be a non-negative integer"),
])
def test_bad_calibrations_are_one_line(gyro_y: Path, workdir: Path, capsys: pytest.CaptureFixture[str],
                                       args: tuple[str, ...], words: str) -> None:
    code, _, err = run(capsys, "calibrate", f"recording={gyro_y}", "out=cal", *args)
    assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (workdir / "cal").exists() and not (workdir / "mlflow.db").exists()


def test_a_seed_sweep_resolves_each_seed_and_never_shares_an_output(gyro_y: Path, workdir: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``out=cal/${seed}`` is resolved per job (the launcher composed one config per group of
    seeds, so every seed wrote into the first seed's folder); seeds writing one folder are refused."""
    code, _, err = run(capsys, "calibrate", "-m", f"recording={gyro_y}", "seed=range(2)", "methods=[bp]",
                       "out=cal/${seed}", "tracking.enabled=false")
    assert code == 0, err
    boards = [pd.read_csv(workdir / "cal" / s / "calibration.csv") for s in ("0", "1")]
    assert boards[0]["drift_rms_deg_per_s"].tolist() != boards[1]["drift_rms_deg_per_s"].tolist()
    code, _, err = run(capsys, "calibrate", "-m", f"recording={gyro_y}", "seed=range(2)", "methods=[raw]",
                       "out=same", "tracking.enabled=false")
    assert code == 2 and len(err) == 1 and "jobs 1 and 2 of the sweep would both write same" in err[0], err
    assert not (workdir / "same").exists()
