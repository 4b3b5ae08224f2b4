"""Content hashes of recordings: which data a run or a calibration used, whatever the files are called.

A file's digest is the sha256 of its bytes, read in blocks (a large recording is never held in
memory) and computed once per process for a file's size and modification time. A recording's
hash covers its table and its sidecar (``rec.json`` beside ``rec.csv``) when there is one.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Iterable
from pathlib import Path

from tcbench.sensors.recording import sidecar_path

HASH_HEX = 12  # hex digits of a content hash in keys and tags
BLOCK_BYTES = 1 << 20


class DataHashError(ValueError):
    """A recording that cannot be read to be hashed (one line naming it)."""


@functools.lru_cache(maxsize=256)
def _digest(path: str, size: int, mtime_ns: int, inode: int) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(BLOCK_BYTES):
            h.update(block)
    return h.hexdigest()


def file_sha256(path: str | Path) -> str:
    """The sha256 (64 hex) of one file's bytes; :class:`DataHashError` if it cannot be read."""
    try:
        resolved = Path(path).resolve()
        st = resolved.stat()
        if not resolved.is_file():
            raise IsADirectoryError(21, "not a file")
        return _digest(str(resolved), st.st_size, st.st_mtime_ns, st.st_ino)
    except OSError as exc:
        raise DataHashError(f"{path}: cannot be read to hash its content ({exc.strerror or exc})") from None


def _recording_digest(path: str | Path) -> str:
    side = sidecar_path(path)
    return f"{file_sha256(path)} {file_sha256(side) if side.is_file() and side != Path(path) else '-'}"


def content_hash(paths: Iterable[str | Path], *more: Iterable[str | Path]) -> str:
    """Short content hash (12 hex) of recordings: sha256 over each one's table digest and its
    sidecar's (``-`` for none), in order. ``more`` are further groups (e.g. the test files after
    the training files), hashed apart, so moving a recording from one group to another changes it."""
    h = hashlib.sha256()
    for group in (paths, *more):
        h.update(b"group\n")
        for p in group:
            h.update(f"{_recording_digest(p)}\n".encode())
    return h.hexdigest()[:HASH_HEX]


def shared_recordings(first: Iterable[str | Path], second: Iterable[str | Path]) -> list[str]:
    """The recordings of ``second`` that are also in ``first``: the same file (resolved path) or
    the same table bytes; as given in ``second``."""
    first = list(first)
    paths = {Path(p).resolve() for p in first}
    digests = {file_sha256(p) for p in first}
    return [str(p) for p in second if Path(p).resolve() in paths or file_sha256(p) in digests]
