"""All-or-nothing output directories: write into a temporary sibling, move into place on success.

Before anything moves, every target is checked: no staged file may replace an input, go through
a link that leads out of the output folder, land on a folder (or a staged folder on a file), or
replace an existing file unless ``overwrite`` is given. A refusal leaves the folder as it was."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path, PurePath

from tcbench.outputs import overwritten_input, short_name


class InputOverwriteError(ValueError):
    """Moving the staged files into place would replace one of the command's input files."""

    def __init__(self, target: Path, source: Path) -> None:
        self.target, self.source = target, source
        super().__init__(f"writing {target} would replace the input {source}")


class OutputRefusedError(ValueError):
    """An output cannot be moved into its folder: a link there leads out of it, or a file would
    land where a folder is (or a folder where a file is)."""


class OutputExistsError(OutputRefusedError):
    """Output files already exist and ``overwrite`` was not given; ``existing`` lists them."""

    def __init__(self, existing: list[Path]) -> None:
        self.existing = existing
        more = len(existing) - 1
        super().__init__(f"{existing[0]} already exists" + (f" (and {more} more file{'s' * (more > 1)})" if more else ""))


def refusal_line(exc: OutputRefusedError, hint: str = "out=") -> str:
    """A command's one line for a refused output: for existing files, how to replace them or
    what else to change (``hint``: ``out=``, ``out= or name=``)."""
    if isinstance(exc, OutputExistsError):
        them = "it" if len(exc.existing) == 1 else "them"
        return f"{exc}; give overwrite=true to replace {them}, or choose another {hint}"
    return str(exc)


REPLACED = "tcbench: overwrite=true: replaced "  # how the line below starts


def replaced_line(replaced: list[Path], shown: int = 5) -> str:
    """The one line an ``overwrite=true`` command prints for the files it replaced."""
    names = ", ".join(str(p) for p in replaced[:shown])
    more = len(replaced) - shown
    return f"{REPLACED}{names}" + (f" and {more} more file{'s' * (more > 1)}" if more > 0 else "")


def _inside(path: Path, root: Path) -> bool:
    return path == root or path.is_relative_to(root)


def _link_out_of(out: Path, root: Path, rel: PurePath) -> Path | None:
    """The first link on the way from ``out`` to ``out/rel`` (``rel`` itself included) whose
    target lies outside ``root`` (``out`` resolved), or None."""
    path = out
    for part in rel.parts:
        path = path / part
        if os.path.islink(path) and not _inside(Path(os.path.realpath(path)), root):
            return path
        if not os.path.lexists(path):
            return None
    return None


def check_targets(out: str | Path, entries: Iterable[tuple[str | PurePath, bool]], overwrite: bool = False) -> list[Path]:
    """Check that each entry (a path relative to ``out``, True when it is a folder) can be put
    into ``out``; the existing files it would replace. Raises :class:`OutputRefusedError` for a
    link out of ``out`` or a file where a folder is (or the reverse), and
    :class:`OutputExistsError` for existing files without ``overwrite``. Nothing is changed."""
    out = Path(out)
    root = Path(os.path.realpath(out))
    existing: list[Path] = []
    for rel, is_dir in entries:
        rel = PurePath(rel)
        if link := _link_out_of(out, root, rel):
            raise OutputRefusedError(f"{link} is a link to {os.path.realpath(link)}, outside out={out}: tcbench "
                                     "writes nothing through it; remove the link or choose another out=")
        target = out / rel
        if not os.path.lexists(target):
            continue
        if is_dir and not target.is_dir():
            raise OutputRefusedError(f"{target} is a file where an output folder goes; move it away or choose "
                                     "another out=")
        if not is_dir and target.is_dir():
            raise OutputRefusedError(f"{target} is a folder where an output file goes; move it away or choose "
                                     "another out=")
        if not is_dir:
            existing.append(target)
    if existing and not overwrite:
        raise OutputExistsError(existing)
    return existing


@contextmanager
def staged_dir(out: str | Path, inputs: Iterable[str | Path] = (), overwrite: bool = False,
               replaced: list[Path] | None = None) -> Iterator[Path]:
    """A temporary sibling directory of ``out`` to write into. When the block completes its files
    move into ``out`` (created if needed, folders merged); when it raises, nothing is moved and
    ``out`` stays as it was (not even created, nor its missing parents). Before anything moves,
    a staged file that would replace one of ``inputs`` raises :class:`InputOverwriteError`, and
    the targets are checked by :func:`check_targets` (existing files are replaced only with
    ``overwrite``; their paths are appended to ``replaced``)."""
    out = Path(out)
    made = _make_parents(out.parent)
    moved_any = False
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{short_name(out.name)}.", dir=out.parent))
        try:
            yield tmp
            entries = sorted((p.relative_to(tmp), p.is_dir()) for p in tmp.rglob("*"))
            if clash := overwritten_input([out / rel for rel, is_dir in entries if not is_dir], inputs):
                raise InputOverwriteError(*clash)
            existing = check_targets(out, entries, overwrite)
            moved_any = True
            out.mkdir(exist_ok=True)
            _move_into(tmp, out)
            if replaced is not None:
                replaced.extend(existing)
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
