"""Thermal profiles, effects, sensor models and device populations."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.sensors import effects as fx
from tcbench.sensors.kinds import gyro as G
from tcbench.sensors.kinds import msra as M
from tcbench.sensors.kinds import unit
from tcbench.sensors.kinds.gyro import gyro_unit
from tcbench.sensors.kinds.msra import msra_unit
from tcbench.sensors.models import DPH, MSRA, Gyro
from tcbench.sensors.thermal import Segment, first_order_lag, segment_index, setpoint


def test_first_order_lag_step_response() -> None:
    x = np.r_[np.zeros(1), np.ones(3000)]
    y = first_order_lag(x, 1.0, 600.0)
    assert y[0] == 0.0
    assert y[601] == pytest.approx(1 - np.exp(-1), rel=1e-3)  # one time constant after the step


def test_setpoint_ramps_at_the_rate_limit() -> None:
    segs = [Segment(35.0, 100.0), Segment(25.0, 50.0)]
    t, sp = setpoint(segs, 25.0, 2.0, 1.0)
    assert t[-1] == pytest.approx(300 + 100 + 300 + 50 - 1)
    assert sp[150] == pytest.approx(30.0)  # halfway up the 10 degC ramp at 2 degC/min
    idx = segment_index(segs, 25.0, 2.0, np.array([10.0, 350.0, 500.0, 720.0]))
    assert idx.tolist() == [-1, 0, -1, 1]


def test_fulltemp_protocol_shape() -> None:
    prof = M.msra_fulltemp()
    labels = prof.position
    assert set(labels) == {"", "+0g", "+1g", "-0g", "-1g"}
    assert np.count_nonzero(labels == "+1g") == 6 * 40
    plus1 = labels == "+1g"
    assert np.all(prof.accel_g[plus1] == 1.0) and np.all(prof.cross_g[plus1] == 0.0)
    # the package reaches each node during the soak: the four positions are taken at the node
    for node in (-40, -20, 0, 20, 40, 60):
        near = np.abs(prof.temp_c - node) < 0.05
        assert np.any(near & (labels == "-1g"))
    assert prof.t_s[-1] > 6 * 3600


def test_gyro_oven_protocol_follows_seed_001() -> None:
    prof = G.gyro_oven()
    hours = prof.t_s / 3600
    assert prof.sample_rate_hz == 10.0
    assert prof.temp_c[hours < 1].max() == pytest.approx(25.0, abs=0.01)
    assert prof.temp_c.max() == pytest.approx(60.0, abs=0.05)
    assert prof.temp_c[-1] == pytest.approx(-40.0, abs=0.05)
    assert np.all(prof.rate_dps == 0.0)


def test_thermal_lag_delays_the_die() -> None:
    prof = G.gyro_oven()
    s = fx.Signals(prof.t_s, prof.dt_s, prof.temp_c, prof.temp_c, np.gradient(prof.temp_c, prof.dt_s),
                   prof.accel_g, prof.cross_g, prof.rate_dps)
    die = fx.ThermalLag(480.0).die_temperature(s)
    cooling = np.gradient(prof.temp_c) < -1e-4
    assert np.all(die[cooling] >= prof.temp_c[cooling] - 1e-9)  # die warmer while cooling


def test_play_operator_and_hysteresis_memory() -> None:
    temp = np.r_[np.linspace(20, 40, 201), np.linspace(40, 30, 101), np.full(50, 30.0),
                 np.linspace(30, 20, 101), np.linspace(20, 30, 101), np.full(50, 30.0)]
    state = (temp - fx.play_operator(temp, 2.0)) / 2.0
    after_cooling = state[201 + 101 + 10]
    after_heating = state[-10]
    assert after_cooling == pytest.approx(-1.0) and after_heating == pytest.approx(1.0)


def test_effect_registry_and_errors() -> None:
    assert set(fx.EFFECTS) >= {
        "thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift",
        "temperature_cubic", "accel_nonlinearity", "bias_instability",
    }
    assert fx.make_effect("warmup", amplitude=2.0).params() == {"amplitude": 2.0, "tau_s": 1200.0}
    with pytest.raises(ValueError, match="unknown effect 'nope'; known: accel_nonlinearity"):
        fx.make_effect("nope")
    with pytest.raises(ValueError, match="no parameter colour"):
        fx.make_effect("warmup", colour=1)


def _signals(n=100, dt=1.0, temp=None, accel=None):
    t = np.arange(n) * dt
    temp = np.full(n, 25.0) if temp is None else temp
    z = np.zeros(n)
    return fx.Signals(t, dt, temp, temp, np.gradient(temp, dt), z if accel is None else accel, z, z)


def test_output_effects_by_hand() -> None:
    rng = np.random.default_rng(0)
    s = _signals(temp=np.linspace(20, 30, 100), accel=np.full(100, 2.0))
    np.testing.assert_allclose(fx.TemperatureCubic(0.5).term(s, rng), 0.5 * (s.temp_die_c - 25) ** 3)
    np.testing.assert_allclose(fx.AccelNonlinearity(0.1).term(s, rng), 0.4)
    np.testing.assert_allclose(fx.Warmup(3.0, 10.0).term(s, rng), 3.0 * np.exp(-s.t_s / 10))
    np.testing.assert_allclose(fx.TemperatureRate(2.0).term(s, rng), 2.0 * 10 / 99, rtol=1e-9)
    aging = fx.AgingDrift(rate_per_h=3600.0, relax_amplitude=1.0, relax_tau_s=50.0).term(s, rng)
    np.testing.assert_allclose(aging, s.t_s + np.exp(-s.t_s / 50))


def test_msra_core_by_hand() -> None:
    """Differential output at rest and at +-1 g, eq. of docs/concepts/physics.md, sensor kinds evaluated by hand."""
    m = MSRA(f0_hz=(30000.0, 29850.0), k_hz_per_g=(100.0, 100.0), tce_ppm_per_k=(-30.0, -30.0),
             stress_ppm_per_k=(-10.0, -8.0), c2_ppb_per_k2=(0.0, 0.0), gk_ppm_per_k=100.0,
             misalignment_rad=0.0)
    s = _signals(n=3, temp=np.array([25.0, 35.0, 35.0]), accel=np.array([0.0, 0.0, 1.0]))
    u = m.core(s)
    assert u[0] == pytest.approx(150.0)
    drift = 30000 * -40e-6 * 10 - 29850 * -38e-6 * 10
    assert u[1] == pytest.approx(150.0 + drift)
    assert u[2] - u[1] == pytest.approx(200.0 * (1 + 100e-6 * 10))


def test_gyro_core_by_hand() -> None:
    g = Gyro(sf_ppm_per_k=0.0, b0_dph=36.0, b1_dph_per_k=1.0, b2_dph_per_k2=0.01)
    s = _signals(n=2, temp=np.array([25.0, 35.0]))
    np.testing.assert_allclose(g.core(s), np.array([36.0, 36.0 + 10 + 1.0]) * DPH)


def test_devices_differ_and_repeat() -> None:
    a, b = msra_unit(0), msra_unit(1)
    assert a.model != b.model and a.device_id == "msra-0000"
    assert msra_unit(0).model == a.model
    assert gyro_unit(3).model == gyro_unit(3).model
    with pytest.raises(ValueError, match="device_seed must be a non-negative integer"):
        unit("msra", -1)
    with pytest.raises(ValueError, match="unknown sensor 'imu'"):
        unit("imu", 0)


def test_simulation_is_seeded() -> None:
    model = gyro_unit(0).model
    prof = G.gyro_static(duration_s=600.0, sample_rate_hz=10.0)
    a = model.simulate(prof, np.random.default_rng(4))
    b = model.simulate(prof, np.random.default_rng(4))
    c = model.simulate(prof, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_wrong_protocol_for_sensor() -> None:
    with pytest.raises(ValueError, match="is for a gyro, not a msra"):
        msra_unit(0).model.simulate(G.gyro_static(60.0, sample_rate_hz=1.0), np.random.default_rng(0))


def test_removing_effects() -> None:
    model = gyro_unit(0).model
    quiet = model.without("white_noise", "bias_instability", "quantisation")
    assert quiet.effect("white_noise") is None and quiet.effect("thermal_lag") is not None
    prof = G.gyro_static(duration_s=100.0, sample_rate_hz=10.0)
    y = quiet.simulate(prof, np.random.default_rng(0))
    assert np.ptp(y) == pytest.approx(0.0, abs=1e-12)  # constant temperature, no noise
