"""Which effects the model misses: greedy forward selection on held-out error.

Each round tries every effect not yet in the model at every value of its grid, scoring

    gain = (SSE_heldout(model) - SSE_heldout(model + effect)) / v - 2 * extra parameters

(the held-out SSE from blocked cross-validation; ``v`` the variance of the noise along the
added signal: white output noise plus the thermometer's noise carried through the model; the
``2`` per parameter is Akaike's penalty). The effect with the largest gain is kept when its gain
exceeds ``threshold`` and a Wald statistic with a variance robust to slow noise (cluster scores
with Bartlett-weighted neighbours, never above the known-noise Wald) exceeds
``wald_threshold``; both are checked on recordings with nothing missing
(``experiments/diagnose-concealed/calibrate.py``). Its nonlinear parameter is then refined
between its grid neighbours. After the forward pass each kept effect must still earn its place,
and when the residual turns out to hold flicker, :func:`recheck_with_flicker` tests the kept
effects again with that flicker in the noise model. Pairs that look alike (PHYSICS.md §3) are
tested by swapping one for the other: when the swap costs less than the threshold the
recording cannot tell them apart, and the report says which test would.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import minimize_scalar

from tcbench.diagnose.crossval import Fit, block_folds, fit_cv, robust_wald
from tcbench.diagnose.design import DETERMINISTIC, Designer, Model, grid_values
from tcbench.diagnose.thermometer import thermometer_variance
from tcbench.sensors.noise import flicker

PENALTY_PER_PARAM = 2.0
DETECTION_THRESHOLD = 10.0  # gain in units of sigma^2; see experiments/diagnose-concealed/calibrate.py
WALD_THRESHOLD = 25.0  # cluster-robust Wald statistic; same calibration
CLUSTER_S = (300.0, 900.0)  # clusters of the robust variance: duration / 32, within these bounds
CONFUSABLE: dict[frozenset[str], str] = {
    frozenset({"thermal_lag", "temperature_rate"}): (
        "soaks of at least five die time constants after fast ramps: a lagging die keeps drifting "
        "into the soak, a thermal-gradient term stops with the ramp"),
    frozenset({"hysteresis", "thermal_lag"}): (
        "soaks at one temperature approached from above and from below, each long enough to settle: "
        "a lag dies out during the soak, hysteresis persists"),
    frozenset({"hysteresis", "temperature_rate"}): (
        "soaks at one temperature approached from above and from below: a gradient term is zero "
        "during a soak, hysteresis is not"),
    frozenset({"warmup", "aging_drift"}): (
        "a longer run or a power cycle: warm-up settles within the hour after power-on, ageing keeps going"),
    frozenset({"aging_drift", "temperature_cubic"}): (
        "a profile that revisits the same temperatures hours apart: ageing follows time, a cubic follows temperature"),
}


@dataclass
class Evidence:
    """How one effect fared: ``status`` is ``kept``, ``rejected`` or ``not identifiable``;
    ``gain`` its best penalised held-out gain (sigma^2 units) in the last round it was tried,
    at nonlinear parameter ``value``."""

    effect: str
    status: str
    gain: float = float("nan")
    threshold: float = DETECTION_THRESHOLD
    value: float | None = None
    reason: str = ""
    confusable_with: list[str] = field(default_factory=list)
    wald: float = float("nan")


@dataclass
class Attribution:
    """Outcome of :func:`attribute`: the final model and its fit, the baseline's fit, the
    per-effect evidence and the confusable pairs ``(kept, alternative, test that would tell)``."""

    base: Model
    final: Model
    base_fit: Fit
    final_fit: Fit
    evidence: dict[str, Evidence]
    confusions: list[tuple[str, str, str]]
    designer: Designer
    fold: np.ndarray
    k: int


class _Scorer:
    """Held-out fits of models on one recording, memoised."""

    def __init__(self, designer: Designer, fold: np.ndarray, k: int, cluster: np.ndarray) -> None:
        self.designer, self.fold, self.k, self.cluster = designer, fold, k, cluster
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
        return drop * share - PENALTY_PER_PARAM * (model.n_params - base.n_params)

    def wald(self, base: Model, model: Model) -> float:
        """Robust Wald statistic (cluster covariance), never above the one with the known
        white-plus-thermometer variance."""
        robust = robust_wald(self.fit(base), self.fit(model), self.cluster)
        z = self.fit(base).residual - self.fit(model).residual
        known = float(z @ self.fit(base).residual) ** 2 / max(self._noise(base, model)[1], 1e-300)
        return min(robust, known)

    def best(self, base: Model, effect: str) -> tuple[float, float | None]:
        """Best gain of adding ``effect`` to ``base`` over its grid, then refined."""
        values = grid_values(effect)
        gains = [self.gain(base, base.with_effect(effect, v)) for v in values]
        i = int(np.argmax(gains))
        if values[i] is None:
            return gains[i], None
        lo, hi = np.log(values[max(i - 1, 0)]), np.log(values[min(i + 1, len(values) - 1)])  # type: ignore[arg-type]
        res = minimize_scalar(lambda z: -self.gain(base, base.with_effect(effect, float(np.exp(z)))),
                              bounds=(lo, hi), method="bounded", options={"xatol": 0.02})
        if -res.fun > gains[i]:
            return float(-res.fun), float(np.exp(res.x))
        return gains[i], values[i]


def attribute(
    designer: Designer,
    base: Model | None = None,
    *,
    threshold: float = DETECTION_THRESHOLD,
    wald_threshold: float = WALD_THRESHOLD,
    block_s: float = 900.0,
    k: int = 5,
    max_effects: int = 4,
) -> Attribution:
    """Forward selection of the library's deterministic effects onto ``base`` (see module doc)."""
    base = base or Model()
    data = designer.data
    fold = block_folds(data.t_s, block_s, k)
    cluster_s = float(np.clip((data.t_s[-1] - data.t_s[0]) / 32.0, *CLUSTER_S))
    cluster = np.floor((data.t_s - data.t_s[0]) / cluster_s).astype(np.int64)
    scorer = _Scorer(designer, fold, k, cluster)
    evidence: dict[str, Evidence] = {}
    for effect in DETERMINISTIC:
        if effect in base.ids:
            evidence[effect] = Evidence(effect, "in the model", reason="declared in the starting model")
        elif (why := designer.why_not_identifiable(effect)) is not None:
            evidence[effect] = Evidence(effect, "not identifiable", reason=why)
    model = base
    while len(model.ids) - len(base.ids) < max_effects:
        open_effects = [e for e in DETERMINISTIC if e not in evidence or evidence[e].status == "rejected"]
        open_effects = [e for e in open_effects if e not in model.ids]
        if not open_effects:
            break
        tried = {e: scorer.best(model, e) for e in open_effects}
        walds = {e: scorer.wald(model, model.with_effect(e, v)) for e, (g, v) in tried.items()}
        for e, (g, v) in tried.items():
            why = ("held-out gain below the threshold" if g <= threshold else
                   "not significant against the residual's slow noise (robust Wald below the threshold)")
            evidence[e] = Evidence(e, "rejected", g, threshold, v, why, wald=walds[e])
        passing = [e for e in tried if tried[e][0] > threshold and walds[e] > wald_threshold]
        if not passing:
            break
        winner = max(passing, key=lambda e: tried[e][0])
        gain, value = tried[winner]
        model = model.with_effect(winner, value)
        evidence[winner] = Evidence(winner, "kept", gain, threshold, value, "held-out gain above the threshold",
                                    wald=walds[winner])
    for effect in [e for e in model.ids if e not in base.ids]:  # backward check
        reduced = model.without(effect)
        cost, wald = scorer.gain(reduced, model), scorer.wald(reduced, model)
        if cost <= threshold or wald <= wald_threshold:
            model = reduced
            evidence[effect].status = "rejected"
            evidence[effect].reason = "superseded: the other kept effects explain what it did"
        else:
            evidence[effect].gain, evidence[effect].wald = cost, wald
            evidence[effect].value = _value(model, effect)
    confusions = _confusions(scorer, model, base, evidence, threshold)
    return Attribution(base, model, scorer.fit(base), scorer.fit(model), evidence, confusions,
                       designer, fold, k)


