"""A new run is a new power-on (docs/concepts/split-tiers.md): what differs between simulated runs of one device."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.sensors.runs import Placement, placement, power_on
from tcbench.sensors.kinds import unit
from tcbench.sensors.simulate import simulate_recording
from tcbench.sensors.timing import Timing, running
from tcbench.sensors.truth import simulate_truth
from tcbench.sensors.kinds.accel import chamber


def _short(sensor: str = "accel", seed: int = 0, **kw: object):
    return simulate_recording(sensor, "chamber", 0, seed, levels_c=(45.0, 5.0), soak_s=900.0, room_s=600.0, **kw)


def test_same_seed_same_bytes() -> None:
    a, b = _short(seed=4), _short(seed=4)
    assert a.data.equals(b.data)
    assert a.meta.extra == b.meta.extra


def test_runs_differ_beyond_their_noise() -> None:
    """Two runs of one device: the noise-free outputs differ (turn-on), and so do the programmes'
    timing (their lengths) and the thermometer's run-to-run offset."""
    ta = simulate_truth("accel", "chamber", 0, 1, levels_c=(45.0, 5.0), soak_s=900.0, room_s=600.0)
    tb = simulate_truth("accel", "chamber", 0, 2, levels_c=(45.0, 5.0), soak_s=900.0, room_s=600.0)
    assert ta.t_s.size != tb.t_s.size  # ramp rate and soak lengths within tolerance
    n = min(ta.t_s.size, tb.t_s.size)
    assert np.max(np.abs(ta.output_det[:n] - tb.output_det[:n])) > 1e-3  # more than a mg: a new turn-on
    pa, pb = (_short(seed=s).meta.extra["power_on"] for s in (1, 2))
    assert pa["thermometer_offset_c"] != pb["thermometer_offset_c"]
    assert pa["turn_on"]["turn_on_bias_mg"] != pb["turn_on"]["turn_on_bias_mg"]


def test_power_on_replays_another_runs_signal_with_new_noise() -> None:
    """``power_on=s``: run s's noise-free signal exactly, this run's noise (the replay tier)."""
    kw = {"levels_c": (45.0, 5.0), "soak_s": 900.0, "room_s": 600.0}
    own = simulate_truth("accel", "chamber", 0, 1, **kw)
    replay = simulate_truth("accel", "chamber", 0, 7, power_on=1, **kw)
    np.testing.assert_array_equal(own.output_det, replay.output_det)
    a, b = _short(seed=1), _short(seed=7, power_on=1)
    assert a.time_s.size == b.time_s.size and not np.array_equal(a.output, b.output)


def test_thermometer_sits_apart_and_the_thermometer_oracle_is_a_floor() -> None:
    """The reading is the package plus the placement's offset and heat-flow gradient; the
    thermometer-limited oracle, which does not know this power-on, is a real floor above the
    die-temperature oracle (its residual is more than the noise)."""
    rec = _short(seed=3)
    truth = simulate_truth("accel", "chamber", 0, 3, levels_c=(45.0, 5.0), soak_s=900.0, room_s=600.0)
    where = placement("accel", 0)
    assert 1.0 <= abs(where.offset_c) <= 3.0 and 0.1 <= where.gradient_c_per_c_per_min <= 1.0
    noise = rec.output - truth.output_det
    limited = rec.output - truth.output_det_thermometer
    assert np.std(limited - np.mean(limited)) > 1.05 * np.std(noise)
    run = rec.meta.extra["power_on"]
    assert run["thermometer_offset_c"] != pytest.approx(where.offset_c, abs=1e-9)


def test_placement_inverts_its_reading() -> None:
    t = np.arange(0.0, 3600.0)
    package = 25.0 + 20.0 * np.sin(t / 1200.0)  # up to 1 degC/min
    p = Placement(2.0, 0.5)
    np.testing.assert_allclose(p.package_c(p.reading_c(package, 1.0), 1.0)[5:-5], package[5:-5], atol=0.02)


def test_timing_reverses_the_holds_and_scales_the_ramps() -> None:
    nominal = chamber(levels_c=(60.0, -20.0), soak_s=1800.0, room_s=1200.0)
    with running(Timing(ramp_scale=2.0, reverse=True)):
        changed = chamber(levels_c=(60.0, -20.0), soak_s=1800.0, room_s=1200.0)
    # the room hold stays first; then -20 before 60, at 2 degC/min
    first_cold = np.argmax(changed.temp_c < 0.0)
    first_hot = np.argmax(changed.temp_c > 50.0)
    assert first_cold < first_hot
    assert np.argmax(nominal.temp_c > 50.0) < np.argmax(nominal.temp_c < 0.0)
    assert changed.t_s[-1] < nominal.t_s[-1]  # faster ramps: a shorter programme
    assert changed.info["chamber_ramp_c_per_min"] == pytest.approx(2.0)


@pytest.mark.parametrize("sensor", ["msra", "gyro", "accel"])
def test_each_kind_draws_its_turn_on(sensor: str) -> None:
    device = unit(sensor, 0)
    model_a, a = power_on(sensor, device.model, 1, placement(sensor, 0))
    model_b, b = power_on(sensor, device.model, 2, placement(sensor, 0))
    assert a.turn_on and a.turn_on != b.turn_on
    assert model_a != model_b != device.model
    again, a2 = power_on(sensor, device.model, 1, placement(sensor, 0))
    assert again == model_a and a2 == a


def test_hysteresis_state_starts_where_the_power_on_left_it() -> None:
    """The accelerometer's stress hysteresis starts in the drawn state: two power-ons at one
    temperature differ at t=0 by their states' difference times the amplitude."""
    device = unit("accel", 0)
    models = [power_on("accel", device.model, s, placement("accel", 0)) for s in (1, 2)]
    states = [m.effect("hysteresis").start_state for m, _ in models]  # type: ignore[union-attr]
    assert states[0] != states[1] and all(-1.0 <= s <= 1.0 for s in states)
    assert [p.hysteresis_state for _, p in models] == states


def test_two_devices_do_not_share_a_runs_power_on() -> None:
    """Run seed s of device 0 and of device 1 are two draws (the power-on stream mixes in the device)."""
    _, a = power_on("accel", unit("accel", 0).model, 1, Placement(), device_seed=0)
    _, b = power_on("accel", unit("accel", 1).model, 1, Placement(), device_seed=1)
    assert a.timing != b.timing and a.turn_on != b.turn_on
