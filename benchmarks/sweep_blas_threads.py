"""A sweep's workers with their share of the cores' BLAS threads against each with every core's.

Two workers of ``tcbench``'s own launcher (:func:`hydra_plugins.tcbench_launcher.pool.run_jobs`)
each diagnose ``--jobs`` / 2 simulated chamber cycles (the diagnosed row of the compensation
boards), once as the launcher now starts them (``cores // workers`` BLAS threads each) and once
as it started them before, with OpenBLAS free to use every core in each worker (its threads
spin while they wait, so on two cores four of them share two). Reported: the wall time of each
sweep, their ratio, and the BLAS threads each worker ran with. The two configurations alternate
over ``--repeats`` so that the machine's load falls on both.

    python benchmarks/sweep_blas_threads.py --jobs 4 --repeats 2
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

from common import add_json, command_line, environment, environment_line, parser_for, write_json

from hydra_plugins.tcbench_launcher.pool import BLAS_THREAD_VARS, blas_threads_per_worker, run_jobs

DEFAULT_JSON = Path(__file__).with_name("sweep_blas_threads.json")


def diagnose_cycle(cfg: dict[str, Any]) -> tuple[bool, Any]:
    """One job: the diagnosis of a simulated chamber cycle; the BLAS threads it ran with."""
    import joblib
    from threadpoolctl import threadpool_info

    from tcbench.compensation.data import simulated_data
    from tcbench.diagnose.rate.native_rate import diagnose_any_rate

    rec = simulated_data("chamber", 0, int(cfg["draw"]), 1, 1).train[0].recording
    with joblib.parallel_config(backend="sequential"):  # the job's own two windows in turn: one core each
        diagnose_any_rate(rec)
    return True, sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})


def sweep_s(jobs: int, every_core: bool) -> tuple[float, list[int]]:
    """Wall seconds of ``jobs`` diagnoses on two workers, and the workers' BLAS thread counts."""
    saved = {var: os.environ.pop(var, None) for var in BLAS_THREAD_VARS}
    if every_core:  # as before: each worker's BLAS on every core
        os.environ.update({var: str(os.cpu_count() or 1) for var in BLAS_THREAD_VARS})
    try:
        start = time.perf_counter()
        outcomes = run_jobs([{"draw": i} for i in range(jobs)], 2, diagnose_cycle)
        wall = time.perf_counter() - start
    finally:
        for var, value in saved.items():
            os.environ.pop(var, None)
            if value is not None:
                os.environ[var] = value
    assert all(ok for ok, _ in outcomes), outcomes
    return wall, sorted({n for _, threads in outcomes for n in threads})


def main() -> None:
    parser = parser_for(__doc__ or "")
    parser.add_argument("--jobs", type=int, default=4, help="diagnoses per sweep (default 4)")
    parser.add_argument("--repeats", type=int, default=2, help="sweeps of each configuration (default 2)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    times: dict[str, list[float]] = {"share": [], "every_core": []}
    threads: dict[str, list[int]] = {}
    for _ in range(args.repeats):
        for key in times:
            wall, used = sweep_s(args.jobs, key == "every_core")
            times[key].append(wall)
            threads[key] = used
            print(f"{key}: {wall:.1f} s (BLAS threads per worker {used})", flush=True)
    best = {key: min(values) for key, values in times.items()}
    env = environment()
    result = {"jobs": args.jobs, "workers": 2, "share_threads": blas_threads_per_worker(2), "wall_s": times,
              "threads": threads, "ratio_every_core_over_share": best["every_core"] / best["share"],
              "load_average": os.getloadavg(), "environment": env, "command": command_line()}
    print(f"\nbest of {args.repeats}: share {best['share']:.1f} s, every core {best['every_core']:.1f} s, "
          f"ratio {result['ratio_every_core_over_share']:.2f}x; load average {os.getloadavg()[0]:.1f}")
    print(environment_line(env, "OpenBLAS as numpy loads it"))
    if args.json:
        write_json(args.json, result)


if __name__ == "__main__":
    main()
