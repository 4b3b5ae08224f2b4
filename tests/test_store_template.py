"""A new SQLite store is a copy of a cached, migrated empty store: the same database MLflow makes."""

from __future__ import annotations

import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import mlflow
import pytest

from tcbench.tracking import template as store_template
from tcbench.tracking import store as tracking


def _schema_and_rows(db: Path) -> tuple[list[tuple], list[tuple], list[tuple]]:
    with sqlite3.connect(db) as con:
        # the clauses of a table's DDL, unordered: MLflow's own migrations order the constraints of
        # a rebuilt table differently from one process to the next (set iteration)
        schema = sorted((kind, name, tuple(sorted(c.strip() for c in (sql or "").split(","))))
                        for kind, name, sql in con.execute("select type, name, sql from sqlite_master"
                                                           " where name not like 'sqlite_%'"))
        version = con.execute("select version_num from alembic_version").fetchall()
        experiments = con.execute("select experiment_id, name, artifact_location, lifecycle_stage from experiments").fetchall()
    con.close()
    return schema, version, experiments


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_copy_equals_the_store_mlflow_builds(workdir: Path, cache: Path, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    # the template is built from another directory: the copy must still point Default at this one
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    template = store_template.ensure_template()
    with sqlite3.connect(template) as con:  # as if the template were built long ago
        con.execute("update experiments set creation_time = 0, last_update_time = 0")
    con.close()
    monkeypatch.chdir(workdir)
    assert store_template.create_store(workdir / "copy.db")
    mlflow.MlflowClient(f"sqlite:///{workdir / 'direct.db'}").search_experiments()
    copy, direct = _schema_and_rows(workdir / "copy.db"), _schema_and_rows(workdir / "direct.db")
    assert copy == direct  # experiments compared without their times
    assert copy[2][0][2] == str(workdir / "mlruns" / "0")
    with sqlite3.connect(workdir / "copy.db") as con:
        (created_ms,) = con.execute("select creation_time from experiments where experiment_id = 0").fetchone()
    con.close()
    assert abs(created_ms / 1000 - time.time()) < 60  # not the template's time


def test_prepare_store_uses_the_template_and_leaves_no_temporary_file(workdir: Path, cache: Path) -> None:
    uri = f"sqlite:///{workdir / 'sub' / 'mlflow.db'}"
    eid = tracking.prepare_store(uri, "tcbench")
    assert store_template.template_path().is_file()
    client = mlflow.MlflowClient(uri)
    assert client.get_experiment_by_name("tcbench").experiment_id == eid
    run = client.create_run(eid)
    client.log_metric(run.info.run_id, "m", 1.5)
    assert client.get_run(run.info.run_id).data.metrics == {"m": 1.5}
    assert sorted(p.name for p in (workdir / "sub").iterdir()) == ["mlflow.db", "mlflow.db.lock"]


def test_a_job_on_a_new_store_makes_it_from_the_template(workdir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A job's run (the library's :func:`~tcbench.runner.job.run_job`, no command before it) on a
    store not made yet copies the migrated empty store, as a command does, instead of letting MLflow
    migrate one; a resume's lookup on no store makes none."""
    from test_tracking import BASE

    from tcbench.runner.job import run_job

    made: list[Path] = []
    create = store_template.create_store
    monkeypatch.setattr(store_template, "create_store", lambda db: made.append(Path(db)) or create(db))
    uri = f"sqlite:///{workdir / 'new.db'}"
    cfg = {**BASE, "tracking": {**BASE["tracking"], "uri": uri, "resume": True}}
    assert tracking.finished_run(cfg) is None and not (workdir / "new.db").exists()
    assert run_job(cfg) is not None
    assert made == [workdir / "new.db"]
    assert tracking.finished_run(cfg) is not None


@pytest.mark.parametrize("damage", ["garbage", "no note"])
def test_a_broken_template_is_rebuilt(workdir: Path, cache: Path, damage: str) -> None:
    template = store_template.ensure_template()
    if damage == "garbage":
        template.write_bytes(b"garbage, not SQLite")
    else:
        template.with_suffix(".json").unlink()
    assert store_template.create_store(workdir / "a.db")
    assert _schema_and_rows(workdir / "a.db")[1]  # migrated
    assert _schema_and_rows(template)[1] and template.with_suffix(".json").is_file()


def test_an_unusable_cache_leaves_the_store_to_mlflow(workdir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (workdir / "cache").write_text("a file where the cache folder should be")
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(workdir / "cache"))
    assert not store_template.create_store(workdir / "b.db")
    assert not (workdir / "b.db").exists()
    uri = f"sqlite:///{workdir / 'b.db'}"
    eid = tracking.prepare_store(uri, "tcbench")  # MLflow migrates it itself
    assert mlflow.MlflowClient(uri).get_experiment_by_name("tcbench").experiment_id == eid


def test_an_existing_store_is_not_replaced(workdir: Path, cache: Path) -> None:
    uri = f"sqlite:///{workdir / 'mlflow.db'}"
    tracking.prepare_store(uri, "first")
    tracking.prepare_store(uri, "second")
    names = {e.name for e in mlflow.MlflowClient(uri).search_experiments()}
    assert {"first", "second"} <= names


_FLOCK = ("import fcntl, sys; h = open(sys.argv[1], 'a'); print('waiting', flush=True); "
          "fcntl.flock(h, fcntl.LOCK_EX | (fcntl.LOCK_NB if sys.argv[2] == 'try' else 0)); print('got', flush=True)")


def test_the_store_lock_is_an_exclusive_blocking_flock_on_db_lock(workdir: Path) -> None:
    """Held by one process, the lock on ``<db>.lock`` is refused to another's non-blocking
    ``flock`` (so it also excludes a tcbench that locks with plain ``flock``), and another's
    blocking ``flock`` waits until it is released."""
    db = workdir / "mlflow.db"
    lock = db.with_name("mlflow.db.lock")
    with tracking.store_lock(f"sqlite:///{db}"):
        assert lock.is_file()
        tried = subprocess.run([sys.executable, "-c", _FLOCK, str(lock), "try"], capture_output=True, text=True)
        assert tried.returncode != 0 and "BlockingIOError" in tried.stderr
        waiter = subprocess.Popen([sys.executable, "-c", _FLOCK, str(lock), "wait"], stdout=subprocess.PIPE, text=True)
        assert waiter.stdout is not None and waiter.stdout.readline() == "waiting\n"
        time.sleep(0.5)
        assert waiter.poll() is None  # still blocked in flock
    assert waiter.wait(timeout=30) == 0 and waiter.stdout.read() == "got\n"
    assert subprocess.run([sys.executable, "-c", _FLOCK, str(lock), "try"], capture_output=True).returncode == 0
    assert lock.is_file()  # left in place for the next process, as before


def test_the_tests_stores_commit_without_fsync(tmp_path: Path) -> None:
    """The tests' own rule (tests/conftest.py): a SQLite connection made through SQLAlchemy, as
    MLflow makes its store's, skips the fsync per commit; sqlite3's own connections keep the default."""
    from sqlalchemy import create_engine

    engine = create_engine(f"sqlite:///{tmp_path / 'x.db'}")
    try:
        with engine.connect() as con:
            assert con.exec_driver_sql("pragma synchronous").scalar() == 0  # off
    finally:
        engine.dispose()
    with sqlite3.connect(tmp_path / "y.db") as plain:
        assert plain.execute("pragma synchronous").fetchone()[0] == 2  # full, SQLite's default
    plain.close()
