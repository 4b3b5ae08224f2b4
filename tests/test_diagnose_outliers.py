"""tcbench diagnose: isolated outliers get zero weight and a finding of their own.

Worked by hand on the concealed gyro control (seed 5: 38398 samples at 1 Hz, white sigma ``s``
about the minimal model; held-out RMSE 1.002 s). One extra spike of ``k s`` at the last sample
adds ``k^2 s^2`` to the held-out sum of squares, so without robust fitting the held-out RMSE is
at least ``sqrt(1 + k^2 / n) s``: measured 1.033 s for k = 50 (one sample carries 6 % of the
squared error), 1.83 s for k = 300 and 10.3 s for k = 2000, and for k = 300 and 2000 the
Allan deviation, which sees the spike in its last cluster, names ``bias_instability``. With the
spike given zero weight the held-out RMSE is the clean record's 1.002 s whatever ``k``, and the
finding names the time and size of the spike.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_profile, concealed_recording
from tcbench.diagnose import diagnosis as dg
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.model_file import read_model, to_sensor_model
from tcbench.diagnose.report.markdown import render_markdown
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.screens import spikes as outlier_screen
from tcbench.diagnose.screens.outliers import Outliers, find_outliers, z_bound
from tcbench.sensors.recording import Recording

def _with_spikes(rec: Recording, index: list[int], sizes: list[float]) -> Recording:
    data = rec.data.copy()
    out = data["output"].to_numpy(dtype=float).copy()
    out[index] += sizes
    data["output"] = out
    return Recording(data, rec.meta)


@pytest.fixture(scope="module")
def clean() -> tuple[Recording, float]:
    rec, truth = concealed_recording("gyro", None, 5)
    return rec, truth.white_sigma


@pytest.fixture(scope="module")
def clean_diagnosis(clean: tuple[Recording, float]) -> dg.Diagnosis:
    """The clean record's diagnosis, one for the tests that compare a spiked record with it."""
    return diagnose(clean[0])


def test_bound_is_bonferroni_over_the_record() -> None:
    # 1.1 * Phi^-1(1 - 0.01 / (2 * 86400)) = 1.1 * 5.30; the bound grows with the record's length.
    assert z_bound(86_400) == pytest.approx(5.83, abs=0.01)
    assert z_bound(100) == pytest.approx(4.5)  # floor for short records
    assert z_bound(10**7) > z_bound(86_400)


def test_clean_day_of_gaussian_noise_has_no_outlier() -> None:
    # 24 h at 1 Hz of white noise, 100 independent records: at the 1 % level at most one may
    # show a false outlier (binomial(100, 0.01): P(>= 2) = 26 %, so this is a loose check
    # of the level; 0 of 300 measured with another seed).
    rng = np.random.default_rng(20261125)
    t = np.arange(86_400.0)
    alarms = sum(find_outliers(t, rng.normal(0.0, 1.0, t.size), 1.0).count > 0 for _ in range(100))
    assert alarms <= 1


@pytest.mark.parametrize("k", [50.0, 300.0])
def test_spike_at_the_last_sample(clean: tuple[Recording, float], clean_diagnosis: dg.Diagnosis, k: float) -> None:
    rec, sigma = clean
    n = rec.time_s.size
    spiked = _with_spikes(rec, [n - 1], [k * sigma])
    d_clean, d_spiked = clean_diagnosis, diagnose(spiked)
    # the clean record: nothing found, nothing excluded
    assert d_clean.effect_ids == []
    assert d_clean.outliers is not None and d_clean.outliers.count == 0
    # the spike is found at the last time with its size, and only it
    finding = next(e for e in d_spiked.to_json()["effects"] if e["id"] == "outliers")
    assert finding["shape"] == "outliers" and finding["library"] is False
    assert finding["params"]["count"] == 1
    assert finding["where"]["time_s"] == [pytest.approx(float(rec.time_s[-1]))]
    assert finding["params"]["size"][0] == pytest.approx(k * sigma, rel=0.08)
    assert finding["evidence"]["robust_z"][0] > 0.9 * k > finding["evidence"]["bound_z"]
    assert "glitch" in finding["explanation"] and finding["confirm_with"]
    # it no longer dominates: held-out RMSE as the clean record's, near 1 sigma; no effect named for it
    assert d_spiked.final.rmse_heldout == pytest.approx(d_clean.final.rmse_heldout, rel=1e-3)
    assert d_spiked.final.rmse_heldout < 1.1 * sigma
    assert d_spiked.baseline.rmse_heldout < 1.1 * sigma
    assert [e for e in d_spiked.effect_ids if e != "outliers"] == []
    assert "bias_instability" not in d_spiked.effect_ids
    assert d_spiked.noise.samples == n - 1
    assert "zero weight" in d_spiked.verdict
    md = render_markdown(d_spiked, {})
    assert "### outliers" in md and f"{rec.time_s[-1]:.8g}" in md


