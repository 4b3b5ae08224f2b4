"""A sweep goes on whatever its jobs do: raise, call ``sys.exit``, kill their worker; with
tracking or without; and a killed sweep's runs do not stay RUNNING for ever."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_here import install_here
from cli_here import tcbench as here
from mlflow.tracking import MlflowClient

# An optimiser plugin whose behaviour the task's dimension picks: 2-D works, 3-D calls
# sys.exit(3), 4-D kills its own process, 5-D raises, 6-D sleeps while $CRASHY_SLEEP is set,
# 7-D allocates 400 MB.
CRASHY = (
    "import os, signal, sys, time\n"
    "from tcbench.optimisers.fa import FireflyAlgorithm\n"
    "class Crashy(FireflyAlgorithm):\n"
    "    name = 'crashy'\n"
    "    def ask(self):\n"
    "        d = self.lower.size\n"
    "        if d == 3:\n"
    "            sys.exit(3)\n"
    "        if d == 4:\n"
    "            os.kill(os.getpid(), signal.SIGKILL)\n"
    "        if d == 5:\n"
    "            raise RuntimeError('crashy broke')\n"
    "        if d == 6 and os.environ.get('CRASHY_SLEEP'):\n"
    "            time.sleep(600)\n"
    "        if d == 7:\n"
    "            import numpy\n"
    "            numpy.ones(50_000_000)\n"
    "        return super().ask()\n"
)


@pytest.fixture
def site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A directory on PYTHONPATH holding the crashing optimiser as an installed plugin, here
    (:func:`tcbench`) and in the processes :func:`in_a_process` starts."""
    site = tmp_path / "site"
    info = site / "crashy_plugin-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: crashy_plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[tcbench.optimisers]\ncrashy = crashy_mod:Crashy\n")
    (site / "crashy_mod.py").write_text(CRASHY)
    install_here(monkeypatch, site)
    return site


