"""Errors every layer may raise or report: a leaf module (imports nothing of tcbench)."""

from __future__ import annotations

import re


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
