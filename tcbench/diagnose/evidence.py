"""How one candidate term fared in a diagnosis, and why."""

from __future__ import annotations

from dataclasses import dataclass, field

from tcbench.diagnose.significance import named

DETECTION_THRESHOLD = 10.0  # gain in units of sigma^2; see experiments/diagnose-concealed/calibrate.py


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
    test: str = ""
    p_value: float = float("nan")



def not_significant(test: str, p: float) -> str:
    """Why an effect with a gain above the threshold was rejected by the test named ``test``
    (p-value ``p``)."""
    return named(test).why_not(p)
