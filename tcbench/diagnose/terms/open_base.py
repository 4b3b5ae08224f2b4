"""The base of an open-world term: structure outside the effect library (docs/concepts/diagnosis-report.md, shapes) as
regressors, found by the detectors of :mod:`tcbench.diagnose.terms.detectors` and scored by
:mod:`tcbench.diagnose.select.discover`.

An open-world term has an id (its key in ``model.yaml`` ``effects``, simulated by the effect of
the same id in :mod:`tcbench.sensors.effects`), a ``shape`` of the report contract, nonlinear
parameters ``value`` (a tuple named by ``value_names``, proposed from the residual by
:meth:`OpenTerm.propose` and moved by :meth:`OpenTerm.refine`) and ``n_coef`` linear
coefficients of its :meth:`OpenTerm.columns`, fitted with the rest of the model. ``T`` below is
the model temperature (the smoothed thermometer, or the die once ``thermal_lag`` is in the
model); ``t`` the recording's clock, taken as time since power-on as for ``warmup``.

A subclass of :class:`OpenTerm` registers like a library term (:mod:`.base`), and installed
packages may add one under the entry-point group ``tcbench.terms``. :func:`~.base.terms` with
``open=True`` lists them in the order a round of the search tries them (and names what cannot be
tested); :func:`report_order` is the order of the report's candidates.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar, Protocol, TypeVar

import numpy as np
from scipy.optimize import minimize_scalar

from tcbench.diagnose.findings import SHAPES, Finding
from tcbench.diagnose.settings import DEFAULTS, DetectorSettings
from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms.base import _NO_DRAW, Extent, Term, signals, term, terms
from tcbench.diagnose.terms.detectors import line_periods, step_times
from tcbench.sensors.effects import MAX_REPEATS, Effect

Value = tuple[float, ...]
T = TypeVar("T")
# search_log's tolerance on its log-scale parameter: 5e-4 in ln(period) is a period to 0.05 %,
# which keeps a line of hundreds of cycles over the record in phase at its ends
SEARCH_LOG_XATOL = 5e-4


class Screen(Protocol):
    """What a refinement reads: the record, the in-sample residual of the current model, the
    detectors' settings and the in-sample drop of squared error of adding a term's columns at a
    value."""

    data: DiagnosisData
    residual: np.ndarray
    detectors: DetectorSettings

    def drop(self, term_id: str, value: Value) -> float: ...


def step_range(t_s: np.ndarray, fold: np.ndarray) -> tuple[float, float]:
    """The times between which a step has samples of at least two folds on each side, so every
    fold's held-out prediction is fitted on both levels: after the first block, before the last."""
    first_change = int(np.argmax(fold != fold[0]))
    last_change = fold.size - 1 - int(np.argmax(fold[::-1] != fold[-1]))
    return float(t_s[first_change]), float(t_s[last_change])


@dataclass
class Search:
    """What the detectors read in one round: the record, the in-sample residual of the current
    model, the model temperature, the cross-validation folds and the detectors' settings. Each
    detector runs once per round, on first use, whichever terms read it."""

    data: DiagnosisData
    residual: np.ndarray
    temp_c: np.ndarray
    fold: np.ndarray
    detectors: DetectorSettings = DEFAULTS.detectors

    _shared: dict[str, Any] = field(default_factory=dict, repr=False)

    def shared(self, name: str, compute: Callable[[], T]) -> T:
        """``compute()`` once per round under ``name``, whichever terms read it."""
        if name not in self._shared:
            self._shared[name] = compute()
        return self._shared[name]

    @cached_property
    def span_s(self) -> float:
        return float(self.data.t_s[-1] - self.data.t_s[0])

    @cached_property
    def testable(self) -> tuple[float, float]:
        """:func:`step_range` of the record and folds."""
        return step_range(self.data.t_s, self.fold)

    @cached_property
    def steps(self) -> list[float]:
        """Change points of the residual (:func:`~tcbench.diagnose.terms.detectors.step_times`) where a step is testable."""
        lo, hi = self.testable
        return [t for t in step_times(self.data.t_s, self.residual, self.detectors) if lo < t < hi]

    @cached_property
    def lines(self) -> list[float]:
        """Periods of the residual's spectral lines (:func:`~tcbench.diagnose.terms.detectors.line_periods`)."""
        return line_periods(self.data.t_s, self.residual, self.detectors)