def test_without_exclusion_the_spike_dominates(clean: tuple[Recording, float], monkeypatch: pytest.MonkeyPatch) -> None:
    # the same 300-sigma spike, detector switched off: the behaviour this module removes
    rec, sigma = clean
    monkeypatch.setattr(outlier_screen, "find_outliers", lambda t, r, w, **_: Outliers(*(np.zeros(0),) * 4, w, 5.0))
    d = dg.diagnose(_with_spikes(rec, [rec.time_s.size - 1], [300.0 * sigma]))
    assert d.final.rmse_heldout > 1.7 * sigma
    assert "bias_instability" in d.effect_ids


def test_spike_in_the_middle_of_a_soak(clean: tuple[Recording, float]) -> None:
    rec, sigma = clean
    rate = np.abs(np.gradient(rec.temperature_c, rec.time_s))
    soak = np.flatnonzero(rate < 1e-4)  # thermometer flat: inside a soak
    i = int(soak[soak.size // 2])
    spiked = _with_spikes(rec, [i, i + 1], [-30.0 * sigma, -25.0 * sigma])  # a run of two samples
    d = diagnose(spiked)
    finding = next(e for e in d.to_json()["effects"] if e["id"] == "outliers")
    assert finding["params"]["count"] == 2
    assert finding["where"]["time_s"] == [pytest.approx(float(rec.time_s[i])), pytest.approx(float(rec.time_s[i + 1]))]
    assert finding["params"]["size"] == [pytest.approx(-30.0 * sigma, rel=0.1), pytest.approx(-25.0 * sigma, rel=0.1)]
    assert [e for e in d.effect_ids if e != "outliers"] == []
    assert d.final.rmse_heldout < 1.1 * sigma


def test_a_long_run_is_not_a_spike() -> None:
    # a step held for 60 samples is structure for the other detectors, not an outlier
    rng = np.random.default_rng(7)
    t = np.arange(5000.0)
    r = rng.normal(0.0, 1.0, t.size)
    r[2000:2060] += 40.0
    r[4000] += 40.0
    found = find_outliers(t, r, 1.0)
    assert found.index.tolist() == [4000]
    assert found.size[0] == pytest.approx(40.0, abs=4.0)


def test_model_file_reproduces_the_spikes(clean: tuple[Recording, float], clean_diagnosis: dg.Diagnosis,
                                         tmp_path: Path) -> None:
    # model.yaml records the spikes; the simulated model adds each at its sample and nowhere else
    rec, sigma = clean
    i = rec.time_s.size // 3
    spiked = _with_spikes(rec, [i, rec.time_s.size - 1], [80.0 * sigma, -300.0 * sigma])
    d = diagnose(spiked)
    files = write_report(d, tmp_path / "report", with_plots=False)
    spec = read_model(files["model.yaml"])
    assert [t for t, _ in spec.outliers] == [pytest.approx(rec.time_s[i]), pytest.approx(rec.time_s[-1])]
    assert [v for _, v in spec.outliers] == [pytest.approx(80.0 * sigma, rel=0.1), pytest.approx(-300.0 * sigma, rel=0.03)]
    model = to_sensor_model(spec)
    profile = concealed_profile("gyro", np.random.default_rng(np.random.SeedSequence(5).spawn(7)[0]))
    assert np.allclose(profile.t_s, rec.time_s)  # the record's own clock
    with_spikes = model.simulate(profile, np.random.default_rng(1))
    without_spikes = dataclasses.replace(model, spike_time_s=(), spike_size=()).simulate(profile, np.random.default_rng(1))
    diff = with_spikes - without_spikes
    assert np.flatnonzero(diff).tolist() == [i, rec.time_s.size - 1]
    assert diff[[i, -1]].tolist() == [v for _, v in spec.outliers]
    # and a model without outliers writes no outliers key (older files stay as they were)
    clean_files = write_report(clean_diagnosis, tmp_path / "clean", with_plots=False)
    assert "outliers" not in clean_files["model.yaml"].read_text()
    assert read_model(clean_files["model.yaml"]).outliers == ()
