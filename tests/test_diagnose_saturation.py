"""tcbench diagnose: an output clipped at a ceiling or a floor.

Worked by hand: ``y = 3 sin(2 pi t / 2000) + N(0, 1)`` over 20000 samples, clipped at +2.5 and
-2.8. Each side of the sine spends the fraction of time where ``y`` crosses the clip: the count
of clipped samples is exactly ``sum(y_raw >= 2.5)`` and ``sum(y_raw <= -2.8)`` (3496 and about
2700), where an unclipped noisy output holds one sample at its maximum.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.model_file import ModelFileError, parse_model, to_sensor_model
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.screens.saturation import find_saturation
from tcbench.diagnose.signals import DiagnosisData
from tcbench.sensors.protocols import Profile
from tcbench.sensors.recording import Recording


def _data(y: np.ndarray, sigma: float, temp_c: np.ndarray | None = None) -> DiagnosisData:
    """Arrays as the diagnosis prepares them (1 Hz, one run, temperature a ramp unless given)."""
    t = np.arange(y.size, dtype=float)
    temp = np.linspace(0.0, 40.0, y.size) if temp_c is None else temp_c
    return DiagnosisData("gyro", "deg/s", t, temp, temp, np.zeros(y.size), np.zeros(y.size), y,
                         np.zeros(y.size, dtype=np.int64), sigma, 1.0, 120.0)


def test_clipped_sine_worked_by_hand() -> None:
    rng = np.random.default_rng(11)
    t = np.arange(20_000.0)
    raw = 3.0 * np.sin(2 * np.pi * t / 2000.0) + rng.standard_normal(t.size)
    y = np.clip(raw, -2.8, 2.5)
    sat = find_saturation(_data(y, 1.0))
    assert sat.upper is not None and sat.lower is not None
    assert sat.upper.level == 2.5 and sat.lower.level == -2.8
    # at the clip level, to its tolerance of 1e-3 sigma (which takes in an unclipped sample or two)
    assert sat.upper.count == int(np.sum(raw >= 2.5 - 1e-3)) and sat.lower.count == int(np.sum(raw <= -2.8 + 1e-3))
    assert sat.upper.count - int(np.sum(raw >= 2.5)) <= 10  # about 2900 samples per sigma there: 3 expected
    assert sat.clipped == sat.upper.count + sat.lower.count
    clipped = np.flatnonzero((raw >= 2.5 - 1e-3) | (raw <= -2.8 + 1e-3))
    assert np.isin(clipped, sat.index).all()  # every clipped sample gets zero weight
    assert sat.index.size < 0.5 * y.size  # and the record keeps most of its samples
    finding = sat.finding("deg/s")
    assert finding.shape == "saturation" and finding.library is False
    assert finding.where["level"] == [2.5, -2.8]
    assert finding.params["upper"] == 2.5 and finding.params["lower"] == -2.8
    assert "range" in finding.explanation and "datasheet" in finding.confirm_with


def test_one_sided_clip_gives_its_temperature_band() -> None:
    # the output rises with temperature and is clipped only above the level it reaches at 30 degC
    rng = np.random.default_rng(12)
    temp = np.linspace(0.0, 40.0, 10_000)
    raw = 0.5 * temp + rng.standard_normal(temp.size)
    y = np.minimum(raw, 15.0)
    sat = find_saturation(_data(y, 1.0, temp))
    assert sat.lower is None and sat.upper is not None and sat.upper.level == 15.0
    assert sat.model_params() == {"upper": 15.0}
    low, high = sat.temperature_c  # type: ignore[misc]
    assert 24.0 < low < 30.0 and high == 40.0  # the noise reaches the clip a few degrees before 30 degC


@pytest.mark.parametrize("step", [0.0, 0.5, 2.0])
def test_no_clip_no_finding(step: float) -> None:
    # 100 unclipped noisy sines (continuous, or on a lattice of 0.5 or 2 sigma): at the 1 %
    # level at most a few alarms; measured 0 of 100 for each.
    rng = np.random.default_rng(13)
    t = np.arange(10_000.0)
    alarms = 0
    for _ in range(100):
        y = 3.0 * np.sin(2 * np.pi * t / rng.uniform(500, 5000)) + rng.standard_normal(t.size)
        if step:
            y = np.round(y / step) * step
        alarms += find_saturation(_data(y, 1.0), step).found
    assert alarms <= 2


def test_noise_free_sine_on_a_lattice_is_not_clipping() -> None:
    # a slow sine read on a coarse grid with little noise spends longer on its top level than on
    # the next (its density rises towards the peak), but not the 3 times a clip would
    t = np.arange(20_000.0)
    rng = np.random.default_rng(14)
    for phase in np.linspace(0.0, 1.0, 7):
        y = np.round(5.3 * np.sin(2 * np.pi * t / 4000.0 + phase) + 0.05 * rng.standard_normal(t.size))
        assert not find_saturation(_data(y, 0.05), 1.0).found


def test_model_file_clips_the_simulated_output() -> None:
    spec = parse_model({"tcbench_model": 1, "sensor": "gyro",
                        "core": {"centre_c": 20.0, "half_range_c": 20.0, "bias": [0.0, 1.0], "scale_factor": [1.0]},
                        "effects": {"white_noise": {"density": 0.1}, "saturation": {"upper": 0.5, "lower": -0.7}}},
                       "m.yaml")
    model = to_sensor_model(spec)
    n = 4000
    temp = np.linspace(0.0, 40.0, n)
    t = np.arange(n, dtype=float)
    prof = Profile("test", "gyro", 1.0, t, temp, np.zeros(n), np.zeros(n), np.zeros(n))
    y = model.simulate(prof, np.random.default_rng(1))
    assert y.max() == 0.5 and y.min() == -0.7
    # the bias runs linearly from -1 to +1 deg/s (noise 0.1): a quarter of the samples lie above
    # 0.5 and 15 % below -0.7
    assert np.sum(y == 0.5) == pytest.approx(1000, rel=0.1) and np.sum(y == -0.7) == pytest.approx(600, rel=0.1)
    assert find_saturation(_data(y, 0.1, temp)).model_params() == {"upper": 0.5, "lower": -0.7}


@pytest.mark.parametrize(("effects", "words"), [
    ({"saturation": {"upper": 1.0, "lower": 2.0}}, "m.yaml: effects.saturation: upper must be above lower"),
    ({"saturation": {}}, "m.yaml: effects.saturation: give upper, lower or both"),
])
def test_model_file_errors(effects: dict, words: str) -> None:
    data = {"tcbench_model": 1, "sensor": "gyro", "effects": effects,
            "core": {"centre_c": 20.0, "half_range_c": 20.0, "bias": [0.0], "scale_factor": [1.0]}}
    with pytest.raises(ModelFileError, match=words) as err:
        parse_model(data, "m.yaml")
    assert "\n" not in str(err.value)


def test_diagnosis_names_a_clipped_recording(tmp_path: Path) -> None:
    # the concealed gyro control clipped at its 93 % quantile: about 2700 samples at the ceiling,
    # at every temperature (the gyro's bias moves less than the noise)
    rec, truth = concealed_recording("gyro", None, 5)
    data = rec.data.copy()
    level = float(np.quantile(rec.output, 0.93))
    data["output"] = np.minimum(rec.output, level)
    d = diagnose(Recording(data, rec.meta))
    found = {e["id"]: e for e in d.to_json()["effects"]}
    assert set(found) == {"saturation"}  # and nothing else (the truncated samples do not look quieter)
    sat = found["saturation"]
    assert sat["where"]["level"] == level
    assert 0 <= sat["params"]["clipped"] - int(np.sum(rec.output >= level)) <= 10  # and a few within 1e-3 sigma
    low, high = sat["where"]["temperature_c"]
    assert low <= float(np.min(d.series.temp_c)) + 1.0 and high >= float(np.max(d.series.temp_c)) - 1.0
    # the fit without the clipped samples is as good as the clean record's
    assert d.final.rmse_heldout < 1.05 * truth.white_sigma
    files = write_report(d, tmp_path / "report", with_plots=False)
    assert "saturation: {upper: " in files["model.yaml"].read_text()
