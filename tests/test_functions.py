"""Function values at known points, domains and optima."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.tasks import functions as fn
from tcbench.tasks.functions import FUNCTIONS


@pytest.mark.parametrize("key", sorted(FUNCTIONS))
@pytest.mark.parametrize("dim", [2, 5, 30])
def test_value_at_optimum(key: str, dim: int) -> None:
    f = FUNCTIONS[key]
    x = np.full((1, dim), f.x_opt)
    expected = -1.0 if key == "schaffer" else 0.0
    assert f.fn(x)[0] == pytest.approx(expected, abs=1e-9)
    assert f.f_opt(dim) == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("key", sorted(FUNCTIONS))
def test_optimum_is_minimum_over_random_points(key: str) -> None:
    f = FUNCTIONS[key]
    rng = np.random.default_rng(0)
    x = rng.uniform(f.lower, f.upper, size=(20000, 3 if f.min_dim <= 3 else f.min_dim))
    assert np.all(f.fn(x) >= f.f_opt(x.shape[1]) - 1e-12)


def test_hand_worked_values() -> None:
    x = np.array([[1.0, 2.0]])
    assert fn.sphere(x)[0] == 5.0
    # Rastrigin: 20 + (1 - 10 cos 2pi) + (4 - 10 cos 4pi) = 20 - 9 - 6 = 5
    assert fn.rastrigin(x)[0] == pytest.approx(5.0)
    # Rastrigin at 0.5: 10 + 0.25 - 10 cos(pi) = 20.25
    assert fn.rastrigin(np.array([[0.5]]))[0] == pytest.approx(20.25)
    # Rosenbrock (1, 2): 100 (2 - 1)^2 + 0 = 100
    assert fn.rosenbrock(x)[0] == pytest.approx(100.0)
    # Griewank at (pi, 0): 1 + pi^2/4000 - cos(pi) cos(0) = 2 + pi^2/4000
    assert fn.griewank(np.array([[np.pi, 0.0]]))[0] == pytest.approx(2 + np.pi**2 / 4000)
    # Ackley at (1, 0): -20 e^{-0.2 sqrt(1/2)} - e^{(cos 2pi + cos 0)/2} + 20 + e = 20 - 20 e^{-0.1414}
    assert fn.ackley(np.array([[1.0, 0.0]]))[0] == pytest.approx(20 - 20 * np.exp(-0.2 * np.sqrt(0.5)))
    # Schaffer on the ring r = pi: sin^2 = 0, so g = -0.5/(1 + 0.001 pi^2)^2 - 0.5
    r = np.pi / np.sqrt(2)
    assert fn.schaffer(np.array([[r, r]]))[0] == pytest.approx(-0.5 / (1 + 1e-3 * np.pi**2) ** 2 - 0.5)
    # Schaffer at r = pi/2: sin^2 = 1 -> 0.5/(1 + 0.001 pi^2/4)^2 - 0.5
    assert fn.schaffer(np.array([[np.pi / 2, 0.0]]))[0] == pytest.approx(0.5 / (1 + 1e-3 * np.pi**2 / 4) ** 2 - 0.5)
    # Levy at the origin, d = 1 term structure: w = 0.75
    w = 0.75
    expected = np.sin(np.pi * w) ** 2 + (w - 1) ** 2 * (1 + np.sin(2 * np.pi * w) ** 2)
    assert fn.levy(np.array([[0.0]]))[0] == pytest.approx(expected)
    # Schwefel at the origin: d * 418.9829 (the offset)
    assert fn.schwefel(np.zeros((1, 2)))[0] == pytest.approx(2 * 418.98288727, rel=1e-9)


def test_batch_matches_rows() -> None:
    rng = np.random.default_rng(1)
    x = rng.uniform(-5, 5, size=(7, 4))
    for f in FUNCTIONS.values():
        batch = f.fn(x)
        rows = np.array([f.fn(r[None, :])[0] for r in x])
        np.testing.assert_allclose(batch, rows, rtol=1e-12)


def test_unknown_function_names_known_ones() -> None:
    with pytest.raises(KeyError, match="known: ackley"):
        fn.get_function("nope")


def test_schwefel_shift_box_keeps_optimum_global() -> None:
    """Leftward shifts up to 0.2 half-width: no reachable point beats the optimum (1-D grid)."""
    f = FUNCTIONS["schwefel"]
    low, high = f.shift_box()
    z = np.linspace(f.lower - high, f.upper - low, 400001)[:, None]
    assert f.fn(z).min() >= -1e-9
