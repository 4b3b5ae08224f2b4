"""The report contract of one finding: every entry of ``report.json`` ``effects``.

A finding is whatever the diagnosis located and modelled, from the effect library or not:

- ``id``: the model term's id (the key it has in ``model.yaml`` ``effects``, or ``outliers``);
- ``shape``: one of :data:`SHAPES`, what the structure looks like in the data;
- ``library``: whether ``id`` is one of the effect library's (docs/concepts/physics.md, the effect library);
- ``params``: its fitted parameters (names with units, as in ``model.yaml``);
- ``where``: whichever of :data:`WHERE_KEYS` apply: ``time_s`` (an instant or a list of them),
  ``period_s`` and ``frequency_hz``, ``temperature_c`` (a ``[low, high]`` band), ``level`` (an
  output or temperature level: a clip level, a quantisation step);
- ``evidence``: the test that decided and its statistics;
- ``explanation``: the candidate physical causes in plain words;
- ``confirm_with``: the measurement or test profile that would confirm it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

SHAPES = (
    "step", "periodic", "trend", "transient", "temperature_function", "temperature_dynamics",
    "input_function", "variance", "saturation", "outliers", "quantisation", "noise",
)
WHERE_KEYS = ("time_s", "period_s", "frequency_hz", "temperature_c", "level")
KEYS = ("id", "shape", "library", "params", "where", "evidence", "explanation", "confirm_with")


@dataclass
class Finding:
    """One entry of ``report.json`` ``effects`` (see module doc)."""

    id: str
    shape: str
    library: bool
    params: dict[str, Any]
    where: dict[str, Any]
    evidence: dict[str, Any]
    explanation: str
    confirm_with: str
    extra: dict[str, Any] = field(default_factory=dict)  # e.g. ``confusable_with``

    def __post_init__(self) -> None:
        check_finding(self.to_json())

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        extra = out.pop("extra")
        return out | extra

    @classmethod
    def from_json(cls, entry: Mapping[str, Any]) -> Finding:
        """The finding of a report.json ``effects`` entry (keys beyond :data:`KEYS` as ``extra``)."""
        return cls(**{k: entry[k] for k in KEYS}, extra={k: v for k, v in entry.items() if k not in KEYS})


def check_finding(entry: Mapping[str, Any]) -> None:
    """Raise ``ValueError`` naming what a finding ``entry`` lacks or gets wrong."""
    name = entry.get("id", "?")
    missing = [k for k in KEYS if k not in entry]
    if missing:
        raise ValueError(f"finding {name!r} lacks {', '.join(missing)}")
    if entry["shape"] not in SHAPES:
        raise ValueError(f"finding {name!r}: unknown shape {entry['shape']!r}; known: {', '.join(SHAPES)}")
    unknown = [k for k in entry["where"] if k not in WHERE_KEYS]
    if unknown:
        raise ValueError(f"finding {name!r}: unknown where key(s) {', '.join(unknown)}; known: {', '.join(WHERE_KEYS)}")
    band = entry["where"].get("temperature_c")
    if band is not None and (len(band) != 2 or band[0] > band[1]):
        raise ValueError(f"finding {name!r}: where.temperature_c must be [low, high], got {band!r}")
    for key in ("explanation", "confirm_with"):
        if not str(entry[key]).strip():
            raise ValueError(f"finding {name!r}: empty {key}")
