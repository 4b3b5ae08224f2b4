"""Open-world discovery: model what the effect library does not hold.

In every round of the forward selection (:func:`tcbench.diagnose.attribute.attribute`), beside
the library's effects, :func:`best_open` reads the in-sample residual of the current model, lets the detectors of
:mod:`tcbench.diagnose.detectors` propose values for every term of
:mod:`tcbench.diagnose.open_terms` (a step at each change point, a line at each periodogram
peak, a transient from each change point at several time constants, a bump at each matched
temperature, a second thermal node at several time constants), scores each proposal by the
same penalised held-out gain as a library effect, refines the best one's continuous parameter,
and offers the best term when its gain exceeds :data:`OPEN_THRESHOLD` and it is significant
against the residual's slow noise by the test the recording supports (the surrogate test
repeats the search over every proposal); the round keeps whichever, library effect or open-world
term, gains most. Ranking the proposals and refining them uses the in-sample drop of squared
error (one projection each); only the best of each term is cross-validated. The threshold is higher than the library's because
the detectors search positions and periods: it is set on recordings with nothing hidden
(``experiments/diagnose-concealed/calibrate.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from tcbench.diagnose.detectors import (
    DUTY_PHASES,
    LINE_BINS,
    bin_width,
    bump_centres,
    duty_phase,
    line_periods,
    line_window,
    step_times,
    why_no_bumps,
    why_no_lines,
    why_no_steps,
)
from tcbench.diagnose.design import Model
from tcbench.diagnose.evidence import Evidence, not_significant
from tcbench.diagnose.open_terms import free_id, term_columns, term_threshold

OPEN_THRESHOLD = 25.0  # penalised held-out gain (sigma^2 units) an open-world term must exceed
TRANSIENT_TAU_S = np.geomspace(300.0, 4.0 * 3600.0, 8)
NODE_TAU_S = np.geomspace(600.0, 4.0 * 3600.0, 9)
GATED_MIN_CYCLES = 4.0  # a line present in part of the run must hold this many cycles there: flicker makes one or two
DUTY_MIN_CYCLES = 3.0  # a switched load's square cycle is a sharper shape than a line's: flicker does not mimic three
GATED_MAX_PART = 0.8  # ... and be absent from more than this fraction of the span
NODE_SPANS = 4.0  # a second node's time constant is searched below the span over this


def _testable(t_s: np.ndarray, fold: np.ndarray) -> tuple[float, float]:
    """The times between which a step has samples of at least two folds on each side, so every
    fold's held-out prediction is fitted on both levels: after the first block, before the last."""
    first_change = int(np.argmax(fold != fold[0]))
    last_change = fold.size - 1 - int(np.argmax(fold[::-1] != fold[-1]))
    return float(t_s[first_change]), float(t_s[last_change])


def proposals(scorer: Any, model: Model) -> dict[str, list[tuple[float, ...]]]:
    """Values of each open-world term's nonlinear parameters worth scoring on ``model``'s residual."""
    d = scorer.designer.data
    r = scorer.fit(model).residual
    temp = scorer.designer.temperature(model.lag_tau_s)
    span = float(d.t_s[-1] - d.t_s[0])
    lo, hi = _testable(d.t_s, scorer.fold)
    steps = [t for t in step_times(d.t_s, r) if lo < t < hi]
    lines = line_periods(d.t_s, r)
    windows = [(p, *line_window(d.t_s, r, p)) for p in lines if DUTY_MIN_CYCLES * p < GATED_MAX_PART * span]
    gated = [(p, a, b) for p, a, b in windows if GATED_MIN_CYCLES * p <= b - a < GATED_MAX_PART * span]
    switched = [(p, a, b) for p, a, b in windows if DUTY_MIN_CYCLES * p <= b - a < GATED_MAX_PART * span]
    out: dict[str, list[tuple[float, ...]]] = {
        "bias_step": [(t,) for t in steps],
        "transient": [(t, tau) for t in steps for tau in TRANSIENT_TAU_S if tau < 0.5 * (d.t_s[-1] - t)],
        "periodic": [(p,) for p in lines],
        "gated_periodic": gated,
        "duty_cycle": [(p, *duty_phase(d.t_s, r, p, a, b), a, b) for p, a, b in switched],
        "temperature_bump": [(c, w) for c, w in bump_centres(temp, r)],
    }
    if scorer.designer.why_not_identifiable("thermal_lag") is None:
        out["second_node"] = [(float(tau),) for tau in NODE_TAU_S if tau < span / NODE_SPANS]
    return {k: v for k, v in out.items() if v}


