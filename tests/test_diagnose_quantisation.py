"""tcbench diagnose: the output and the thermometer read on a grid.

Worked by hand: values ``0.3 + 0.25 k`` (a converter of 0.25 LSB with an offset) are found with
step 0.25 whether noise of 1 LSB dithers them or a noise-free ramp walks up the staircase;
a whole-degree thermometer on a 0.1 degC/min ramp steps every 600 s, so the smoothing window
becomes 3 x 600 = 1800 s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.model_file import ModelFileError, parse_model
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.screens import BEFORE_FIT, MODEL_ORDER, ScreenInput, run_screens
from tcbench.diagnose.screens.quantisation import (
    find_output_quantisation,
    lattice_step,
    thermometer_steps,
)
from tcbench.diagnose.settings import DEFAULTS
from tcbench.sensors.recording import Recording, read_recording
from tcbench.sensors.simulate import simulate_recording


def test_lattice_worked_by_hand() -> None:
    rng = np.random.default_rng(21)
    dithered = 0.3 + 0.25 * np.round(rng.normal(0.0, 4.0, 5000))
    staircase = 0.3 + 0.25 * np.round(np.linspace(0.0, 40.0, 5000))  # noise-free: one step at a time
    for y in (dithered, staircase):
        found = lattice_step(y)
        assert found is not None
        assert found[0] == pytest.approx(0.25, rel=1e-12) and found[1] > 0.999999


def test_values_off_a_lattice_are_not_one() -> None:
    rng = np.random.default_rng(22)
    for _ in range(100):
        assert lattice_step(rng.standard_normal(5000)) is None  # continuous
    # quantised, then noise added after the converter: no longer on the grid
    assert lattice_step(np.round(rng.normal(0.0, 4.0, 5000)) + 0.1 * rng.standard_normal(5000)) is None
    assert lattice_step(np.round(rng.normal(0.0, 4.0, 15))) is None  # too few jumps to judge


def test_a_lattice_far_below_the_noise_is_not_reported() -> None:
    rng = np.random.default_rng(23)
    y = np.round(rng.standard_normal(5000), 3)  # a CSV's third decimal: 0.001 sigma
    assert lattice_step(y) is not None and find_output_quantisation(y, 1.0) is None
    found = find_output_quantisation(np.round(rng.standard_normal(5000) / 0.5) * 0.5, 1.0)
    assert found is not None and found.step == pytest.approx(0.5)
    finding = found.finding("Hz")
    assert finding.shape == "quantisation" and finding.where == {"level": pytest.approx(0.5)}
    assert finding.params == {"step": pytest.approx(0.5)} and "converter" in finding.explanation


def test_thermometer_staircase_worked_by_hand() -> None:
    rng = np.random.default_rng(24)
    t = np.arange(0.0, 6 * 3600.0)
    rate = 0.1 / 60.0  # degC/s: a whole degree every 600 s
    true = 10.3 + np.minimum(t, 3 * 3600.0) * rate  # a 3 h ramp of 18 degC, then a soak
    reading = np.round(true + 0.02 * rng.standard_normal(t.size))
    steps = thermometer_steps(t, reading, 120.0)
    assert steps is not None and steps.staircase
    assert steps.step_c == 1.0 and steps.rate_c_per_s == pytest.approx(rate, rel=0.05)
    assert steps.smooth_s == pytest.approx(DEFAULTS.screens.thermometer.periods * 600.0, rel=0.05)
    finding = steps.finding()
    assert finding.id == "thermometer_quantisation" and finding.shape == "quantisation"
    assert finding.where == {"level": 1.0} and "whole degrees" in finding.explanation
    # dithered by noise of a third of a step (the concealed thermometer: 1/16 degC, 0.02 degC
    # noise) or of half a step (tcbench simulate's: 0.01 degC, 0.005 degC): nothing to report
    fine = np.round((true + 0.02 * rng.standard_normal(t.size)) * 16.0) / 16.0
    dithered = thermometer_steps(t, fine, 120.0)
    assert dithered is not None and not dithered.staircase and dithered.smooth_s == 120.0
    assert thermometer_steps(t, np.round(true + 0.005 * rng.standard_normal(t.size), 2), 120.0) is None


def test_simulate_model_file_reproduces_both_grids(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = """\
tcbench_model: 1
sensor: msra
core: {kind: polynomial, centre_c: 10.0, half_range_c: 50.0, bias: [150.0, -8.0, 0.5], scale_factor: [200.0]}
effects:
  white_noise: {density: 0.002}
  quantisation: {step: 0.004}
  thermometer_quantisation: {step_c: 1.0}
