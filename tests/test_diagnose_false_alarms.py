"""Controls of unusual form (short, fast, in bursts) name nothing and never crash."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.datasets.controls import Form, bursts_for, control_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.signals import DiagnosisDataError, fitted_window_s, savgol

DEV_SEED = 44_900_000  # the development base of experiments/diagnose-concealed/false_alarms.py


def _named(sensor: str, form: Form, seed: int) -> list[str]:
    rec, _ = control_recording(sensor, form, seed)
    return [e["id"] for e in diagnose(rec, sensor=sensor).to_json()["effects"]]


def test_form_control_has_the_form() -> None:
    form = Form(3600.0, 10.0, *bursts_for(3600.0))
    rec, truth = control_recording("msra", form, DEV_SEED)
    assert rec.meta.sample_rate_hz == 10.0
    assert 0.12 < len(rec.data) / (3600.0 * 10.0) < 0.22  # 50 s of every 5 min, programme within -/+ 20 %
    assert 0.7 * 3600.0 < truth["span_s"] < 1.25 * 3600.0


def test_ten_minute_fast_record_is_refused_not_crashed() -> None:
    rec, _ = control_recording("gyro", Form(600.0, 100.0), DEV_SEED + 1)
    with pytest.raises(DiagnosisDataError, match="too short"):
        diagnose(rec, sensor="gyro")


@pytest.mark.parametrize(("sensor", "form"), [
    pytest.param("msra", Form(1200.0, 10.0), marks=pytest.mark.slow),  # 20 min at 10 Hz (a whole diagnosis: slow)
    ("gyro", Form(3600.0, 1.0, *bursts_for(3600.0))),  # 1 h at 1 Hz, 50 s every 5 min
])
def test_unusual_controls_name_nothing(sensor: str, form: Form) -> None:
    assert _named(sensor, form, DEV_SEED + 2) == []


def test_fast_staircase_shortens_the_smoothing_window() -> None:
    """A 1 h staircase's ramp corners bias a 120 s smoother; the 10 h one keeps it."""
    for duration_s, expected in ((3600.0, lambda w: w < 120.0), (36000.0, lambda w: w == 120.0)):
        rec, _ = control_recording("gyro", Form(duration_s, 1.0), DEV_SEED)
        assert expected(fitted_window_s(rec.time_s, rec.temperature_c, 120.0))


def test_long_savgol_matches_scipy() -> None:
    from scipy.signal import savgol_filter
    x = np.cumsum(np.random.default_rng(0).standard_normal(5000))
    for deriv in (0, 1):
        np.testing.assert_allclose(savgol(x, 1001, deriv, 0.1),
                                   savgol_filter(x, 1001, 2, deriv=deriv, delta=0.1, mode="interp"), atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize(("sensor", "form"), [
    ("msra", Form(1800.0, 100.0)),
    ("gyro", Form(72 * 3600.0, 0.5, *bursts_for(72 * 3600.0))),
])
def test_large_controls_name_nothing(sensor: str, form: Form) -> None:
    assert _named(sensor, form, DEV_SEED + 3) == []