def _why_no_transient(t_s: np.ndarray, fold: np.ndarray) -> str | None:
    """Why no transient can be proposed: its shortest time constant needs twice its length of
    record after a testable step."""
    lo, hi = _testable(t_s, fold)
    after = float(t_s[-1]) - lo
    need = 2.0 * float(TRANSIENT_TAU_S[0])
    if after > need and hi > lo:
        return None
    return (f"a transient of time constant {TRANSIENT_TAU_S[0]:.0f} s needs {need:.0f} s of record after a "
            f"testable step; this record has {max(after, 0.0):.0f} s after the earliest one")


def _why_no_gated(t_s: np.ndarray, min_cycles: float = GATED_MIN_CYCLES, what: str = "a line") -> str | None:
    """Why no line present in part of the record (or switched load, ``min_cycles`` apart) can be
    tested: even the shortest period the periodogram resolves needs its cycles inside less than
    the whole record."""
    span = float(t_s[-1] - t_s[0])
    longest = GATED_MAX_PART * span / min_cycles
    shortest = 3.0 * bin_width(t_s, LINE_BINS)
    if longest >= shortest:
        return None
    return (f"{what} present in part of the record needs {min_cycles:g} cycles inside "
            f"{GATED_MAX_PART:.0%} of it: the longest testable period is {longest:.4g} s, below the shortest "
            f"the periodogram resolves ({shortest:.4g} s)")


def _why_no_node(designer: Any) -> str | None:
    """Why no second thermal node can be proposed: thermal lag not identifiable, or a record
    shorter than :data:`NODE_SPANS` times the shortest time constant."""
    why = designer.why_not_identifiable("thermal_lag")
    if why is not None:
        return f"a second thermal node needs what thermal lag needs: {why}"
    d = designer.data
    span, need = float(d.t_s[-1] - d.t_s[0]), NODE_SPANS * float(NODE_TAU_S[0])
    if span > need:
        return None
    return (f"a second thermal node of time constant {NODE_TAU_S[0]:.0f} s needs a record of more than "
            f"{need:.0f} s; this record spans {span:.0f} s")


def why_untestable(designer: Any, fold: np.ndarray) -> dict[str, str]:
    """``{open-world term: why its detector cannot run on this record}`` for every term whose
    detector cannot propose anything whatever the residual (too few bins, too short a span, too
    narrow a temperature range)."""
    t = designer.data.t_s
    lines = why_no_lines(t)
    steps = why_no_steps(t)
    lo, hi = _testable(t, fold)
    if steps is None and not hi > lo:
        steps = "a step needs samples of two cross-validation folds on each side; this record has no such time"
    why = {
        "bias_step": steps,
        "transient": steps or _why_no_transient(t, fold),
        "periodic": lines,
        "gated_periodic": lines or _why_no_gated(t),
        "duty_cycle": lines or _why_no_gated(t, DUTY_MIN_CYCLES, "a switched load"),
        "temperature_bump": why_no_bumps(designer.temperature(None)),
        "second_node": _why_no_node(designer),
    }
    return {k: v for k, v in why.items() if v is not None}


class _Screen:
    """In-sample SSE drop of adding columns to ``model``, cheap enough to rank every proposal:
    the residual's squared projection on the new columns made orthogonal to the model's."""

    def __init__(self, scorer: Any, model: Model) -> None:
        self.scorer, self.model = scorer, model
        x = scorer.designer.matrix(model)
        scale = np.sqrt(np.mean(x * x, axis=0))
        scale[scale == 0] = 1.0
        self.q = np.linalg.qr(x / scale)[0]
        self.r = scorer.fit(model).residual

    def drop(self, term: str, value: tuple[float, ...]) -> float:
        designer = self.scorer.designer  # not through its cache: a search visits many values once
        c = term_columns(designer.data, term, value, designer.temperature(self.model.lag_tau_s))
        c = c - self.q @ (self.q.T @ c)
        norm = np.sqrt(np.sum(c * c, axis=0))
        if not np.all(norm > 1e-9 * np.sqrt(c.shape[0])):
            return 0.0
        qc = np.linalg.qr(c / norm)[0]
        proj = qc.T @ self.r
        return float(proj @ proj)


def _refine_window(screen: _Screen, term: str, value: tuple[float, ...]) -> tuple[float, ...]:
    """A gated line's value with each edge of its span (the last two entries) moved, on a grid
    of a 16th of the period within 1.5 periods, to the largest in-sample drop: the demodulated
    envelope places the edges only to about a period, and a switched load's level inside the
    span makes a misplaced edge costly. The span keeps :data:`GATED_MIN_CYCLES` cycles
    (:data:`DUTY_MIN_CYCLES` for a switched load)."""
    period = value[0]
    offsets = period * np.arange(-24, 25) / 16.0
    for edge in (len(value) - 2, len(value) - 1):
        moved = [(*value[:edge], float(value[edge] + off), *value[edge + 1:]) for off in offsets]
        moved = [v for v in moved if v[-1] - v[-2] >= (DUTY_MIN_CYCLES if term == "duty_cycle" else GATED_MIN_CYCLES) * period]
        if moved:
            value = max(moved, key=lambda v: screen.drop(term, v))
    return value


