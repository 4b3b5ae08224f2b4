"""All-or-nothing output directories: write into a temporary sibling, move into place on success."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from tcbench.outputs import overwritten_input, short_name


class InputOverwriteError(ValueError):
    """Moving the staged files into place would replace one of the command's input files."""

    def __init__(self, target: Path, source: Path) -> None:
        self.target, self.source = target, source
        super().__init__(f"writing {target} would replace the input {source}")


@contextmanager
def staged_dir(out: str | Path, inputs: Iterable[str | Path] = ()) -> Iterator[Path]:
    """A temporary sibling directory of ``out`` to write into. When the block completes its files
    move into ``out`` (created if needed, files of the same name replaced, folders merged); when
    it raises, nothing is moved and ``out`` stays as it was (not even created, nor its missing
    parents). A staged file that would replace one of ``inputs`` raises
    :class:`InputOverwriteError` before anything is moved."""
    out = Path(out)
    made = _make_parents(out.parent)
    moved_any = False
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{short_name(out.name)}.", dir=out.parent))
        try:
            yield tmp
            staged = [out / p.relative_to(tmp) for p in tmp.rglob("*") if not p.is_dir()]
            if clash := overwritten_input(staged, inputs):
                raise InputOverwriteError(*clash)
            moved_any = True
            out.mkdir(exist_ok=True)
            _move_into(tmp, out)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    except BaseException:
        if not moved_any:
            _remove_empty(made)
        raise


def _make_parents(folder: Path) -> list[Path]:
    """Make ``folder`` and its missing ancestors; the ones made, deepest first."""
    missing = []
    while not folder.exists() and folder.parent != folder:
        missing.append(folder)
        folder = folder.parent
    for made in reversed(missing):
        made.mkdir(exist_ok=True)
    return missing


def _remove_empty(folders: list[Path]) -> None:
    """Remove those of ``folders`` (deepest first) that are empty."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def _move_into(src: Path, dst: Path) -> None:
    """Move the entries of folder ``src`` into folder ``dst``: files replace those of the same
    name, a folder that already exists there receives the entries of the new one."""
    for item in sorted(src.iterdir()):
        target = dst / item.name
        if item.is_dir() and target.is_dir():
            _move_into(item, target)
        else:
            os.replace(item, target)


def moved(paths: dict[str, Path], tmp: Path, out: Path) -> dict[str, Path]:
    """``paths`` inside ``tmp`` as they are named once moved into ``out``."""
    return {k: Path(out) / Path(p).relative_to(tmp) for k, p in paths.items()}
