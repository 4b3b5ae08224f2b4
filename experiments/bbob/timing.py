"""Time one run of each method per dimension and project the BBOB sweep's cost.

Each method runs, exactly as a sweep job, on f1 (solved early by the good methods, which then
stop at 1e-8) and f15 (rotated Rastrigin: nobody reaches 1e-8, the whole budget is spent),
instance 1, at its sweep budget; the mean CPU time of the two stands for a run of that method
in that dimension. Projected sweep time = sum over methods and dimensions of runs x that mean,
divided by the workers (two idle cores: one job each).

Run from the repository root: python experiments/bbob/timing.py [--methods ...] [--jobs 2]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from sweep import (
    FUNCTIONS,
    INSTANCES,
    METHODS,
    base_configs,
    budget,
    job_config,
    run_one,
)

SAMPLE = (1, 15)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--dims", default="5,20")
    ap.add_argument("--jobs", type=int, default=2)
    ns = ap.parse_args(argv)
    from tcbench.optimisers import registry

    methods = [m for m in ns.methods.split(",") if m in registry.available()]
    dims = [int(d) for d in ns.dims.split(",")]
    total_cpu_s = 0.0
    print("| method | dim | budget | f1 evals | f1 CPU s | f15 evals | f15 CPU s | runs | projected CPU s |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        bases = base_configs(methods, Path(tmp) / "ioh")
        for d in dims:
            n_runs = len(FUNCTIONS) * len(INSTANCES.get(d, range(15)))
            for m in methods:
                evals = budget(m, d, {})
                cells, cpu = [], []
                for f in SAMPLE:
                    cpu_s, evaluations, error = run_one(job_config(bases[m], f, d, 1, evals))
                    if error:
                        print(f"{m} f{f} {d}-D failed: {error}", file=sys.stderr)
                        return 1
                    cells += [str(evaluations), f"{cpu_s:.2f}"]
                    cpu.append(cpu_s)
                projected = n_runs * sum(cpu) / len(cpu)
                total_cpu_s += projected
                print(f"| {m} | {d} | {evals} | {' | '.join(cells)} | {n_runs} | {projected:.0f} |", flush=True)
    print(f"\nprojected sweep: {total_cpu_s:.0f} CPU s = {total_cpu_s / ns.jobs / 60:.0f} min on {ns.jobs} workers "
          "(plus start-up and the leaderboard build, about a minute)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
