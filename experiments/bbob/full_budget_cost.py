"""What NGOpt and TPE would cost at the issue's full BBOB budget (10^4 d), measured on a prefix.

A full run is too long to time, so each method is built with the full budget (NGOpt chooses its
algorithm from the budget, so the budget must be the real one) and driven through tcbench's own
ask/tell on the rotated Rastrigin (f15, instance 1) for the first ``--evals`` evaluations. The
CPU time per evaluation is printed for stretches of the prefix: flat for NGOpt, growing with the
trials made for TPE (optuna refits its Parzen estimators on every trial). The projection
multiplies by the 24 x 15 runs of one dimension: for NGOpt at the flat rate; for TPE with the
rate fitted as a line in the trials made (a + b n per trial, at the middles of the stretches),
which a run sums to a B + b B^2 / 2 (a lower bound if it grows faster).

Run from the repository root: python experiments/bbob/full_budget_cost.py [--evals 2000]
"""

from __future__ import annotations

import argparse
import time

import ioh
import numpy as np

from tcbench.optimisers import registry

RUNS_PER_DIM = 24 * 15
BUDGET_PER_DIM = 10_000


def time_prefix(method: str, dim: int, evals: int, marks: int = 4) -> list[tuple[int, float]]:
    """CPU seconds per evaluation over ``marks`` equal stretches of the first ``evals``
    evaluations, as ``(evaluations made at the stretch's end, seconds per evaluation)``."""
    problem = ioh.get_problem(15, instance=1, dimension=dim, problem_class=ioh.ProblemClass.BBOB)
    lower, upper = np.full(dim, -5.0), np.full(dim, 5.0)
    opt = registry.create(method, lower, upper, BUDGET_PER_DIM * dim, np.random.default_rng(1))
    ends = np.linspace(0, evals, marks + 1).astype(int)[1:]
    out, made, start = [], 0, time.process_time()
    for end in ends:
        while made < end:
            x = opt.ask()
            opt.tell(x, np.asarray(problem(x), dtype=np.float64))
            made += len(x)
        now = time.process_time()
        out.append((made, (now - start) / (made - (out[-1][0] if out else 0))))
        start = now
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--evals", type=int, default=2000, help="evaluations timed per method and dimension")
    ap.add_argument("--methods", default="ngopt,tpe")
    ap.add_argument("--dims", default="5,20")
    ns = ap.parse_args(argv)
    for method in ns.methods.split(","):
        for dim in (int(d) for d in ns.dims.split(",")):
            stretches = time_prefix(method, dim, ns.evals)
            budget = BUDGET_PER_DIM * dim
            rates = ", ".join(f"{1e3 * s:.2f} ms to {n}" for n, s in stretches)
            made = np.array([n for n, _ in stretches], dtype=float)
            rate = np.array([r for _, r in stretches])
            if method == "tpe":  # per trial a + b * trials made (fit at the stretches' middles)
                b, a = np.polyfit(made - made[0] / 2.0, rate, 1)
                run_s = a * budget + b * budget**2 / 2.0
            else:  # flat: the mean rate over the prefix
                run_s = float(np.sum(rate * made[0])) / made[-1] * budget
            print(f"{method} {dim}-D, budget {budget}: CPU per evaluation {rates}; one full run about "
                  f"{run_s:,.0f} s, {RUNS_PER_DIM} runs about {RUNS_PER_DIM * run_s / 3600:,.0f} CPU h")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
