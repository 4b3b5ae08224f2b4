"""tcbench diagnose: noise whose level changes with temperature or time.

Worked by hand: white noise of sigma 1 below 30 degC and 2 above, on a temperature that swings
between 0 and 40 degC. Pair differences have variance 2 and 8; their blocks' log variance
jumps by log 4 = 1.39 at 30 degC, tens of times its scatter (about sqrt(2 / m) = 0.2 for
blocks of m = 47 pairs), so the F test rejects constant variance by far, and the noisiest band
starts within one bin (5 degC) of 30 degC.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_profile, concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.model_file import ModelFileError, parse_model, read_model, to_sensor_model
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.screens.variance import find_variance, paired_differences
from tcbench.diagnose.settings import DEFAULTS
from tcbench.sensors.protocols import Profile
from tcbench.sensors.recording import Recording

N = 38_000


def _clock(n: int = N) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n, dtype=float)
    return t, 20.0 + 20.0 * np.sin(2 * np.pi * t / n * 1.5), np.zeros(n, dtype=np.int64)


def test_pairs_do_not_overlap_and_stay_in_a_run() -> None:
    t = np.array([0.0, 1, 2, 3, 4, 5, 9, 10, 11])
    run = np.array([0, 0, 0, 1, 1, 1, 1, 1, 1])
    start, d = paired_differences(t, np.arange(9.0) ** 2, run)
    assert start.tolist() == [0, 3, 6]  # (2, 3) crosses runs, (5, 6) a gap, (1, 2) overlaps (0, 1)
    assert d.tolist() == [1.0, 16.0 - 9.0, 49.0 - 36.0]


def test_sigma_doubling_at_30_degc_worked_by_hand() -> None:
    rng = np.random.default_rng(31)
    t, temp, run = _clock()
    r = rng.standard_normal(N) * np.where(temp > 30.0, 2.0, 1.0)
    v = find_variance(t, temp, r, run, 1.0)
    assert v.found is not None and v.found.against == "temperature"
    assert v.found.p_value < 1e-12
    low, high = v.found.band
    assert 25.0 <= low <= 31.0 and high == pytest.approx(temp.max(), abs=0.5)
    assert v.found.sigma_band == pytest.approx((1.0, 2.0), rel=0.1)
    effect, params = v.model_effect()  # type: ignore[misc]
    assert effect == "noise_temperature" and params["growth_per_c"] > 0
    finding = v.finding("deg/s")
    assert finding.shape == "variance" and finding.where["temperature_c"][0] == pytest.approx(low, abs=1e-3)
    assert "quality factor" in finding.explanation and "Allan deviation per temperature band" in finding.confirm_with


def test_noise_growing_with_time_is_told_from_temperature() -> None:
    # sigma grows 40 % over the record while the temperature swings 1.5 times: time, not temperature
    rng = np.random.default_rng(32)
    t, temp, run = _clock()
    r = rng.standard_normal(N) * np.exp(np.log(1.4) * t / t[-1])
    v = find_variance(t, temp, r, run, 1.0)
    assert v.found is not None and v.found.against == "time"
    effect, params = v.model_effect()  # type: ignore[misc]
    per_h = np.log(1.4) / (t[-1] / 3600.0)
    assert effect == "noise_time" and params["growth_per_h"] == pytest.approx(per_h, rel=0.25)
    at_zero = params["density"] * np.exp(-params["growth_per_h"] * params["ref_s"] / 3600.0)
    assert at_zero == pytest.approx(1.0, rel=0.1)  # sigma at t = 0, 1 Hz
    assert v.found.band[1] == pytest.approx(t[-1], abs=100.0)  # noisiest at the end (a block is 95 s)


@pytest.mark.parametrize("tails", ["gauss", "student5"])
def test_false_alarms_at_one_percent(tails: str) -> None:
    # 300 records of constant-level noise, Gaussian or with Student-t (5 dof) tails: the F test
    # estimates the blocks' scatter itself, so heavy tails do not raise the level. Binomial(300,
    # 0.01): P(>= 8) = 1.2 %; measured 3 and 2 (n = 4000), 1 and 3 (38000), 1 and 2 (86400) of 300.
    rng = np.random.default_rng(33 if tails == "gauss" else 34)
    t, temp, run = _clock()
    draw = (lambda: rng.standard_normal(N)) if tails == "gauss" else (lambda: rng.standard_t(5, N))
    alarms = sum(find_variance(t, temp, draw(), run, 1.0).found is not None for _ in range(300))
    assert alarms <= 8
    assert DEFAULTS.screens.variance.alpha == 0.01


def test_a_small_significant_change_is_not_reported() -> None:
    # sigma 10 % higher above 30 degC over a day at 1 Hz: significant, but below the 1.2 ratio
    rng = np.random.default_rng(38)
    t, temp, run = _clock(86_400)
    v = find_variance(t, temp, rng.standard_normal(t.size) * np.where(temp > 30.0, 1.1, 1.0), run, 1.0)
    tested = {x.against: x for x in v.tests}
    assert tested["temperature"].p_value < 1e-6 and v.found is None
    assert tested["temperature"].sigma_band[1] / tested["temperature"].sigma_band[0] < DEFAULTS.screens.variance.min_sigma_ratio


def test_short_record_says_so() -> None:
    t, temp, run = _clock(300)
    v = find_variance(t, temp, np.random.default_rng(35).standard_normal(300), run, 1.0)
    assert v.found is None and "too few pairs" in v.statistics()["not_tested"]


def test_effect_reproduces_the_growth() -> None:
    spec = parse_model({"tcbench_model": 1, "sensor": "gyro",
                        "core": {"centre_c": 20.0, "half_range_c": 20.0, "bias": [0.0], "scale_factor": [1.0]},
                        "effects": {"noise_temperature": {"density": 0.01, "growth_per_c": 0.03, "ref_c": 20.0}}},
                       "m.yaml")
    t, temp, run = _clock()
    prof = Profile("test", "gyro", 1.0, t, temp, np.zeros(N), np.zeros(N), np.zeros(N))
    y = to_sensor_model(spec).simulate(prof, np.random.default_rng(36))
    v = find_variance(t, temp, y, run, 1.0)
    assert v.found is not None and v.found.against == "temperature"
    assert v.found.slope == pytest.approx(0.03, rel=0.1)
    assert v.sigma_ref * np.exp(-0.03 * (v.ref - 20.0)) == pytest.approx(0.01, rel=0.05)
    with pytest.raises(ModelFileError, match=r"^m.yaml: effects.noise_temperature: density must be >= 0"):
        parse_model({**spec_data(), "effects": {"noise_temperature": {"density": -1}}}, "m.yaml")


def spec_data() -> dict:
    return {"tcbench_model": 1, "sensor": "gyro",
            "core": {"centre_c": 20.0, "half_range_c": 20.0, "bias": [0.0], "scale_factor": [1.0]}}


def test_diagnosis_names_noise_growing_with_temperature(tmp_path: Path) -> None:
    # the concealed gyro control, its noise doubled above its median temperature
    rec, truth = concealed_recording("gyro", None, 5)
    rng = np.random.default_rng(37)
    hot = rec.temperature_c > np.median(rec.temperature_c)
    data = rec.data.copy()
    data["output"] = rec.output + np.where(hot, np.sqrt(3.0) * truth.white_sigma, 0.0) * rng.standard_normal(hot.size)
    d = diagnose(Recording(data, rec.meta))
    report = d.to_json()
    found = {e["id"]: e for e in report["effects"]}
    # and nothing else: each sample is judged for outliers at its own noise level (against the
    # record's, the noisy half showed 3-8 false outliers)
    assert set(found) == {"noise_temperature"}
    finding = found["noise_temperature"]
    assert finding["shape"] == "variance"
    low, high = finding["where"]["temperature_c"]
    median = float(np.median(rec.temperature_c))
    assert abs(low - median) < 5.0 and high > float(np.max(d.series.temp_c)) - 1.0
    assert finding["params"]["sigma_noisy"] / finding["params"]["sigma_quiet"] == pytest.approx(2.0, rel=0.15)
    assert "variance" in report["statistics"]
    # the white sigma is the record's RMS (sqrt((1 + 4) / 2) = 1.58 sigma), not the median
    # difference's 1.35, so the Allan test does not take the noisy half for flicker
    assert "bias_instability" not in found
    assert d.noise.white_sigma == pytest.approx(np.sqrt(2.5) * truth.white_sigma, rel=0.05)
    # model.yaml: the noise level follows temperature instead of one white sigma, and a
    # simulation of it shows the same growth
    spec = read_model(write_report(d, tmp_path / "r", with_plots=False)["model.yaml"])
    assert "noise_temperature" in spec.effects and "white_noise" not in spec.effects
    model = to_sensor_model(spec)
    profile = concealed_profile("gyro", np.random.default_rng(np.random.SeedSequence(5).spawn(7)[0]))
    noisy = model.simulate(profile, np.random.default_rng(1)) - model.without("noise_temperature").simulate(
        profile, np.random.default_rng(1))
    v = find_variance(profile.t_s, profile.temp_c, noisy, np.zeros(noisy.size, dtype=np.int64), 1.0)
    assert v.found is not None and v.found.against == "temperature" and v.found.slope > 0
