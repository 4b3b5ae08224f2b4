"""Errors every layer may raise or report: a leaf module (imports nothing of tcbench)."""

from __future__ import annotations

import re
from collections.abc import Iterable


class ConfigError(ValueError):
    """A config value is out of range or names something unknown."""


def error_line(text: str) -> str:
    """One line of an error's text: the first, or where a database names its error (SQLAlchemy
    puts "(sqlite3.OperationalError) database or disk is full" below a line about autoflush)."""
    lines = [ln.strip() for ln in str(text).strip().splitlines() if ln.strip()] or [""]
    named = next((ln for ln in lines if re.match(r"\(\w+(\.\w+)*(Error|Exception)\)", ln)), None)
    if named is None:
        return lines[0]
    prefix = lines[0].split(":", 1)[0] + ": " if ":" in lines[0] else ""
    return prefix + named


# American spellings and tcbench's (British) ones, applied to every word of a key: optimizer ->
# optimiser, normalize -> normalise, analyze -> analyse, color -> colour, center -> centre
_BRITISH = ((re.compile(r"(?<=[a-z])iz(?=e|ing|ation)"), "is"), (re.compile(r"(?<=[a-z])yz(?=e|ing)"), "ys"),
            (re.compile(r"(?<=[a-z]{3})or(?=$|[_.])"), "our"), (re.compile(r"(?<=[a-z]{3})ter(?=$|[_.])"), "tre"))


def british(name: str) -> str:
    """``name`` with American spellings in the British form tcbench's keys use (``optimizer``: ``optimiser``)."""
    for pattern, replacement in _BRITISH:
        name = pattern.sub(replacement, name)
    return name


def did_you_mean(name: str, known: Iterable[str]) -> str | None:
    """The known name ``name`` was probably meant to be: its British spelling when that is known,
    else the closest by :mod:`difflib`; None when nothing is close."""
    import difflib

    known = [str(k) for k in known]
    if (spelt := british(name)) != name and spelt in known:
        return spelt
    close = difflib.get_close_matches(name, known, n=1)
    return close[0] if close else None
