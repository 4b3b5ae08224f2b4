"""The BBOB sweep: every method on f1-f24, its IOHprofiler logs written straight to disk.

Each job is what ``tcbench run task=bbob task.function=F task.dim=D task.instance=I seed=I
optimiser=M budget=B tracking.enabled=false tracking.ioh_dir=OUT/ioh`` does (the same config,
composed by Hydra once per method, validated once per method and dimension, and the same
``tcbench.runner.job.run_job``), run in a process pool instead of one Hydra job each: Hydra's
per-job start costs about 0.5-1 s, as much as a whole run of most methods at d = 5.

Writes ``OUT/plan.json`` (the grid), ``OUT/ioh/<method>/<task>-s<seed>-<hash>/`` (one IOHprofiler
folder per run, written atomically, so a re-started sweep skips the runs already there),
``OUT/jobs.csv`` (CPU seconds and evaluations per finished job) and ``OUT/failed.jsonl``.

Run from the repository root: python experiments/bbob/sweep.py --out experiments/bbob/runs
"""

from __future__ import annotations

import argparse
import copy
import csv
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

# Methods in the order of the tables; peers that are not installed are left out with a note.
METHODS = ["fa", "ifa", "ga", "pso", "bas", "sa", "cmaes", "ipop_cmaes", "scipy_de", "dual_annealing",
           "ng_de", "ngopt", "tpe"]
FUNCTIONS = list(range(1, 25))
INSTANCES = {5: list(range(1, 16)), 20: list(range(1, 16))}
BUDGET_PER_DIM = 10_000
# Methods slow per evaluation get a smaller budget where a full one would not fit in a session on
# two cores (experiments/bbob/README.md has the timings): evaluations per dimension, per method and
# dimension ...
REDUCED_BUDGET_PER_DIM = {"ngopt": {5: 50, 20: 50}}
# ... or in total, whatever the dimension (TPE's cost per trial grows with the trials so far).
FIXED_BUDGET = {"tpe": 200}
# Rough relative cost per run, to start the longest jobs first (balances the pool).
COST_ORDER = {"sa": 0, "ipop_cmaes": 1, "bas": 2, "dual_annealing": 3, "ifa": 4, "fa": 5, "tpe": 6}


