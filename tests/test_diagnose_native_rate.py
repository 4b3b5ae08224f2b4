"""A record of more rows than a diagnosis takes: thermal terms on bin means, noise on every sample
(:mod:`tcbench.diagnose.rate.native_rate`), through the API, ``tcbench diagnose`` and ``calibrate``."""

from __future__ import annotations

import contextlib
import io
import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from tcbench.cli import main
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.rate import native_rate
from tcbench.diagnose.rate.native_rate import bin_means, full_rate_noise, plan_bins, plan_for
from tcbench.diagnose.settings import DEFAULTS, RateSettings
from tcbench.sensors.recording import Recording, make_recording, write_recording
from averaging import by_hand

OFF = "tracking.enabled=false"
RATE_HZ, MINUTES, SIGMA = 200.0, 21.0, 0.3  # 252 000 rows, a little over the 20 min a full diagnosis needs
BUDGET = 3000  # settings.rate.max_rows: the record is averaged into 1 s bins of 200 samples, 1260 rows
RATE_COEF = 2.0  # deg/s per degC/s: the temperature_rate hidden in the record


def _record(seed: int = 0, spikes: int = 0) -> Recording:
    """A gyro at 200 Hz through a 15 min temperature cycle, its output 0.05 deg/s per degC plus a
    temperature_rate term and white noise of :data:`SIGMA` per sample (``spikes`` of 60 sigma)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, MINUTES * 60.0, 1.0 / RATE_HZ)
    temp = 30.0 + 12.0 * np.sin(2.0 * np.pi * t / 900.0)
    rate = 12.0 * 2.0 * np.pi / 900.0 * np.cos(2.0 * np.pi * t / 900.0)
    out = 0.05 * temp + RATE_COEF * rate + SIGMA * rng.standard_normal(t.size)
    out[rng.choice(t.size, spikes, replace=False)] += 60.0 * SIGMA
    return make_recording(t, temp + 0.02 * rng.standard_normal(t.size), np.zeros(t.size), out, sensor="gyro",
                          sample_rate_hz=RATE_HZ, device_id="d")


def _intervals_meet(a: dict[str, Any], b: dict[str, Any], z: float = 3.0) -> tuple[bool, Any]:
    """Whether two findings' amplitudes lie inside each other's intervals (``z`` standard errors,
    the error from the cluster-robust Wald statistic: se = |coef| / sqrt(Wald))."""
    (key, x), (_, y) = next(iter(a["params"].items())), next(iter(b["params"].items()))
    se = [abs(v) / np.sqrt(f["evidence"]["robust_wald"]) for v, f in ((x, a), (y, b))]
    return all(abs(x - y) <= z * s for s in se), (key, x, y, se)


def test_the_bin_is_max_bin_s_once_a_record_is_over_the_budget() -> None:
    assert plan_bins(100_000, 1000.0).bin_samples == 1 and not plan_bins(100_000, 1000.0).averaged
    day = plan_bins(8_640_000, 100.0)  # 24 h at 100 Hz: means of 100 samples, 86 400 rows
    assert (day.bin_samples, day.diagnosed_rows, day.capped) == (100, 86_400, False)
    log = plan_bins(2_700_000, 1000.0)  # 45 min at 1 kHz: 2 700 rows of 1 s
    assert (log.bin_samples, log.diagnosed_rows, log.bin_s) == (1000, 2700, 1.0)
    long = plan_bins(8_640_000, 100.0, RateSettings(max_rows=50_000, max_bin_s=1.0))
    assert long.capped and "86400 bins are more than the budget" in long.why()


def test_a_record_within_the_budget_goes_to_the_diagnosis_as_it_is(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[Recording] = []

    class Given(Exception):
        """Stops the front stage once it hands the diagnosis its record."""

    def given(rec: Recording, **_: Any) -> None:
        seen.append(rec)
        raise Given

    monkeypatch.setattr(native_rate, "diagnose", given)
    rec = _record()
    with pytest.raises(Given):
        native_rate.diagnose_any_rate(rec, settings=replace(DEFAULTS, rate=RateSettings(max_rows=rec.time_s.size)))
    assert seen[-1] is rec  # the same object, not a copy or a resampling
    with pytest.raises(Given):
        native_rate.diagnose_any_rate(rec, settings=replace(DEFAULTS, rate=RateSettings(max_rows=BUDGET)))
    assert seen[-1].time_s.size == rec.time_s.size // 200 == 1260
    assert seen[-1].meta.sample_rate_hz == 1.0  # the stated 200 Hz in 200-sample bins, exactly


def test_noise_terms_come_from_every_sample_and_outliers_enter_no_bin() -> None:
    rec = _record(seed=1, spikes=5)
    full = full_rate_noise(rec)
    assert full.white_sigma == pytest.approx(SIGMA, rel=0.03)  # per sample at 200 Hz, not the bins' 0.3 / sqrt(200)
    assert full.outliers.count == 5 and full.zero_weight.size == 5
    binned, dropped = bin_means(rec, plan_bins(rec.time_s.size, RATE_HZ, RateSettings(max_rows=BUDGET)),
                                full.zero_weight)
    clean = _record(seed=1)
    hand = by_hand(clean, 200)
    n = hand.time_s.size
    # a bin holding a spike is the mean of its other 199 samples: within a few bin sigmas of the clean mean
    assert dropped == 0 and np.max(np.abs(binned.output[:n] - hand.output)) < 5.0 * SIGMA / np.sqrt(199.0)


def test_a_clipped_output_is_found_on_every_sample_and_its_clipped_samples_enter_no_bin() -> None:
    rec = _record(seed=2)
    level = float(np.quantile(rec.output, 0.9))
    rec.data["output"] = np.minimum(rec.output, level)
    full = full_rate_noise(rec)
    assert full.saturation.found and full.saturation.upper.level == pytest.approx(level)
    at = int(np.count_nonzero(rec.output >= level))  # the clip, and samples within its tolerance below it
    assert at <= full.saturation.clipped <= 1.01 * at
    assert np.isin(np.flatnonzero(rec.output >= level), full.zero_weight).all()


@pytest.fixture(scope="module")
def averaged() -> tuple[dict[str, Any], str, dict[str, Any]]:
    """The diagnosis of the 200 Hz record with ``settings.rate.max_rows`` lowered: report.json,
    report.md (without plots) and model.yaml's mapping."""
    from tcbench.diagnose.report.markdown import render_markdown
    from tcbench.diagnose.report.write import _plain

    diag = native_rate.diagnose_any_rate(_record(), settings=replace(DEFAULTS, rate=RateSettings(max_rows=BUDGET)))
    return _plain(diag.to_json()), render_markdown(diag, {}), _plain(diag.model)


