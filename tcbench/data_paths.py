"""Where tcbench's real recordings are: the one place the rest of the code asks.

The public recordings of real IMUs that the tests, the experiments and the README read are kept
in the repository, one folder each under ``data/real/`` with its ``PROVENANCE.md`` and licence
(``data/real/README.md``). A clone (and an editable install of it) has them; a wheel does not.
"""

from __future__ import annotations

from pathlib import Path

from tcbench.errors import ConfigError

REAL_DATA = Path(__file__).resolve().parents[1] / "data" / "real"


def real_file(path: str | Path) -> Path:
    """The file ``path`` of ``data/real/`` (relative to it, or absolute); ConfigError (one line
    naming the path) when it is not there."""
    full = REAL_DATA / path
    if not full.is_file():
        raise ConfigError(f"real recording {full} not found: tcbench's real recordings are in data/real/ "
                          "of a clone of its repository (data/real/README.md)")
    return full
