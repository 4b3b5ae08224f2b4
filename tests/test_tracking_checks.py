"""A command checks its tracking store before any work without importing MLflow; the checks
stay reachable from :mod:`tcbench.tracking.store` as before."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tcbench.tracking import announce, checks, store
from tcbench.tracking.template import create_store


def test_the_store_checks_import_no_mlflow(tmp_path: Path) -> None:
    code = ("import sys; from tcbench.tracking.checks import check_store; "
            f"print(check_store('sqlite:///{tmp_path / 'm.db'}', create=True)); "
            "print('mlflow' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == [f"sqlite:///{tmp_path / 'm.db'}", "False"]


def test_the_checks_are_the_store_s(tmp_path: Path) -> None:
    assert store.check_store is checks.check_store and store.StoreError is checks.StoreError
    (tmp_path / "folder.db").mkdir()
    with pytest.raises(store.StoreError, match="is a folder"):
        store.check_store(f"sqlite:///{tmp_path / 'folder.db'}", create=True)
    with pytest.raises(checks.StoreError, match="no tracking store"):
        checks.check_store(f"sqlite:///{tmp_path / 'none.db'}", create=False)


@pytest.fixture
def http_answering(request: pytest.FixtureRequest):  # type: ignore[no-untyped-def]
    """A local HTTP server answering every GET with the status and body of ``request.param``."""
    import http.server
    import threading

    status, body = request.param

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 - the standard library's name
            self.send_response(status)
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args: object) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.parametrize(("http_answering", "problem"), [
    ((200, b'{"experiments": []}'), None),
    ((401, b""), None),  # credentials wanted: MLflow's client sends them
    ((404, b"no such page"), "does not answer as an MLflow server (HTTP 404 for "),
    ((200, b"<html>a web page</html>"), "does not answer as an MLflow server ("),
], indirect=["http_answering"])
def test_a_server_store_is_asked_once_whether_it_is_mlflow(http_answering: str, problem: str | None) -> None:
    if problem is None:
        assert checks.check_store(http_answering, create=True) == http_answering
    else:
        with pytest.raises(checks.StoreError, match=rf"^tracking store {http_answering}: ") as info:
            checks.check_store(http_answering, create=True)
        assert problem in str(info.value) and "\n" not in str(info.value)


def test_the_store_helpers_on_runs_and_processes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A server store takes no file lock and keeps no local artifacts; a finished process is not
    alive; a run is marked ended with its error; every job run is announced to ``on_run_created``."""
    monkeypatch.chdir(tmp_path)
    with store.store_lock("http://127.0.0.1:5000"):
        assert list(tmp_path.iterdir()) == []  # no lock file: the server keeps its own store
    assert store.local_artifact_dir("http://127.0.0.1:5000/artifacts/1") is None
    assert store.local_artifact_dir(f"file://{tmp_path}") == tmp_path
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    assert not store.process_alive(gone.pid) and store.process_alive(os.getpid())
    uri = f"sqlite:///{tmp_path / 'mlflow.db'}"
    create_store(tmp_path / "mlflow.db")  # the migrated empty store, copied
    created: list[str] = []
    monkeypatch.setattr(announce, "on_run_created", created.append)
    cfg = {"tracking": {"uri": uri, "experiment": "helpers"}, "seed": 0}
    with store.job_run(cfg, "job", {}) as run:
        pass
    assert created == [run.run_id]
    c = store.client(uri)
    assert c.get_run(run.run_id).info.status == "FINISHED"
    assert store.mark_failed(c, run.run_id, "worker died")
    ended = c.get_run(run.run_id)
    assert ended.info.status == "FAILED" and ended.data.tags["tcbench.error"] == "worker died"
