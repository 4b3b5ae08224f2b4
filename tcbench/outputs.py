"""Is an output folder usable? Asked before any work is done, so a long run does not end in a
traceback at its first write (a read-only disk, a file where a folder should be, a typo'd mount).

Also the checks every command that writes shares: a ``name=`` keeps its files inside the folder,
no output replaces an input, and a failed write is told in words."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path


def folder_problem(path: str | Path) -> str | None:
    """Why ``path`` cannot be used as an output folder (made if missing), or None if it can.

    The folder, or its nearest existing ancestor when it does not exist yet, must be a folder in
    which a sub-folder can be made: this is tried (an empty temporary folder, removed at once),
    since permission bits do not tell a read-only mount or a virtual file system apart, nor bind
    the superuser. Nothing is left behind."""
    target = Path(path)
    probe_in = target
    try:
        while not probe_in.exists():
            if probe_in.parent == probe_in:
                return "no part of the path exists"
            probe_in = probe_in.parent
    except OSError as exc:  # a name longer than the file system takes
        return f"cannot be made ({exc.strerror or type(exc).__name__})"
    if not probe_in.is_dir():
        return "is not a folder" if probe_in == target else f"cannot be made: {probe_in} is not a folder"
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".tcbench-probe-", dir=probe_in))
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        if probe_in == target:
            return f"cannot be written ({reason})"
        return f"cannot be made in {probe_in} ({reason})"
    return None


NAME_MAX_BYTES = 255  # the longest file name of the common file systems (ext4, xfs, btrfs, tmpfs, APFS)
TEMP_NAME_BYTES = 64  # what a temporary name keeps of the name it stands for


def name_problem(name: str, suffix: str = "") -> str | None:
    """Why ``name`` cannot be the stem of files written inside an output folder, or None if it
    can: it must be a plain file name, so that every write stays inside the folder, and with
    ``suffix`` (the longest ending the command adds: ``.json``) no longer than a file name may be."""
    if not name:
        return "is empty"
    if (size := len(f"{name}{suffix}".encode(errors="surrogateescape"))) > NAME_MAX_BYTES:
        return (f"makes a file name of {size} bytes ({'NAME' + suffix if suffix else 'NAME'}), longer than the "
                f"{NAME_MAX_BYTES} a file name may have; give a shorter one")
    if "\0" in name:
        return "holds a NUL character"
    if "/" in name or "\\" in name or (os.altsep and os.altsep in name):
        return "must be a file name without a directory (no / or \\)"
    if name in {".", ".."}:
        return f"{name!r} is not a file name"
    return None


def same_file(a: str | Path, b: str | Path) -> bool:
    """True when ``a`` and ``b`` both exist and are the same file (links and ``..`` seen through)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def overwritten_input(targets: Iterable[str | Path], inputs: Iterable[str | Path]) -> tuple[Path, Path] | None:
    """The first ``(target, input)`` pair where writing ``target`` would replace an input file."""
    inputs = [Path(p) for p in inputs]
    for target in targets:
        for source in inputs:
            if same_file(target, source):
                return Path(target), source
    return None


def write_problem(exc: OSError) -> str:
    """The reason an ``OSError`` of a write gives, in words (``No space left on device``)."""
    if exc.strerror:
        return exc.strerror
    if exc.errno:
        return os.strerror(exc.errno)
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__


def short_name(name: str) -> str:
    """At most :data:`TEMP_NAME_BYTES` of ``name`` (whole characters): what a temporary name
    keeps of the name it stands for, so that it fits wherever ``name`` fits."""
    return name.encode(errors="surrogateescape")[:TEMP_NAME_BYTES].decode(errors="ignore")


def temp_name(name: str, tag: str) -> str:
    """A hidden temporary name beside the file ``name``: ``.<short name>.<tag>.tmp``."""
    return f".{short_name(name)}.{tag}.tmp"
