"""What a sweep costs beyond its jobs' computation: tcbench's launcher against Hydra's default.

The sweep is the one a new user would start: 2-D Rastrigin, IFA, budget 2000 per run, tracking
on into a fresh embedded SQLite store, ``tcbench run -m task=rastrigin task.dim=2 budget=2000
seed='range(N)'``, each command in a fresh temporary folder. Two launchers, same jobs:

- ``tcbench``: the default (``hydra/sweeper: tcbench``, ``hydra/launcher: tcbench``, one process);
- ``hydra basic``: ``hydra/sweeper=basic hydra/launcher=basic`` (Hydra's defaults, what tcbench
  used before), run at fewer jobs because it is slow.

Measured per command: the wall time of the whole command; the time to the first job, from the
command's start to the start time MLflow recorded for its first run; and the overhead per job,
``(wall - time to first job - N * compute) / N``, where ``compute`` is the median time of one
run's optimisation measured in this process (``tcbench.runner.loop.run_optimisation``, no tracking).
Every run must be recorded FINISHED, once. The time to the first job is also measured alone, on
2-job sweeps repeated ``--first-repeats`` times: with tcbench's user cache empty (``cold``: the
first sweep on a machine, which builds the migrated empty store every new store is copied from)
and with it filled (``warm``: every later sweep). The 1000-job row runs warm. Also: the wall time
of ``tcbench --help`` in a fresh process (10 calls).

Usage::

    python benchmarks/sweep_overhead.py --jobs 1000 --basic-jobs 100
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import add_json, blas_threads, command_line, parser_for, table_head, table_row, versions, write_json

DEFAULT_JSON = Path(__file__).with_name("sweep_overhead.json")
BASE = ["task=rastrigin", "task.dim=2", "budget=2000", "optimiser=ifa"]
TARGET_FIRST_JOB_S = 3.0
TARGET_OVERHEAD_S = 0.2


def compute_s(runs: int = 20) -> float:
    """Median seconds of one job's optimisation alone (no tracking), in this process."""
    from tcbench.runner.loop import run_optimisation

    task = {"name": "rastrigin", "dim": 2, "shift": False, "target_precision": 1e-8, "lower": None, "upper": None}
    optimiser = {"name": "ifa"}
    run_optimisation(task, optimiser, 2000, 0)  # warm-up: imports, caches
    times = []
    for seed in range(runs):
        t0 = time.perf_counter()
        run_optimisation(task, optimiser, 2000, seed)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def help_s(repeats: int = 10) -> list[float]:
    """Wall times of ``tcbench --help`` in fresh processes."""
    tcbench = str(Path(sys.executable).with_name("tcbench"))
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run([tcbench, "--help"], capture_output=True, check=True)
        times.append(time.perf_counter() - t0)
    return times


