"""The polynomial model: exact recovery of cubic b(T) and K(T), validation, the auto form."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.learners import create
from tcbench.learners.polynomial import AUTO_ERROR, PolynomialModel, PolynomialParams


def _cubic_sensor(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Temperature (degC), applied input (g) and output (Hz) of ``U = b(T) + K(T) a`` with
    cubic b and K, no noise."""
    rng = np.random.default_rng(seed)
    temp_c = rng.uniform(-40.0, 60.0, n)
    accel_g = rng.choice([-1.0, 0.0, 1.0], n) + rng.uniform(-0.1, 0.1, n)
    dt = temp_c - 25.0
    bias_hz = 150.0 - 0.16 * dt + 2e-4 * dt**2 - 3e-6 * dt**3
    k_hz_per_g = 200.0 * (1.0 + 2e-4 * dt - 1e-6 * dt**2 + 5e-9 * dt**3)
    return temp_c, accel_g, bias_hz + k_hz_per_g * accel_g


def test_inverse_form_recovers_target_exactly() -> None:
    temp_c, accel_g, out_hz = _cubic_sensor()
    model = PolynomialModel(2, {"degree": 3, "form": "inverse"})
    history = model.fit(np.c_[out_hz, temp_c], accel_g)
    assert history.stopped == "closed_form" and history.iterations == 1
    assert history.loss[0] < 1e-20
    assert model.n_params == 8 and model.get_params().shape == (8,)
    test_t, test_a, test_u = _cubic_sensor(100, seed=1)
    np.testing.assert_allclose(model.predict(np.c_[test_u, test_t]), test_a, atol=1e-9)


def test_bias_form_recovers_target_exactly_and_ignores_other_columns() -> None:
    temp_c, _, _ = _cubic_sensor()
    dt = temp_c - 25.0
    target_hz = 150.0 - 0.16 * dt + 2e-4 * dt**2 - 3e-6 * dt**3
    rate = np.random.default_rng(2).normal(0.0, 0.01, temp_c.size)
    model = create("poly", 2, {"degree": 3, "form": "bias"})
    history = model.fit(np.c_[temp_c, rate], target_hz)
    assert history.loss[0] < 1e-20 and model.n_params == 4
    np.testing.assert_allclose(model.predict(np.c_[temp_c, rate]), target_hz, atol=1e-9)
    np.testing.assert_allclose(model.predict(np.c_[temp_c, rate * 0.0]), target_hz, atol=1e-9)


def test_params_round_trip() -> None:
    temp_c, accel_g, out_hz = _cubic_sensor()
    model = PolynomialModel(2, {"form": "inverse", "degree": 2})
    model.fit(np.c_[out_hz, temp_c], accel_g)
    coef = model.get_params()
    before = model.predict(np.c_[out_hz, temp_c])
    model.set_params(coef * 1.01)
    assert not np.allclose(model.predict(np.c_[out_hz, temp_c]), before)
    model.set_params(coef)
    np.testing.assert_allclose(model.predict(np.c_[out_hz, temp_c]), before)
    with pytest.raises(ValueError, match="expected 6 parameters"):
        model.set_params(coef[:-1])


@pytest.mark.parametrize("degree", [0, 7, 2.5, True])
def test_degree_validation(degree: object) -> None:
    with pytest.raises(ValueError, match="degree"):
        PolynomialParams(degree=degree, form="bias")  # type: ignore[arg-type]


def test_form_validation_and_auto_error() -> None:
    with pytest.raises(ValueError, match="form must be one of"):
        PolynomialModel(2, {"form": "forward"})
    with pytest.raises(ValueError, match="2 inputs"):
        PolynomialModel(3, {"form": "inverse"})
    model = PolynomialModel(2)
    assert model.settings.form == "auto"
    temp_c, accel_g, out_hz = _cubic_sensor(20)
    with pytest.raises(ValueError) as info:
        model.fit(np.c_[out_hz, temp_c], accel_g)
    assert str(info.value) == AUTO_ERROR


def test_no_coefficients_before_fit() -> None:
    model = PolynomialModel(2, {"form": "inverse"})
    for call in (lambda: model.n_params, model.get_params, lambda: model.set_params(np.zeros(8)),
                 lambda: model.predict(np.zeros((3, 2)))):
        with pytest.raises(RuntimeError, match="after fit"):
            call()
    assert not model.searchable


def test_inverse_form_needs_a_varying_target() -> None:
    temp_c, _, out_hz = _cubic_sensor(50)
    model = PolynomialModel(2, {"form": "inverse"})
    with pytest.raises(ValueError, match="not determined"):
        model.fit(np.c_[out_hz, temp_c], np.zeros_like(temp_c))


@pytest.mark.parametrize("form", ["bias", "inverse"])
def test_per_run_offsets_recover_the_shape_the_runs_share(form: str) -> None:
    """Three power-ons, each at its own ambient with its own turn-on bias (0, +3, -2 Hz): pooled, the
    cubic bends to the offsets; fitted within runs it recovers the shared shape exactly, up to the
    mean offset (+1/3 Hz)."""
    rng = np.random.default_rng(3)
    temps = [rng.uniform(lo, lo + 6.0, 300) for lo in (10.0, 20.0, 30.0)]
    offsets_hz = (0.0, 3.0, -2.0)
    accel = [rng.choice([-1.0, 0.0, 1.0], 300) for _ in temps]
    bias = [150.0 - 0.16 * (t - 25) + 2e-4 * (t - 25) ** 2 + o for t, o in zip(temps, offsets_hz, strict=True)]
    k = 200.0
    outputs = [b + k * a for b, a in zip(bias, accel, strict=True)]
    runs = np.repeat(np.arange(3), 300)
    temp_c = np.concatenate(temps)
    if form == "bias":
        x, y = np.c_[temp_c, temp_c * 0.0], np.concatenate(bias)
        truth = 150.0 - 0.16 * (temp_c - 25) + 2e-4 * (temp_c - 25) ** 2 + 1.0 / 3.0
    else:
        x, y = np.c_[np.concatenate(outputs), temp_c], np.concatenate(accel)
        truth = (x[:, 0] - (150.0 - 0.16 * (temp_c - 25) + 2e-4 * (temp_c - 25) ** 2 + 1.0 / 3.0)) / k
    within = create("poly", 2, {"degree": 3, "form": form, "offsets": "per_run"})
    assert within.uses_runs
    within.fit(x, y, runs=runs)
    np.testing.assert_allclose(within.predict(x), truth, atol=1e-8)
    pooled = create("poly", 2, {"degree": 3, "form": form})
    pooled.fit(x, y)
    assert np.max(np.abs(pooled.predict(x) - truth)) > 0.1 * (1.0 if form == "bias" else 1.0 / k)
    with pytest.raises(ValueError, match="needs the run of each training row"):
        create("poly", 2, {"degree": 3, "form": form, "offsets": "per_run"}).fit(x, y)
    with pytest.raises(ValueError, match="offsets must be one of shared, per_run"):
        PolynomialParams(offsets="each")