class OpenTerm(Term):
    """One open-world term: its columns, its parameters and findings, and how the search proposes
    and refines its values.

    - ``value_names``: the names of the nonlinear parameters ``value``, in order;
    - ``n_coef``: how many columns (linear coefficients) it adds;
    - ``search_scale``: its held-out gain threshold over the open world's (a wider search finds
      more by chance).
    """

    open_world = True
    units = {"amplitude": "{unit}"}
    value_names: ClassVar[tuple[str, ...]] = ()
    n_coef: ClassVar[int] = 1
    search_scale: ClassVar[float] = 1.0

    def unit_effects(self, value: Value) -> tuple[Effect, ...]:
        """The library effect at ``value`` with a unit coefficient on each column in turn: their
        output terms are the columns, where the term uses the simulator's formula."""
        raise NotImplementedError(f"term {self.id!r} does not build its columns from its effect")

    def columns(self, data: DiagnosisData, value: Value, temp_c: np.ndarray) -> np.ndarray:
        """The columns (n, :attr:`n_coef`) at ``value`` on the model temperature ``temp_c``."""
        s = signals(data, temp_c)
        return np.column_stack([e.term(s, _NO_DRAW) for e in self.unit_effects(value)])

    def n_params(self, value: Any) -> int:
        """Parameters it adds to the minimal model: its coefficients and its searched values."""
        return self.n_coef + len(self.value_names)

    def gain_threshold(self, open_threshold: float) -> float:
        """The held-out gain it must exceed, for the open world's ``open_threshold``."""
        return open_threshold * self.search_scale

    def free_id(self, ids: tuple[str, ...]) -> str | None:
        """The id a new instance takes beside ``ids`` (``bias_step``, ``bias_step_2``, ...), or
        None once :data:`~tcbench.sensors.effects.MAX_REPEATS` are in."""
        taken = set(ids)
        return next((i for i in (self.id, *(f"{self.id}_{k}" for k in range(2, MAX_REPEATS + 1))) if i not in taken),
                    None)

    def propose(self, search: Search) -> list[Value]:
        """Values worth scoring on this round's residual (none: not searched)."""
        return []

    def refine(self, screen: Screen, value: Value) -> Value:
        """``value`` moved to the largest in-sample drop nearby (as proposed: nothing to refine)."""
        return value

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,  # type: ignore[override]
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        """Why its detector, run as ``detectors`` says, cannot propose anything on ``data`` with
        cross-validation ``fold`` (None: unknown, not checked) whatever the residual, or None."""
        return None

    def where(self, extent: Extent | None = None, params: Mapping[str, float] | None = None) -> dict[str, Any]:
        """Where the fitted term shows (report contract ``where``): placed by its fitted ``params``
        (:meth:`located`), not by the recording's extent."""
        return {} if params is None else self.located(params)

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        """Where the term with fitted ``params`` shows (nowhere in particular: ``{}``)."""
        return {}

    @abstractmethod
    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:  # type: ignore[override]
        """The fitted coefficients ``coef`` (one per column) and ``value`` as the effect's parameters."""


def is_open(term_id: str) -> bool:
    """Whether ``term_id`` is an open-world term (or a further instance of one, ``bias_step_2``)."""
    try:
        return isinstance(term(term_id), OpenTerm)
    except KeyError:
        return False


def open_term(term_id: str) -> OpenTerm:
    """The open-world term of ``term_id`` (or of a further instance); ``KeyError`` otherwise."""
    t = term(term_id)
    if not isinstance(t, OpenTerm):
        raise KeyError(f"not an open-world term: {term_id!r}")
    return t


def report_order() -> tuple[str, ...]:
    """The open-world term ids in the order the report lists them: by shape, in the report
    contract's order (:data:`~tcbench.diagnose.findings.SHAPES`), then as registered."""
    return tuple(t.id for t in sorted(terms(open=True), key=lambda t: SHAPES.index(t.shape)))


def open_finding(term_id: str, params: dict[str, float], evidence: dict[str, Any], unit: str) -> dict[str, Any]:
    """The report.json ``effects`` entry of a kept open-world term (the contract of
    :mod:`tcbench.diagnose.findings`)."""
    t = open_term(term_id)
    return Finding(term_id, t.shape, False, dict(params), t.where(params=params), evidence,
                   t.explanation(params, unit), t.confirm_with).to_json()


def search_log(screen: Screen, term_id: str, value: Value, lo: float, hi: float, make: Callable[[float], Value],
               bracket: int = 0) -> Value:
    """``make(z)`` at the largest in-sample drop for ``z`` (a log-scale parameter) in ``[lo, hi]``,
    or ``value`` when that drops no more; ``bracket`` grid points first narrow the interval to
    the best one's neighbours (a drop with side maxima)."""
    if bracket:
        grid = np.linspace(lo, hi, bracket)
        i = int(np.argmax([screen.drop(term_id, make(z)) for z in grid]))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    # a line holding many cycles needs its period to a fraction of a cycle over the span
    res = minimize_scalar(lambda z: -screen.drop(term_id, make(z)), bounds=(lo, hi), method="bounded",
                          options={"xatol": SEARCH_LOG_XATOL})
    return make(res.x) if -res.fun > screen.drop(term_id, value) else value
