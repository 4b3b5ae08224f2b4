"""Single-objective test functions, vectorised over a batch of candidates.

Every function takes ``x`` of shape ``(n, d)`` and returns ``(n,)`` objective values
(minimisation). Each is described by an :class:`ObjectiveFunction` record that documents its
default domain, its global optimum, and the box inside which a per-instance shift may move the
optimum while it stays the global minimum over the (fixed) domain.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tcbench.errors import unknown_name

Array = np.ndarray


def sphere(x: Array) -> Array:
    """Sphere: sum(x_i^2); minimum 0 at the origin."""
    return np.einsum("ij,ij->i", x, x)


def rastrigin(x: Array) -> Array:
    """Rastrigin: 10 d + sum(x_i^2 - 10 cos(2 pi x_i)); minimum 0 at the origin."""
    return 10.0 * x.shape[1] + np.sum(x * x - 10.0 * np.cos(2.0 * np.pi * x), axis=1)


def _schaffer_pair(a: Array, b: Array) -> Array:
    r2 = a * a + b * b
    return (np.sin(np.sqrt(r2)) ** 2 - 0.5) / (1.0 + 1e-3 * r2) ** 2 - 0.5


def schaffer(x: Array) -> Array:
    """Schaffer F6 written with a minimum of -1 at the origin, as in seed 000 §2.2.3.

    For two dimensions ``g(x, y) = (sin^2 sqrt(x^2 + y^2) - 0.5) / (1 + 0.001 (x^2 + y^2))^2 - 0.5``.
    For ``d > 2`` it is the mean of ``g`` over consecutive pairs ``(x_i, x_{i+1})``, so the
    minimum stays -1 at the origin for every dimension.
    """
    return np.mean(_schaffer_pair(x[:, :-1], x[:, 1:]), axis=1)


def rosenbrock(x: Array) -> Array:
    """Rosenbrock: sum(100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2); minimum 0 at (1, ..., 1)."""
    head, tail = x[:, :-1], x[:, 1:]
    return np.sum(100.0 * (tail - head * head) ** 2 + (1.0 - head) ** 2, axis=1)


def ackley(x: Array) -> Array:
    """Ackley (a=20, b=0.2, c=2 pi); minimum 0 at the origin."""
    d = x.shape[1]
    term1 = -20.0 * np.exp(-0.2 * np.sqrt(np.einsum("ij,ij->i", x, x) / d))
    term2 = -np.exp(np.mean(np.cos(2.0 * np.pi * x), axis=1))
    # Guard the exact optimum against a -1 ulp result from exp/e cancellation.
    return np.maximum(term1 + term2 + 20.0 + np.e, 0.0)


def griewank(x: Array) -> Array:
    """Griewank: 1 + sum(x_i^2)/4000 - prod(cos(x_i / sqrt(i))); minimum 0 at the origin."""
    i = np.arange(1, x.shape[1] + 1, dtype=float)
    return 1.0 + np.einsum("ij,ij->i", x, x) / 4000.0 - np.prod(np.cos(x / np.sqrt(i)), axis=1)


SCHWEFEL_X_OPT = 420.968746359982025
_SCHWEFEL_OFFSET = SCHWEFEL_X_OPT * np.sin(np.sqrt(SCHWEFEL_X_OPT))


def schwefel(x: Array) -> Array:
    """Schwefel 2.26 offset so the minimum is 0: sum(c - x_i sin(sqrt|x_i|)), x_i* = 420.9687.

    The offset ``c = x* sin(sqrt(x*))`` (= 418.98288727...) is computed, not rounded, so the
    value at the optimum is 0 to rounding error.
    """
    return np.sum(_SCHWEFEL_OFFSET - x * np.sin(np.sqrt(np.abs(x))), axis=1)


def levy(x: Array) -> Array:
    """Levy: w = 1 + (x - 1)/4; minimum 0 at (1, ..., 1)."""
    w = 1.0 + (x - 1.0) / 4.0
    head, last = w[:, :-1], w[:, -1]
    body = np.sum((head - 1.0) ** 2 * (1.0 + 10.0 * np.sin(np.pi * head + 1.0) ** 2), axis=1)
    tail = (last - 1.0) ** 2 * (1.0 + np.sin(2.0 * np.pi * last) ** 2)
    return np.sin(np.pi * w[:, 0]) ** 2 + body + tail


@dataclass(frozen=True)
class ObjectiveFunction:
    """A test function with its documented domain, optimum and admissible shift box.

    ``shift_low`` / ``shift_high`` bound the per-coordinate displacement of the optimum that
    keeps it the global minimum over the domain (see :func:`shift_box`).
    """

    key: str
    title: str
    fn: Callable[[Array], Array]
    lower: float
    upper: float
    x_opt: float
    min_dim: int = 1
    shift_low: float = -0.4
    shift_high: float = 0.4

    def f_opt(self, dim: int) -> float:
        """Objective value at the global optimum in ``dim`` dimensions."""
        return float(self.fn(np.full((1, dim), self.x_opt))[0])

    def shift_box(self) -> tuple[float, float]:
        """Displacement range for the optimum, in domain units."""
        half = 0.5 * (self.upper - self.lower)
        return self.shift_low * half, self.shift_high * half


FUNCTIONS: dict[str, ObjectiveFunction] = {
    f.key: f
    for f in (
        ObjectiveFunction("sphere", "Sphere", sphere, -5.12, 5.12, 0.0),
        ObjectiveFunction("rastrigin", "Rastrigin", rastrigin, -5.12, 5.12, 0.0),
        ObjectiveFunction("schaffer", "Schaffer F6 (min -1)", schaffer, -100.0, 100.0, 0.0, 2),
        # The optimum at 1 sits off-centre in [-5, 10]; keep it inside when shifted.
        ObjectiveFunction("rosenbrock", "Rosenbrock", rosenbrock, -5.0, 10.0, 1.0, 2),
        ObjectiveFunction("ackley", "Ackley", ackley, -32.768, 32.768, 0.0),
        ObjectiveFunction("griewank", "Griewank", griewank, -600.0, 600.0, 0.0),
        # x* = 420.97 lies near the upper edge. Moving it right would bring z = x - shift
        # below -500 into reach, where values fall below 0; so only leftward shifts, at most
        # 0.2 of the half-width, which keep every reachable z in (-500, 600] (checked in tests).
        ObjectiveFunction(
            "schwefel", "Schwefel 2.26", schwefel, -500.0, 500.0, SCHWEFEL_X_OPT,
            shift_low=-0.2, shift_high=0.0,
        ),
        ObjectiveFunction("levy", "Levy", levy, -10.0, 10.0, 1.0),
    )
}


def get_function(key: str) -> ObjectiveFunction:
    """Look up a function by key; unknown keys raise ``KeyError`` naming the known ones."""
    try:
        return FUNCTIONS[key]
    except KeyError:
        raise KeyError(unknown_name("function", key, sorted(FUNCTIONS))) from None
