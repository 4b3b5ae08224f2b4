"""Parameter dataclasses of optimisers and learners, built from config mappings: a leaf module that
both the optimiser protocol and the learner base class use (numpy only)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np


def make_params(cls: type[Any], params: Any) -> Any:
    """Build and validate ``cls.Params`` from a dataclass instance, a mapping or ``None``: ``cls`` is
    an optimiser or a learner class (a ``name`` and a ``Params`` dataclass)."""
    if isinstance(params, cls.Params):
        return params
    values = dict(params or {})
    known = {f.name: f for f in dataclasses.fields(cls.Params)}
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise ValueError(
            f"{cls.name} has no parameter {', '.join(map(repr, unknown))}; "
            f"known: {', '.join(sorted(known))}"
        )
    for key, value in values.items():
        values[key] = coerce_param(cls.name, key, known[key].type, value)
    return cls.Params(**values)


def coerce_param(owner: str, key: str, annotation: Any, value: Any) -> Any:
    """Check a parameter value against a simple annotation (int, float, bool, str, optional); a
    float must be finite (no parameter of tcbench's takes ``inf`` or ``nan``)."""
    ann = str(annotation)
    optional = "None" in ann
    if value is None:
        if optional:
            return None
        raise ValueError(f"{owner}.{key} must not be null")
    base = ann.replace("| None", "").replace("Optional[", "").replace("]", "").strip()
    if base == "bool":
        if isinstance(value, bool):
            return value
    elif base == "int":
        if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            return int(value)
    elif base == "float":
        if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
            if not np.isfinite(float(value)):
                raise ValueError(f"{owner}.{key} must be a finite number, got {value!r}")
            return float(value)
    elif base == "str":
        if isinstance(value, str):
            return value
    else:
        return value
    raise ValueError(f"{owner}.{key} must be {base}, got {value!r}")
