"""The content hash that keys a user's data: the same bytes, the same key, whatever the file is called."""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from pathlib import Path

CHUNK_BYTES = 1 << 20


def content_hash(paths: Iterable[str | Path], length: int = 12) -> str:
    """The first ``length`` hex digits of the SHA-256 of the files' bytes, in order (a path that
    does not exist, such as an absent sidecar, adds nothing), read in chunks."""
    digest = hashlib.sha256()
    for path in paths:
        path = Path(path)
        if not path.is_file():
            continue
        with path.open("rb") as f:
            while chunk := f.read(CHUNK_BYTES):
                digest.update(chunk)
    return digest.hexdigest()[:length]
