"""How one candidate term fared in a diagnosis, and why."""

from __future__ import annotations

from dataclasses import dataclass, field

from tcbench.diagnose.surrogate import LEVEL
from tcbench.diagnose.plan import SURROGATE

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
    """Why an effect with a gain above the threshold was rejected by ``test`` (p-value ``p``)."""
    if test == SURROGATE:
        return (f"not significant against the residual's slow noise (surrogate test p = {p:.3g} above "
                f"{LEVEL:g})")
    return "not significant against the residual's slow noise (robust Wald below the threshold)"