def tcbench(*args: str, cwd: Path, site: Path) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` run in this process with the plugins of ``site`` and no tracking URI set."""
    assert str(site) in os.environ["PYTHONPATH"]
    return here(*args, cwd=cwd, env={"MLFLOW_TRACKING_URI": None})


def in_a_process(*args: str, cwd: Path, site: Path, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m tcbench ARGS`` in a process of its own with the plugins of ``site``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")]))}
    env.pop("MLFLOW_TRACKING_URI", None)
    return subprocess.run([sys.executable, "-m", "tcbench", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


def statuses(cwd: Path) -> dict[str, list[str]]:
    """Run status by task key ``sphere-<d>d``."""
    c = MlflowClient(tracking_uri=f"sqlite:///{cwd / 'mlflow.db'}")
    exp = c.get_experiment_by_name("tcbench")
    out: dict[str, list[str]] = {}
    for r in c.search_runs([exp.experiment_id], max_results=1000):
        out.setdefault(r.data.tags["tcbench.task"], []).append(r.info.status)
    return out


@pytest.mark.parametrize("workers", [1, 2])
def test_a_job_that_exits_or_kills_its_worker_fails_alone(site: Path, tmp_path: Path, workers: int) -> None:
    """sys.exit(3) used to end the whole sweep (exit 3, 2 of 8 runs recorded); a killed worker
    ended it with BrokenProcessPool and a run left RUNNING. Every job now leaves a run, the bad
    ones FAILED, and the command exits 1 after naming them."""
    dims = "2,3,5" if workers == 1 else "2,3,4,5"  # the SIGKILL case would kill the main process itself
    seeds = 2 if workers == 1 else 1  # on workers, one job of each kind shows it: 4 jobs, not 8
    run = tcbench("run", "-m", "task=sphere", f"task.dim={dims}", "optimiser=fa", "optimiser.name=crashy",
                  f"seed=range({seeds})", "budget=60", f"hydra.launcher.n_jobs={workers}", cwd=tmp_path, site=site)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "Traceback" not in run.stderr
    s = statuses(tmp_path)
    assert s.pop("sphere-2d") == ["FINISHED"] * seeds
    assert len(s) == len(dims.split(",")) - 1 and all(v == ["FAILED"] * seeds for v in s.values()), s
    n = seeds * len(dims.split(","))
    assert f"{n} jobs recorded" in run.stdout and f"{n - seeds} failed" in run.stdout
    assert "sys.exit(3)" in run.stdout and "RuntimeError: crashy broke" in run.stdout
    if workers == 2:
        assert "killed by signal SIGKILL" in run.stdout


def test_untracked_failures_are_listed_and_the_sweep_goes_on(site: Path, tmp_path: Path) -> None:
    """With tracking off a raising job ended the sweep with a traceback."""
    run = tcbench("run", "-m", "task=sphere", "task.dim=5,2,3", "optimiser=fa", "optimiser.name=crashy",
                  "seed=0", "budget=60", "tracking.enabled=false", cwd=tmp_path, site=site)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "Traceback" not in run.stderr
    assert "2 of 3 jobs failed" in run.stdout
    assert "RuntimeError: crashy broke" in run.stdout and "sys.exit(3)" in run.stdout
    assert not (tmp_path / "mlflow.db").exists()


def test_a_job_too_big_by_its_estimate_is_refused_before_it_starts(site: Path, tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``task.dim=100000000`` grew to 24 GB and was killed by the kernel without a word: a job too
    big by its optimiser's estimate is refused before it starts, against the free memory or
    ``$TCBENCH_JOB_MEMORY_MB``, which must be a positive number of megabytes."""
    args = ("run", "task=sphere", "task.dim=100000000", "budget=200")
    before = tcbench(*args, cwd=tmp_path, site=site)
    assert before.returncode == 2 and "Traceback" not in before.stderr
    assert "task.dim=100000000: a run of optimiser ifa would need about" in before.stderr
    assert "one job may use here (free memory, or $TCBENCH_JOB_MEMORY_MB)" in before.stderr
    monkeypatch.setenv("TCBENCH_JOB_MEMORY_MB", "1.5")
    small = tcbench("run", "task=sphere", "task.dim=20000", "budget=200", cwd=tmp_path, site=site)
    assert small.returncode == 2 and "more than the 1.5 MB one job may use here" in small.stderr
    for bad, words in (("lots", "must be a number of megabytes, got 'lots'"), ("-3", "must be positive, got '-3'")):
        monkeypatch.setenv("TCBENCH_JOB_MEMORY_MB", bad)
        out = tcbench(*args, cwd=tmp_path, site=site)
        assert out.returncode == 2 and f"$TCBENCH_JOB_MEMORY_MB {words}" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "mlflow.db").exists()


def test_a_memory_error_names_the_budget() -> None:
    from tcbench.runner.job import FAILURES, failed

    try:
        failure = failed("big-job", MemoryError())
    finally:
        FAILURES.clear()
    assert failure.error == "MemoryError (more than one job may use here: the memory free when it started, " \
        "or $TCBENCH_JOB_MEMORY_MB)" and not failure.user
    try:
        failure = failed("big-job", MemoryError("Unable to allocate 3 GiB"))
    finally:
        FAILURES.clear()
    assert failure.error.startswith("MemoryError: Unable to allocate 3 GiB (more than one job may use here")


@pytest.mark.slow  # a process of its own, capped: tests/test_sweep_failures.py's refusals above stay in CI
def test_a_job_past_its_memory_is_a_failed_job_not_a_killed_machine(site: Path, tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """A job that allocates past the budget fails with a MemoryError while the sweep goes on."""
    monkeypatch.setenv("TCBENCH_JOB_MEMORY_MB", "200")  # a cap on the process of its one job: not this one
    run = in_a_process("run", "-m", "task=sphere", "task.dim=7,2", "optimiser=fa", "optimiser.name=crashy",
                  "seed=0", "budget=60", cwd=tmp_path, site=site)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "Traceback" not in run.stderr
    assert statuses(tmp_path) == {"sphere-7d": ["FAILED"], "sphere-2d": ["FINISHED"]}
    assert "MemoryError" in run.stdout and "TCBENCH_JOB_MEMORY_MB" in run.stdout + run.stderr  # the log line: stderr


def running_now(cwd: Path) -> dict[str, int]:
    """RUNNING runs by task key, read from the store without touching it: an ``MlflowClient``
    polled while the sweep is still creating the store would create (and migrate) it too."""
    db = cwd / "mlflow.db"
    if not db.exists():
        return {}
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=1) as con:
            rows = con.execute("SELECT t.value FROM runs r JOIN tags t ON t.run_uuid = r.run_uuid "
                               "WHERE t.key = 'tcbench.task' AND r.status = 'RUNNING'").fetchall()
    except sqlite3.Error:  # the store's tables are not made yet, or it is locked for a moment
        return {}
    out: dict[str, int] = {}
    for (task,) in rows:
        out[task] = out.get(task, 0) + 1
    return out


def _wait_for(predicate, timeout_s: float) -> bool:  # type: ignore[no-untyped-def]
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.2)
    return False


def _children(pid: int) -> set[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True)
    return {int(p) for p in out.stdout.split()}


def test_a_resume_marks_the_runs_of_a_gone_process_killed(tmp_path: Path) -> None:
    """A sweep's runs left RUNNING by a process of this host that no longer exists are marked KILLED
    by a resume of the sweep (which then runs their jobs again); runs of a live process or of
    another host are left alone (the kill -9 of a whole sweep, workers and all, is the slow test below)."""
    import socket

    args = ("run", "-m", "task=sphere", "optimiser=fa", "seed=range(2)", "budget=60", "tracking.sweep_id=gone")
    first = here(*args, cwd=tmp_path, env={"MLFLOW_TRACKING_URI": None})
    assert first.returncode == 0, first.stderr
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"])
    c = MlflowClient(tracking_uri=f"sqlite:///{tmp_path / 'mlflow.db'}")
    exp = c.get_experiment_by_name("tcbench").experiment_id
    left = {name: c.create_run(exp, run_name=name, tags={"tcbench.sweep_id": "gone", "tcbench.host": host,
                                                          "tcbench.pid": str(pid), "tcbench.task": "sphere-2d"}).info.run_id
            for name, host, pid in (("dead", socket.gethostname(), gone.pid), ("alive", socket.gethostname(), alive.pid),
                                    ("elsewhere", "another-host", gone.pid))}
    try:
        resume = here(*args, "tracking.resume=true", cwd=tmp_path, env={"MLFLOW_TRACKING_URI": None})
    finally:
        alive.kill()
        alive.wait()
    assert resume.returncode == 0, resume.stdout + resume.stderr
    assert "1 run of sweep gone left RUNNING by a process that is gone marked KILLED" in resume.stderr
    dead = c.get_run(left["dead"])
    assert dead.info.status == "KILLED"
    assert dead.data.tags["tcbench.error"] == f"process {gone.pid} on {socket.gethostname()} killed (found RUNNING)"
    assert [c.get_run(left[k]).info.status for k in ("alive", "elsewhere")] == ["RUNNING", "RUNNING"]


@pytest.mark.slow  # processes killed from outside; the resume's marking above stays in CI
@pytest.mark.skipif(sys.platform != "linux", reason="process groups and pgrep as on Linux")
def test_killed_sweep_workers_exit_and_resume_marks_dead_runs(site: Path, tmp_path: Path) -> None:
    """kill -9 of the sweep's main process left its workers (and the resource tracker) alive for
    ever, and the runs they held RUNNING: every later resume exited 1. Now the workers exit with
    their parent, and a resume marks the dead runs KILLED and completes the sweep (exit 0)."""
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"} | {"PYTHONPATH": str(site)}
    args = [sys.executable, "-m", "tcbench", "run", "-m", "task=sphere", "task.dim=6", "optimiser=fa",
            "optimiser.name=crashy", "seed=range(2)", "budget=60", "hydra.launcher.n_jobs=2",
            "tracking.sweep_id=killme"]
    log = tmp_path / "sweep.log"
    with log.open("w") as sink:
        proc = subprocess.Popen(args, cwd=tmp_path, env=env | {"CRASHY_SLEEP": "1"},
                                stdout=sink, stderr=subprocess.STDOUT)
    try:
        def two_running() -> bool:
            return proc.poll() is not None or running_now(tmp_path).get("sphere-6d", 0) == 2

        assert _wait_for(two_running, 300) and proc.poll() is None, \
            f"the sweep never had two jobs running (exit {proc.poll()}):\n{log.read_text()[-3000:]}"
        workers = _children(proc.pid)
        assert len(workers) >= 2
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
        assert _wait_for(lambda: not any(Path(f"/proc/{p}").exists() for p in workers), 20), \
            "workers outlived the sweep's main process"
    finally:
        if proc.poll() is None:
            proc.kill()
    assert statuses(tmp_path)["sphere-6d"] == ["RUNNING", "RUNNING"]
    # the resume in this process, its jobs one after another here (the workers were the killed sweep's)
    resume = tcbench(*[a.replace("n_jobs=2", "n_jobs=1") for a in args[3:]], "tracking.resume=true",
                     cwd=tmp_path, site=site)
    s = statuses(tmp_path)["sphere-6d"]
    assert sorted(s) == ["FINISHED"] * 2 + ["KILLED"] * 2, s
    assert "2 runs of sweep killme left RUNNING by a process that is gone marked KILLED" in resume.stderr
    assert resume.returncode == 0, resume.stdout + resume.stderr
    assert "2 finished, 0 failed; 2 earlier attempts replaced by a re-run" in resume.stdout


@pytest.fixture
def small_disk(tmp_path: Path):  # type: ignore[no-untyped-def]
    """``mount(size)``: a tmpfs of ``size`` (e.g. ``"1200k"``) under tmp_path; skipped where
    mounting is not allowed (not root, a container without the capability)."""
    mounted: list[Path] = []

    def mount(size: str) -> Path:
        where = tmp_path / f"disk{len(mounted)}"
        where.mkdir()
        out = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                             capture_output=True, text=True)
        if out.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here: {out.stderr.strip()}")
        mounted.append(where)
        return where

    yield mount
    for where in mounted:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


@pytest.mark.parametrize("plots", [[], ["tracking.plots=true"]], ids=["no-plots", "plots"])
def test_a_full_store_disk_fails_jobs_in_one_line_each(site: Path, tmp_path: Path, small_disk,  # type: ignore[no-untyped-def]
                                                       plots: list[str]) -> None:
    """A full disk under the store ended in 55-126-line tracebacks and left runs RUNNING, later
    reported as another process's. Now every job ends (FINISHED, FAILED, or no run), each error
    is one line, and no run is left RUNNING. With plots, the figure that filled the disk left its
    run RUNNING: the failed copy (then the failed run's artifacts) are removed to record its end."""
    disk = small_disk("1200k")  # room for the empty store (about 0.95 MB) and some runs
    work = tmp_path / "work"
    work.mkdir()
    run = tcbench("run", "-m", "task=sphere", "budget=60", "seed=range(40)", *plots,
                  f"tracking.uri=sqlite:///{disk / 'mlflow.db'}", cwd=work, site=site)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "Traceback" not in run.stdout + run.stderr
    assert "database or disk is full" in run.stdout
    assert "RUNNING" not in run.stdout
    c = MlflowClient(tracking_uri=f"sqlite:///{disk / 'mlflow.db'}")
    runs = c.search_runs([c.get_experiment_by_name("tcbench").experiment_id], max_results=100)
    assert runs and all(r.info.status != "RUNNING" for r in runs)


def test_a_store_that_does_not_fit_is_one_line_and_not_left_half_made(site: Path, tmp_path: Path,
                                                                      small_disk) -> None:  # type: ignore[no-untyped-def]
    disk = small_disk("500k")
    run = tcbench("run", "budget=20", f"tracking.uri=sqlite:///{disk / 'mlflow.db'}", cwd=tmp_path, site=site)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert "cannot be prepared (database or disk is full)" in run.stderr
    assert not (disk / "mlflow.db").exists()


def test_job_folders_on_a_full_disk_stop_the_sweep_in_one_line(site: Path, small_disk) -> None:  # type: ignore[no-untyped-def]
    disk = small_disk("100k")
    run = tcbench("run", "-m", "task=sphere", "budget=20", "seed=range(200)", "tracking.enabled=false",
                  cwd=disk, site=site)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    (line,) = [ln for ln in run.stderr.splitlines() if ln.startswith("tcbench: error:")]
    assert "cannot write multirun/" in line and "No space left on device" in line


def test_simulate_on_a_full_store_disk_is_one_line(site: Path, tmp_path: Path, small_disk) -> None:  # type: ignore[no-untyped-def]
    """simulate and metrics open their MLflow run after writing their files (a bad input leaves
    neither): a store that cannot be made then is one line naming it, and leaves no half-made
    database."""
    disk = small_disk("500k")
    run = tcbench("simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=200",
                  "protocol_params.sample_rate_hz=1", "out=o", f"tracking.uri=sqlite:///{disk / 'mlflow.db'}",
                  cwd=tmp_path, site=site)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert "could not record them" in run.stderr and "database or disk is full" in run.stderr
    assert (tmp_path / "o" / "gyro-static-dev0-seed0.csv").exists()
    assert not (disk / "mlflow.db").exists()
