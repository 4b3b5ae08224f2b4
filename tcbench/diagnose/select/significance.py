"""The significance tests an effect with a gain above the threshold must pass, as objects.

:class:`~tcbench.diagnose.select.plan.StatsPlan` holds the one a recording supports
(:func:`~tcbench.diagnose.select.plan.plan_for`, from the settings' thresholds and level); the forward
selection asks it through :meth:`SignificanceTest.judge`, and every
:class:`~tcbench.diagnose.select.evidence.Evidence` names the test that decided by its
:attr:`~SignificanceTest.name` (report.json's ``test`` and ``statistics.significance_test``);
:meth:`SignificanceTest.decided_by` finds that test again from the plan's:

- :class:`RobustWald`: the cluster-robust Wald statistic above its threshold; an effect that
  removes most of the held-out error above the noise and fails it is tried by the surrogate test
  instead (its cluster variance then counts the structure still unexplained as noise);
- :class:`SpectralSurrogate`: the parametric bootstrap of :mod:`tcbench.diagnose.select.surrogate`, at
  p <= its settings' ``level``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, SurrogateSettings

ROBUST_WALD = "cluster-robust Wald"
SURROGATE = "spectral surrogate (parametric bootstrap)"

Judgement = tuple[bool, float, float, str]  # (passed, robust Wald, surrogate p-value, name of the test that decided)


class Scorer(Protocol):
    """What a test asks of the forward selection's scorer (:class:`tcbench.diagnose.select.score.Scorer`)."""

    def removes_most(self, base: Any, model: Any) -> bool: ...

    def surrogate_p(self, base: Any, effect: str, value: Any, searched: list[Any] | None,
                    settings: SurrogateSettings) -> float: ...


class SignificanceTest(ABC):
    """Whether adding an effect is significant against the residual's slow noise."""

    name: ClassVar[str]

    @abstractmethod
    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float,
              searched: list[Any] | None = None) -> Judgement:
        """Adding ``effect`` at ``value`` to the model ``base``, whose robust Wald statistic is ``wald``."""

    def decided_by(self, name: str) -> SignificanceTest:
        """The test named ``name`` (an evidence's ``test``) that this one decides by: itself, or
        the test it hands an effect to."""
        if name != self.name:
            raise KeyError(f"{self.name} does not decide by {name!r}")
        return self

    def why_not(self, p: float) -> str:
        """Why an effect with a gain above the threshold was rejected (surrogate p-value ``p``)."""
        return "not significant against the residual's slow noise (robust Wald below the threshold)"

    def to_json(self, wald: float, p: float) -> dict[str, Any]:
        """report.json's evidence of the test that decided: its name and statistic."""
        out: dict[str, Any] = {"test": self.name}
        if math.isfinite(wald):
            out["robust_wald"] = round(float(wald), 2)
        return out


@dataclass(frozen=True)
class SpectralSurrogate(SignificanceTest):
    """The surrogate test (:func:`~tcbench.diagnose.select.surrogate.surrogate_test`) at p <= ``settings.level``."""

    settings: SurrogateSettings = DEFAULTS.surrogate
    name: ClassVar[str] = SURROGATE

    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float,
              searched: list[Any] | None = None) -> Judgement:
        p = scorer.surrogate_p(base, effect, value, searched, self.settings)
        return p <= self.settings.level, wald, p, self.name

    def why_not(self, p: float) -> str:
        return (f"not significant against the residual's slow noise (surrogate test p = {p:.3g} above "
                f"{self.settings.level:g})")

    def to_json(self, wald: float, p: float) -> dict[str, Any]:
        out = super().to_json(wald, p)
        if math.isfinite(p):
            out |= {"p_value": round(float(p), 4), "level": self.settings.level}
        return out


@dataclass(frozen=True)
class RobustWald(SignificanceTest):
    """The cluster-robust Wald statistic above ``wald_threshold``; the ``surrogate`` test decides
    for an effect that removes most of the excess held-out error and fails it."""

    wald_threshold: float = DEFAULTS.selection.wald_threshold
    surrogate: SpectralSurrogate = field(default_factory=SpectralSurrogate)
    name: ClassVar[str] = ROBUST_WALD

    def judge(self, scorer: Scorer, base: Any, effect: str, value: Any, wald: float,
              searched: list[Any] | None = None) -> Judgement:
        if wald > self.wald_threshold or not scorer.removes_most(base, base.with_effect(effect, value)):
            return wald > self.wald_threshold, wald, float("nan"), self.name
        return self.surrogate.judge(scorer, base, effect, value, wald, searched)

    def decided_by(self, name: str) -> SignificanceTest:
        return self.surrogate if name == self.surrogate.name else super().decided_by(name)


def significance_tests(settings: DiagnoseSettings = DEFAULTS) -> tuple[RobustWald, SpectralSurrogate]:
    """The robust Wald test and the surrogate test at ``settings``' Wald threshold and level."""
    surrogate = SpectralSurrogate(settings.surrogate)
    return RobustWald(settings.selection.wald_threshold, surrogate), surrogate
