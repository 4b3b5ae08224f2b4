"""What a record too short for a full diagnosis can tell: a 200 s, 100 000-sample inclinometer
record with a 5 degC ramp gets its temperature slope, its level step and its white noise tested,
through the API and through ``tcbench diagnose`` (report.json, report.md, the MLflow run)."""

from __future__ import annotations

import contextlib
import io
import json
import os

import mlflow
import numpy as np
import pytest
from scipy.signal import lfilter

from tcbench.cli import main
from tcbench.diagnose.select.crossval import block_folds
from tcbench.diagnose.select.plan import min_full_duration_s
from tcbench.diagnose.settings import DEFAULTS
from tcbench.diagnose.short.short_record import short_record
from tcbench.sensors.recording import Recording, make_recording, write_recording

FOLDS = DEFAULTS.plan.folds
DEFAULT_SMOOTH_S = DEFAULTS.smoothing.default_window_s
MIN_FIT_SAMPLES = DEFAULTS.short.min_fit_samples
RATE_HZ = 500.0
RAMP_START_S = 50.0
RAMP_END_S = 200.0
SLOPE_G_PER_C = 5e-5
STEP_G = 1e-4
NOISE_G = 5e-4


def _inclinometer(slope: float, step: float, seed: int, corr_s: float = 0.0, n: int = 100_000) -> Recording:
    """An accelerometer at 1 g (tilted, static): 50 s at 25 degC, then a 5 degC ramp to 200 s;
    ``slope`` g/degC, a ``step`` g at the ramp start, white noise (through a first-order filter of
    ``corr_s`` when given) and a thermometer with 0.02 degC noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE_HZ
    temp = 25.0 + 5.0 * np.clip((t - RAMP_START_S) / (RAMP_END_S - RAMP_START_S), 0.0, 1.0)
    noise = rng.normal(0.0, NOISE_G, n)
    if corr_s:
        a = np.exp(-1.0 / (corr_s * RATE_HZ))
        noise = lfilter([np.sqrt(1.0 - a * a)], [1.0, -a], noise)
    out = 1.0 + slope * (temp - 25.0) + step * (t >= RAMP_START_S) + noise
    return make_recording(t, temp + rng.normal(0.0, 0.02, n), np.ones(n), out, sensor="accel",
                          sample_rate_hz=RATE_HZ, device_id="incl-1")


def _tests(report: dict) -> dict[str, dict]:
    return {t["id"]: t for t in report["tests"]}


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """``tcbench diagnose`` on the stepped, sloped record: exit code, printed lines, report files, MLflow run."""
    where = tmp_path_factory.mktemp("short")
    uri = f"sqlite:///{where / 'mlflow.db'}"
    old = os.environ.get("MLFLOW_TRACKING_URI")
    os.environ["MLFLOW_TRACKING_URI"] = uri
    try:
        path = write_recording(_inclinometer(SLOPE_G_PER_C, STEP_G, seed=7), where / "incl.csv")
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            code = main(["diagnose", f"recording={path}", f"out={where / 'out'}"])
    finally:
        if old is None:
            os.environ.pop("MLFLOW_TRACKING_URI", None)
        else:
            os.environ["MLFLOW_TRACKING_URI"] = old
    client = mlflow.MlflowClient(uri)
    exp = client.get_experiment_by_name("diagnoses")
    runs = client.search_runs([exp.experiment_id]) if exp else []
    return {"code": code, "out": buf.getvalue(), "dir": where / "out",
            "json": json.loads((where / "out" / "report.json").read_text()),
            "md": (where / "out" / "report.md").read_text(), "runs": runs, "client": client}


def test_min_full_duration_is_five_folds_of_two_smoothing_windows() -> None:
    need = min_full_duration_s()
    assert need == FOLDS * 2 * DEFAULT_SMOOTH_S == 1200.0
    block_s = 2 * DEFAULT_SMOOTH_S  # plan_for's floor on a record this short
    for span_s, whole in ((need, True), (need - 100.0, False)):
        t = np.arange(0.0, span_s, 1.0)
        fold = block_folds(t, block_s, FOLDS)
        counts = np.bincount(fold, minlength=FOLDS)
        assert bool(counts.min() >= block_s) is whole  # every fold holds a whole block only from 1200 s on


def test_cli_on_a_short_record_exits_0_with_the_short_report(cli_run: dict) -> None:
    assert cli_run["code"] == 0
    out = cli_run["out"]
    assert "short record (200 s of the 1200 s a full diagnosis needs)" in out
    assert "ran: temperature_slope (significant), level_step (significant), white_noise (white)" in out
    assert "needs more time: effect_attribution (1200 s), second_node (2400 s)" in out
    assert sorted(p.name for p in cli_run["dir"].iterdir()) == ["report.json", "report.md"]
    report = cli_run["json"]
    assert report["report"] == "short_record" and report["samples"] == 100_000 and report["unit"] == "g"
    assert [r["id"] for r in report["needs_more_time"]] == ["effect_attribution", "second_node"]
    assert report["settings"]["short"]["alpha"] == report["level"]  # every setting it ran with, as a full report
    assert report["settings"]["plan"]["folds"] == FOLDS
    md = cli_run["md"]
    assert "## Tests run" in md and "| level_step | significant |" in md
    assert "## Not run on this record" in md and "- **effect_attribution**: needs 1200 s (20 min)" in md


def test_short_report_finds_the_slope(cli_run: dict) -> None:
    slope = _tests(cli_run["json"])["temperature_slope"]
    assert slope["status"] == "significant" and slope["p_value"] < 0.01
    assert slope["ci_low"] < SLOPE_G_PER_C < slope["ci_high"]
    assert slope["ci_high"] - slope["ci_low"] < 0.3 * SLOPE_G_PER_C
    assert "drift in time" in slope["confusable_with"]  # the temperature only rises


def test_short_report_finds_the_step_at_the_ramp_start(cli_run: dict) -> None:
    step = _tests(cli_run["json"])["level_step"]
    assert step["status"] == "significant" and step["p_value"] <= 0.01
    assert step["ci_low"] < STEP_G < step["ci_high"] and step["ci_low"] < step["size"] < step["ci_high"]
    assert abs(step["time_s"] - RAMP_START_S) < 0.5 and step["at_ramp_start"]


def test_short_report_measures_the_white_noise(cli_run: dict) -> None:
    noise = _tests(cli_run["json"])["white_noise"]
    assert noise["status"] == "white" and abs(noise["white_sigma"] / NOISE_G - 1.0) < 0.02
    assert noise["density_per_sqrt_hz"] == pytest.approx(noise["white_sigma"] / np.sqrt(RATE_HZ))
    assert noise["tau_s"][0] == pytest.approx(10 / RATE_HZ) and noise["tau_max_s"] <= 20.0


def test_mlflow_run_records_the_short_report(cli_run: dict) -> None:
    (run,) = cli_run["runs"]
    tags, metrics = run.data.tags, run.data.metrics
    assert tags["tcbench.report"] == "short_record" and tags["tcbench.short.level_step"] == "significant"
    assert tags["tcbench.short.temperature_slope"] == "significant" and tags["tcbench.verdict"].startswith("short record")
    assert metrics["level_step.significant"] == 1.0 and metrics["level_step.time_s"] == pytest.approx(50.0, abs=0.5)
    names = {a.path for a in cli_run["client"].list_artifacts(run.info.run_id)}
    assert {"report.json", "report.md"} <= names


def test_record_without_slope_or_step_is_not_significant() -> None:
    tests = {t.id: t for t in short_record(_inclinometer(0.0, 0.0, seed=3)).tests}
    assert tests["temperature_slope"].status == "not significant"
    assert tests["level_step"].status == "not significant"
    assert tests["temperature_slope"].values["ci_low"] < 0.0 < tests["temperature_slope"].values["ci_high"]


def test_correlated_noise_does_not_make_a_slope() -> None:
    """Noise correlated over 0.5 s: the white-noise formula would call a slope of zero significant."""
    tests = {t.id: t for t in short_record(_inclinometer(0.0, 0.0, seed=11, corr_s=0.5)).tests}
    slope = tests["temperature_slope"].values
    assert abs(slope["slope_per_c"]) / slope["se_white_noise_formula"] > 2.58  # white-noise formula: p < 0.01
    assert tests["temperature_slope"].status == "not significant" and slope["se"] > 5 * slope["se_white_noise_formula"]
    assert slope["effective_samples"] < 5000
    assert tests["level_step"].status == "not significant"
    assert tests["white_noise"].status == "excess over white noise"


def test_too_few_samples_or_one_temperature_say_so_per_test() -> None:
    tiny = {t.id: t for t in short_record(_inclinometer(SLOPE_G_PER_C, 0.0, seed=1, n=20)).tests}
    assert all(t.status == "not run" for t in tiny.values())
    assert f"needs at least {MIN_FIT_SAMPLES} samples; this record has 20" in tiny["temperature_slope"].reason
    assert "this record has 20" in tiny["level_step"].reason and "this record has 20" in tiny["white_noise"].reason
    rec = _inclinometer(0.0, STEP_G, seed=2, n=5000)  # 10 s: before the ramp, constant temperature
    flat = {t.id: t for t in short_record(rec).tests}
    assert flat["temperature_slope"].status == "not run" and "needs the temperature to change" in flat["temperature_slope"].reason
    assert flat["level_step"].ran and flat["white_noise"].ran
