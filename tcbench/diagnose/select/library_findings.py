"""Effects of the library (docs/concepts/physics.md, the effect library) as findings of the report contract
(:mod:`tcbench.diagnose.findings`).

Each library effect's term (:mod:`tcbench.diagnose.terms`) gives the shape its signature takes
in a residual (docs/concepts/diagnosis-report.md, shapes), where it shows (the recording's temperature band for a
temperature term, ``time_s`` 0 for the warm-up, nothing for the others) and its explanation;
``confirm_with`` names the measurement or test profile that would confirm the effect and, when
the recording cannot tell it from another effect, the test of
:func:`~tcbench.diagnose.terms.confusable_pairs` that would separate the two.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.terms import Extent, confusable_pairs, is_term, term, terms


def where_of(effect: str, extent: Extent) -> dict[str, Any]:
    """Where ``effect`` shows in a recording of ``extent`` (its term's ``where``)."""
    return term(effect).where(extent)


def confirm_with(effect: str, confusable_with: Sequence[str] = ()) -> str:
    """The measurement that would confirm ``effect``; for each effect it ``confusable_with``,
    the test that would separate the two."""
    text, pairs = term(effect).confirm_with, confusable_pairs()
    for other in confusable_with:
        test = pairs.get(frozenset({effect, other}))
        if test:
            text += f"; to tell it from {other}: {test}"
    return text


def library_finding(
    effect: str,
    params: Mapping[str, float],
    evidence: Mapping[str, Any],
    extent: Extent,
    confusable_with: Sequence[str] = (),
) -> Finding:
    """The report finding of a kept library ``effect`` with its fitted ``params`` and the
    ``evidence`` that kept it, on a recording of ``extent``; ``confusable_with`` (the effects
    this recording cannot tell it from) rides along as an extra key when not empty."""
    if not is_term(effect) or term(effect).open_world:
        raise ValueError(f"{effect!r} is not an effect of the library; known: {', '.join(t.id for t in terms())}")
    t = term(effect)
    return Finding(
        id=effect, shape=t.shape, library=True, params=dict(params), where=t.where(extent),
        evidence=dict(evidence), explanation=t.explanation(params, extent.unit),
        confirm_with=confirm_with(effect, confusable_with),
        extra={"confusable_with": list(confusable_with)} if confusable_with else {},
    )
