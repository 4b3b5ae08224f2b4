"""The input files of the commands' jobs (``recording=``, ``csv=``, ``model=`` ...), checked to
exist before the libraries that read them are imported: a missing file is one line at once.
Which keys name input files is each command's spec's ``inputs`` (:mod:`.registry`); the
commands' own checks (``check_*``) read and validate the files later."""

from __future__ import annotations

from typing import Any

from tcbench.commands.errors import CommandError
from tcbench.commands.registry import SPECS
from tcbench.errors import file_problem


def check_inputs_exist(c: dict[str, Any]) -> None:
    """A :class:`CommandError` ``PATH: no such file`` for the first input file of the job config
    ``c`` that is not there, or ``PATH: a named pipe, not a regular file`` (a symlink loop, a
    device ...) for one that cannot be read as a file (:func:`tcbench.errors.file_problem`; an
    empty or null key, and a directory, are left to the command's own checks)."""
    kind = str(c.get("kind"))
    for key in next((spec.inputs for spec in SPECS.values() if kind in spec.kinds), ()):
        value = c.get(key)
        for path in value if isinstance(value, list) else [value]:
            problem = file_problem(str(path)) if path else None
            if problem:
                raise CommandError(f"{path}: {problem}")
