"""Writing the pages: into a command's ``out=`` (nothing outside it, existing files replaced only
with ``overwrite``) and into the site's generated folder at build time, where a file is rewritten
only when its bytes change and files the pages no longer have are removed, so that ``mkdocs
serve`` does not rebuild for ever."""

from __future__ import annotations

import os
import shutil
from pathlib import Path, PurePosixPath

from tcbench.leaderboard.pages.render import Content
from tcbench.outputs import temp_name


def content(value: Content) -> bytes:
    """A file's bytes: given, read from the committed file, or made now (a plot)."""
    if isinstance(value, bytes):
        return value
    if isinstance(value, Path):
        return value.read_bytes()
    return value()


def _write(target: Path, data: bytes) -> None:
    """``data`` into ``target`` through a hidden temporary file beside it, renamed when complete."""
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(temp_name(target.name, "pages"))
    try:
        tmp.write_bytes(data)
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def write_files(files: dict[PurePosixPath, Content], out: Path) -> list[Path]:
    """Every file under ``out`` (made if missing); the paths written. Checks of what may be
    replaced are the caller's (:func:`tcbench.staging.check_targets`)."""
    written = []
    for rel in sorted(files):
        target = out / rel
        _write(target, content(files[rel]))
        written.append(target)
    return written


def sync_files(files: dict[PurePosixPath, Content], folder: Path) -> tuple[int, int]:
    """Make ``folder`` (a generated folder: the site's ``docs/leaderboards/``) hold exactly
    ``files``: write those whose bytes differ, remove every other file and the folders left
    empty. The numbers of files written and removed."""
    written = 0
    for rel in sorted(files):
        target = folder / rel
        data = content(files[rel])
        if target.is_file() and target.read_bytes() == data:
            continue
        if target.is_dir():
            shutil.rmtree(target)
        _write(target, data)
        written += 1
    keep = {folder / rel for rel in files}
    removed = 0
    for path in sorted(folder.rglob("*"), reverse=True):
        if path.is_dir() and not path.is_symlink():
            if not any(path.iterdir()):
                path.rmdir()
        elif path not in keep:
            path.unlink()
            removed += 1
    return written, removed
