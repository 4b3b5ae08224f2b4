"""Results that take minutes and depend only on their inputs and the code, kept between processes.

The VMD tuning of a gyro task (MOPSO's 440 fuzzy-entropy evaluations: about two CPU-minutes,
70 % of a BAS-Elman run) depends on the training record and the tuner's settings alone (its
random stream is fixed), so every row of an experiment on the same draw of runs tunes the same
thing. :func:`remembered` keeps such a result in tcbench's user cache
(:func:`~tcbench.tracking.template.cache_dir`, beside the store template) under a key made of
the inputs given, the bytes of any recording file among them, the versions of numpy and scipy
and the digest of tcbench's own source: a change to any of them makes a new key, never a stale
hit. A result is written to a temporary file and renamed into place (concurrent workers may both
compute it; neither sees half a file); a cache that cannot be used computes without keeping.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import logging
import os
import pickle
import uuid
from collections.abc import Callable
from importlib.metadata import version
from pathlib import Path
from typing import Any, TypeVar

from tcbench.tracking.template import cache_dir

log = logging.getLogger(__name__)
T = TypeVar("T")
PACKAGE = Path(__file__).resolve().parents[1]


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """Digest of every Python file of the tcbench package (paths and bytes)."""
    h = hashlib.blake2b(digest_size=16)
    for path in sorted(PACKAGE.rglob("*.py")):
        h.update(str(path.relative_to(PACKAGE)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _file_digest(path: str) -> str:
    return hashlib.blake2b(Path(path).read_bytes(), digest_size=16).hexdigest()


def key_of(inputs: dict[str, Any], files: list[str] | tuple[str, ...] = ()) -> str:
    """The cache key of ``inputs`` (JSON-serialisable) and the contents of ``files``."""
    payload = {"inputs": inputs, "files": {f: _file_digest(f) for f in files}, "numpy": version("numpy"),
               "scipy": version("scipy"), "tcbench": source_digest()}
    return hashlib.blake2b(json.dumps(payload, sort_keys=True, default=str).encode(), digest_size=20).hexdigest()


def remembered(kind: str, key: str, compute: Callable[[], T]) -> T:
    """``compute()``, or the result kept under ``kind``/``key`` by an earlier call."""
    path = cache_dir() / kind / f"{key}.pkl"
    try:
        with path.open("rb") as f:
            value = pickle.load(f)
        log.info("%s: the result kept in %s", kind, path)
        return value
    except FileNotFoundError:
        pass
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError) as exc:  # unreadable: computed anew
        log.info("%s: %s not read (%s); computing", kind, path, exc)
    value = compute()
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tmp.open("wb") as f:
            pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except OSError as exc:
        log.info("%s: not kept (%s)", kind, exc)
        with contextlib.suppress(OSError):  # a full disk leaves no half-written file behind
            tmp.unlink(missing_ok=True)
    return value
