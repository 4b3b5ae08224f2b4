"""``tcbench ARGS`` run in the test's own process, with what it writes to stdout and stderr.

A command started as ``python -m tcbench`` pays its imports (Hydra, MLflow, pandas, matplotlib)
anew, 5 to 7 s, before its first job; here they are paid once per test process. The tests of
what the commands do call :func:`tcbench` here; a few keep a real ``python -m tcbench`` (the
command-line smoke tests: ``run``, ``run -m`` and ``leaderboard`` in tests/test_cli.py with
``diagnose``, ``simulate`` and ``metrics`` in tests/test_simulate.py, ``list`` with plugins in
tests/test_plugins.py, ``export`` in tests/test_run_c_export.py), and so do the tests of what
only a process of its own shows (signals, kill -9, memory caps, sweeps racing on one store): all
but a worker killed mid-sweep (tests/test_sweep_failures.py) in the slow suite, with in-process
tests of what they reach in CI (a resume marking a gone process's runs, the memory refusals, the
checks of a server store).
"""

from __future__ import annotations

import contextlib
import logging
import os
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest


@contextlib.contextmanager
def _fd_captured() -> Iterator[dict[str, str]]:
    """File descriptors 1 and 2 (and ``sys.stdout``/``sys.stderr`` over them) sent to two
    temporary files, also what the worker processes a sweep starts write; their text, in the
    dict yielded (``out``, ``err``), once the block ends."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        saved_fds = os.dup(1), os.dup(2)
        saved_streams = sys.stdout, sys.stderr
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        sys.stdout = open(1, "w", encoding="utf-8", errors="replace", closefd=False, buffering=1)  # noqa: SIM115
        sys.stderr = open(2, "w", encoding="utf-8", errors="replace", closefd=False, buffering=1)  # noqa: SIM115
        texts: dict[str, str] = {}
        try:
            yield texts
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            sys.stdout, sys.stderr = saved_streams
            os.dup2(saved_fds[0], 1)
            os.dup2(saved_fds[1], 2)
            os.close(saved_fds[0])
            os.close(saved_fds[1])
            for name, file in (("out", out), ("err", err)):
                file.seek(0)
                texts[name] = file.read().decode("utf-8", "replace")


@contextlib.contextmanager
def _as_a_fresh_process(cwd: Path, env: Mapping[str, str | None] | None) -> Iterator[None]:
    """The working folder ``cwd``, the environment with ``env`` over it (a None value unsets its
    variable), and the root logger as a fresh process has it (no handler a Hydra run of an
    earlier call left); all restored after (the other loggers keep what imports set on them)."""
    old_cwd, old_env = Path.cwd(), dict(os.environ)
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    root.handlers, root.level = [], logging.WARNING
    for name, value in (env or {}).items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value
    os.chdir(cwd)
    try:
        yield
    finally:
        os.chdir(old_cwd)
        os.environ.clear()
        os.environ.update(old_env)
        root.handlers, root.level = handlers, level


def tcbench(*args: str, cwd: Path, env: Mapping[str, str | None] | None = None) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` in the folder ``cwd`` (with ``env`` over the environment, None unsetting), run by
    :func:`tcbench.cli.main` here: its exit code and its output, as :func:`subprocess.run` gives
    them for ``python -m tcbench ARGS``."""
    from hydra.core.global_hydra import GlobalHydra

    from tcbench.cli import main

    with _as_a_fresh_process(cwd, env), _fd_captured() as texts:
        GlobalHydra.instance().clear()
        try:
            code = main(list(args))
        finally:  # as after a process: no Hydra left initialised for the next test
            GlobalHydra.instance().clear()
    return subprocess.CompletedProcess(["tcbench", *args], code, texts["out"], texts["err"])


def install_here(monkeypatch: pytest.MonkeyPatch, site: Path) -> None:
    """The plugins of the folder ``site`` (modules and their ``*.dist-info`` entry points), as a
    process started with ``PYTHONPATH=site`` has them: on ``sys.path`` here and in the worker
    processes a sweep starts, and the registries of optimisers, learners, effects and diagnosis
    terms read anew (all undone after the test). The diagnosis reads its term lists from the
    registry at each use, so a term installed here is a candidate of the next diagnosis."""
    import importlib

    from tcbench.diagnose.terms import base as terms
    from tcbench.learners.registry import REGISTRY as LEARNERS
    from tcbench.optimisers.registry import REGISTRY as OPTIMISERS
    from tcbench.sensors.effects import PLUGINS as EFFECTS

    terms._registry()  # the built-in terms (and those installed before, left out below)
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")])))
    monkeypatch.setattr(terms, "_REGISTRY", {k: v for k, v in terms._REGISTRY.items()
                                             if type(v).__module__.startswith("tcbench.")})
    monkeypatch.setattr(terms, "_loaded", False)
    for registry in (OPTIMISERS, LEARNERS, EFFECTS, terms._PLUGINS):
        fresh = registry in (EFFECTS, terms._PLUGINS)  # a term registers on import: its module is imported anew
        monkeypatch.setattr(registry, "_points", None)
        monkeypatch.setattr(registry, "_entries", {} if fresh else dict(registry._entries))
        monkeypatch.setattr(registry, "_broken", {} if fresh else dict(registry._broken))
    tops = {p.stem for p in site.glob("*.py")} | {p.name for p in site.iterdir() if (p / "__init__.py").exists()}
    for module in [m for m in sys.modules if m.partition(".")[0] in tops]:  # imported anew, so their terms register
        monkeypatch.delitem(sys.modules, module)
    importlib.invalidate_caches()
    end_reused_workers()  # and, after the test, the ones started with the plugins are not reused


def end_reused_workers() -> None:
    """joblib's reused worker processes (a diagnosis's two smoothing windows run there) end: those
    started before a test installed plugins have neither the plugins' folder on their path nor
    their terms (and those started with them have them after it); the next ones start from this
    process's environment, as in a process started anew."""
    from joblib.externals.loky import reusable_executor

    with reusable_executor._executor_lock:
        executor, reusable_executor._executor = reusable_executor._executor, None
    if executor is not None:
        executor.shutdown(wait=True)
