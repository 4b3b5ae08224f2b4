"""Type checks of the envs' keyword arguments, so that a value of the wrong type (``None``, a
string) is refused with the same one-line ValueError naming the parameter as a value out of range,
rather than a TypeError from ``int()`` or ``np.isfinite``."""

from __future__ import annotations

import numbers

import numpy as np


def is_real(value: object) -> bool:
    """A finite real number (Python or numpy; not a bool)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and bool(np.isfinite(value))


def is_integer(value: object) -> bool:
    """A finite real number with an integer value (``3`` or ``3.0``; not a bool)."""
    return is_real(value) and int(value) == value  # type: ignore[call-overload]
