"""The checks of a tracking store that need no MLflow: which store a URI names, whether a local
SQLite store can be made or read, and whether a server answers (asked once, with a short
timeout). Kept apart from :mod:`tcbench.tracking.store` so that a command checks its store before
any work without importing MLflow (about 2.5 s); only an unknown kind of store imports it."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path

from tcbench.errors import error_line


def tracking_uri(uri: str | None = None) -> str:
    """The store to use: explicit ``uri``, else ``$MLFLOW_TRACKING_URI``, else ./mlflow.db."""
    if uri:
        return uri
    env = os.environ.get("MLFLOW_TRACKING_URI")
    if env:
        return env
    return f"sqlite:///{Path.cwd() / 'mlflow.db'}"


def sqlite_path(uri: str | None = None) -> Path | None:
    """The database file of a local SQLite store; None for any other store."""
    resolved = tracking_uri(uri)
    return Path(resolved[len("sqlite:///"):]) if resolved.startswith("sqlite:///") else None


class StoreError(Exception):
    """The tracking store cannot be used: one line saying why."""


def first_line(exc: BaseException) -> str:
    """One line of an exception's text (a database error's own message where it wraps one)."""
    return error_line(str(getattr(exc, "orig", None) or exc))[:300] or type(exc).__name__


def _http_problem(uri: str, timeout_s: float) -> str | None:
    """Why the MLflow server at ``uri`` cannot be used, asked once with a short timeout (MLflow's
    own client retries a dead server for minutes), or None."""
    import urllib.error
    import urllib.request
    from urllib.parse import urlsplit

    parts = urlsplit(uri)
    if not parts.hostname:
        return "no host in the address"
    try:
        port = parts.port or (443 if parts.scheme == "https" else 80)
        with socket.create_connection((parts.hostname, port), timeout=timeout_s):
            pass
    except (OSError, ValueError) as exc:
        return f"nothing answers at {parts.netloc} ({getattr(exc, 'strerror', None) or exc})"
    probe = uri.rstrip("/") + "/api/2.0/mlflow/experiments/search?max_results=1"
    try:
        with urllib.request.urlopen(probe, timeout=timeout_s) as reply:  # noqa: S310 - http(s) only
            json.loads(reply.read(1 << 20) or b"{}")
    except urllib.error.HTTPError as exc:
        if exc.code in (401, 403):
            return None  # a server that wants credentials: MLflow's client sends them
        return f"does not answer as an MLflow server (HTTP {exc.code} for {probe})"
    except (OSError, ValueError) as exc:
        return f"does not answer as an MLflow server ({getattr(exc, 'reason', None) or exc})"
    return None


def check_store(uri: str | None, *, create: bool, timeout_s: float = 5.0) -> str:
    """The resolved store URI if the store can be used, checked once and quickly; else a
    :class:`StoreError` with one line. ``create=False`` (reading, e.g. a leaderboard) refuses a
    local store that does not exist instead of making an empty one; ``create=True`` refuses one
    whose folder does not exist (no folder is made for a store)."""
    resolved = tracking_uri(uri)
    if resolved.startswith("sqlite:") and not resolved.removeprefix("sqlite:").lstrip("/").strip():
        raise StoreError(f"tracking store {resolved} names no database file (an in-memory store keeps nothing); "
                         "give one, e.g. sqlite:///mlflow.db")
    db = sqlite_path(resolved)
    if db is not None:
        if db.is_dir():
            raise StoreError(f"tracking store {db} is a folder, not a database file")
        if not create and not db.exists():
            raise StoreError(f"no tracking store at {db}: run a sweep here first, or name the store "
                             "(MLFLOW_TRACKING_URI, tracking.uri=, --tracking-uri)")
        from tcbench.outputs import folder_problem

        if create and not db.parent.exists() and not db.parent.is_symlink():
            raise StoreError(f"tracking store {db}: its folder {db.parent} does not exist; make it first "
                             "(a store's folder is never made for it)")
        if create and (problem := folder_problem(db.parent)):
            raise StoreError(f"tracking store {db}: its folder {db.parent} {problem}")
        return resolved
    if resolved.startswith(("http://", "https://")):
        problem = _http_problem(resolved, timeout_s)
    else:
        try:
            from mlflow.tracking import MlflowClient

            MlflowClient(tracking_uri=resolved).search_experiments(max_results=1)
            problem = None
        except Exception as exc:  # noqa: BLE001 - any failure of an unknown store is the user's to fix
            problem = first_line(exc)
    if problem:
        raise StoreError(f"tracking store {resolved}: {problem}")
    return resolved
