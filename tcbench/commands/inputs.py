"""The input files of the commands' jobs (``recording=``, ``csv=``, ``model=`` ...), checked to
exist before the libraries that read them are imported: a missing file is one line at once.
Which keys name input files is each command's spec's ``inputs`` (:mod:`.registry`); the
commands' own checks (``check_*``) read and validate the files later."""

from __future__ import annotations

import os
from typing import Any

from tcbench.commands.errors import CommandError
from tcbench.commands.registry import SPECS


def check_inputs_exist(c: dict[str, Any]) -> None:
    """A :class:`CommandError` ``PATH: no such file`` for the first input file of the job config
    ``c`` that is not there (an empty or null key is left to the command's own checks)."""
    kind = str(c.get("kind"))
    for key in next((spec.inputs for spec in SPECS.values() if kind in spec.kinds), ()):
        value = c.get(key)
        for path in value if isinstance(value, list) else [value]:
            if path and not os.path.lexists(str(path)):
                raise CommandError(f"{path}: no such file")
