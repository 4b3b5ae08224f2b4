"""Which effects the model misses: greedy forward selection on held-out error.

Each round tries every effect not yet in the model at every value of its grid, scoring
each (:class:`~tcbench.diagnose.select.score.Scorer`: fit a model, score a candidate) by

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

import numpy as np

from tcbench.diagnose.select.crossval import Fit, block_folds
from tcbench.diagnose.select.design import Designer, Model, deterministic
from tcbench.diagnose.select.discover import best_open
from tcbench.diagnose.select.evidence import Evidence, not_significant
from tcbench.diagnose.select.plan import StatsPlan, plan_for
from tcbench.diagnose.select.score import Scorer
from tcbench.diagnose.select.significance import SURROGATE
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings
from tcbench.diagnose.terms import confusable_pairs, is_open, open_term, term


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
    scorer = Scorer(designer, fold, k, cluster, selection, np.random.default_rng(settings.surrogate.seed))
    evidence: dict[str, Evidence] = {}
    candidates = deterministic()
    for effect in candidates:
        if effect in base.ids:
            evidence[effect] = Evidence(effect, "in the model", reason="declared in the starting model")
        elif (why := term(effect).skip(data)) is not None:  # the recording cannot show it at all
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
    scorer: Scorer, model: Model, base: Model, evidence: dict[str, Evidence], threshold: float
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
    scorer = Scorer(att.designer, att.fold, att.k, cluster, att.settings.selection)
    model = att.final
    while True:
        judged = [e for e in model.ids if e not in att.base.ids and att.evidence[e].test != SURROGATE]
        # a surrogate test's null noise already had the residual's whole spectrum, flicker included
        scores = sorted((scorer.flicker_wald(model.without(e), model, b), e) for e in judged)
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