def sweep(jobs: int, launcher: list[str], cache_dir: str) -> dict[str, float]:
    """Run one sweep command in a fresh folder with tcbench's cache in ``cache_dir``; its wall
    time, time to first job and run counts."""
    tcbench = str(Path(sys.executable).with_name("tcbench"))
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "MLFLOW_TRACKING_URI": f"sqlite:///{tmp}/mlflow.db", "TCBENCH_CACHE_DIR": cache_dir}
        start_ms = time.time() * 1000.0
        t0 = time.perf_counter()
        proc = subprocess.run([tcbench, "run", "-m", *BASE, f"seed=range({jobs})", *launcher], cwd=tmp, env=env,
                              capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            raise RuntimeError(f"sweep failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
        from mlflow.tracking import MlflowClient

        client = MlflowClient(env["MLFLOW_TRACKING_URI"])
        exp = client.get_experiment_by_name("tcbench")
        runs = client.search_runs([exp.experiment_id], max_results=50000)
        finished = [r for r in runs if r.info.status == "FINISHED"]
        seeds = {r.data.tags.get("tcbench.seed") for r in finished}
        first_ms = min(r.info.start_time for r in runs)
    return {"jobs": jobs, "wall_s": wall, "first_job_s": (first_ms - start_ms) / 1000.0,
            "finished": len(finished), "distinct_seeds": len(seeds), "recorded": len(runs)}


def first_job_s(repeats: int, cold: bool, warm_cache: str) -> list[float]:
    """Times to the first job of 2-job sweeps, each with an empty cache (cold) or ``warm_cache``."""
    times = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            times.append(sweep(2, [], cache if cold else warm_cache)["first_job_s"])
    return times


def main() -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--jobs", type=int, default=1000, help="jobs of the tcbench-launcher sweep")
    parser.add_argument("--basic-jobs", type=int, default=100, help="jobs of the Hydra-basic sweep")
    parser.add_argument("--first-repeats", type=int, default=5, help="2-job sweeps per cache state")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    load_start = os.getloadavg()[0]
    helps = help_s()
    compute = compute_s()
    warm_cache = tempfile.mkdtemp(prefix="tcbench-cache-")
    firsts = {"cold": first_job_s(args.first_repeats, True, warm_cache),
              "warm": first_job_s(args.first_repeats, False, warm_cache)}
    rows = []
    for label, jobs, launcher in (("tcbench (default)", args.jobs, []),
                                  ("hydra basic", args.basic_jobs, ["hydra/sweeper=basic", "hydra/launcher=basic"])):
        print(f"sweeping {jobs} jobs with {label} ...", file=sys.stderr, flush=True)
        r = sweep(jobs, launcher, warm_cache)
        r["label"] = label
        r["overhead_per_job_s"] = (r["wall_s"] - r["first_job_s"] - jobs * compute) / jobs
        rows.append(r)
    load = (load_start, os.getloadavg()[0])
    libraries = versions("tcbench", "hydra-core", "mlflow", "numpy")
    print(f"## Sweep overhead: {args.jobs} jobs with tcbench's launcher, {args.basic_jobs} with Hydra's basic one\n")
    print(f"Command: `{command_line()}`\n")
    print(f"Machine: Linux x86_64, {os.cpu_count()} cores; " + ", ".join(f"{k} {v}" for k, v in libraries.items())
          + f"; BLAS {blas_threads()}; 1-min load average {load[0]:.1f} at the start, {load[1]:.1f} at the end.\n")
    print(f"One job's optimisation alone (2-D Rastrigin, IFA, 2000 evaluations): {1000 * compute:.1f} ms (median of 20).\n")
    print("\n".join(table_head(["launcher", "jobs", "wall (s)", "time to first job (s)", "overhead per job (s)",
                                "FINISHED runs", "distinct seeds", f"first job <= {TARGET_FIRST_JOB_S:g} s",
                                f"overhead <= {TARGET_OVERHEAD_S:g} s"], "lrrrrrrll")))
    for r in rows:
        print(table_row([r["label"], r["jobs"], f"{r['wall_s']:.1f}", f"{r['first_job_s']:.2f}",
                         f"{r['overhead_per_job_s']:.3f}", r["finished"], r["distinct_seeds"],
                         "met" if r["first_job_s"] <= TARGET_FIRST_JOB_S else "**not met**",
                         "met" if r["overhead_per_job_s"] <= TARGET_OVERHEAD_S else "**not met**"]))
    print(f"\nTime to the first job alone (2-job sweeps, {args.first_repeats} each, fresh folder and store):")
    for state, times in firsts.items():
        med = statistics.median(times)
        print(f"- {state} cache: median {med:.2f} s, range {min(times):.2f}-{max(times):.2f} s "
              f"(target <= {TARGET_FIRST_JOB_S:g} s: {'met' if med <= TARGET_FIRST_JOB_S else '**not met**'})")
    print(f"\n`tcbench --help` in a fresh process: median {statistics.median(helps):.2f} s, "
          f"range {min(helps):.2f}-{max(helps):.2f} s over {len(helps)} calls (target < 0.5 s: "
          f"{'met' if statistics.median(helps) < 0.5 else '**not met**'}).")
    ratio = rows[1]["overhead_per_job_s"] / rows[0]["overhead_per_job_s"]
    print(f"\nOverhead per job, Hydra basic / tcbench: {ratio:.1f}x (equal work: the same jobs, one process each).")
    write_json(args.json, {"compute_s": compute, "help_s": helps, "load_average_1min": load, "versions": libraries,
                            "first_job_s": firsts, "rows": rows})
    shutil.rmtree(warm_cache, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
