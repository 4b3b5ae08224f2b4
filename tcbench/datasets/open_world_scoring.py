"""The fixed rules that score a report's findings against an open-world truth.

A recording is *characterised* when one finding of ``report.json`` ``effects`` has the true
``shape`` and states every key of the truth's ``where`` within: instants, max(10 min, 2 % of
the span) (a list of instants must agree both ways); period, 15 % (``frequency_hz`` read as
1/f); temperature band, overlapping the middle half of the true band; level, 25 %. Findings are
read by shape and where, never by id; a missing or malformed key is no match, not an error.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.datasets.open_world import OpenWorld

TIME_TOLERANCE_S = 600.0
TIME_TOLERANCE_SPAN = 0.02
PERIOD_TOLERANCE = 0.15
LEVEL_TOLERANCE = 0.25
NOISE_SHAPES = ("noise",)
NOISE_IDS = ("bias_instability",)


def time_tolerance_s(span_s: float) -> float:
    """How far a stated instant may be from the true one: max(10 min, 2 % of the span)."""
    return max(TIME_TOLERANCE_S, TIME_TOLERANCE_SPAN * float(span_s))


def _numbers(x: Any) -> np.ndarray:
    """A number or a list of numbers as a 1-d float array (ValueError/TypeError otherwise)."""
    arr = np.atleast_1d(np.asarray(x, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ValueError("not a finite number or list of numbers")
    return arr


def _times_match(true: Any, found: Any, tol_s: float) -> bool:
    """Every true instant has a stated one within ``tol_s`` and every stated one a true one."""
    a, b = _numbers(true), _numbers(found)
    close = np.abs(np.subtract.outer(a, b)) <= tol_s
    return bool(close.any(axis=1).all() and close.any(axis=0).all())


def _period(where: Mapping[str, Any]) -> float | None:
    if where.get("period_s") is not None:
        return float(_numbers(where["period_s"])[0])
    if where.get("frequency_hz") is not None:
        f = float(_numbers(where["frequency_hz"])[0])
        return 1.0 / f if f > 0 else None
    return None


def _band_matches(true: Sequence[float], found: Any) -> bool:
    """The stated band overlaps the middle half of the true band (for a Gaussian bump stated as
    centre -/+ 2 widths: centre -/+ 1 width)."""
    lo, hi = (float(x) for x in true)
    f = _numbers(found)
    if f.size != 2 or f[0] > f[1]:
        return False
    quarter = (hi - lo) / 4.0
    return bool(f[0] <= hi - quarter and f[1] >= lo + quarter)


def _time_matches(true: Any, found: Mapping[str, Any], span_s: float) -> bool:
    return found.get("time_s") is not None and _times_match(true, found["time_s"], time_tolerance_s(span_s))


def _period_matches(true: Any, found: Mapping[str, Any], span_s: float) -> bool:
    p = _period(found)
    return p is not None and abs(p - float(true)) <= PERIOD_TOLERANCE * float(true)


def _temperature_matches(true: Any, found: Mapping[str, Any], span_s: float) -> bool:
    return found.get("temperature_c") is not None and _band_matches(true, found["temperature_c"])


def _level_matches(true: Any, found: Mapping[str, Any], span_s: float) -> bool:
    if found.get("level") is None:
        return False
    level = float(_numbers(found["level"])[0])
    return abs(level - float(true)) <= LEVEL_TOLERANCE * abs(float(true))


# How each key of a truth's ``where`` is matched: ``(true value, found where, span_s) -> bool``.
WHERE_MATCHERS: dict[str, Callable[[Any, Mapping[str, Any], float], bool]] = {
    "time_s": _time_matches,
    "period_s": _period_matches,
    "temperature_c": _temperature_matches,
    "level": _level_matches,
}


def where_matches(true: Mapping[str, Any], found: Mapping[str, Any] | None, span_s: float) -> bool:
    """Whether ``found`` states every key of the truth's ``where`` within the fixed tolerances:
    instants within :func:`time_tolerance_s`, period within 15 % (``frequency_hz`` accepted),
    temperature band overlapping the true band's middle half, level within 25 %. A missing or
    malformed key does not match; a truth without ``where`` (``second_node``) matches anything."""
    found = found if isinstance(found, Mapping) else {}
    try:
        for key, value in true.items():
            matches = WHERE_MATCHERS.get(key)
            if matches is None or not matches(value, found, span_s):  # the truth only uses the keys above
                return False
    except (TypeError, ValueError):
        return False
    return True


def finding_matches(truth: OpenWorld, finding: Mapping[str, Any]) -> bool:
    """Whether one report finding characterises the hidden structure: same shape and where."""
    if truth.shape is None or finding.get("shape") != truth.shape:
        return False
    return where_matches(truth.where, finding.get("where"), truth.span_s)


@dataclass(frozen=True)
class Score:
    """How a report fared on one recording (see :func:`score`)."""

    characterised: bool  # some finding matches shape and where
    shape_found: bool  # some finding has the true shape
    explained_as_noise: bool  # findings only of shape noise / bias_instability
    false_alarm: bool  # a control with any finding
    findings: int


def score(truth: OpenWorld, effects: Sequence[Mapping[str, Any]]) -> Score:
    """Score the ``effects`` of a report (``Diagnosis.to_json()["effects"]``) against the truth."""
    effects = [e for e in effects if isinstance(e, Mapping)]
    noise_only = bool(effects) and all(e.get("shape") in NOISE_SHAPES or e.get("id") in NOISE_IDS for e in effects)
    if truth.kind is None:
        return Score(False, False, noise_only, bool(effects), len(effects))
    return Score(
        characterised=any(finding_matches(truth, e) for e in effects),
        shape_found=any(e.get("shape") == truth.shape for e in effects),
        explained_as_noise=noise_only,
        false_alarm=False,
        findings=len(effects),
    )
