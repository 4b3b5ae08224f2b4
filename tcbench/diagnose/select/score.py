"""Fit a model, score a candidate: what the forward selection asks of one recording.

:class:`Scorer` holds the recording's design (:class:`~tcbench.diagnose.select.design.Designer`),
its blocked folds and clusters, and answers the selection's three questions about adding an
effect to a model, each from memoised held-out fits (:func:`~tcbench.diagnose.select.crossval.fit_cv`):

- how much it gains (:meth:`Scorer.gain`, :meth:`Scorer.best` over the effect's grid, refined):
  the held-out SSE drop in units of the noise variance along the added signal (white output
  noise plus the thermometer's noise the model inherits,
  :func:`~tcbench.diagnose.select.thermometer_noise.thermometer_variance`) minus Akaike's penalty;
- whether it is significant (:meth:`Scorer.significant`, by the plan's
  :class:`~tcbench.diagnose.select.significance.SignificanceTest`, which asks back for
  :meth:`Scorer.removes_most` and :meth:`Scorer.surrogate_p`);
- its Wald statistic with flicker in the noise model (:meth:`Scorer.flicker_wald`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from tcbench.diagnose.select.crossval import Fit, fit_cv, robust_wald
from tcbench.diagnose.select.design import Designer, Model
from tcbench.diagnose.select.significance import SignificanceTest
from tcbench.diagnose.select.surrogate import surrogate_test
from tcbench.diagnose.select.thermometer_noise import thermometer_variance
from tcbench.diagnose.settings import DEFAULTS, SelectionSettings, SurrogateSettings
from tcbench.diagnose.terms import term
from tcbench.sensors.noise import flicker_score_variance

# the refinement of a term's parameter between its best grid neighbours, on the log scale: 0.02
# in ln(value) is the value to 2 %, finer than any term's parameter is determined by a record
REFINE_XATOL = 0.02


class Scorer:
    """Held-out fits of models on one recording, memoised; gains penalised and excess judged
    as ``selection`` says, surrogates drawn from ``rng``."""

    def __init__(self, designer: Designer, fold: np.ndarray, k: int, cluster: np.ndarray,
                 selection: SelectionSettings = DEFAULTS.selection, rng: np.random.Generator | None = None) -> None:
        self.designer, self.fold, self.k, self.cluster = designer, fold, k, cluster
        self.selection = selection
        self.rng = rng if rng is not None else np.random.default_rng(DEFAULTS.surrogate.seed)
        self.sigma2 = designer.data.white_sigma**2
        self._memo: dict[Model, Fit] = {}
        self._noise_memo: dict[tuple[Model, Model], tuple[float, float]] = {}

    def fit(self, model: Model) -> Fit:
        """The held-out fit of ``model`` (memoised)."""
        if model not in self._memo:
            x = self.designer.matrix(model)
            self._memo[model] = fit_cv(x, self.designer.data.output, self.fold, self.k)
        return self._memo[model]

    def noise(self, base: Model, model: Model) -> tuple[float, float]:
        """Variance of the added signal's score under white output noise alone, and with the
        thermometer noise the model inherits."""
        key = (base, model)
        if key not in self._noise_memo:
            z = self.fit(base).residual - self.fit(model).residual
            white = self.sigma2 * float(z @ z)
            total = white + thermometer_variance(self.designer, model, self.fit(model).beta, z)
            self._noise_memo[key] = (white, total)
        return self._noise_memo[key]

    def gain(self, base: Model, model: Model) -> float:
        """Held-out SSE drop in units of the noise variance along the added signal (white plus
        thermometer), minus the parameter penalty."""
        white, total = self.noise(base, model)
        drop = (self.fit(base).sse_heldout - self.fit(model).sse_heldout) / self.sigma2
        share = white / total if total > 0 else 1.0
        return drop * share - self.selection.penalty_sigma2_per_param * (model.n_params - base.n_params)

    def best(self, base: Model, effect: str) -> tuple[float, float | None]:
        """Best gain of adding ``effect`` to ``base`` over its grid, then refined."""
        values = term(effect).grid_values()
        gains = [self.gain(base, base.with_effect(effect, v)) for v in values]
        i = int(np.argmax(gains))
        if values[i] is None:
            return gains[i], None
        lo, hi = np.log(values[max(i - 1, 0)]), np.log(values[min(i + 1, len(values) - 1)])  # type: ignore[arg-type]
        if i == len(values) - 1 and (top := term(effect).past_grid(self.designer.data)) is not None:
            hi = max(hi, float(np.log(top)))  # best at the grid's edge: search on, as far as the term allows
        res = minimize_scalar(lambda z: -self.gain(base, base.with_effect(effect, float(np.exp(z)))),
                              bounds=(lo, hi), method="bounded", options={"xatol": REFINE_XATOL})
        if -res.fun > gains[i]:
            return float(-res.fun), float(np.exp(res.x))
        return gains[i], values[i]

    def wald(self, base: Model, model: Model) -> float:
        """Robust Wald statistic (cluster covariance), never above the one with the known
        white-plus-thermometer variance."""
        robust = robust_wald(self.fit(base), self.fit(model), self.cluster, self.selection.wald_lags)
        z = self.fit(base).residual - self.fit(model).residual
        known = float(z @ self.fit(base).residual) ** 2 / max(self.noise(base, model)[1], 1e-300)
        return min(robust, known)

    def significant(self, base: Model, effect: str, value: Any, test: SignificanceTest,
                    searched: list[Any] | None = None) -> tuple[bool, float, float, str]:
        """Whether adding ``effect`` at ``value`` to ``base`` is significant against slow noise by
        ``test``: ``(passed, robust Wald, surrogate p-value, name of the test that decided)``."""
        wald = self.wald(base, base.with_effect(effect, value))
        return test.judge(self, base, effect, value, wald, searched)

    def removes_most(self, base: Model, model: Model) -> bool:
        """Whether ``model`` removes at least the selection's ``most_of_excess`` of the held-out
        squared error that ``base`` leaves above the white noise."""
        excess = self.fit(base).sse_heldout - self.designer.data.n * self.sigma2
        drop = self.fit(base).sse_heldout - self.fit(model).sse_heldout
        return excess > 0 and drop >= self.selection.most_of_excess * excess

    def surrogate_p(self, base: Model, effect: str, value: Any, searched: list[Any] | None,
                    settings: SurrogateSettings) -> float:
        """p-value of adding ``effect`` to ``base`` by the surrogate test of ``settings``,
        searched over its grid (or the values ``searched``) and ``value``; the noise model is the
        residual of ``base`` plus ``effect`` at ``value``."""
        grid = term(effect).grid_values() if searched is None else list(searched)
        values = [*grid, *([value] if value is not None and value not in grid else [])]
        xs = [self.designer.matrix(base.with_effect(effect, v)) for v in values]
        noise = self.fit(base.with_effect(effect, value)).residual
        p, _ = surrogate_test(self.designer.matrix(base), xs, self.designer.data.output, noise, self.rng, settings)
        return p

    def flicker_wald(self, base: Model, model: Model, b: float) -> float:
        """Wald statistic of what ``model`` adds to ``base`` with flicker of coefficient ``b`` in
        the noise model beside the white and thermometer noise (its exact expected score variance,
        :func:`~tcbench.sensors.noise.flicker_score_variance`)."""
        data = self.designer.data
        z = self.fit(base).residual - self.fit(model).residual
        var_flicker = flicker_score_variance(z, float(np.median(np.diff(data.t_s))), b)
        return float(z @ self.fit(base).residual) ** 2 / (self.noise(base, model)[1] + var_flicker)
