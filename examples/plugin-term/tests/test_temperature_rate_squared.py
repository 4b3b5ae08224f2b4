"""The plugin's own tests: the effect's formula, and tcbench finding both entry points."""

import numpy as np

from tcbench.diagnose.terms import term, term_source
from tcbench.sensors.effects import Signals, effect_class, make_effect
from tcbench_rate2.temperature_rate_squared import TemperatureRateSquared, TemperatureRateSquaredTerm


def test_even_in_the_rate() -> None:
    rate = np.array([-2.0, -1.0, 0.0, 1.0, 2.0]) / 60.0  # degC/s
    z = np.zeros(5)
    s = Signals(t_s=np.arange(5.0), dt_s=1.0, temp_meas_c=z, temp_die_c=z, temp_rate_c_per_s=rate,
                accel_g=z, cross_g=z, rate_dps=z)
    y = TemperatureRateSquared(coef_per_c2_per_min2=0.5).term(s, np.random.default_rng(0))
    np.testing.assert_allclose(y, [2.0, 0.5, 0.0, 0.5, 2.0])


def test_registered() -> None:
    assert effect_class("temperature_rate_squared") is TemperatureRateSquared
    assert make_effect("temperature_rate_squared", coef_per_c2_per_min2=1).coef_per_c2_per_min2 == 1.0
    assert isinstance(term("temperature_rate_squared"), TemperatureRateSquaredTerm)
    assert term_source("temperature_rate_squared") == "tcbench-rate2"
