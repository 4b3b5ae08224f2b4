"""Which effects the model misses: greedy forward selection on held-out error.

Each round tries every effect not yet in the model at every value of its grid, scoring

    gain = (SSE_heldout(model) - SSE_heldout(model + effect)) / v - 2 * extra parameters

(the held-out SSE from blocked cross-validation with blocks sized to the recording,
:mod:`tcbench.diagnose.select.plan`; ``v`` the variance of the noise along the added signal: white
output noise plus the thermometer's noise carried through the model; the ``2`` per parameter is
Akaike's penalty; the numbers, thresholds, penalty, share of the excess and most effects, are
:class:`~tcbench.diagnose.settings.SelectionSettings`). The effect with the largest gain is kept
when its gain exceeds ``threshold`` and it is significant against the residual's slow noise, by the strongest test the recording
supports (the :class:`~tcbench.diagnose.select.significance.SignificanceTest` its plan holds):

- with enough clusters, a Wald statistic with a variance robust to slow noise (cluster scores
  with Bartlett-weighted neighbours, never above the known-noise Wald) above
  the Wald threshold; both thresholds are checked on recordings with nothing missing
  (``experiments/diagnose-concealed/calibrate.py``);
- with few clusters (a short recording), or when the effect removes at least half of the
  held-out error above the noise and the Wald test still rejects it (its cluster variance then
  counts the structure still unexplained as noise), the spectral surrogate test of
  :mod:`tcbench.diagnose.select.surrogate` at p <= its level.

Each effect's evidence says which test decided. Its nonlinear parameter is then refined
between its grid neighbours. After the forward pass each kept effect must still earn its place,
and when the residual turns out to hold flicker, :func:`recheck_with_flicker` tests the kept
effects again with that flicker in the noise model. Pairs that look alike (docs/concepts/physics.md, the effect library) are
tested by swapping one for the other: when the swap costs less than the threshold the
recording cannot tell them apart, and the report says which test would.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from tcbench.diagnose.select.crossval import Fit, block_folds, fit_cv, robust_wald
from tcbench.diagnose.select.design import Designer, Model, deterministic, grid_values
from tcbench.diagnose.select.discover import best_open
from tcbench.diagnose.select.evidence import Evidence, not_significant
from tcbench.diagnose.select.plan import StatsPlan, plan_for
from tcbench.diagnose.select.significance import SURROGATE, SignificanceTest
from tcbench.diagnose.select.surrogate import surrogate_test
from tcbench.diagnose.select.thermometer_noise import thermometer_variance
from tcbench.diagnose.settings import (
    DEFAULTS,
    DiagnoseSettings,
    SelectionSettings,
    SurrogateSettings,
)
from tcbench.diagnose.terms import confusable_pairs, is_open, open_term, term
from tcbench.sensors.noise import flicker_score_variance

# the refinement of a term's parameter between its best grid neighbours, on the log scale: 0.02
# in ln(value) is the value to 2 %, finer than any term's parameter is determined by a record
REFINE_XATOL = 0.02



@dataclass
class Attribution:
    """Outcome of :func:`attribute`: the final model and its fit, the baseline's fit, the
    per-effect evidence and the confusable pairs ``(kept, alternative, test that would tell)``,
    and the settings it was made with."""

    base: Model
    final: Model
    base_fit: Fit
    final_fit: Fit
    evidence: dict[str, Evidence]
    confusions: list[tuple[str, str, str]]
    designer: Designer
    fold: np.ndarray
    k: int
    plan: StatsPlan | None = None
    settings: DiagnoseSettings = DEFAULTS


class _Scorer:
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
        if model not in self._memo:
            x = self.designer.matrix(model)
            self._memo[model] = fit_cv(x, self.designer.data.output, self.fold, self.k)
        return self._memo[model]

    def _noise(self, base: Model, model: Model) -> tuple[float, float]:
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
        white, total = self._noise(base, model)
        drop = (self.fit(base).sse_heldout - self.fit(model).sse_heldout) / self.sigma2
        share = white / total if total > 0 else 1.0
        return drop * share - self.selection.penalty_sigma2_per_param * (model.n_params - base.n_params)

    def wald(self, base: Model, model: Model) -> float:
        """Robust Wald statistic (cluster covariance), never above the one with the known
        white-plus-thermometer variance."""
        robust = robust_wald(self.fit(base), self.fit(model), self.cluster, self.selection.wald_lags)
        z = self.fit(base).residual - self.fit(model).residual
        known = float(z @ self.fit(base).residual) ** 2 / max(self._noise(base, model)[1], 1e-300)
        return min(robust, known)

    def surrogate_p(self, base: Model, effect: str, value: Any, searched: list[Any] | None,
                    settings: SurrogateSettings) -> float:
        """p-value of adding ``effect`` to ``base`` by the surrogate test of ``settings``,
        searched over its grid (or the values ``searched``) and ``value``; the noise model is the
        residual of ``base`` plus ``effect`` at ``value``."""
        grid = grid_values(effect) if searched is None else list(searched)
        values = [*grid, *([value] if value is not None and value not in grid else [])]
        xs = [self.designer.matrix(base.with_effect(effect, v)) for v in values]
        noise = self.fit(base.with_effect(effect, value)).residual
        p, _ = surrogate_test(self.designer.matrix(base), xs, self.designer.data.output, noise, self.rng, settings)
        return p

    def removes_most(self, base: Model, model: Model) -> bool:
        """Whether ``model`` removes at least the selection's ``most_of_excess`` of the held-out
        squared error that ``base`` leaves above the white noise."""
        excess = self.fit(base).sse_heldout - self.designer.data.n * self.sigma2
        drop = self.fit(base).sse_heldout - self.fit(model).sse_heldout
        return excess > 0 and drop >= self.selection.most_of_excess * excess

    def significant(self, base: Model, effect: str, value: Any, test: SignificanceTest,
                    searched: list[Any] | None = None) -> tuple[bool, float, float, str]:
        """Whether adding ``effect`` at ``value`` to ``base`` is significant against slow noise by
        ``test``: ``(passed, robust Wald, surrogate p-value, name of the test that decided)``."""
        wald = self.wald(base, base.with_effect(effect, value))
        return test.judge(self, base, effect, value, wald, searched)

    def best(self, base: Model, effect: str) -> tuple[float, float | None]:
        """Best gain of adding ``effect`` to ``base`` over its grid, then refined."""
        values = grid_values(effect)
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


def attribute(
    designer: Designer,
    base: Model | None = None,
    *,
    settings: DiagnoseSettings = DEFAULTS,
    plan: StatsPlan | None = None,
    open_world: bool = True,
    open_threshold: float | None = None,
) -> Attribution:
    """Forward selection of the library's deterministic effects onto ``base`` (see module doc),
    its thresholds, penalty and most effects ``settings.selection``, the surrogate test's
    generator seeded with ``settings.surrogate.seed``; ``plan`` the blocks, clusters and test
    (default: sized to the recording by :func:`~tcbench.diagnose.select.plan.plan_for`); with
    ``open_world`` the terms of :mod:`tcbench.diagnose.select.discover` compete with the library's
    effects in every round, kept above ``open_threshold`` (default the selection's)."""
    selection = settings.selection
    threshold, max_effects = selection.detection_threshold_sigma2, selection.max_effects
    open_threshold = selection.open_threshold_sigma2 if open_threshold is None else open_threshold
    base = base or Model()
    data = designer.data
    plan = plan or plan_for(data, settings)
    k = plan.k
    fold = block_folds(data.t_s, plan.block_s, k)
    cluster = np.floor((data.t_s - data.t_s[0]) / plan.cluster_s).astype(np.int64)
    scorer = _Scorer(designer, fold, k, cluster, selection, np.random.default_rng(settings.surrogate.seed))
    evidence: dict[str, Evidence] = {}
    candidates = deterministic()
    for effect in candidates:
        if effect in base.ids:
            evidence[effect] = Evidence(effect, "in the model", reason="declared in the starting model")
        elif (why := designer.why_not_identifiable(effect)) is not None:
            evidence[effect] = Evidence(effect, "not identifiable", reason=why)
    model = base
    while len(model.ids) - len(base.ids) < max_effects:
        open_effects = [e for e in candidates if e not in evidence or evidence[e].status == "rejected"]
        open_effects = [e for e in open_effects if e not in model.ids]
        if not open_effects and not open_world:
            break
        tried = {e: scorer.best(model, e) for e in open_effects}
        beyond = (best_open(scorer, model, evidence, plan.test, open_threshold, settings.detectors) if open_world
                  else None)
        for e, (g, v) in tried.items():
            if g <= threshold:
                evidence[e] = Evidence(e, "rejected", g, threshold, v, "held-out gain below the threshold",
                                       wald=scorer.wald(model, model.with_effect(e, v)))
        passing = []
        for e in (e for e in tried if tried[e][0] > threshold):
            g, v = tried[e]
            ok, wald, p, test = scorer.significant(model, e, v, plan.test)
            evidence[e] = Evidence(e, "rejected", g, threshold, v, not_significant(plan.test, test, p), wald=wald,
                                   test=test, p_value=p)
            if ok:
                passing.append(e)
        if beyond is not None:
            tried[beyond[0]] = beyond[1:]
            passing.append(beyond[0])
        if not passing:
            break
        winner = max(passing, key=lambda e: tried[e][0])
        gain, value = tried[winner]
        model = model.with_effect(winner, value)
        evidence[winner].status, evidence[winner].reason = "kept", "held-out gain above the threshold"
    for effect in [e for e in model.ids if e not in base.ids]:  # backward check
        reduced = model.without(effect)
        cost = scorer.gain(reduced, model)
        value = _value(model, effect)
        searched = [value] if is_open(effect) else None
        ok, wald, p, test = (scorer.significant(reduced, effect, value, plan.test, searched)
                             if cost > (open_term(effect).gain_threshold(open_threshold) if is_open(effect) else threshold) else (False, scorer.wald(reduced, model), float("nan"), plan.test.name))
        if not ok:
            model = reduced
            evidence[effect].status = "rejected"
            evidence[effect].reason = "superseded: the other kept effects explain what it did"
        else:
            ev = evidence[effect]
            ev.gain, ev.wald, ev.p_value, ev.test = cost, wald, p, test
            ev.value = None if is_open(effect) else value  # an open-world term's values are in its params
    confusions = _confusions(scorer, model, base, evidence, threshold)
    return Attribution(base, model, scorer.fit(base), scorer.fit(model), evidence, confusions,
                       designer, fold, k, plan, settings)


def _value(model: Model, effect: str) -> float | None:
    if term(effect).transforms_temperature:
        return model.lag_tau_s
    return dict(model.terms).get(effect)


def _confusions(
    scorer: _Scorer, model: Model, base: Model, evidence: dict[str, Evidence], threshold: float
) -> list[tuple[str, str, str]]:
    out = []
    for kept in [e for e in model.ids if e not in base.ids]:
        for pair, test in confusable_pairs().items():
            if kept not in pair:
                continue
            (other,) = pair - {kept}
            if other in model.ids or evidence.get(other, Evidence(other, "")).status == "not identifiable":
                continue
            reduced = model.without(kept)
            swap_gain, _ = scorer.best(reduced, other)
            keep_gain = scorer.gain(reduced, model)
            if keep_gain - swap_gain <= threshold:
                out.append((kept, other, test))
                evidence[kept].confusable_with.append(other)
    return out


def recheck_with_flicker(att: Attribution, b: float,
                         flicker_of: Callable[[Model, Fit], float | None] | None = None,
                         structure_remains: Callable[[float], bool] | None = None) -> Attribution:
    """Backward elimination of the kept effects with flicker of coefficient ``b`` (found in the
    final residual) in the noise model: the weakest effect whose Wald statistic with that flicker
    is at or below the selection's Wald threshold (``att.settings``) is dropped, the flicker is
    measured again on the residual of what remains (``flicker_of(model, fit)``, its ``b`` or None
    once the residual shows none) and every remaining effect judged again against it, until each
    one passes. A slow random excursion of the bias can look like a warm-up, a trend or a step.
    An effect is not dropped where the model without it has the held-out RMSE at which
    ``structure_remains`` (the reference's deterministic structure is not flicker).

    The variance of each effect's score under that flicker is its exact expectation over the
    flicker's draws (:func:`~tcbench.sensors.noise.flicker_score_variance`); it was the mean over
    16 seeded draws, whose ratio to the expectation spreads as chi-squared with 16 degrees of
    freedom over 16 (a kept trend was rejected by the seed's luck once six of 93 035 samples were
    deleted). The elimination was one pass in the model's order against the flicker of the full
    model's residual, and both let a stand-in survive (issue 46, a 25 h 1 Hz chamber record with a
    20-min gap): a step at 71 553 s read 9.8 with the other kept effects in the model, but was
    judged after a warm-up and a second step had been dropped, and then read above 25; and the
    effects dropped had taken up part of the flicker, so the flicker the report named (b 5.6e-5 g
    without the gap, 6.3e-5 with it) was larger than the one the remaining effects were judged
    against (4.2e-5): the trend kept on the record without the gap read 25.7 against the smaller
    flicker and 15.6 against the one named."""
    data = att.designer.data
    wald_threshold = att.settings.selection.wald_threshold
    cluster = np.zeros(data.n, dtype=np.int64)  # the robust test is not used here
    scorer = _Scorer(att.designer, att.fold, att.k, cluster, att.settings.selection)
    dt_s = float(np.median(np.diff(data.t_s)))
    model = att.final

    def wald(effect: str, flicker_b: float) -> float:
        reduced = model.without(effect)
        z = scorer.fit(reduced).residual - scorer.fit(model).residual
        var_flicker = flicker_score_variance(z, dt_s, flicker_b)
        return float(z @ scorer.fit(reduced).residual) ** 2 / (scorer._noise(reduced, model)[1] + var_flicker)

    while True:
        judged = [e for e in model.ids if e not in att.base.ids and att.evidence[e].test != SURROGATE]
        # a surrogate test's null noise already had the residual's whole spectrum, flicker included
        scores = sorted((wald(e, b), e) for e in judged)
        weakest = next(((w, e) for w, e in scores if w <= wald_threshold and not (
            structure_remains is not None and structure_remains(
                float(np.sqrt(scorer.fit(model.without(e)).sse_heldout / data.n))))), None)
        if weakest is None:
            break
        model = model.without(weakest[1])
        ev = att.evidence[weakest[1]]
        ev.status, ev.wald = "rejected", weakest[0]
        ev.reason = ("explained as well by the flicker found in the residual (Wald with flicker in the noise "
                     "model below the threshold); a second power-on or a longer run would tell")
        found = flicker_of(model, scorer.fit(model)) if flicker_of is not None else b
        if found is None:
            break
        b = found
    if model == att.final:
        return att
    return replace(att, final=model, final_fit=scorer.fit(model))
