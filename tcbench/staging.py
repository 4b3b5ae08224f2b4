"""All-or-nothing output directories: write into a temporary sibling, move into place on success."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged_dir(out: str | Path) -> Iterator[Path]:
    """A temporary sibling directory of ``out`` to write into. When the block completes its files
    move into ``out`` (created if needed, files of the same name replaced); when it raises,
    nothing is moved and ``out`` stays as it was (not even created)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        yield tmp
        out.mkdir(exist_ok=True)
        for item in sorted(tmp.iterdir()):
            os.replace(item, out / item.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def moved(paths: dict[str, Path], tmp: Path, out: Path) -> dict[str, Path]:
    """``paths`` inside ``tmp`` as they are named once moved into ``out``."""
    return {k: Path(out) / Path(p).relative_to(tmp) for k, p in paths.items()}
