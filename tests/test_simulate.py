"""Simulate -> write -> load -> metrics, through the library and the command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import mlflow
import numpy as np
import pytest
from cli_here import tcbench as here

from tcbench.metrics.report import analyse
from tcbench.sensors.recording import read_recording, write_recording
from tcbench.sensors.simulate import build_profile, simulate_recording

MALFORMED = Path(__file__).parent / "data" / "malformed"


def tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``python -m tcbench ARGS``: the smoke test of simulate and metrics."""
    return subprocess.run([sys.executable, "-m", "tcbench", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def test_same_seeds_same_recording() -> None:
    a = simulate_recording("gyro", "static", 1, 2, duration_s=600.0, sample_rate_hz=10.0)
    b = simulate_recording("gyro", "static", 1, 2, duration_s=600.0, sample_rate_hz=10.0)
    c = simulate_recording("gyro", "static", 1, 3, duration_s=600.0, sample_rate_hz=10.0)
    d = simulate_recording("gyro", "static", 2, 2, duration_s=600.0, sample_rate_hz=10.0)
    np.testing.assert_array_equal(a.output, b.output)
    assert not np.array_equal(a.output, c.output) and not np.array_equal(a.output, d.output)
    assert a.meta.device_id == "gyro-0001" and a.meta.extra["seed"] == 2
    assert a.meta.extra["device"]["effects"]["thermal_lag"]["tau_s"] > 0


def test_round_trip_keeps_metrics(tmp_path: Path) -> None:
    rec = simulate_recording("msra", "fulltemp", 3, 0)
    direct = analyse(rec).metrics
    for suffix in (".csv", ".parquet"):
        loaded = read_recording(write_recording(rec, tmp_path / f"r{suffix}"))
        assert analyse(loaded).metrics == pytest.approx(direct, rel=1e-12)
    assert direct["nodes"] == 6
    assert 1_000 < direct["sf_variation_ppm"] < 30_000
    assert 20_000 < direct["bias_variation_ug"] < 60_000


def test_roomtemp_metrics_order() -> None:
    rec = simulate_recording("msra", "roomtemp", 0, 0)
    m = analyse(rec).metrics
    assert m["after_30min_ug"] < m["after_20min_ug"] < m["zero_start_ug"]
    assert m["scale_factor_hz_per_g"] == pytest.approx(200.0, rel=0.1)


def test_protocol_parameters_checked() -> None:
    with pytest.raises(ValueError, match="no parameter nope; known: duration_s"):
        build_profile("gyro", "static", np.random.default_rng(0), nope=1)
    with pytest.raises(ValueError, match="unknown protocol 'oven' for msra; known: roomtemp, fulltemp"):
        build_profile("msra", "oven", np.random.default_rng(0))


def test_cli_simulate_then_metrics(workdir: Path) -> None:
    out = tcbench("simulate", "sensor=gyro", "protocol=oven", "device_seed=1", "out=rec",  # 15 min holds, not 1 h
                  "protocol_params.hold_s=900", "protocol_params.room_s=900", cwd=workdir)
    assert out.returncode == 0, out.stderr
    csv = workdir / "rec" / "gyro-oven-dev1-seed0.csv"
    assert csv.exists() and csv.with_suffix(".json").exists()
    report = workdir / "rec" / "gyro-oven-dev1-seed0_metrics"
    payload = json.loads((report / "metrics.json").read_text())
    assert 0.4 < payload["metrics"]["arw_deg_per_sqrt_h"] < 0.7
    assert "drift_60_to_m40_dps" in payload["metrics"]
    assert (report / "overview.png").stat().st_size > 10_000 and (report / "allan.png").exists()
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("simulations").experiment_id])
    assert run.info.status == "FINISHED" and run.data.params["protocol"] == "oven"
    assert run.data.metrics["arw_deg_per_sqrt_h"] == pytest.approx(payload["metrics"]["arw_deg_per_sqrt_h"])
    assert {"overview.png", "allan.png", "metrics.json"} <= {a.path for a in client.list_artifacts(run.info.run_id)}

    again = tcbench("metrics", str(csv), "out=again", "tracking.enabled=false", cwd=workdir)
    assert again.returncode == 0, again.stderr
    assert json.loads((workdir / "again" / "metrics.json").read_text())["metrics"] == payload["metrics"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sensor=imu"], "unknown sensor 'imu'; known: msra, gyro, accel"),
        (["sensor=msra", "protocol=oven"], "unknown protocol 'oven' for msra"),
        (["device_seed=-1"], "non-negative"),
        (["device_seed=abc"], "device_seed: Value 'abc'"),
        (["format=xls"], "format=xls: unknown format 'xls'; known: csv, parquet"),
        (["colour=red"], "colour"),
        (["sensor=gyro", "protocol=static", "protocol_params.nope=1"], "no parameter nope"),
        (["justaword"], "expected key=value"),
    ],
)
def test_cli_simulate_bad_input(workdir: Path, args: list[str], message: str) -> None:
    out = here("simulate", "out=rec", *args, cwd=workdir)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr
    assert not (workdir / "rec").exists()


