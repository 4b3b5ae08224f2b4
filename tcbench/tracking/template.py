"""A fresh SQLite MLflow store in milliseconds: a copy of an empty, fully migrated store.

MLflow builds a new SQLite store by running its ~50 alembic migrations, about 1.5 s, which was
half of a sweep's wait for its first job. tcbench builds that empty store once per MLflow
version in the user cache (``$TCBENCH_CACHE_DIR``, else ``$XDG_CACHE_HOME/tcbench``, else
``~/.cache/tcbench``) and copies it wherever a new store is needed. The copy is the same database
MLflow would have made (its own migrations, its ``Default`` experiment), with the ``Default``
experiment's artifact folder set from the current directory as MLflow sets it. Both the template
and each copy are written to a temporary file and renamed into place, so no reader ever sees a
half-built store. If the cache cannot be used, MLflow creates the store itself as before.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import sqlite3
import time
import uuid
from collections.abc import Iterator
from contextlib import closing, contextmanager
from pathlib import Path

from filelock import FileLock

log = logging.getLogger(__name__)


def cache_dir() -> Path:
    """Where tcbench keeps its per-user cache."""
    explicit = os.environ.get("TCBENCH_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "tcbench"


def _is_store(path: Path) -> bool:
    """True if ``path`` is a SQLite file holding a migrated MLflow schema."""
    try:
        with closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as con:
            return con.execute("select count(*) from alembic_version").fetchone()[0] == 1
    except sqlite3.Error:
        return False


@contextmanager
def _fast_sqlite(path: Path) -> Iterator[None]:
    """No fsync per transaction on connections to ``path`` (a temporary file, fsynced once at the
    end): the migrations run about 1.5x faster."""
    from sqlalchemy import event
    from sqlalchemy.engine import Engine

    def on_connect(dbapi_connection, _record) -> None:  # type: ignore[no-untyped-def]
        files = [row[2] for row in dbapi_connection.execute("pragma database_list")]
        if str(path) in files:
            dbapi_connection.execute("pragma synchronous = off")

    event.listen(Engine, "connect", on_connect)
    try:
        yield
    finally:
        event.remove(Engine, "connect", on_connect)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _build(template: Path) -> None:
    """Let MLflow create and migrate an empty store at ``template`` (atomically)."""
    from mlflow.tracking import MlflowClient

    # a name never used before: MLflow keeps a client's engine per URI for the process's life
    tmp = template.with_name(f"{template.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        with _fast_sqlite(tmp):
            MlflowClient(f"sqlite:///{tmp}").search_experiments(max_results=1)
        _fsync(tmp)
        meta = {"cwd": str(Path.cwd())}
        tmp.with_suffix(".json.tmp").write_text(json.dumps(meta))
        os.replace(tmp.with_suffix(".json.tmp"), template.with_suffix(".json"))
        os.replace(tmp, template)
    finally:
        tmp.unlink(missing_ok=True)
        tmp.with_suffix(".json.tmp").unlink(missing_ok=True)


def template_path() -> Path:
    """The cached empty store for the installed MLflow version."""
    import mlflow

    return cache_dir() / f"mlflow-{mlflow.__version__}-empty.db"


def ensure_template() -> Path:
    """The cached empty store, built first if it or its note of where it was built is missing
    or unreadable."""
    template = template_path()
    template.parent.mkdir(parents=True, exist_ok=True)
    with FileLock(template.with_name(template.name + ".lock")):
        if not (_is_store(template) and template.with_suffix(".json").is_file()):
            _build(template)
    return template


def create_store(db: Path) -> bool:
    """Create the SQLite store ``db`` (which must not exist yet, or be empty) as a copy of the
    cached template; False, leaving ``db`` untouched, if the cache cannot be used."""
    try:
        template = ensure_template()
        built_in = Path(json.loads(template.with_suffix(".json").read_text())["cwd"])
    except (OSError, ValueError, KeyError, sqlite3.Error) as exc:
        log.debug("no store template (%s): MLflow creates %s itself", exc, db)
        return False
    tmp = db.with_name(f"{db.name}.{os.getpid()}.tmp")
    try:
        shutil.copyfile(template, tmp)
        with sqlite3.connect(tmp) as con:  # the Default experiment as MLflow makes it here and now
            (location,) = con.execute("select artifact_location from experiments where experiment_id = 0").fetchone()
            if Path(location).is_relative_to(built_in):
                location = str(Path.cwd() / Path(location).relative_to(built_in))
            now_ms = int(time.time() * 1000)
            con.execute("update experiments set artifact_location = ?, creation_time = ?, last_update_time = ?"
                        " where experiment_id = 0", (location, now_ms, now_ms))
        con.close()
        os.replace(tmp, db)
    except (OSError, sqlite3.Error, TypeError) as exc:
        log.debug("copying the store template failed (%s): MLflow creates %s itself", exc, db)
        return False
    finally:
        tmp.unlink(missing_ok=True)
    return True
