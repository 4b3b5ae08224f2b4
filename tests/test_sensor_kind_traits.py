"""What differs between the sensor kinds is declared by the kind (:mod:`tcbench.sensors.kinds`),
never asked of its name elsewhere: the metrics a run gets, the nominal scale factor, whether a
fitted model carries one, a turned unit's input cycle, the autopilots' parameter names."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import pytest

from tcbench.compensation.ardupilot import _letters
from tcbench.metrics.report import analyse
from tcbench.sensors import kinds
from tcbench.sensors.fitted import PolynomialModel
from tcbench.sensors.simulate import simulate_recording


def test_the_builtin_kinds_declare_their_traits() -> None:
    msra, gyro, accel = (kinds.get(n) for n in ("msra", "gyro", "accel"))
    assert (msra.report, gyro.report, accel.report) == ("zero_bias", "rate", "inertial")
    assert (msra.nominal_scale_factor, gyro.nominal_scale_factor, accel.nominal_scale_factor) == (200.0, 1.0, 1.0)
    assert (msra.scaled, gyro.scaled, accel.scaled) == (True, False, False)
    assert (msra.positions, gyro.positions, accel.positions) == (True, False, True)
    assert (gyro.px4_letter, gyro.px4_cal, accel.px4_letter, accel.px4_cal) == ("G", "GYRO", "A", "ACC")
    assert (msra.ardupilot_letters, gyro.ardupilot_letters, accel.ardupilot_letters) == (None, "GYR", "ACC")
    with pytest.raises(ValueError, match="report must be one of inertial, zero_bias, rate, got 'nope'"):
        dataclasses.replace(accel, name="other", report="nope")
    with pytest.raises(ValueError, match=r"covers accel, gyro, not 'msra'"):
        _letters("msra")


@pytest.fixture
def twins() -> Iterator[None]:
    """``msra2``, an MSRA by another name; ``gyro2``, a gyro that asks for the inertial metrics."""
    kinds.register(dataclasses.replace(kinds.get("msra"), name="msra2"))
    kinds.register(dataclasses.replace(kinds.get("gyro"), name="gyro2", report="inertial"))
    yield
    kinds.unregister("msra2")
    kinds.unregister("gyro2")


def _as(rec, sensor: str):  # type: ignore[no-untyped-def]
    return dataclasses.replace(rec, meta=dataclasses.replace(rec.meta, sensor=sensor))


def test_the_metrics_follow_the_kinds_report_not_its_name(twins: None) -> None:
    zero_bias = simulate_recording("msra", "roomtemp", 0, 0)
    metrics = analyse(zero_bias).metrics
    assert {"after_30min_ug", "zero_start_ug", "scale_factor_hz_per_g"} <= set(metrics)  # seed 000's Table 1
    assert analyse(_as(zero_bias, "msra2")).metrics == metrics
    static = simulate_recording("gyro", "static", 0, 0, duration_s=1800.0)
    rate, inertial = analyse(static).metrics, analyse(_as(static, "gyro2")).metrics
    assert "arw_deg_per_sqrt_h" in rate and "noise_density_dph_per_sqrt_hz" not in rate
    assert {"noise_density_dph_per_sqrt_hz", "bias_stability_dph"} <= set(inertial) and "arw_deg_per_sqrt_h" not in inertial
    assert PolynomialModel(sensor="msra2", scale_factor=(3.5, 0.1)).scale_factor_hz_per_g == 3.5
    assert PolynomialModel(sensor="gyro2", scale_factor=(3.5, 0.1)).scale_factor_hz_per_g is None