@pytest.mark.parametrize("name", ["truncated_last_line.csv", "text_in_numeric.csv", "unknown_unit.csv", "empty.csv"])
def test_cli_metrics_on_malformed_files(workdir: Path, name: str) -> None:
    out = here("metrics", str(MALFORMED / name), "tracking.enabled=false", cwd=workdir)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and Path(name).stem in lines[0], out.stderr
    assert "Traceback" not in out.stderr


def test_effects_changed_added_and_removed() -> None:
    base = simulate_recording("msra", "fulltemp", 0, 0, without=("white_noise", "bias_instability"))
    loops = simulate_recording("msra", "fulltemp", 0, 0, effects={"hysteresis": {"amplitude": 0.05}},
                               without=("white_noise", "bias_instability"))
    assert "hysteresis" in loops.meta.extra["device"]["effects"]
    assert "white_noise" not in loops.meta.extra["device"]["effects"]
    diff = loops.output - base.output
    assert 0.03 < np.abs(diff).max() <= 0.05 + 1e-3  # hysteresis term bounded by its amplitude
    slow = simulate_recording("msra", "fulltemp", 0, 0, effects={"thermal_lag": {"tau_s": 1800.0}})
    assert slow.meta.extra["device"]["effects"]["thermal_lag"] == {"tau_s": 1800.0}
    with pytest.raises(ValueError, match="unknown effect 'nope'"):
        simulate_recording("msra", "roomtemp", 0, 0, effects={"nope": {}})


def test_cli_effect_arguments(workdir: Path) -> None:
    out = here("simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=600",
               "protocol_params.sample_rate_hz=10", "effects.warmup.amplitude=0.01",
               "without=[bias_instability]", "metrics=false", "out=rec", cwd=workdir)
    assert out.returncode == 0, out.stderr
    meta = json.loads((workdir / "rec" / "gyro-static-dev0-seed0.json").read_text())
    assert meta["extra"]["device"]["effects"]["warmup"]["amplitude"] == 0.01
    assert "bias_instability" not in meta["extra"]["device"]["effects"]
    bad = here("simulate", "effects.hysteresis.colour=1", "out=rec2", cwd=workdir)
    assert bad.returncode == 2 and "has no parameter colour" in bad.stderr


def _generated_bad_files(where: Path) -> dict[str, str]:
    """Malformed recordings the corpus folder does not hold, made here: name -> expected words."""
    gyro_side = ('{"schema_version": 1, "sensor": "gyro", "units": {"time_s": "s", "temperature_c": "degC", '
                 '"input": "deg/s", "output": "deg/s"}, "sample_rate_hz": 10.0, "device_id": "g"}')
    files = {
        "inf.csv": ("time_s,temperature_c,input,output\n0.0,25.0,0.0,inf\n0.1,25.0,0.0,1.0\n", "is not finite"),
        "semicolons.csv": ("time_s;temperature_c;input;output\n0.0;25.0;0.0;1.0\n", "missing column"),
        "one_row.csv": ("time_s,temperature_c,input,output\n0.0,25.0,0.0,1.0\n", ""),
        "kelvin.csv": ("time_s,temperature_c,input,output\n0.0,300.0,0.0,1.0\n0.1,300.0,0.0,1.0\n", "kelvin"),
    }
    for name, (text, _) in files.items():
        (where / name).write_text(text)
        (where / name).with_suffix(".json").write_text(gyro_side)
    (where / "garbage.csv").write_bytes(np.random.default_rng(0).bytes(300))
    (where / "folder.csv").mkdir()
    return {**{k: v for k, (_, v) in files.items()}, "garbage.csv": "not UTF-8", "folder.csv": "is a directory",
            "missing.csv": "no such file"}


def test_cli_metrics_refuses_every_malformed_kind(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The whole corpus plus the kinds made here: exit 2, one line naming the file, nothing
    written (in process: the command's own entry point, one call per file)."""
    from tcbench.cli import main

    bad = workdir / "bad"
    bad.mkdir()
    expected = _generated_bad_files(bad)
    cases = [(MALFORMED / p.name, "") for p in sorted(MALFORMED.iterdir())
             if p.suffix in (".csv", ".parquet") and p.name != "valid.csv"]
    cases += [(bad / name, words) for name, words in expected.items()]
    assert len(cases) >= 20
    for path, words in cases:
        code = main(["metrics", str(path), "out=report", "tracking.enabled=false"])
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert code == 2, (path.name, err)
        assert len(lines) == 1 and path.stem in lines[0] and words in lines[0], (path.name, err)
        assert not (workdir / "report").exists() and not list(workdir.glob(".report*"))