def test_the_averaged_diagnosis_names_what_the_hand_averaged_record_shows(
        averaged: tuple[dict[str, Any], str, dict[str, Any]]) -> None:
    report = averaged[0]
    hand = diagnose(by_hand(_record(), 200)).to_json()
    assert [e["id"] for e in report["effects"]] == [e["id"] for e in hand["effects"]]
    assert "temperature_rate" in [e["id"] for e in hand["effects"]]
    for mine, theirs in zip(report["effects"], hand["effects"], strict=True):
        if "robust_wald" in mine["evidence"]:
            ok, said = _intervals_meet(mine, theirs)
            assert ok, said
    rate = next(e for e in report["effects"] if e["id"] == "temperature_rate")["params"]["coef_per_c_per_s"]
    assert rate == pytest.approx(RATE_COEF, rel=0.05)


def test_the_report_says_what_was_averaged_to_what_rate_and_why(
        averaged: tuple[dict[str, Any], str, dict[str, Any]]) -> None:
    report, markdown, model = averaged
    said = report["native_rate"]
    assert (said["rows"], said["bin_samples"], said["bins_diagnosed"]) == (252_000, 200, 1260)
    assert said["bin_rate_hz"] == pytest.approx(RATE_HZ / 200)
    assert "means of 200 samples" in said["why"] and "200 Hz" in said["why"]
    assert "## Native rate" in markdown and "means of 200 samples" in markdown
    assert "rate" not in report["statistics"]["settings"]  # the front stage's knobs are said in native_rate


