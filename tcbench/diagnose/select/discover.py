"""Open-world discovery: model what the effect library does not hold.

In every round of the forward selection (:func:`tcbench.diagnose.select.attribute.attribute`), beside
the library's effects, :func:`best_open` reads the in-sample residual of the current model, lets the detectors of
:mod:`tcbench.diagnose.terms.detectors` propose values for every open-world term
(:class:`~tcbench.diagnose.terms.OpenTerm`, its ``propose``: a step at each change point, a line at each
periodogram peak, a transient from each change point at several time constants, a bump at each
matched temperature, a second thermal node at several time constants), scores each proposal by the
same penalised held-out gain as a library effect, refines the best one's continuous parameter (its ``refine``),
and offers the best term when its gain exceeds the open-world threshold and it is significant
against the residual's slow noise by the test the recording supports (the surrogate test
repeats the search over every proposal); the round keeps whichever, library effect or open-world
term, gains most. Ranking the proposals and refining them uses the in-sample drop of squared
error (one projection each); only the best of each term is cross-validated. The threshold is higher than the library's because
the detectors search positions and periods: it is set on recordings with nothing hidden
(``experiments/diagnose-concealed/calibrate.py``). The threshold is the selection's
``open_threshold_sigma2``, the detectors' numbers :class:`~tcbench.diagnose.settings.DetectorSettings`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.diagnose.select.design import Model
from tcbench.diagnose.select.evidence import Evidence, not_significant
from tcbench.diagnose.select.score import Scorer
from tcbench.diagnose.select.significance import SignificanceTest
from tcbench.diagnose.settings import DEFAULTS, DetectorSettings
from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms import Search, open_term, terms


def proposals(scorer: Scorer, model: Model, detectors: DetectorSettings = DEFAULTS.detectors
              ) -> dict[str, list[tuple[float, ...]]]:
    """Values of each open-world term's nonlinear parameters worth scoring on ``model``'s residual
    (each term's :meth:`~tcbench.diagnose.terms.OpenTerm.propose`, its detectors run as
    ``detectors`` says), for the terms with any."""
    designer = scorer.designer
    search = Search(designer.data, scorer.fit(model).residual, designer.temperature(model.lag_tau_s), scorer.fold,
                    detectors)
    out = {t.id: t.propose(search) for t in terms(open=True)}
    return {k: v for k, v in out.items() if v}


def why_untestable(designer: Any, fold: np.ndarray, detectors: DetectorSettings = DEFAULTS.detectors
                   ) -> dict[str, str]:
    """``{open-world term: why its detector cannot run on this record}`` for every term whose
    detector cannot propose anything whatever the residual (too few bins, too short a span, too
    narrow a temperature range): each term's :meth:`~tcbench.diagnose.terms.OpenTerm.skip`."""
    why = {t.id: t.skip(designer.data, fold, detectors) for t in terms(open=True)}
    return {k: v for k, v in why.items() if v is not None}


class _Screen:
    """In-sample SSE drop of adding columns to ``model``, cheap enough to rank every proposal:
    the residual's squared projection on the new columns made orthogonal to the model's; a
    term's refinement reads the ``detectors`` settings from it."""

    def __init__(self, scorer: Scorer, model: Model, detectors: DetectorSettings = DEFAULTS.detectors) -> None:
        self.scorer, self.model, self.detectors = scorer, model, detectors
        self.data: DiagnosisData = scorer.designer.data
        x = scorer.designer.matrix(model)
        scale = np.sqrt(np.mean(x * x, axis=0))
        scale[scale == 0] = 1.0
        self.q = np.linalg.qr(x / scale)[0]
        self.residual: np.ndarray = scorer.fit(model).residual

    def drop(self, term_id: str, value: tuple[float, ...]) -> float:
        designer = self.scorer.designer  # not through its cache: a search visits many values once
        c = open_term(term_id).columns(designer.data, value, designer.temperature(self.model.lag_tau_s))
        c = c - self.q @ (self.q.T @ c)
        norm = np.sqrt(np.sum(c * c, axis=0))
        if not np.all(norm > 1e-9 * np.sqrt(c.shape[0])):
            return 0.0
        qc = np.linalg.qr(c / norm)[0]
        proj = qc.T @ self.residual
        return float(proj @ proj)


def best_open(scorer: Scorer, model: Model, evidence: dict[str, Any], test: SignificanceTest,
              threshold: float = DEFAULTS.selection.open_threshold_sigma2,
              detectors: DetectorSettings = DEFAULTS.detectors) -> tuple[str, float, tuple[float, ...]] | None:
    """One round: the open-world term that adds most to ``model`` above ``threshold`` and
    passes ``test`` (``(id, gain, value)``), or None; every term's
    :class:`~tcbench.diagnose.select.evidence.Evidence` is written into ``evidence``."""
    tried: dict[str, tuple[float, tuple[float, ...], list[tuple[float, ...]]]] = {}
    screen = _Screen(scorer, model, detectors)
    for term_id, values in proposals(scorer, model, detectors).items():
        t = open_term(term_id)
        new = t.free_id(model.ids)  # a second step, line ... is a further instance of its term
        if new is None:
            continue
        value = t.refine(screen, max(values, key=lambda v: screen.drop(term_id, v)))
        tried[new] = (scorer.gain(model, model.with_effect(new, value)), value, values)
    passing = []
    for term, (gain, value, values) in tried.items():
        bound = open_term(term).gain_threshold(threshold)
        if gain <= bound:
            evidence[term] = Evidence(term, "rejected", gain, bound, None, "held-out gain below the threshold")
            continue
        ok, wald, p, used = scorer.significant(model, term, value, test, searched=values)
        evidence[term] = Evidence(term, "rejected", gain, bound, None, not_significant(test, used, p),
                                  wald=wald, test=used, p_value=p)
        if ok:
            passing.append(term)
    if not passing:
        return None
    winner = max(passing, key=lambda t: tried[t][0])
    return winner, tried[winner][0], tried[winner][1]
