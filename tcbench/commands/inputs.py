"""The input files of the commands' jobs (``recording=``, ``csv=``, ``model=`` ...), checked to
exist before the libraries that read them are imported: a missing file is one line at once.
The commands' own checks (``check_*``) read and validate them later."""

from __future__ import annotations

import os
from typing import Any

from tcbench.commands.errors import CommandError

# job kind -> the keys of its config naming files it reads (a key may hold a list of them)
INPUT_KEYS: dict[str, tuple[str, ...]] = {
    "simulate": ("model",),
    "metrics": ("recording",),
    "import": ("csv",),
    "diagnose": ("recording", "model"),
    "calibrate": ("recording", "test_recordings"),
}


def check_inputs_exist(c: dict[str, Any]) -> None:
    """A :class:`CommandError` ``PATH: no such file`` for the first input file of the job config
    ``c`` that is not there (an empty or null key is left to the command's own checks)."""
    for key in INPUT_KEYS.get(str(c.get("kind")), ()):
        value = c.get(key)
        for path in value if isinstance(value, list) else [value]:
            if path and not os.path.lexists(str(path)):
                raise CommandError(f"{path}: no such file")