"""
    path = tmp_path / "fit.yaml"
    path.write_text(text)
    out = tmp_path / "rec"
    code = main(["simulate", f"model={path}", "protocol=fulltemp", f"out={out}", "metrics=false", "seed=3"])
    assert code == 0, capsys.readouterr().err
    rec = read_recording(out / "fit-fulltemp-seed3.csv")
    step = lattice_step(rec.output)
    assert step is not None and step[0] == pytest.approx(0.004, rel=1e-6)
    assert np.array_equal(rec.temperature_c, np.round(rec.temperature_c))  # whole degrees
    assert np.unique(rec.temperature_c).size > 20  # and it still follows the profile
    # without the thermometer effect the reading keeps tcbench's 0.01 degC resolution
    plain = simulate_recording("msra", "fulltemp", 0, 3, soak_s=600.0)
    assert not np.array_equal(plain.temperature_c, np.round(plain.temperature_c))


def test_model_file_rejects_a_zero_thermometer_step() -> None:
    data = {"tcbench_model": 1, "sensor": "gyro", "effects": {"thermometer_quantisation": {"step_c": 0}},
            "core": {"centre_c": 20.0, "half_range_c": 20.0, "bias": [0.0], "scale_factor": [1.0]}}
    with pytest.raises(ModelFileError, match=r"^m.yaml: effects.thermometer_quantisation: step_c must be > 0"):
        parse_model(data, "m.yaml")


def _with(rec: Recording, column: str, values: np.ndarray) -> Recording:
    data = rec.data.copy()
    data[column] = values
    return Recording(data, rec.meta)


@pytest.mark.parametrize("lsb", [1.0, 2.0])
def test_diagnosis_names_a_quantised_output(tmp_path: Path, lsb: float) -> None:
    # one or two white sigmas per LSB; on the coarser grid most samples equal their neighbours'
    # median, and the outlier test's robust scale (0.002 sigma) fell back to the white sigma
    # only when exactly zero: 13000 samples were taken for outliers before it had a floor
    rec, truth = concealed_recording("gyro", None, 5)
    q = lsb * truth.white_sigma
    d = diagnose(_with(rec, "output", np.round(rec.output / q) * q))
    found = {e["id"]: e for e in d.to_json()["effects"]}
    assert set(found) == {"quantisation"}
    assert found["quantisation"]["where"]["level"] == pytest.approx(q, rel=1e-9)
    assert d.model["effects"]["quantisation"] == {"step": pytest.approx(q, rel=1e-9)}
    # a grid adds q^2/12 of variance: the fit is no worse than that
    assert d.final.rmse_heldout < 1.05 * np.sqrt(1.0 + lsb**2 / 12.0) * truth.white_sigma
    assert d.noise.white_sigma == pytest.approx(np.sqrt(1.0 + lsb**2 / 12.0) * truth.white_sigma, rel=0.05)
    assert "quantisation: {step: " in write_report(d, tmp_path / "r", with_plots=False)["model.yaml"].read_text()


def test_diagnosis_names_a_whole_degree_thermometer() -> None:
    # the concealed gyro (seed 7) read in whole degrees: ramps of about 0.4 degC/min step every
    # ~266 s, so the window grows to about 800 s; the gyro's small temperature slope keeps the
    # held-out RMSE that of the clean record
    rec, truth = concealed_recording("gyro", None, 7)
    d = diagnose(_with(rec, "temperature_c", np.round(rec.temperature_c)))
    report = d.to_json()
    found = {e["id"]: e for e in report["effects"]}
    assert set(found) == {"thermometer_quantisation"}
    assert found["thermometer_quantisation"]["where"] == {"level": 1.0}
    assert report["statistics"]["thermometer_smooth_s"] > 3 * 120.0
    assert d.model["effects"]["thermometer_quantisation"] == {"step_c": 1.0}
    assert d.final.rmse_heldout < 1.01 * truth.white_sigma


def test_noise_on_a_coarse_grid_is_measured_and_simulated_right() -> None:
    # sigma 1 on a grid of 1.5: the MAD of first differences reads about 1.57, the truth with the
    # grid's variance is sqrt(1 + 1.5^2 / 12) = 1.09; the model's white noise (before the grid) is 1
    from tcbench.diagnose.signals import DiagnosisData

    rng = np.random.default_rng(25)
    n = 50_000
    y = np.round(rng.standard_normal(n) / 1.5) * 1.5
    t = np.arange(n, dtype=float)
    temp = np.linspace(0.0, 40.0, n)
    screens = [s for s in BEFORE_FIT if s.id != "outliers"]  # the output's grid, clipping and noise level
    screened = run_screens(screens, ScreenInput(None, DiagnosisData(
        "gyro", "deg/s", t, temp, temp, np.zeros(n), np.zeros(n), y, np.zeros(n, dtype=np.int64), 1.57, 1.0, 120.0)))
    data = screened.data
    assert data.white_sigma == pytest.approx(np.sqrt(1.0 + 1.5**2 / 12.0), rel=0.02)
    assert "quantisation step (1.5) exceeds its white noise" in screened.not_tested["variance"]
    model = {"effects": {"white_noise": {"density": data.white_sigma}}}
    for key in (k for k in MODEL_ORDER if k in screened.results):
        screened.results[key].write_model(model)
    assert model["effects"]["white_noise"]["density"] == pytest.approx(1.0, rel=0.03)
    assert model["effects"]["quantisation"] == {"step": pytest.approx(1.5)}
