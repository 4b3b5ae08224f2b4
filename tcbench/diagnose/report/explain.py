"""One paragraph in plain words per effect found: what the data showed and what physics does
that (each library effect's term, :mod:`tcbench.diagnose.terms`, writes its own)."""

from __future__ import annotations

from collections.abc import Mapping

from tcbench.diagnose.terms import is_term, term


def explain(effect: str, params: Mapping[str, float], unit: str) -> str:
    """The physical explanation of ``effect`` with its fitted ``params`` (output ``unit``)."""
    if not is_term(effect):
        raise ValueError(f"no explanation for effect {effect!r}")
    return term(effect).explanation(params, unit)
