"""The library terms of the diagnosis (tcbench.diagnose.terms): one term per library effect the
diagnosis models, each column the simulator's formula, a consistent registry."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np
import pytest

from tcbench.datasets.concealed import EFFECTS_BY_SENSOR
from tcbench.diagnose.attribute import CONFUSABLE
from tcbench.diagnose.design import DETERMINISTIC, Designer
from tcbench.diagnose.open_terms import TERMS as OPEN_TERMS
from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms import Term, confusable_pairs, is_term, term, terms
from tcbench.diagnose.terms.base import signals
from tcbench.sensors.effects import EFFECTS, Signals, make_effect
from tcbench.sensors.truth import STOCHASTIC_EFFECTS
from tcbench.compensation.fitted_model import RIG_EFFECTS

COLUMN_TERMS = [t.id for t in terms() if t.deterministic and t.id != "thermal_lag"]
VALUES = {"hysteresis": 1.5, "warmup": 900.0}


def _data(n: int = 7200, levels: tuple[float, ...] = (1.0, 0.0, -1.0, 0.0), seed: int = 0) -> DiagnosisData:
    """A 1 Hz record heating and cooling through 10..50 degC with an input cycling through ``levels``."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    temp = 30.0 + 20.0 * np.sin(2.0 * np.pi * t / 3600.0) + 0.01 * rng.standard_normal(n)
    rate = np.gradient(temp, t)
    inp = np.asarray(levels, dtype=float)[(t // 90).astype(int) % len(levels)]
    return DiagnosisData("msra", "Hz", t, temp, temp, rate, inp, np.zeros(n), np.zeros(n, dtype=int), 1.0, 1.0, 0.0)


def test_every_library_effect_the_diagnosis_models_has_exactly_one_term() -> None:
    modelled = {e for effects in EFFECTS_BY_SENSOR.values() for e in effects}
    assert {t.id for t in terms()} == modelled
    for t in terms():
        assert EFFECTS[t.id] is t.effect  # the term is that effect of the library, not a look-alike
    assert len({t.effect for t in terms()}) == len(terms())
    assert not set(OPEN_TERMS) & {t.id for t in terms()}  # an id is either a library term or an open-world one


def test_ids_unique_and_a_second_registration_refused() -> None:
    ids = [t.id for t in terms()]
    assert len(ids) == len(set(ids))
    with pytest.raises(ValueError, match="registered twice"):
        type("Again", (type(term("warmup")),), {})  # a subclass keeping the id registers it again
    assert [t.id for t in terms()] == ids


def test_order_is_the_forward_selection_and_report_order() -> None:
    assert DETERMINISTIC == ("thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift",
                             "temperature_cubic", "accel_nonlinearity")
    assert [t.id for t in terms() if not t.deterministic] == ["bias_instability"]


@pytest.mark.parametrize("effect", COLUMN_TERMS)
def test_column_times_its_coefficient_is_the_simulators_effect(effect: str) -> None:
    """The fitted coefficient and value, as :meth:`Term.params` reports them, rebuild through
    ``make_effect`` the same output term the simulator adds (at the scaling's centre)."""
    d = _data()
    des = Designer(d)
    t = term(effect)
    value = VALUES.get(effect)
    coef = -0.37
    col = t.column(d, value, d.temp_c, des.centre_c, des.half_range_c)
    params = t.params(coef, value, des.half_range_c)
    fx = make_effect(effect, **params)
    s: Signals = dataclasses.replace(signals(d, d.temp_c), ref_c=des.centre_c)
    np.testing.assert_allclose(coef * col, fx.term(s, np.random.default_rng(0)), rtol=1e-12, atol=1e-12)
    assert set(params) <= {f.name for f in dataclasses.fields(fx)}
    if t.param:
        assert params[t.param] == value


def test_the_design_column_is_the_terms() -> None:
    d = _data()
    des = Designer(d)
    for effect in COLUMN_TERMS:
        value = VALUES.get(effect)
        expected = term(effect).column(d, value, d.temp_c, des.centre_c, des.half_range_c)
        np.testing.assert_array_equal(des.columns(effect, value, None)[:, 0], expected)
    with pytest.raises(ValueError, match="no regressor"):
        term("thermal_lag").column(d, 600.0, d.temp_c, des.centre_c, des.half_range_c)


def test_grids_and_parameter_names() -> None:
    for t in terms():
        assert (t.grid is None) == (t.param is None)
        if t.grid is not None:
            assert np.all(np.diff(t.grid) > 0) and t.param in {f.name for f in dataclasses.fields(t.effect)}
            assert t.grid_values() == list(t.grid)
        else:
            assert t.grid_values() == [None]


def test_confusable_pairs_are_symmetric_and_name_registered_terms() -> None:
    pairs = confusable_pairs()
    assert pairs == CONFUSABLE and pairs
    for t in terms():
        partners: Mapping[str, str] = t.partners()
        assert t.id not in partners
        for other, test in partners.items():
            assert is_term(other) and term(other).deterministic
            assert term(other).partners()[t.id] == test  # symmetric, same separating test
            assert pairs[frozenset({t.id, other})] == test
    declared = sum(len(t.confusable) for t in terms())
    assert declared == len(pairs)  # each pair declared on one side only


def test_skip_reasons_where_the_recording_cannot_show_the_effect() -> None:
    d = _data()
    assert all(t.skip(d) is None for t in terms())
    two = _data(levels=(1.0, -1.0))
    assert "square term needs at least three" in str(term("accel_nonlinearity").skip(two))
    n = 3600
    t_s = np.arange(n, dtype=float)
    rising = dataclasses.replace(d, t_s=t_s, temp_c=10.0 + t_s / 60.0, rate_c_per_s=np.full(n, 1 / 60.0),
                                 input=d.input[:n], temp_raw_c=10.0 + t_s / 60.0)
    assert "only moves one way" in str(term("hysteresis").skip(rising))
    assert term("thermal_lag").skip(rising) is None
    still = dataclasses.replace(rising, rate_c_per_s=np.zeros(n))
    for effect in ("thermal_lag", "temperature_rate"):
        assert "never changes faster" in str(term(effect).skip(still))
        assert Designer(still).why_not_identifiable(effect) == term(effect).skip(still)


def test_unknown_ids_are_refused() -> None:
    assert not is_term("bias_step")
    with pytest.raises(KeyError, match="known: thermal_lag"):
        term("bias_step")


def test_noise_and_rig_tuples_come_from_the_effect_classes() -> None:
    assert set(STOCHASTIC_EFFECTS) == {"white_noise", "bias_instability", "random_walk", "quantisation",
                                       "noise_temperature", "noise_time"}
    assert set(RIG_EFFECTS) == {"periodic", "gated_periodic", "duty_cycle"}
    assert all(issubclass(type(t), Term) for t in terms())
