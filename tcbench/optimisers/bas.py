"""Beetle antennae search (BAS), seed 001 §3.4.2, eq. 30-33 (Jiang & Li 2017).

A beetle at ``x_t`` draws a random unit direction ``b`` (eq. 30), smells with its two antennae
``x_l = x_t - d_t b`` and ``x_r = x_t + d_t b`` (eq. 31), steps ``lambda_t`` along ``b`` toward the
better-smelling antenna (eq. 32), and both lengths shrink (eq. 33):
``d_{t+1} = 0.95 d_t + 0.01``, ``lambda_{t+1} = 0.95 lambda_t``.

**Sign of eq. 32.** As printed, ``x_{t+1} = x_t + lambda_t b sign(f(x_r) - f(x_l))`` moves toward
``x_r`` when ``f(x_r) > f(x_l)``: toward the *higher* value, which is right for the paper's
"information intensity" (maximisation) but wrong for its MSE fitness (eq. 36) and for tcbench,
which minimises. This module implements the minimising form
``x_{t+1} = x_t - lambda_t b sign(f(x_r) - f(x_l)) = x_t + lambda_t b sign(f(x_l) - f(x_r))``,
i.e. the beetle moves toward the antenna with the LOWER value. Equal values, including two
non-finite ones (both ``inf`` after the base class maps NaN/inf to ``inf``), give sign 0: the
beetle stays put for that iteration.

Choices where the paper is silent (parameters in :class:`BASParams`):

- **Units.** Eq. 31-33 use absolute lengths fitted to the paper's own problem (Elman network
  weights, domain not stated). Here ``d`` and ``lambda`` are fractions of the domain width and are
  applied per axis: ``x +- d (w * b)`` with ``w = upper - lower``. On a cubic box of width ``W``
  this is eq. 31-32 with absolute lengths ``d W`` and ``lambda W``; on a non-cubic box it is BAS
  run in the box rescaled to the unit cube.
- **The additive 0.01 of eq. 33** is ``d_floor_fraction`` (a fraction of the width). The paper's
  absolute 0.01 on a domain of width ``W`` maps to ``d_floor_fraction = 0.01 / W`` (9.8e-4 on
  Rastrigin's ``[-5.12, 5.12]``). It is not a floor that ``d`` stops at: the recursion converges
  geometrically to ``d_inf = d_floor_fraction / (1 - d_decay)`` -- 20 times the term, i.e. 0.2
  absolute units for the paper's constants -- and the antennae stay that far from the beetle for
  ever, which caps the precision of the best antenna (on the sphere ``f >= (d_inf W)^2``). The
  default is 0 (``d`` decays geometrically like ``lambda``; ``d / lambda`` stays ``d0 / step0``):
  in the tuning runs a floor of 1e-4 worsened the 10-D sphere 2-30x with no consistent gain on
  Rastrigin, and 0.01 left the sphere at ~1.
- **Decay rate.** The paper decays once per iteration (``decay_every = 1``). With 0.95 the step
  halves every ~13.5 iterations and the beetle's total path is bounded by
  ``lambda_0 / (1 - 0.95) = 20 lambda_0``; in ``n`` dimensions a random direction has only a
  ``~sqrt(2 / (pi n))`` component along the descent direction, so in 10-D the beetle freezes after
  ~200 iterations whatever the budget (10-D sphere median ~25 from ~85 at the start, budgets 1000
  and 10000 alike). ``decay_every = k`` applies eq. 33 once every ``k`` iterations, stretching the
  same sequence of lengths over ``k`` times as many iterations. The default ``None`` picks
  ``k = max(1, round(iterations / 100))`` with ``iterations = budget // (2 population)`` (or
  ``max_generations`` if smaller): eq. 33 is applied ~100 times per run, so the final step is
  ``0.95^100 = 0.6 %`` of ``step0`` whatever the budget. Below 150 iterations (300 evaluations
  for one beetle) this is the paper's schedule.
- **Direction (eq. 30).** ``rands(n, 1)`` is uniform on ``[-1, 1]^n``; normalised, it is *not*
  isotropic: directions crowd toward the cube's diagonals (the corners hold more volume), more so
  as ``n`` grows. ``direction = "gaussian"`` (default) normalises a standard normal vector, which is
  exactly uniform on the unit sphere; ``direction = "uniform"`` is the paper's ``rands``.
- **Initial position**: uniform in the box ("position of the center of mass", §3.4.4 step 2).
- **What is evaluated.** One iteration asks exactly the ``2 x population`` antennae (rows
  ``2i`` = left, ``2i + 1`` = right antenna of beetle ``i``), as the paper compares only antennae.
  The beetle's position is never evaluated for the move; best-so-far (kept by the base class) is
  therefore the best antenna told. Antennae and positions are clamped to the box (as seed 000's
  eq. 11 does); a clamped antenna pair is no longer symmetric about ``x_t`` but the comparison is
  still between two feasible points.
- **Population.** ``population = 1`` is the paper's single beetle. ``population = p > 1`` runs
  ``p`` independent beetles in one batch (own positions and directions, shared ``d``/``lambda``
  schedule, no information exchanged): a restart-in-parallel swarm, not a cooperative one.
- **Budget.** An iteration costs ``2 p`` evaluations, so the budget must be at least ``2 p``
  (checked at construction). When fewer than ``2 p`` remain, the last iteration moves only the
  first ``remaining // 2`` beetles; if then a single evaluation is left it is spent on the
  position of the beetle whose last antennae were best (a look the paper never takes, but the
  only useful one-point query). Each of these counts as a generation, so the budget is always
  spent exactly.

Defaults ``d0 = 0.2``, ``step0 = 0.1`` (fractions of the width), ``d_floor_fraction = 0``,
``decay_every = None`` come from a small grid (d0 in {0.05, 0.1, 0.2, 0.3, 0.5}, step0 in
{0.05, 0.1, 0.2}, floor in {0, 1e-4, 1e-2}, decay_every in {1 .. 100}) on the 10-D sphere and
Rastrigin in ``[-5.12, 5.12]^10`` (budgets 1000 and 10000, 6-10 seeds, one beetle). Medians with
the defaults: sphere 1.5e-4 / 7e-5, Rastrigin 42 / 22 (budget 1000 / 10000); 2-D, budget 1000:
sphere 3e-5, Rastrigin 1.0. Larger antennae (d0 = 0.3-0.5) smooth Rastrigin's ripples (median
down to 15 / 7.6) at 2-5x worse sphere precision; 0.2 is the compromise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams, make_params

DIRECTIONS = ("gaussian", "uniform")
AUTO_DECAYS = 100  # eq. 33 applications per run when decay_every is None: 0.95^100 = 0.6 %


@dataclass(frozen=True)
class BASParams(OptimiserParams):
    """BAS parameters. Lengths are fractions of the domain width (per axis).

    population: number of independent beetles, >= 1 (1 = the paper's single beetle).
    d0: initial antenna length d_0 of eq. 31, in (0, 1].
    step0: initial step lambda_0 of eq. 32, in (0, 1].
    d_decay: factor on d in eq. 33 (paper 0.95), in (0, 1].
    d_floor_fraction: additive term of eq. 33 as a fraction of the width (paper: 0.01 in absolute
        units, i.e. 0.01 / W on a domain of width W), >= 0; d tends to
        ``d_floor_fraction / (1 - d_decay)``.
    step_decay: factor on lambda in eq. 33 (paper 0.95), in (0, 1].
    decay_every: apply eq. 33 once every this many iterations (paper: 1), >= 1; None: spread
        ``AUTO_DECAYS`` = 100 applications over the iterations the budget allows.
    direction: "gaussian" (isotropic, default) or "uniform" (the paper's normalised rands).
    max_generations: stop after this many iterations (None: run until the budget is spent).
    """

    population: int = 1
    d0: float = 0.2
    step0: float = 0.1
    d_decay: float = 0.95
    d_floor_fraction: float = 0.0
    step_decay: float = 0.95
    decay_every: int | None = None
    direction: str = "gaussian"
    max_generations: int | None = None

    def __post_init__(self) -> None:  # BAS allows a single beetle: no call to the base check
        if self.population < 1:
            raise ValueError(f"population must be >= 1, got {self.population}")
        if not 0 < self.d0 <= 1:
            raise ValueError(f"d0 must be in (0, 1] (fraction of the width), got {self.d0}")
        if not 0 < self.step0 <= 1:
            raise ValueError(f"step0 must be in (0, 1] (fraction of the width), got {self.step0}")
        if not 0 < self.d_decay <= 1:
            raise ValueError(f"d_decay must be in (0, 1], got {self.d_decay}")
        if not self.d_floor_fraction >= 0:
            raise ValueError(f"d_floor_fraction must be >= 0, got {self.d_floor_fraction}")
        if self.d_decay == 1 and self.d_floor_fraction > 0:
            raise ValueError("d_decay = 1 with d_floor_fraction > 0 makes d grow without bound")
        if not 0 < self.step_decay <= 1:
            raise ValueError(f"step_decay must be in (0, 1], got {self.step_decay}")
        if self.decay_every is not None and self.decay_every < 1:
            raise ValueError(f"decay_every must be >= 1, got {self.decay_every}")
        if self.direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {DIRECTIONS}, got {self.direction!r}")
        if self.max_generations is not None and self.max_generations < 1:
            raise ValueError(f"max_generations must be >= 1, got {self.max_generations}")


def random_directions(
    n: int, dim: int, rng: np.random.Generator, kind: str = "gaussian"
) -> np.ndarray:
    """Eq. 30: ``n`` unit rows ``b = r / ||r||``, ``r`` standard normal ("gaussian", isotropic)
    or uniform on ``[-1, 1]^dim`` ("uniform", the paper's ``rands``). A zero draw (probability 0)
    stays zero, i.e. no move."""
    if kind == "gaussian":
        r = rng.standard_normal((n, dim))
    elif kind == "uniform":
        r = rng.uniform(-1.0, 1.0, size=(n, dim))
    else:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {kind!r}")
    norm = np.linalg.norm(r, axis=1, keepdims=True)
    return r / np.where(norm > 0, norm, 1.0)


def antennae(x: np.ndarray, b: np.ndarray, d: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 31: left and right antennae ``x - d b`` and ``x + d b`` (``d`` a scalar or per-axis
    lengths broadcast against ``b``)."""
    offset = d * b
    return x - offset, x + offset


def move_sign(f_left: np.ndarray, f_right: np.ndarray) -> np.ndarray:
    """``sign(f(x_l) - f(x_r))`` for minimisation (eq. 32 with its sign flipped, see the module
    docstring): +1 toward the right antenna when it is lower, -1 toward the left, 0 on ties
    (``inf`` vs ``inf`` included)."""
    f_left, f_right = np.asarray(f_left), np.asarray(f_right)
    return (f_right < f_left).astype(np.float64) - (f_left < f_right).astype(np.float64)


def beetle_step(
    x: np.ndarray,
    b: np.ndarray,
    step: np.ndarray | float,
    f_left: np.ndarray,
    f_right: np.ndarray,
) -> np.ndarray:
    """Eq. 32 (minimising): ``x + step b sign(f(x_l) - f(x_r))`` row-wise, moving by ``step``
    toward the antenna with the lower value."""
    return x + step * b * move_sign(f_left, f_right)[..., None]


def decay(
    d: float, step: float, d_decay: float, d_floor: float, step_decay: float
) -> tuple[float, float]:
    """Eq. 33: ``d <- d_decay d + d_floor`` and ``step <- step_decay step`` (paper 0.95, 0.01,
    0.95)."""
    return d_decay * d + d_floor, step_decay * step


class BeetleAntennaeSearch(Optimiser):
    """Beetle antennae search, ``population`` independent beetles per ask/tell (eq. 30-33)."""

    name = "bas"
    Params = BASParams
    params: BASParams

    def __init__(
        self,
        lower: np.ndarray,
        upper: np.ndarray,
        budget: int,
        rng: np.random.Generator,
        params: OptimiserParams | dict[str, Any] | None = None,
        n_objectives: int = 1,
    ) -> None:
        checked = make_params(type(self), params)
        if int(budget) != budget or budget < 2 * checked.population:
            raise ValueError(
                f"budget of {budget} evaluations is smaller than one BAS iteration "
                f"(2 antennae x population {checked.population} = {2 * checked.population})"
            )
        super().__init__(lower, upper, budget, rng, checked, n_objectives)
        p = self.params
        self.width = self.upper - self.lower
        iterations = self.budget // (2 * p.population)
        if p.max_generations is not None:
            iterations = min(iterations, p.max_generations)
        self.decay_every = p.decay_every or max(1, round(iterations / AUTO_DECAYS))
        self.d = p.d0  # fractions of the width
        self.step = p.step0
        self.x = self.uniform(p.population)
        self.fitness = np.full(p.population, np.inf)  # best antenna of each beetle, last look
        self._b = np.empty((0, self.dim))

    def _stopped(self) -> bool:
        limit = self.params.max_generations
        return limit is not None and self.generation >= limit

    def _ask(self) -> np.ndarray:
        k = min(self.params.population, self.remaining // 2)
        if k == 0:  # one evaluation left: look at the most promising beetle itself
            self._b = np.empty((0, self.dim))
            return self.x[[int(np.argmin(self.fitness))]]
        self._b = random_directions(k, self.dim, self.rng, self.params.direction)  # eq. 30
        left, right = antennae(self.x[:k], self._b, self.d * self.width)  # eq. 31
        return self.clip(np.stack([left, right], axis=1).reshape(2 * k, self.dim))

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        p = self.params
        k = len(self._b)
        if k > 0:
            f_left, f_right = f[0::2], f[1::2]
            moved = beetle_step(self.x[:k], self._b, self.step * self.width, f_left, f_right)
            self.x[:k] = self.clip(moved)  # eq. 32, clamped
            self.fitness[:k] = np.minimum(f_left, f_right)
        self.generation += 1
        if self.generation % self.decay_every == 0:  # eq. 33
            self.d, self.step = decay(
                self.d, self.step, p.d_decay, p.d_floor_fraction, p.step_decay
            )
