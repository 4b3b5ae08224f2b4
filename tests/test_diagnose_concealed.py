"""Recordings with one effect hidden under the noise (tcbench.datasets.concealed)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from tcbench.datasets.concealed import (
    EFFECTS_BY_SENSOR,
    Concealed,
    _build,
    concealed_profile,
    concealed_recording,
)
from tcbench.sensors.kinds import profile_input, unit
from tcbench.sensors.recording import standard_units
from tcbench.sensors.thermal import Segment, segment_index

CASES = [(s, e) for s, effects in EFFECTS_BY_SENSOR.items() for e in effects]


def _left_rms(d: np.ndarray, temp_c: np.ndarray, accel_g: np.ndarray | None) -> float:
    """RMS of what [1, u, u^2] (and a times those) cannot absorb, u = (T - 25) / 50."""
    u = (temp_c - 25.0) / 50.0
    cols = [np.ones_like(u), u, u * u]
    if accel_g is not None:
        cols += [accel_g * c for c in cols]
    x = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(x, d, rcond=None)
    return float(np.sqrt(np.mean((d - x @ coef) ** 2)))


def test_same_seed_same_recording() -> None:
    a, ta = concealed_recording("msra", "hysteresis", 11)
    b, tb = concealed_recording("msra", "hysteresis", 11)
    pd.testing.assert_frame_equal(a.data, b.data)
    assert ta == tb and a.meta == b.meta
    c, _ = concealed_recording("msra", "hysteresis", 12)
    assert len(c.data) != len(a.data) or not np.array_equal(c.output, a.output)


@pytest.mark.parametrize("sensor", ["msra", "gyro"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_profile_heats_and_cools_through_the_same_levels(sensor: str, seed: int) -> None:
    p = concealed_profile(sensor, np.random.default_rng(seed))
    levels = [float(x) for x in str(p.info["levels_c"]).split()]
    soaks = [float(x) for x in str(p.info["soaks_s"]).split()]
    ramp = float(p.info["chamber_ramp_c_per_min"])
    assert p.sample_rate_hz == 1.0 and np.all(np.diff(p.t_s) == 1.0)
    assert 8 * 3600 <= p.t_s[-1] <= 12 * 3600
    assert all(35 * 60 <= s <= 50 * 60 for s in soaks) and 0.5 <= ramp <= 2.0
    assert 20.0 <= levels[0] <= 28.0 and -40.0 <= min(levels) and max(levels) <= 70.0
    assert max(levels) - min(levels) >= 30.0
    assert np.max(np.abs(np.diff(p.temp_c))) <= ramp / 60.0 + 1e-9
    # Where each soak is, from the set-point programme; the package has settled by its end.
    segments = [Segment(x, s) for x, s in zip(levels, soaks, strict=True)]
    seg = segment_index(segments, levels[0], ramp, p.t_s)
    approached: dict[float, set[str]] = {}
    for i, level in enumerate(levels):
        idx = np.flatnonzero(seg == i)
        assert abs(idx.size - soaks[i]) <= 1
        assert np.all(np.abs(p.temp_c[idx[-600:]] - level) < 0.05)
        if i:
            before = p.temp_c[idx[0]] - p.temp_c[max(idx[0] - 600, 0)]
            direction = "heating" if before > 0 else "cooling"
            assert direction == ("heating" if level > levels[i - 1] else "cooling")
            approached.setdefault(level, set()).add(direction)
    interior = [x for x in approached if min(levels) < x < max(levels)]
    assert interior and all(approached[x] == {"heating", "cooling"} for x in interior)
    assert np.all(p.cross_g == 0.0) and np.all(p.rate_dps == 0.0)
    if sensor == "gyro":
        assert np.all(p.accel_g == 0.0)
        return
    # +1, 0, -1, 0 g in 60-120 s dwells, through ramps and soaks alike.
    change = np.flatnonzero(np.diff(p.accel_g)) + 1
    dwells = np.diff(change)
    assert dwells.min() >= 60 and dwells.max() <= 120
    values = p.accel_g[np.r_[0, change]]
    cycle = np.array([1.0, 0.0, -1.0, 0.0])
    assert np.array_equal(values, cycle[np.arange(values.size) % 4])
    assert (seg[change] == -1).any() and (seg[change] >= 0).any()  # steps during ramps and soaks


def test_thermometer_on_a_sixteenth_degree_grid() -> None:
    parts = _build("gyro", None, 4)
    rec, _ = concealed_recording("gyro", None, 4)
    steps = rec.temperature_c * 16.0
    assert np.array_equal(steps, np.round(steps))
    err = rec.temperature_c - parts.profile.temp_c
    assert 0.02 < err.std() < 0.035 and abs(err.mean()) < 0.002


@pytest.mark.parametrize(("sensor", "effect"), CASES)
def test_hidden_effect_at_its_ratio(sensor: str, effect: str) -> None:
    seed = 5 + len(effect)
    parts = _build(sensor, effect, seed)
    rec, truth = concealed_recording(sensor, effect, seed)
    assert truth == parts.truth and truth.effect == effect and truth.sensor == sensor
    p, sigma = parts.profile, truth.white_sigma
    accel = p.accel_g if sensor == "msra" else None
    ratio = _left_rms(parts.hidden, p.temp_c, accel) / sigma
    assert 0.3 <= ratio <= 0.7 and ratio == pytest.approx(truth.ratio, rel=1e-6)
    np.testing.assert_array_equal(rec.output, parts.base + parts.hidden + parts.white)
    assert parts.white.std() == pytest.approx(sigma, rel=0.03)
    # From the recording alone: remove the effect-free output, what is left beyond white noise.
    left = _left_rms(rec.output - parts.base, p.temp_c, accel)
    assert np.sqrt(max(left**2 - sigma**2, 0.0)) / sigma == pytest.approx(truth.ratio, abs=0.05)
    if effect != "bias_instability":  # the parameters are the truth: they rebuild the contribution
        again = parts.model.with_effects({effect: truth.params}).simulate(p, np.random.default_rng(0)) - parts.base
        np.testing.assert_allclose(again, parts.hidden, rtol=1e-6, atol=1e-9 * sigma)
    extra = json.loads(json.dumps(rec.meta.extra, allow_nan=False))
    assert extra["concealed"]["effect"] == effect and extra["concealed"]["params"] == truth.params


@pytest.mark.parametrize("sensor", ["msra", "gyro"])
def test_control_has_no_effect(sensor: str) -> None:
    parts = _build(sensor, None, 9)
    rec, truth = concealed_recording(sensor, None, 9)
    assert truth == Concealed(sensor, None, {}, 0.0, truth.white_sigma, 9)
    density = unit(sensor, parts.device_seed).model.effect("white_noise").params()["density"]
    assert truth.white_sigma == pytest.approx(density)
    assert not parts.hidden.any() and not parts.model.effects
    accel = parts.profile.accel_g if sensor == "msra" else None
    assert _left_rms(parts.base, parts.profile.temp_c, accel) < 1e-3 * truth.white_sigma
    assert _left_rms(rec.output - parts.base, parts.profile.temp_c, accel) == pytest.approx(truth.white_sigma, rel=0.03)
    assert rec.meta.sensor == sensor and rec.meta.units == standard_units(sensor)
    assert rec.meta.sample_rate_hz == 1.0 and rec.meta.device_id == f"concealed-{sensor}-9"
    assert np.array_equal(rec.input, profile_input(parts.profile))


@pytest.mark.parametrize(
    ("sensor", "effect", "named"),
    [("msra", "fog", "'fog'"), ("gyro", "accel_nonlinearity", "'accel_nonlinearity'"), ("imu", None, "'imu'")],
)
def test_unknown_effect_or_sensor_named(sensor: str, effect: str | None, named: str) -> None:
    with pytest.raises(ValueError, match=named) as err:
        concealed_recording(sensor, effect, 0)
    assert "\n" not in str(err.value)


def test_unknown_sensor_profile_and_bad_seed() -> None:
    with pytest.raises(ValueError, match="'imu'"):
        concealed_profile("imu", np.random.default_rng(0))
    with pytest.raises(ValueError, match="-1"):
        concealed_recording("gyro", None, -1)