def _refold(screen: _Screen, value: tuple[float, ...]) -> tuple[float, ...]:
    """A switched load's ``(period_s, on_s, duty, start_s, end_s)`` with its phase and duty
    read again from the residual folded on its period and span."""
    period, _, _, start, end = value
    d = screen.scorer.designer.data
    return (period, *duty_phase(d.t_s, screen.r, period, start, end), start, end)


def _refine(screen: _Screen, term: str, value: tuple[float, ...]) -> tuple[float, ...]:
    """``value`` with the term's continuous parameter (period, time constant; a gated line's
    edges, a switched load's phase and duty too) moved to the largest in-sample drop nearby."""
    if term in ("periodic", "gated_periodic", "duty_cycle"):
        lo, hi = np.log(value[0] * 0.9), np.log(value[0] * 1.1)
        fold = _refold if term == "duty_cycle" else (lambda _, v: v)
        make = lambda z: fold(screen, (float(np.exp(z)), *value[1:]))  # noqa: E731
    elif term in ("transient", "second_node"):
        k = len(value) - 1
        lo, hi = np.log(value[k] / 1.6), np.log(value[k] * 1.6)
        make = lambda z: (*value[:k], float(np.exp(z)))  # noqa: E731
    else:
        return value
    if term == "duty_cycle":  # a square cycle's drop has side maxima in the period: bracket first
        grid = np.linspace(lo, hi, 41)
        i = int(np.argmax([screen.drop(term, make(z)) for z in grid]))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    # a line holding many cycles needs its period to a fraction of a cycle over the span
    res = minimize_scalar(lambda z: -screen.drop(term, make(z)), bounds=(lo, hi), method="bounded",
                          options={"xatol": 5e-4})
    value = make(res.x) if -res.fun > screen.drop(term, value) else value
    if term == "gated_periodic":
        return _refine_window(screen, term, value)
    if term == "duty_cycle":
        return _refine_edges(screen, _refold(screen, _refine_window(screen, term, value)))
    return value


def _refine_edges(screen: _Screen, value: tuple[float, ...]) -> tuple[float, ...]:
    """A switched load's on and off instants moved within one phase bin of the fold, to the
    largest in-sample drop: a switching edge misplaced by a few samples leaves a spike at every
    cycle, which the Allan test would take for flicker."""
    period, on_s, duty, start, end = value
    step = period / DUTY_PHASES
    grid = np.linspace(-step, step, 17)
    on_s = max((on_s + g for g in grid), key=lambda x: screen.drop("duty_cycle", (period, x, duty, start, end)))
    off = on_s + duty * period
    off = max((off + g for g in grid if 0.0 < off + g - on_s < period),
              key=lambda x: screen.drop("duty_cycle", (period, on_s, (x - on_s) / period, start, end)))
    return period, float(on_s), float((off - on_s) / period), start, end


def best_open(scorer: Any, model: Model, evidence: dict[str, Any], test: str, wald_threshold: float,
              threshold: float = OPEN_THRESHOLD) -> tuple[str, float, tuple[float, ...]] | None:
    """One round: the open-world term that adds most to ``model`` and passes (``(id, gain,
    value)``), or None; every term's :class:`~tcbench.diagnose.evidence.Evidence` is written
    into ``evidence``."""
    tried: dict[str, tuple[float, tuple[float, ...], list[tuple[float, ...]]]] = {}
    screen = _Screen(scorer, model)
    for term, values in proposals(scorer, model).items():
        new = free_id(term, model.ids)  # a second step, line ... is a further instance of its term
        if new is None:
            continue
        value = _refine(screen, term, max(values, key=lambda v: screen.drop(term, v)))
        tried[new] = (scorer.gain(model, model.with_effect(new, value)), value, values)
    passing = []
    for term, (gain, value, values) in tried.items():
        bound = term_threshold(term, threshold)
        if gain <= bound:
            evidence[term] = Evidence(term, "rejected", gain, bound, None, "held-out gain below the threshold")
            continue
        ok, wald, p, used = scorer.significant(model, term, value, test, wald_threshold, searched=values)
        evidence[term] = Evidence(term, "rejected", gain, bound, None, not_significant(used, p),
                                  wald=wald, test=used, p_value=p)
        if ok:
            passing.append(term)
    if not passing:
        return None
    winner = max(passing, key=lambda t: tried[t][0])
    return winner, tried[winner][0], tried[winner][1]
