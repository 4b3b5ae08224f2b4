"""A screen: a test of the record whose structure is not an additive term of the mean model.

Each screen has an ``id`` (its key in report.json ``statistics.not_tested``) and a ``stage``:
``prepare`` (on the raw recording, before its thermometer is smoothed), ``before`` (before any
fit, on the prepared data) or ``after`` (on the final fit). :meth:`Screen.skip` says why it
cannot run on a record (None when it can); :meth:`Screen.run` returns a :class:`ScreenResult`:
what it found and the parts it contributes to the report (findings, ``model.yaml`` terms,
``statistics`` entries), and the data (or the attribution) the screens after it see, where it
changes them. :func:`run_screens` runs a stage's screens in order and collects every skip reason
the same way.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.select.attribute import Attribution
from tcbench.diagnose.select.design import Model
from tcbench.diagnose.select.reference import Reference
from tcbench.diagnose.signals import DiagnosisData
from tcbench.sensors.recording import Recording

PREPARE, BEFORE, AFTER = "prepare", "before", "after"


class ScreenResult:
    """What one screen found; by default it contributes nothing and changes nothing."""

    data: DiagnosisData | None = None  # the data the screens after it see, where it changes it
    attribution: Attribution | None = None  # the final model the screens after it see, where it changes it

    def findings(self, unit: str) -> list[Finding]:
        """Its report.json ``effects`` entries (output in ``unit``)."""
        return []

    def write_model(self, model: dict[str, Any]) -> None:
        """Add its terms to ``model`` (model.yaml's mapping) so that ``tcbench simulate model=``
        reproduces what it found."""

    def statistics(self) -> dict[str, Any]:
        """Its report.json ``statistics`` entries."""
        return {}

    def not_tested(self) -> str | None:
        """Why it ran but could not test this record, or None."""
        return None


@dataclass(frozen=True)
class ScreenInput:
    """What a screen reads: the recording, the data as the screens before it left it, the
    starting model and the effect ids declared in it, the results of the screens before it (by
    id; a later result of one id replaces an earlier one) and, after the fit, the attribution and
    the physics-agnostic reference fit."""

    rec: Recording | None
    data: DiagnosisData | None
    base: Model = field(default_factory=Model)
    declared: frozenset[str] = frozenset()
    results: dict[str, ScreenResult] = field(default_factory=dict)
    attribution: Attribution | None = None
    reference: Reference | None = None

    def with_result(self, screen_id: str, result: ScreenResult) -> ScreenInput:
        """The input of the next screen: ``result`` filed under ``screen_id`` and its data and
        attribution, where it changed them."""
        return replace(self, results={**self.results, screen_id: result},
                       data=result.data if result.data is not None else self.data,
                       attribution=result.attribution if result.attribution is not None else self.attribution)


class Screen(ABC):
    """One screen (see the module doc)."""

    id: ClassVar[str]
    stage: ClassVar[str]

    def skip(self, given: ScreenInput) -> str | None:
        """Why this screen cannot run on ``given``, or None."""
        return None

    @abstractmethod
    def run(self, given: ScreenInput) -> ScreenResult:
        """Run on ``given`` (which :meth:`skip` let through)."""


@dataclass(frozen=True)
class Screened:
    """The screens of one stage run: the input the next stage sees (data, attribution, every
    result so far) and ``{screen id: why it did not test this record}``."""

    given: ScreenInput
    not_tested: dict[str, str]

    @property
    def data(self) -> DiagnosisData:
        assert self.given.data is not None
        return self.given.data

    @property
    def results(self) -> dict[str, ScreenResult]:
        return self.given.results


def run_screens(screens: Sequence[Screen], given: ScreenInput) -> Screened:
    """Run ``screens`` in order, each on what the ones before it left; a screen's skip reason,
    or the reason its result gives, is filed under its id (the first reason of an id stays)."""
    why: dict[str, str] = {}
    for screen in screens:
        reason = screen.skip(given)
        if reason is None:
            result = screen.run(given)
            given = given.with_result(screen.id, result)
            reason = result.not_tested()
        if reason is not None:
            why.setdefault(screen.id, reason)
    return Screened(given, why)

