"""The terms of the diagnosis (tcbench.diagnose.terms): one term per library effect the diagnosis
models and one per open-world structure, each column the simulator's formula, a consistent registry."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from tcbench.compensation.fitted_model import CLOCK_EFFECTS, RIG_EFFECTS
from tcbench.datasets.concealed import EFFECTS_BY_SENSOR
from tcbench.diagnose.findings import WHERE_KEYS, check_finding
from tcbench.diagnose.select.design import Designer, Model, deterministic
from tcbench.diagnose.signals import DiagnosisData, lagged
from tcbench.diagnose.terms import (
    OpenTerm,
    Term,
    confusable_pairs,
    is_open,
    is_term,
    open_finding,
    report_order,
    temperature_transform,
    term,
    terms,
)
from tcbench.diagnose.terms.base import signals
from tcbench.sensors.effects import EFFECTS, Signals, make_effect, repeatable_effects
from tcbench.sensors.truth import STOCHASTIC_EFFECTS

COLUMN_TERMS = [t.id for t in terms() if t.deterministic and not t.transforms_temperature]
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
    assert not {t.id for t in terms(open=True)} & {t.id for t in terms()}  # a library term or an open-world one


def test_every_repeatable_effect_is_an_open_world_term_in_the_registry() -> None:
    open_ids = [t.id for t in terms(open=True)]
    assert set(open_ids) == set(repeatable_effects())
    assert open_ids == ["bias_step", "transient", "periodic", "gated_periodic", "duty_cycle", "temperature_bump",
                        "second_node"]  # the order of a round's search and of the "not tested" reasons
    assert report_order() == ("bias_step", "periodic", "gated_periodic", "duty_cycle", "transient",
                              "temperature_bump", "second_node")  # the report's candidates: by shape
    for t in terms(open=True):
        assert isinstance(t, OpenTerm) and t.open_world and is_open(t.id) and EFFECTS[t.id] is t.effect
        assert t.n_params(None) == t.n_coef + len(t.value_names)
    assert not any(is_open(t.id) for t in terms())


def test_ids_unique_and_a_second_registration_refused() -> None:
    ids = [t.id for t in terms()]
    assert len(ids) == len(set(ids))
    with pytest.raises(ValueError, match="registered twice"):
        type("Again", (type(term("warmup")),), {})  # a subclass keeping the id registers it again
    assert [t.id for t in terms()] == ids


def test_order_is_the_forward_selection_and_report_order() -> None:
    # the one literal list of the library's terms, a guard on the registry's order (the tests
    # elsewhere read their term lists from the registry)
    assert deterministic() == ("thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift",
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


def test_the_designer_asks_the_term_that_transforms_the_temperature(monkeypatch: pytest.MonkeyPatch) -> None:
    """``thermal_lag`` is an input transform: a model holding it runs on the term's model
    temperature (the die lag), with its one parameter; no other term transforms the temperature."""
    assert [t.id for t in (*terms(), *terms(open=True)) if t.transforms_temperature] == ["thermal_lag"]
    lag = temperature_transform()
    assert lag is term("thermal_lag")
    d = _data()
    np.testing.assert_array_equal(Designer(d).temperature(600.0), lagged(d.t_s, d.temp_c, 600.0))
    model = Model().with_effect("warmup", 900.0).with_effect("thermal_lag", 600.0)
    assert model.lag_tau_s == 600.0 and model.ids == ("thermal_lag", "warmup") and model.n_params == 1 + 2
    assert model.without("thermal_lag") == Model().with_effect("warmup", 900.0)
    monkeypatch.setattr(type(lag), "model_temperature", lambda self, data, value: data.temp_c + value)
    des = Designer(d)
    np.testing.assert_array_equal(des.temperature(2.0), d.temp_c + 2.0)
    u = (d.temp_c + 2.0 - des.centre_c) / des.half_range_c
    np.testing.assert_array_equal(des.matrix(Model(lag_tau_s=2.0))[:, 1], u)
    with pytest.raises(ValueError, match="does not transform"):
        term("warmup").model_temperature(d, 1.0)


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
    assert pairs
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
    assert "only rises faster than 0.05 degC/min" in str(term("hysteresis").skip(rising))
    assert term("thermal_lag").skip(rising) is None
    still = dataclasses.replace(rising, rate_c_per_s=np.zeros(n))
    for effect in ("thermal_lag", "temperature_rate"):
        assert "never moves faster than 0 degC/min" in str(term(effect).skip(still))


def test_a_slow_heat_and_cool_is_refused_for_its_rate_not_as_one_way() -> None:
    """Issue 46: a 25 h record heating and cooling at 0.02 degC/min was refused hysteresis because
    "the temperature only moves one way", though it moves both ways: too slowly to count."""
    n = 3600
    t_s = np.arange(n, dtype=float)
    rate_c_per_s = np.where(t_s < n / 2, 0.02, -0.02) / 60.0
    temp_c = 20.0 + np.cumsum(rate_c_per_s)
    d = _data()
    slow = dataclasses.replace(d, t_s=t_s, temp_c=temp_c, rate_c_per_s=rate_c_per_s, input=d.input[:n],
                               temp_raw_c=temp_c)
    for effect in ("hysteresis", "thermal_lag", "temperature_rate"):
        why = str(term(effect).skip(slow))
        assert "never moves faster than 0.02 degC/min" in why and "at least 0.05 degC/min" in why
        assert "one way" not in why


def test_unknown_ids_are_refused() -> None:
    assert not is_term("no_such_effect") and not is_open("no_such_effect")
    with pytest.raises(KeyError, match="known: thermal_lag"):
        term("no_such_effect")
    for unknown in ("bias_step_4", "bias_step_1", "hysteresis_2"):  # only further instances of an open-world term
        assert not is_term(unknown)
        with pytest.raises(KeyError):
            term(unknown)


def test_further_instances_are_their_open_world_term() -> None:
    step = term("bias_step")
    assert term("bias_step_2") is step and term("bias_step_3") is step and is_open("transient_2")
    assert step.free_id(()) == "bias_step"
    assert step.free_id(("warmup", "bias_step")) == "bias_step_2"
    assert step.free_id(("bias_step", "bias_step_2")) == "bias_step_3"
    assert step.free_id(("bias_step", "bias_step_2", "bias_step_3")) is None


def test_noise_and_rig_tuples_come_from_the_effect_classes() -> None:
    assert set(STOCHASTIC_EFFECTS) == {"white_noise", "bias_instability", "random_walk", "quantisation",
                                       "noise_temperature", "noise_time"}
    assert set(RIG_EFFECTS) == {"periodic", "gated_periodic", "duty_cycle"}
    assert set(CLOCK_EFFECTS) == {"bias_step", "transient", "warmup", "aging_drift"}
    assert all(issubclass(type(t), Term) for t in terms())


def test_every_parameter_of_a_term_has_its_unit() -> None:
    """Each fitted parameter of a library term (and the amplitudes of the open-world ones) is in
    the report with a unit: its name says it (``_s``, ``_c``) or the term's ``units`` does."""
    for t in terms():
        for name in t.params(0.5, t.grid_values()[0], 20.0):
            said = name.endswith(("_s", "_c")) and not name.endswith("_per_s")
            assert said or t.unit_of(name, "g") is not None, (t.id, name)
    assert term("temperature_rate").unit_of("coef_per_c_per_s", "deg/s") == "deg/s per degC/s"
    assert term("periodic").unit_of("amplitude", "Hz") == "Hz" and term("periodic").unit_of("phase_rad", "Hz") is None
    assert [t.id for t in (*terms(), *terms(open=True)) if t.gain_name] == ["bias_instability"]
    assert all(not t.deterministic for t in terms() if t.gain_name) and term("bias_instability").gain_label


