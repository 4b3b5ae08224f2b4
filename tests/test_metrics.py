"""Seed 000 accelerometer metrics and seed 001 gyro metrics, on hand-worked cases."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tcbench.metrics import accelerometer as acc
from tcbench.metrics import gyro


def test_zero_bias_stability_by_hand() -> None:
    # 1 Hz samples: windows of 10 s averaging to 0, 200, 0, 200 Hz with a 200 Hz/g scale factor
    y = np.repeat([0.0, 200e-6 * 200, 0.0, 200e-6 * 200], 10)
    t = np.arange(y.size, dtype=float)
    expected = np.std([0, 200, 0, 200], ddof=1)
    assert acc.zero_bias_stability_ug(t, y, 200.0) == pytest.approx(expected)
    # from 20 s on only the last two windows count
    assert acc.zero_bias_stability_ug(t, y, 200.0, start_s=20) == pytest.approx(np.std([0, 200], ddof=1))
    # window of one sample: the raw 1 sigma
    assert acc.zero_bias_stability_ug(t, y, 200.0, window_s=1.0) == pytest.approx(np.std(y / 200, ddof=1) * 1e6)
    with pytest.raises(ValueError, match="fewer than two"):
        acc.zero_bias_stability_ug(t, y, 200.0, start_s=35)


def test_zero_bias_windows_stay_inside_a_loggers_bursts() -> None:
    # three bursts of 25 s at 1 Hz, 300 s apart: two full 10 s windows each (means 0 and 200 ug),
    # then 5 s that make no full window and hold a wild value no window may average in
    burst = np.concatenate([np.zeros(10), np.full(10, 200e-6 * 200), np.full(5, 1.0 * 200)])
    y = np.tile(burst, 3)
    t = np.concatenate([300.0 * k + np.arange(25.0) for k in range(3)])
    assert acc.zero_bias_stability_ug(t, y, 200.0) == pytest.approx(np.std([0, 200] * 3, ddof=1))


def test_zero_bias_table_rows() -> None:
    t = np.arange(5400.0)
    y = 0.2 * np.exp(-t / 1200.0)
    table = acc.zero_bias_table(t, y, 200.0)
    assert table["after_30min_ug"] < table["after_20min_ug"] < table["zero_start_ug"]


def _four_position(u0: float, k: float, mis: float, temps: list[float], samples: int = 5) -> tuple:
    """Blocks +0g, +1g, -0g, -1g per node, with U = u0 + 2k a_eff, a_eff incl. misalignment."""
    labels, out, temp = [], [], []
    for i, tc in enumerate(temps):
        for label, (a, cross) in {"+0g": (0, 1), "+1g": (1, 0), "-0g": (0, -1), "-1g": (-1, 0)}.items():
            labels += ["", *[label] * samples]
            value = u0[i] + 2 * k[i] * (a + cross * mis)
            out += [9999.0, *[value] * samples]  # the unlabelled sample must be ignored
            temp += [tc] * (samples + 1)
    return np.array(temp), np.array(out), np.array(labels)


def test_four_position_eq12_by_hand() -> None:
    temps = [-40.0, 10.0, 60.0]
    u0, k = [150.0, 151.0, 152.5], [100.0, 100.5, 101.0]
    temp, out, labels = _four_position(u0, k, 1e-3, temps)
    nodes = acc.four_position(temp, out, labels)
    np.testing.assert_allclose(nodes["temperature_c"], temps)
    np.testing.assert_allclose(nodes["scale_factor_hz_per_g"], np.array(k) * 2)
    # plus form: the misalignment cancels, bias = 2 u0 / (4 k) g
    np.testing.assert_allclose(nodes["bias_g"], np.array(u0) / (2 * np.array(k)))
    printed = acc.four_position(temp, out, labels, bias_form="printed")
    np.testing.assert_allclose(printed["bias_g"], 1e-3)  # the printed form measures misalignment
    var = acc.temperature_variation(nodes)
    sf = np.array(k) * 2
    assert var.scale_factor_ppm == pytest.approx(np.std(sf, ddof=1) / sf.mean() * 1e6)
    assert var.bias_ug == pytest.approx(np.std(np.array(u0) / (2 * np.array(k)), ddof=1) * 1e6)
    assert var.nodes == 3


def test_four_position_rejects_incomplete_sequences() -> None:
    temp, out, labels = _four_position([150.0], [100.0], 0.0, [20.0])
    labels[labels == "-0g"] = "+0g"
    with pytest.raises(ValueError, match="node 1: positions"):
        acc.four_position(temp, out, labels)
    with pytest.raises(ValueError, match="expected groups of four"):
        acc.four_position(temp[:-6], out[:-6], labels[:-6])
    with pytest.raises(ValueError, match="bias_form"):
        acc.four_position(temp, out, labels, bias_form="minus")
    with pytest.raises(ValueError, match="two temperature nodes"):
        acc.temperature_variation(pd.DataFrame({"scale_factor_hz_per_g": [1.0], "bias_g": [0.0]}))


def test_gyro_drift_between_soaks() -> None:
    t = np.arange(0.0, 4000.0)
    temp = np.where(t < 2000, 60.0, -40.0)
    out = np.where(t < 2000, 0.05, 0.01) + 0.0 * t
    assert gyro.drift_dps(t, temp, out) == pytest.approx(0.04)
    with pytest.raises(ValueError, match="never stays within 0.5 degC of 80 degC"):
        gyro.soak_mean(t, temp, out, 80.0)
    # a thermometer flickering into the band for a moment after the soak does not move it
    temp2 = temp.copy()
    temp2[2500] = 60.2
    out2 = out.copy()
    out2[2500] = 99.0
    assert gyro.drift_dps(t, temp2, out2) == pytest.approx(0.04)


def test_gyro_allan_summary_units() -> None:
    fs = 10.0
    arw_deg_sqrt_h = 0.5
    rng = np.random.default_rng(0)
    y = rng.standard_normal(200_000) * arw_deg_sqrt_h / 60 * np.sqrt(fs)
    _, _, summary = gyro.allan_summary(y, fs)
    assert summary["arw_deg_per_sqrt_h"] == pytest.approx(arw_deg_sqrt_h, rel=0.05)


def test_a_gyro_record_with_soaks_shorter_than_the_drift_window_keeps_its_other_metrics() -> None:
    from tcbench.metrics.report import analyse
    from tcbench.sensors.recording import make_recording

    # 60 and -40 degC soaks of 5 min at 1 Hz: too short for the 10-min drift read-off
    t = np.arange(0.0, 1200.0)
    temp = np.where(t < 300, 60.0, np.where(t < 900, 60.0 - (t - 300) / 6.0, -40.0))
    out = 0.01 + 1e-3 * np.random.default_rng(0).standard_normal(t.size)
    report = analyse(make_recording(t, temp, np.zeros_like(t), out, sensor="gyro", sample_rate_hz=1.0,
                                     device_id="short-soaks"))
    assert "drift_60_to_m40_dps" not in report.metrics and "arw_deg_per_sqrt_h" in report.metrics
    assert any(c.startswith("drift (60 to -40 degC) not read") for c in report.conventions)
