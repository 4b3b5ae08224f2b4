"""How one candidate term fared in a diagnosis, and why."""

from __future__ import annotations

from dataclasses import dataclass, field

from tcbench.diagnose.select.significance import SignificanceTest


@dataclass
class Evidence:
    """How one effect fared: ``status`` is ``kept``, ``rejected`` or ``not identifiable``;
    ``gain`` its best penalised held-out gain (sigma^2 units) in the last round it was tried,
    at nonlinear parameter ``value``, against ``threshold`` (NaN where it was not scored)."""

    effect: str
    status: str
    gain: float = float("nan")
    threshold: float = float("nan")
    value: float | None = None
    reason: str = ""
    confusable_with: list[str] = field(default_factory=list)
    wald: float = float("nan")
    test: str = ""
    p_value: float = float("nan")



def not_significant(test: SignificanceTest, used: str, p: float) -> str:
    """Why an effect with a gain above the threshold was rejected by the test named ``used``
    (that ``test``, the plan's, decides by; p-value ``p``)."""
    return test.decided_by(used).why_not(p)
