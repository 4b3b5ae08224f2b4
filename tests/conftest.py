"""Shared fixtures: every test that touches MLflow or Hydra works in its own directory."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from threadpoolctl import threadpool_limits

os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")

# BLAS at one thread, in the test processes and in the commands they start (inherited): the
# tests run on two workers (pytest -n 2) and the code has its own process pools (joblib), so
# OpenBLAS's threads only spin against them on two cores (the diagnosis tests took 82 s on two
# workers with its default two threads, 49 s with one).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
threadpool_limits(1)  # where a plugin loaded numpy before this file

# The real recordings the tests read, from the repository's data/real/ (tcbench.data_paths),
# always there (tests/test_repository_data.py); imported here, after BLAS is set to one thread.
from tcbench.data_paths import REAL_DATA  # noqa: E402
from tcbench.datasets.real import TOFUPILOT_CSV  # noqa: E402

PAN_CSV = REAL_DATA / "pan_lsm6dsm_tvac_cooling" / "pan_lsm6dsm_tvac_cooling.csv"
PX4_LOG = REAL_DATA / "px4_ulog_samples" / "sample_log_small.ulg"
REAL_FILES = (TOFUPILOT_CSV, PAN_CSV, PX4_LOG)


@pytest.fixture(autouse=True, scope="session")
def _cache_dir(tmp_path_factory):  # type: ignore[no-untyped-def]
    """tcbench's user cache (the MLflow store template) in a folder of this test session."""
    old = os.environ.get("TCBENCH_CACHE_DIR")
    os.environ["TCBENCH_CACHE_DIR"] = str(tmp_path_factory.mktemp("tcbench-cache"))
    yield
    if old is None:
        os.environ.pop("TCBENCH_CACHE_DIR", None)
    else:
        os.environ["TCBENCH_CACHE_DIR"] = old


@pytest.fixture(autouse=True, scope="session")
def _sqlite_unsynced():  # type: ignore[no-untyped-def]
    """No fsync per commit on the SQLite stores the tests' own processes open through SQLAlchemy
    (MLflow's): a test's store lives for one test, and a commit's fsync cost about 5 ms here, some
    3 000 of them over the run. What is committed, and when, is unchanged; commands the tests start
    as processes keep SQLite's default."""
    from sqlalchemy import event
    from sqlalchemy.engine import Engine

    def unsynced(dbapi_connection, _record) -> None:  # type: ignore[no-untyped-def]
        if type(dbapi_connection).__module__.startswith("sqlite3"):
            dbapi_connection.execute("pragma synchronous = off")

    event.listen(Engine, "connect", unsynced)
    yield
    event.remove(Engine, "connect", unsynced)


@pytest.fixture(autouse=True)
def _tracking_store(tmp_path_factory, monkeypatch):  # type: ignore[no-untyped-def]
    """Every command a test runs tracks into a store of its own, never the checkout's ./mlflow.db
    (``workdir`` and tests of the default store unset it)."""
    monkeypatch.setenv("MLFLOW_TRACKING_URI", f"sqlite:///{tmp_path_factory.mktemp('mlflow') / 'mlflow.db'}")


@pytest.fixture(scope="session", autouse=True)
def _joblib_in_turn():  # type: ignore[no-untyped-def]
    """The code's own joblib work (a diagnosis's two smoothing windows) in turn in the test's process,
    module-scoped fixtures included: the two test workers already hold both cores, so the pool's workers
    only add their imports and their memory (tests/test_accel_chamber.py, whose module fixture diagnoses
    three cycles: 38.9 CPU-s with the pool, 33.7 in turn). Tests marked ``worker_processes`` start the
    workers as a user's process does (the same results: tests/test_diagnose_in_worker.py)."""
    from joblib import parallel_config

    with parallel_config(backend="sequential"):
        yield


@pytest.fixture(autouse=True)
def _joblib_workers_where_marked(request):  # type: ignore[no-untyped-def]
    """Tests marked ``worker_processes``: joblib's own default (its process pool), as outside the tests."""
    if not request.node.get_closest_marker("worker_processes"):
        yield
        return
    from joblib import parallel_config

    with parallel_config(backend="loky"):
        yield


@pytest.fixture(autouse=True)
def _figures_unrendered(request, monkeypatch):  # type: ignore[no-untyped-def]
    """A figure written to a PNG file is built (every line of the code that makes it runs: its data,
    labels, marks and file name) but not laid out or rasterised, outside the tests marked ``figures``:
    matplotlib's layout and rendering took 104 CPU-s of the default run over 314 figures (0.1 to 1 s
    each, most of it text and mathtext tick labels), in tests that only check the file is written,
    logged or staged. The file then holds a valid one-pixel PNG. The tests marked ``figures`` (the
    plots' own tests, at least one for every figure the package draws) render as a user's process does,
    and so do the module-scoped fixtures (set up before this one) and the commands the tests start as
    processes of their own. What it saves: README.md (the test command's paragraph)."""
    if request.node.get_closest_marker("figures"):
        yield
        return
    from matplotlib.figure import Figure

    rendered = Figure.savefig

    def savefig(self, fname, *args, **kwargs):  # type: ignore[no-untyped-def]
        if not isinstance(fname, str | os.PathLike) or (kwargs.get("format") or Path(fname).suffix[1:]) != "png":
            return rendered(self, fname, *args, **kwargs)
        Path(fname).write_bytes(_ONE_PIXEL_PNG)
        return None

    monkeypatch.setattr(Figure, "savefig", savefig)
    monkeypatch.setattr(Figure, "tight_layout", lambda self, *args, **kwargs: None)
    yield


def _one_pixel_png() -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (1, 1), "white").save(buf, format="png")
    return buf.getvalue()


_ONE_PIXEL_PNG = _one_pixel_png()


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """Run in an empty directory with no tracking server configured."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    return tmp_path


@pytest.fixture
def builds(monkeypatch):  # type: ignore[no-untyped-def]
    """The ids of the envs ``gym.make`` builds from now on, in order (no env kept by a plan check
    before: :mod:`tcbench.runner.kept_env`)."""
    import gymnasium

    from tcbench.runner import kept_env

    made: list[str] = []
    make = gymnasium.make

    def counted(env_id, *args, **kwargs):  # type: ignore[no-untyped-def]
        made.append(env_id if isinstance(env_id, str) else env_id.id)
        return make(env_id, *args, **kwargs)

    monkeypatch.setattr(gymnasium, "make", counted)
    monkeypatch.setattr(kept_env, "_kept", {})
    return made
