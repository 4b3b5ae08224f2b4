"""Is an output folder usable? Asked before any work is done, so a long run does not end in a
traceback at its first write (a read-only disk, a file where a folder should be, a typo'd mount)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def folder_problem(path: str | Path) -> str | None:
    """Why ``path`` cannot be used as an output folder (made if missing), or None if it can.

    The folder, or its nearest existing ancestor when it does not exist yet, must be a folder in
    which a sub-folder can be made: this is tried (an empty temporary folder, removed at once),
    since permission bits do not tell a read-only mount or a virtual file system apart, nor bind
    the superuser. Nothing is left behind."""
    target = Path(path)
    probe_in = target
    while not probe_in.exists():
        if probe_in.parent == probe_in:
            return "no part of the path exists"
        probe_in = probe_in.parent
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