def test_the_docs_effect_table_lists_the_registrys_terms_in_order() -> None:
    """docs/concepts/physics.md, the effect library: its table lists every library term, in the
    registry's order, before the effects the diagnosis does not model as a term."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "concepts" / "physics.md").read_text()
    table = text.split("## The effect library", 1)[1].split("\n\n")[2]
    rows = [line.split("|")[1].strip().strip("`") for line in table.splitlines()[2:]]
    ids = [t.id for t in terms()]
    assert rows[:len(ids)] == ids
    assert not set(rows[len(ids):]) & {t.id for t in (*terms(), *terms(open=True))}


# Each open-world term at a value, with the coefficients of a fit; ``exact``: its columns are the
# simulator's formula to the last bit (the second node lags on the diagnosis's time grid, the
# effect at the mean sample interval; a line's cosine is the effect's sine a quarter cycle on).
OPEN_CASES = {
    "bias_step": ((3000.0,), [0.8], True),
    "transient": ((2000.0, 600.0), [-1.3], True),
    "periodic": ((900.0,), [0.4, -0.25], False),
    "gated_periodic": ((600.0, 1500.0, 5000.0), [0.3, 1.0, -0.5, 0.2, 0.1, -0.1, 0.05, 0.0, 0.0, 0.02, -0.01], True),
    "duty_cycle": ((600.0, 70.0, 0.35, 1500.0, 5000.0), [-0.3, 0.8], True),
    "temperature_bump": ((30.0, 4.0), [0.7], True),
    "second_node": ((900.0,), [0.2], False),
}


def test_every_open_world_term_has_a_case() -> None:
    assert set(OPEN_CASES) == {t.id for t in terms(open=True)}


@pytest.mark.parametrize("effect", list(OPEN_CASES))
def test_open_world_columns_are_the_simulators_effect(effect: str) -> None:
    """Each column is the output term the simulator adds for the term's parameters with that
    column's coefficient 1 and the others 0 (to the last bit where the formula is shared)."""
    d = _data()
    t = term(effect)
    value, coef, exact = OPEN_CASES[effect]
    assert isinstance(t, OpenTerm) and len(value) == len(t.value_names) and len(coef) == t.n_coef
    cols = t.columns(d, value, d.temp_c)
    assert cols.shape == (d.t_s.size, t.n_coef)
    s = signals(d, d.temp_c)
    for j in range(t.n_coef):
        unit = t.params(np.eye(t.n_coef)[j], value)
        simulated = make_effect(effect, **unit).term(s, np.random.default_rng(0))
        if exact:
            np.testing.assert_array_equal(cols[:, j], simulated)
        else:
            np.testing.assert_allclose(cols[:, j], simulated, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(Designer(d).columns(effect, value, None), cols)  # the design's columns are the term's


@pytest.mark.parametrize("effect", list(OPEN_CASES))
def test_open_world_params_round_trip_through_the_simulator(effect: str) -> None:
    """The fitted coefficients and value, as :meth:`OpenTerm.params` reports them, simulate the
    columns times the coefficients, and the columns fitted to that give the same parameters back."""
    d = _data()
    t = term(effect)
    value, coef, _ = OPEN_CASES[effect]
    assert isinstance(t, OpenTerm)
    cols = t.columns(d, value, d.temp_c)
    params = t.params(np.asarray(coef), value)
    assert tuple(params[name] for name in t.value_names) == value
    fx = make_effect(effect, **params)  # model.yaml reads it back
    assert set(params) <= {f.name for f in dataclasses.fields(fx)}
    simulated = fx.term(signals(d, d.temp_c), np.random.default_rng(0))
    np.testing.assert_allclose(cols @ np.asarray(coef), simulated, rtol=1e-9, atol=1e-9)
    back, *_ = np.linalg.lstsq(cols, simulated, rcond=None)
    assert t.params(back, value) == pytest.approx(params, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("effect", list(OPEN_CASES))
def test_open_world_finding_follows_the_report_contract(effect: str) -> None:
    d = _data()
    t = term(effect)
    value, coef, _ = OPEN_CASES[effect]
    assert isinstance(t, OpenTerm)
    params = t.params(np.asarray(coef), value)
    assert set(t.where(params=params)) <= set(WHERE_KEYS) and t.where() == {}
    entry = open_finding(f"{effect}_2", params, {"gain_sigma2": 40.0}, d.unit)
    check_finding(entry)
    assert entry["id"] == f"{effect}_2" and entry["shape"] == t.shape and entry["library"] is False
    assert entry["explanation"] == t.explanation(params, d.unit) and entry["confirm_with"] == t.confirm_with
    assert entry["where"] == t.where(params=params) and d.unit in entry["explanation"]