def _value(model: Model, effect: str) -> float | None:
    if effect == "thermal_lag":
        return model.lag_tau_s
    return dict(model.terms).get(effect)


def _confusions(
    scorer: _Scorer, model: Model, base: Model, evidence: dict[str, Evidence], threshold: float
) -> list[tuple[str, str, str]]:
    out = []
    for kept in [e for e in model.ids if e not in base.ids]:
        for pair, test in CONFUSABLE.items():
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


def recheck_with_flicker(att: Attribution, b: float, *, draws: int = 16, seed: int = 0,
                         wald_threshold: float = WALD_THRESHOLD) -> Attribution:
    """Drop kept effects that are not significant once flicker of coefficient ``b`` (found in
    the final residual) is part of the noise model. A slow random excursion of the bias can
    look like a warm-up or a trend; the variance of each effect's score under that flicker is
    taken over ``draws`` realisations (fixed ``seed``, so the diagnosis is repeatable)."""
    data = att.designer.data
    cluster = np.zeros(data.n, dtype=np.int64)  # the robust test is not used here
    scorer = _Scorer(att.designer, att.fold, att.k, cluster)
    rng = np.random.default_rng(seed)
    dt_s = float(np.median(np.diff(data.t_s)))
    bank = np.stack([flicker(data.n, dt_s, b, rng) for _ in range(draws)])
    model = att.final
    for effect in [e for e in att.final.ids if e not in att.base.ids]:
        reduced = model.without(effect)
        z = scorer.fit(reduced).residual - scorer.fit(model).residual
        var_flicker = float(np.mean((bank @ z) ** 2))
        wald = float(z @ scorer.fit(reduced).residual) ** 2 / (scorer._noise(reduced, model)[1] + var_flicker)
        ev = att.evidence[effect]
        if wald <= wald_threshold:
            model = reduced
            ev.status, ev.wald = "rejected", wald
            ev.reason = ("explained as well by the flicker found in the residual (Wald with flicker in the noise "
                         "model below the threshold); a second power-on or a longer run would tell")
    if model == att.final:
        return att
    return replace(att, final=model, final_fit=scorer.fit(model))
