"""Units of a user's columns, converted to the recording schema's units through pint.

Any unit pint knows is accepted where its dimension fits (``mrad/s`` or ``deg/h`` for an angular
rate, ``us`` or ``min`` for time, ``degF`` or ``K`` for temperature, ``kHz`` for a frequency),
plus the names sensor logs use that pint does not: ``g`` for standard gravity where an
acceleration is meant (``mg``, ``ug`` with it; pint's ``g`` is the gram), ``dps`` and ``mdps``
(degrees per second), ``dph`` (degrees per hour), and exponents written without a caret
(``m/s2``). A conversion is a :class:`Conversion`: ``schema = value * mul + offset``.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.errors import meant

# schema unit -> pint expression and the quantity it measures (for messages)
SCHEMA = {"s": ("second", "time"), "degC": ("degC", "temperature"), "deg/s": ("degree / second", "angular rate"),
          "Hz": ("hertz", "frequency"), "g": ("gee", "acceleration")}


class UnitError(ValueError):
    """A unit that pint does not know, or that does not measure what the column holds."""


@dataclass(frozen=True)
class Conversion:
    """``schema = value * mul + offset``; the identity leaves values bit for bit."""

    mul: float = 1.0
    offset: float = 0.0

    def to_schema(self, x: np.ndarray) -> np.ndarray:
        y = x * self.mul if self.mul != 1.0 else x
        return y + self.offset if self.offset else y


@functools.cache
def registry() -> Any:
    """pint's registry with the names sensor logs use (imported on first use: pint takes ~0.5 s)."""
    import pint

    ureg = pint.UnitRegistry()
    ureg.define("gee = 9.80665 * meter / second ** 2")
    ureg.define("dps = degree / second")
    ureg.define("dph = degree / hour")
    return ureg


def _expression(unit: str, schema_unit: str) -> str:
    """``unit`` as pint reads it: ``s2`` -> ``s**2``, ``°`` -> ``deg``, and ``g`` (with a prefix)
    as standard gravity when the column holds an acceleration."""
    text = unit.strip().replace("°", "deg").replace("µ", "u").replace("^", "**")
    text = re.sub(r"(?<=[A-Za-z])(\d+)\b", r"**\1", text)
    if schema_unit == "g":
        text = re.sub(r"\b([munk]?)g\b", r"\1gee", text)
    return text


@functools.cache
def conversion(unit: str, schema_unit: str) -> Conversion:
    """How values in ``unit`` become values in ``schema_unit`` (a key of :data:`SCHEMA`);
    :class:`UnitError` with one line when pint does not know ``unit`` or it measures something else."""
    if unit == schema_unit:
        return Conversion()
    ureg = registry()
    target, what = SCHEMA[schema_unit]
    try:
        given = ureg.Unit(_expression(unit, schema_unit))
    except Exception:  # noqa: BLE001 - pint's parser raises many kinds for text that is not a unit
        examples = _examples(schema_unit)
        raise UnitError(f"unknown unit {unit!r}: not a unit pint knows (e.g. {examples}"
                        f"{meant(unit, examples.split(', '))})") from None
    if given.dimensionality != ureg.Unit(target).dimensionality:
        article = "an" if what[0] in "aeiou" else "a"
        raise UnitError(f"unit {unit!r} is a {_dimension(given)}, not {article} {what} (e.g. {_examples(schema_unit)})")
    zero = float(ureg.Quantity(0.0, given).to(target).magnitude)
    if zero == 0.0:
        return Conversion(mul=float(ureg.Quantity(1.0, given).to(target).magnitude))
    span = 1.0e3  # an offset scale (degF, K): the slope over a wide span, so rounding of the offset is negligible
    return Conversion(mul=float(ureg.Quantity(span, given).to(target).magnitude - zero) / span, offset=zero)


def _dimension(unit: Any) -> str:
    dims = str(unit.dimensionality)
    return "dimensionless number" if dims == "dimensionless" else f"unit of {dims}"


def _examples(schema_unit: str) -> str:
    return {"s": "s, ms, us, ns, min, h", "degC": "degC, K, degF", "deg/s": "deg/s, rad/s, mrad/s, dps, mdps, deg/h",
            "Hz": "Hz, mHz, kHz", "g": "g, mg, m/s^2"}[schema_unit]