def test_the_white_noise_is_the_full_rate_streams(averaged: tuple[dict[str, Any], str, dict[str, Any]]) -> None:
    report, _, model = averaged
    # per sample at 200 Hz, where the bins' is 1/sqrt(200) of it
    assert report["noise"]["white_sigma"] == pytest.approx(SIGMA, rel=0.03)
    assert report["noise"]["samples"] == 252_000 and report["noise"]["bins"] == 1260
    assert report["native_rate"]["white_sigma_bins"] == pytest.approx(SIGMA / np.sqrt(200.0), rel=0.1)
    assert model["effects"]["white_noise"]["density"] == pytest.approx(SIGMA / np.sqrt(RATE_HZ), rel=0.03)


@pytest.mark.slow
def test_diagnose_says_it_averages_and_writes_the_report(tmp_path: Path) -> None:
    write_recording(_record(), tmp_path / "rec.parquet")
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()) as out:
        code = main(["diagnose", f"recording={tmp_path / 'rec.parquet'}", f"out={tmp_path / 'd'}",
                     f"settings.rate.max_rows={BUDGET}", OFF])
    assert code == 0, err.getvalue()
    assert "means of 200 samples" in err.getvalue()
    said = re.search(r"white noise ([0-9.]+) deg/s per sample", out.getvalue())
    assert said and float(said.group(1)) == pytest.approx(SIGMA, rel=0.03), out.getvalue()
    report = json.loads((tmp_path / "d" / "report.json").read_text())
    assert report["native_rate"]["bin_samples"] == 200
    assert "## Native rate" in (tmp_path / "d" / "report.md").read_text()
    model = yaml.safe_load((tmp_path / "d" / "model.yaml").read_text())
    assert model["effects"]["white_noise"]["density"] == pytest.approx(SIGMA / np.sqrt(RATE_HZ), rel=0.03)


def test_bins_longer_than_max_rows_are_refused_once_known(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    write_recording(_record(), tmp_path / "rec.parquet")
    code = main(["diagnose", f"recording={tmp_path / 'rec.parquet'}", f"out={tmp_path / 'd'}", "max_rows=1000",
                 f"settings.rate.max_rows={BUDGET}", OFF])
    err = capsys.readouterr().err
    assert code == 2 and "252000 rows (bin means of 1 s)" in err and "max_rows=1260" in err, err
    assert not (tmp_path / "d").exists()


def test_plan_for_takes_the_stated_rate_else_the_clocks_inside_segments() -> None:
    rec = _record()
    rec.data["time_s"] = rec.time_s * (1.0 + 1e-9)  # a clock a hair slow: the sidecar's 200 Hz stands
    assert plan_for(rec, RateSettings(max_rows=BUDGET)).sample_rate_hz == RATE_HZ
    rec.meta = replace(rec.meta, sample_rate_hz=None)
    assert plan_for(rec, RateSettings(max_rows=BUDGET)).sample_rate_hz == pytest.approx(RATE_HZ)


def test_the_tracked_metrics_carry_the_full_rate_sigma_beside_the_bins() -> None:
    from types import SimpleNamespace

    from tcbench.runner.kinds.diagnosis import diagnosis_metrics

    fit = SimpleNamespace(rmse_heldout=0.03)
    diag = SimpleNamespace(noise=SimpleNamespace(white_sigma=0.021), baseline=fit, final=fit, effect_ids=[],
                           native_rate=SimpleNamespace(full=SimpleNamespace(white_sigma=0.3),
                                                       plan=SimpleNamespace(bin_samples=200)))
    said = diagnosis_metrics(diag)
    assert said["white_sigma_full_rate"] == 0.3 and said["bin_samples"] == 200.0 and said["white_sigma"] == 0.021