def parse_ints(text: str) -> list[int]:
    """``"1-5,8"`` -> ``[1, 2, 3, 4, 5, 8]``."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += list(range(int(lo), int(hi or lo) + 1))
    return out


def budget(method: str, dim: int, overrides: dict[tuple[str, int | None], int]) -> int:
    """Evaluations of one run of ``method`` in ``dim`` dimensions. ``overrides`` maps
    ``(method, dim)`` or ``(method, None)`` (every dimension) to evaluations per dimension."""
    for key in ((method, dim), (method, None)):
        if key in overrides:
            return overrides[key] * dim
    if method in FIXED_BUDGET:
        return FIXED_BUDGET[method]
    return REDUCED_BUDGET_PER_DIM.get(method, {}).get(dim, BUDGET_PER_DIM) * dim


def parse_budget(item: str) -> tuple[tuple[str, int | None], int]:
    """``"sa=1000"`` -> ``(("sa", None), 1000)``; ``"ng_de@20=1000"`` -> ``(("ng_de", 20), 1000)``."""
    key, sep, value = item.partition("=")
    method, at, dim = key.partition("@")
    if not sep or not method.strip() or (at and not dim.strip()):
        raise ValueError(f"--budget-per-dim {item!r}: expected METHOD=N or METHOD@DIM=N")
    n = int(value)
    if n < 1:
        raise ValueError(f"--budget-per-dim {item!r}: N must be >= 1")
    return (method.strip(), int(dim) if at else None), n


def base_configs(methods: list[str], ioh_dir: Path) -> dict[str, dict[str, Any]]:
    """The composed job config of each method (``task=bbob optimiser=<m>``, tracking off)."""
    from hydra import compose, initialize_config_module

    from tcbench.runner.config import as_dict, register_schema
    from tcbench.config_dir import CONFIG_MODULE, CONFIG_NAME

    register_schema()  # config.yaml's defaults start from the structured schema
    out = {}
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        for m in methods:
            overrides = ["task=bbob", f"optimiser={m}", "tracking.enabled=false", f"tracking.ioh_dir={ioh_dir}"]
            out[m] = as_dict(compose(CONFIG_NAME, overrides=overrides))
    return out


def job_config(base: dict[str, Any], function: int, dim: int, instance: int, budget: int) -> dict[str, Any]:
    """One job: ``base`` on BBOB ``function`` in ``dim`` dimensions, instance = seed."""
    c = copy.deepcopy(base)
    c["task"].update(function=function, dim=dim, instance=instance)
    c["seed"], c["budget"] = instance, budget
    return c


def run_one(c: dict[str, Any]) -> tuple[float, int | None, str | None]:
    """Run one job in a worker: CPU seconds, evaluations used (None if it failed), the error."""
    from tcbench.runner.job import run_job

    t0 = time.process_time()
    try:
        result = run_job(c)
    except Exception as exc:  # noqa: BLE001 - recorded in failed.jsonl; the sweep goes on
        return time.process_time() - t0, None, f"{type(exc).__name__}: {exc}"
    return time.process_time() - t0, int(result.evaluations), None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="output folder (plan.json, ioh/, jobs.csv)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--methods", default=",".join(METHODS), help="comma-separated optimisers")
    ap.add_argument("--functions", default="1-24", help="BBOB functions, e.g. 1-24 or 1,8")
    ap.add_argument("--dims", default="5,20", help="dimensions")
    ap.add_argument("--instances", action="append", default=[], metavar="DIM:LIST",
                    help="instances of a dimension, e.g. 20:1-5 (default 1-15)")
    reduced = [f"{m}@{d} {n}" for m, per_dim in REDUCED_BUDGET_PER_DIM.items() for d, n in per_dim.items()]
    ap.add_argument("--budget-per-dim", action="append", default=[], metavar="METHOD[@DIM]=N",
                    help=f"evaluations per dimension for a method, in every dimension or in DIM only "
                         f"(default {BUDGET_PER_DIM}; {', '.join(reduced)}; "
                         f"{', '.join(f'{k} {v} in total' for k, v in FIXED_BUDGET.items())})")
    ns = ap.parse_args(argv)
    from tcbench.runner.config import ConfigError, validate
    from tcbench.runner.kinds.optimisation import ioh_folder
    from tcbench.optimisers import registry

    try:
        functions, dims = parse_ints(ns.functions), parse_ints(ns.dims)
        instances = {d: INSTANCES.get(d, list(range(1, 16))) for d in dims}
        for item in ns.instances:
            d, _, spec = item.partition(":")
            instances[int(d)] = parse_ints(spec)
        overrides = dict(parse_budget(item) for item in ns.budget_per_dim)
    except ValueError as exc:
        print(f"sweep: error: {exc}", file=sys.stderr)
        return 2
    known = registry.available()
    requested = [m.strip() for m in ns.methods.split(",") if m.strip()]
    methods = [m for m in requested if m in known]
    for m in sorted(set(requested) - set(methods)):
        print(f"sweep: {m} is not registered here; left out", file=sys.stderr)
    out = ns.out.resolve()
    bases = base_configs(methods, out / "ioh")
    jobs = []
    try:
        for m in methods:
            for d in dims:
                b = budget(m, d, overrides)
                validate(job_config(bases[m], functions[0], d, instances[d][0], b))
                jobs += [job_config(bases[m], f, d, i, b) for f in functions for i in instances[d]]
    except ConfigError as exc:
        print(f"sweep: error: {exc}", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    plan = {"methods": methods, "functions": functions, "dims": dims,
            "instances": {str(d): v for d, v in instances.items()},
            "budgets": {m: {str(d): budget(m, d, overrides) for d in dims} for m in methods},
            "left_out": sorted(set(requested) - set(methods))}
    (out / "plan.json").write_text(json.dumps(plan, indent=1) + "\n")
    todo = [c for c in jobs if not ioh_folder(c).exists()]
    todo.sort(key=lambda c: (-c["task"]["dim"], COST_ORDER.get(c["optimiser"]["name"], 99)))
    print(f"sweep: {len(jobs)} jobs, {len(jobs) - len(todo)} already done, {len(todo)} to run "
          f"on {ns.jobs} workers", file=sys.stderr)
    from tqdm.auto import tqdm

    failed = 0
    t0 = time.perf_counter()
    new_log = not (out / "jobs.csv").exists()
    with open(out / "jobs.csv", "a", newline="") as log, open(out / "failed.jsonl", "a") as fails, \
            ProcessPoolExecutor(max_workers=ns.jobs) as pool:
        writer = csv.writer(log)
        if new_log:
            writer.writerow(["method", "function", "dim", "instance", "budget", "evaluations", "cpu_s"])
        futures = {pool.submit(run_one, c): c for c in todo}
        for fut in tqdm(as_completed(futures), total=len(futures), unit="run"):
            c = futures[fut]
            cpu_s, evaluations, error = fut.result()
            key = [c["optimiser"]["name"], c["task"]["function"], c["task"]["dim"], c["task"]["instance"]]
            if error is None:
                writer.writerow([*key, c["budget"], evaluations, f"{cpu_s:.3f}"])
                log.flush()
            else:
                failed += 1
                fails.write(json.dumps(dict(zip(["method", "function", "dim", "instance"], key, strict=True))
                                       | {"error": error}) + "\n")
                fails.flush()
    print(f"sweep: {len(todo) - failed} runs finished, {failed} failed, "
          f"{time.perf_counter() - t0:.0f} s wall; IOHprofiler logs in {out / 'ioh'}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
