"""The significance tests an effect with a gain above the threshold must pass, as objects.

:class:`~tcbench.diagnose.plan.StatsPlan` holds the one a recording supports
(:func:`~tcbench.diagnose.plan.plan_for`); the forward selection asks it through
:meth:`SignificanceTest.judge`, and every :class:`~tcbench.diagnose.evidence.Evidence` names the
test that decided by its :attr:`~SignificanceTest.name` (report.json's ``test`` and
``statistics.significance_test``):

- :class:`RobustWald`: the cluster-robust Wald statistic above the Wald threshold; an effect that
  removes most of the held-out error above the noise and fails it is tried by the surrogate test
  instead (its cluster variance then counts the structure still unexplained as noise);
- :class:`SpectralSurrogate`: the parametric bootstrap of :mod:`tcbench.diagnose.surrogate`, at
  p <= its ``LEVEL``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar, Protocol

from tcbench.diagnose.surrogate import LEVEL

ROBUST_WALD = "cluster-robust Wald"
SURROGATE = "spectral surrogate (parametric bootstrap)"

Judgement = tuple[bool, float, float, str]  # (passed, robust Wald, surrogate p-value, name of the test that decided)


class Scorer(Protocol):
    """What a test asks of the forward selection's scorer (:class:`tcbench.diagnose.attribute._Scorer`)."""

    def removes_most(self, base: Any, model: Any) -> bool: ...

    def surrogate_p(self, base: Any, effect: str, value: Any, searched: list[Any] | None = None) -> float: ...


class SignificanceTest(ABC):
    """Whether adding an effect is significant against the residual's slow noise."""

    name: ClassVar[str]

    def __reduce__(self) -> tuple[Any, tuple[str]]:
        return named, (self.name,)  # one object per test, also across processes

    @abstractmethod
    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float, wald_threshold: float,
              searched: list[Any] | None = None) -> Judgement:
        """Adding ``effect`` at ``value`` to the model ``base``, whose robust Wald statistic is ``wald``."""

    def why_not(self, p: float) -> str:
        """Why an effect with a gain above the threshold was rejected (surrogate p-value ``p``)."""
        return "not significant against the residual's slow noise (robust Wald below the threshold)"

    def to_json(self, wald: float, p: float) -> dict[str, Any]:
        """report.json's evidence of the test that decided: its name and statistic."""
        out: dict[str, Any] = {"test": self.name}
        if math.isfinite(wald):
            out["robust_wald"] = round(float(wald), 2)
        return out


class SpectralSurrogate(SignificanceTest):
    """The surrogate test (:func:`~tcbench.diagnose.surrogate.surrogate_test`) at p <= ``LEVEL``."""

    name = SURROGATE

    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float, wald_threshold: float,
              searched: list[Any] | None = None) -> Judgement:
        p = scorer.surrogate_p(base, effect, value, searched)
        return p <= LEVEL, wald, p, self.name

    def why_not(self, p: float) -> str:
        return (f"not significant against the residual's slow noise (surrogate test p = {p:.3g} above "
                f"{LEVEL:g})")

    def to_json(self, wald: float, p: float) -> dict[str, Any]:
        out = super().to_json(wald, p)
        if math.isfinite(p):
            out |= {"p_value": round(float(p), 4), "level": LEVEL}
        return out


class RobustWald(SignificanceTest):
    """The cluster-robust Wald statistic above ``wald_threshold``; the surrogate test decides for
    an effect that removes most of the excess held-out error and fails it."""

    name = ROBUST_WALD

    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float, wald_threshold: float,
              searched: list[Any] | None = None) -> Judgement:
        if wald > wald_threshold or not scorer.removes_most(base, base.with_effect(effect, value)):
            return wald > wald_threshold, wald, float("nan"), self.name
        return SURROGATE_TEST.judge(scorer, base, effect, value, wald, wald_threshold, searched)


SURROGATE_TEST = SpectralSurrogate()
ROBUST_WALD_TEST = RobustWald()
TESTS: dict[str, SignificanceTest] = {t.name: t for t in (ROBUST_WALD_TEST, SURROGATE_TEST)}


def named(name: str) -> SignificanceTest:
    """The test whose :attr:`~SignificanceTest.name` is ``name`` (an evidence's ``test``)."""
    return TESTS[name]
