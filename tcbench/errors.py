"""Errors every layer may raise or report: a leaf module (imports nothing of tcbench)."""

from __future__ import annotations

import errno
import os
import re
import stat
from collections.abc import Iterable, Mapping


class ConfigError(ValueError):
    """A config value is out of range or names something unknown."""


# what a path that is not a regular file is, by its ``st_mode`` type
_FILE_KINDS = ((stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a character device"),
               (stat.S_ISBLK, "a block device"))


def file_problem(path: str | os.PathLike[str]) -> str | None:
    """What stops ``path`` being read as an input file, named by what it is ("no such file",
    "a symlink loop", "no such file (a broken symlink ...)", "a named pipe, not a regular file", ...); None for a
    regular file or a directory (a directory is left to the reader's own message). Never opens
    the path, so a named pipe without a writer cannot block."""
    if not os.path.lexists(path):
        return "no such file"
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a symlink loop (the link leads back to itself)"
        if exc.errno == errno.ENOENT:
            return f"no such file (a broken symlink to {os.readlink(path)})"
        return f"cannot be read ({exc.strerror})"
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    kind = next((name for test, name in _FILE_KINDS if test(mode)), "a special file")
    return f"{kind}, not a regular file"


def listed(names: Iterable[str], first: int = 5) -> str:
    """``names`` quoted and joined, at most ``first`` of them and then how many more (a header of
    20 000 unknown columns is one short line, not 87 KB)."""
    names = list(names)
    shown = ", ".join(map(repr, names[:first]))
    return shown if len(names) <= first else f"{shown} and {len(names) - first} more ({len(names)} in all)"


def disk_full(exc: BaseException) -> str | None:
    """The words for a write the disk (or the user's quota) had no room for, naming the file when
    the error does; None for any other error."""
    if not isinstance(exc, OSError) or exc.errno not in (errno.ENOSPC, errno.EDQUOT):
        return None
    where = f" {exc.filename}" if exc.filename else ""
    return f"the disk is full: cannot write{where} ({exc.strerror or os.strerror(exc.errno)})"


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


def did_you_mean(name: str, known: Iterable[str], aliases: Mapping[str, str] | None = None) -> str | None:
    """The known name ``name`` was probably meant to be: its British spelling when that is known,
    else the known name that differs from it in case only, else the closest by :mod:`difflib`, else the name whose alias (a longer name it goes by,
    ``firefly`` for ``fa``: :func:`class_aliases`) is closest; None when nothing is close."""
    import difflib

    known = [str(k) for k in known]
    if (spelt := british(name)) != name and spelt in known:
        return spelt
    if folded := [k for k in known if k.casefold() == name.casefold()]:  # degc: degC
        return folded[0]
    close = difflib.get_close_matches(name, known, n=1)
    if close:
        return close[0]
    usable = {alias: target for alias, target in (aliases or {}).items() if target in known}
    close = difflib.get_close_matches(name.lower(), list(usable), n=1)
    return usable[close[0]] if close else None


def unknown_name(what: str, name: object, known: Iterable[str], where: str = "",
                 aliases: Mapping[str, str] | None = None) -> str:
    """The one line for a name that names nothing: ``unknown optimiser 'fireflyy'; known: bas, fa,
    ...; did you mean 'fa'?``. ``where`` follows the name (`` for gyro``); every lookup of a name
    the user gives says it this way."""
    known = [str(k) for k in known]
    return f"unknown {what} {name!r}{where}; known: {', '.join(known) or 'none'}" + meant(name, known, aliases)


def meant(name: object, known: Iterable[str], aliases: Mapping[str, str] | None = None) -> str:
    """``; did you mean 'x'?`` for the known name ``name`` probably meant (:func:`did_you_mean`),
    or nothing: the end of every line naming something unknown."""
    close = did_you_mean(name, known, aliases) if isinstance(name, str) else None
    return f"; did you mean {close!r}?" if close else ""


def class_aliases(paths: Mapping[str, str]) -> dict[str, str]:
    """The longer names each name goes by, from the class it names (``{"fa":
    "tcbench.optimisers.fa:FireflyAlgorithm"}``: ``firefly`` and ``firefly_algorithm`` for ``fa``),
    nothing imported: the leading words of the class name, lower case, joined by ``_``. A word
    sequence two names share goes to the one whose class name it covers most of."""
    best: dict[str, tuple[int, str]] = {}
    for name, path in paths.items():
        words = [w.lower() for w in re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+", path.rpartition(":")[2])]
        for n in range(1, len(words) + 1):
            alias = "_".join(words[:n])
            left = len(words) - n
            if alias != name and (alias not in best or left < best[alias][0]):
                best[alias] = (left, name)
    return {alias: name for alias, (_, name) in best.items()}
