"""Benchmark tcbench's real-coded GA (``ga``) against pymoo's ``GA`` (single objective).

Each method minimises Rastrigin and sphere on [-5.12, 5.12]^d, d = 10 and 30, with a
population of 100 and exactly 20 000 objective evaluations per run, once per seed, all in this
one process. Every method calls the same vectorised tcbench function
(``tcbench.tasks.functions.rastrigin`` / ``sphere``) on each (n, d) batch: tcbench through its
ask/tell loop, pymoo through a ``pymoo.core.problem.Problem`` whose ``_evaluate`` calls it. For
each run we record the wall time (``time.perf_counter`` around algorithm construction + the whole
optimisation loop), the best objective value and the evaluation count (counted by the wrapper,
not taken from the library).

pymoo is driven through its own ask/tell interface (``setup``, ``ask``, ``evaluator.eval``,
``tell``; the loop ``minimize`` runs internally) so that its last generation can be cut to the
evaluations left, like tcbench's: both spend exactly the budget.

Parameter mapping (checked against pymoo 0.6.2: ``operators/crossover/sbx.py``,
``operators/mutation/pm.py``, ``core/crossover.py``, ``core/mutation.py``,
``algorithms/soo/nonconvex/ga.py``)
--------------------------------------------------------------------------------------------------

===========================  =====================================  ===============================
quantity                     pymoo ``GA``                           tcbench ``ga`` (``GAParams``)
===========================  =====================================  ===============================
population                   ``pop_size=100``                       ``population=100``
initial population           ``FloatRandomSampling`` (uniform)      uniform in the bounds
selection                    binary tournament on F                 binary tournament on f
SBX distribution index       ``SBX(eta=15)``                        ``eta_c=15``
crossover prob. per pair     ``SBX(prob=0.9)``                      ``crossover_prob=0.9``
SBX prob. per variable       ``SBX(prob_var=0.5)``                  ``crossover_var_prob=0.5``
children swap a variable     ``prob_exch=1, prob_bin=0.5``          with probability 1/2
PM distribution index        ``PM(eta=20)``                         ``eta_m=20``
PM prob. per individual      ``PM(prob=1.0)`` (pymoo default 0.9)   every child
PM prob. per variable        ``PM(prob_var=1/d)`` (pymoo default)   ``mutation_prob=None`` (1/d)
duplicate elimination        ``eliminate_duplicates=False``         none
===========================  =====================================  ===============================

SBX and polynomial mutation are the same bounded NSGA-II-code formulas in both (same
``beta``/``alpha``/``beta_q`` and ``delta_q``, same 1e-14 "too close" rule, a final clamp for
rounding). pymoo's own defaults differ in two places, changed above to match tcbench: its
``PM`` mutates only 90 % of the children (``prob=0.9``), and ``GA`` removes duplicate children by
default (tcbench never does).

What cannot be matched by parameters:

- **Survival.** pymoo's ``GA`` uses (mu + lambda) survival (``FitnessSurvival``: parents and
  children merged, the best 100 kept). tcbench's single-objective GA is generational with
  ``elite=2``: the 2 best parents survive and 98 children replace the rest (98 evaluations per
  generation). Rows "pymoo GA" use pymoo's survival with 100 children per generation. Rows
  "pymoo GA, tcbench survival" use a small pymoo ``Survival`` defined here
  (:class:`ElitistGenerational`) with ``n_offsprings=98``: keep the best ``100 - k`` parents and
  all ``k`` children, which is tcbench's rule (also for a shortened last generation). That row
  isolates the implementation from the survival scheme.
- **Tournament draws.** pymoo draws tournament contestants from random permutations (without
  replacement within a permutation) and breaks ties at random; tcbench draws pairs uniformly
  with replacement and a tie goes to the first drawn.

The report also gives the time of the objective alone (the same number of batches of the same
size evaluated in a bare loop), so that "overhead per generation" (wall time minus objective
time, divided by generations) can be compared.

Usage::

    python benchmarks/ga_vs_pymoo.py --seeds 5
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shlex
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from importlib.metadata import version
from pathlib import Path

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.population import Population
from pymoo.core.problem import Problem
from pymoo.core.survival import Survival
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.sampling.rnd import FloatRandomSampling

from tcbench.optimisers import create
from tcbench.tasks.functions import rastrigin, sphere

LOWER, UPPER = -5.12, 5.12
POPULATION = 100
BUDGET = 20_000
ETA_C, ETA_M = 15.0, 20.0
CROSSOVER_PROB, CROSSOVER_VAR_PROB = 0.9, 0.5
ELITE = 2
FUNCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "rastrigin": rastrigin,
    "sphere": sphere,
}
DEFAULT_CASES = ("rastrigin-10", "rastrigin-30", "sphere-10", "sphere-30")
DEFAULT_JSON = Path(__file__).with_name("ga_vs_pymoo.json")
METHODS = {
    "tcbench": "tcbench `ga` (elite 2, generational)",
    "pymoo": "pymoo `GA` ((mu + lambda) survival)",
    "pymoo-tcbench-survival": "pymoo `GA`, tcbench's survival (elite 2)",
}


@dataclass(frozen=True)
class RunResult:
    """One optimisation run."""

    case: str
    method: str
    seed: int
    seconds: float
    best: float
    evaluations: int
    generations: int


class CountingProblem(Problem):
    """A pymoo problem that calls a vectorised tcbench function and counts evaluated rows."""

    def __init__(self, fn: Callable[[np.ndarray], np.ndarray], dim: int) -> None:
        super().__init__(n_var=dim, n_obj=1, xl=np.full(dim, LOWER), xu=np.full(dim, UPPER))
        self.fn = fn
        self.count = 0
        self.batches = 0
        self.best = np.inf

    def _evaluate(self, x, out, *args, **kwargs):  # noqa: ANN001 - pymoo's signature
        f = self.fn(x)
        self.count += x.shape[0]
        self.batches += 1
        self.best = min(self.best, float(f.min()))
        out["F"] = f[:, None]


class ElitistGenerational(Survival):
    """tcbench's single-objective survival for pymoo: of the merged (parents, children)
    population, keep the best ``n_survive - k`` parents and all ``k`` children (pymoo's
    ``GeneticAlgorithm._advance`` merges parents first, children last)."""

    def __init__(self) -> None:
        super().__init__(filter_infeasible=False)

    def _do(self, problem, pop, n_survive=None, **kwargs):  # noqa: ANN001 - pymoo's signature
        k = len(pop) - n_survive  # children appended after the n_survive parents
        parents = pop[:n_survive]
        order = np.argsort(parents.get("F")[:, 0], kind="stable")
        return Population.merge(parents[order[: n_survive - k]], pop[n_survive:])


def parse_case(case: str) -> tuple[str, int]:
    name, dim = case.rsplit("-", 1)
    if name not in FUNCTIONS:
        raise ValueError(f"unknown function {name!r}; known: {', '.join(FUNCTIONS)}")
    return name, int(dim)


def run_tcbench(case: str, seed: int) -> RunResult:
    name, dim = parse_case(case)
    fn = FUNCTIONS[name]
    params = {
        "population": POPULATION, "crossover_prob": CROSSOVER_PROB,
        "crossover_var_prob": CROSSOVER_VAR_PROB, "eta_c": ETA_C, "mutation_prob": None,
        "eta_m": ETA_M, "elite": ELITE,
    }
    count = 0
    start = time.perf_counter()
    opt = create("ga", np.full(dim, LOWER), np.full(dim, UPPER), BUDGET,
                 np.random.default_rng(seed), params)
    while not opt.done:
        x = opt.ask()
        opt.tell(x, fn(x))
        count += x.shape[0]
    seconds = time.perf_counter() - start
    return RunResult(case, "tcbench", seed, seconds, opt.best.f, count, opt.generation)


def run_pymoo(case: str, seed: int, tcbench_survival: bool) -> RunResult:
    name, dim = parse_case(case)
    problem = CountingProblem(FUNCTIONS[name], dim)
    start = time.perf_counter()
    extra = (
        {"survival": ElitistGenerational(), "n_offsprings": POPULATION - ELITE}
        if tcbench_survival else {}
    )
    algo = GA(
        pop_size=POPULATION,
        sampling=FloatRandomSampling(),
        crossover=SBX(eta=ETA_C, prob=CROSSOVER_PROB, prob_var=CROSSOVER_VAR_PROB),
        mutation=PM(eta=ETA_M, prob=1.0, prob_var=1.0 / dim),
        eliminate_duplicates=False,
        **extra,
    )
    algo.setup(problem, termination=("n_eval", BUDGET), seed=seed, verbose=False)
    while algo.has_next():
        pop = algo.ask()
        pop = pop[: BUDGET - algo.evaluator.n_eval]  # last generation: only what is left
        algo.evaluator.eval(problem, pop)
        algo.tell(infills=pop)
    res = algo.result()
    seconds = time.perf_counter() - start
    best = float(np.min(res.F))
    if best != problem.best:
        raise RuntimeError(f"pymoo's optimum {best} is not the best evaluated {problem.best}")
    method = "pymoo-tcbench-survival" if tcbench_survival else "pymoo"
    return RunResult(case, method, seed, seconds, best, problem.count, problem.batches - 1)


def objective_alone(case: str, repeats: int = 5) -> float:
    """Best-of-``repeats`` time of evaluating the objective on BUDGET / POPULATION batches of
    POPULATION random points (the batches tcbench's and pymoo's loops hand it)."""
    name, dim = parse_case(case)
    fn = FUNCTIONS[name]
    x = np.random.default_rng(0).uniform(LOWER, UPPER, size=(POPULATION, dim))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(BUDGET // POPULATION):
            fn(x)
        best = min(best, time.perf_counter() - t0)
    return best


def summarise(runs: list[RunResult], objective_s: dict[str, float]) -> list[dict]:
    rows = []
    for case in dict.fromkeys(r.case for r in runs):
        for method in METHODS:
            mine = [r for r in runs if r.case == case and r.method == method]
            if not mine:
                continue
            seconds = statistics.median(r.seconds for r in mine)
            gens = statistics.median(r.generations for r in mine)
            rows.append({
                "case": case, "method": method,
                "median_seconds": seconds,
                "median_best": statistics.median(r.best for r in mine),
                "min_best": min(r.best for r in mine),
                "max_best": max(r.best for r in mine),
                "evaluations": statistics.median(r.evaluations for r in mine),
                "generations": gens,
                "overhead_ms_per_generation": 1e3 * (seconds - objective_s[case]) / (gens + 1),
            })
    tc = {row["case"]: row["median_seconds"] for row in rows if row["method"] == "tcbench"}
    for row in rows:
        row["time_ratio_vs_tcbench"] = row["median_seconds"] / tc[row["case"]]
    return rows


def environment() -> dict[str, str | int | None]:
    from pymoo.functions import is_compiled

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "pymoo": version("pymoo"),
        "pymoo_compiled": str(is_compiled()),
        "tcbench": version("tcbench"),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
    }


def markdown(rows: list[dict], objective_s: dict[str, float], env: dict, command: str,
             seeds: int) -> str:
    lines = [
        "| problem | method | median wall time (s) | time / tcbench | median final best "
        "| best .. worst seed | evaluations | generations | overhead ms / generation |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {METHODS[r['method']]} | {r['median_seconds']:.3f} "
            f"| {r['time_ratio_vs_tcbench']:.1f}x | {r['median_best']:.4g} "
            f"| {r['min_best']:.3g} .. {r['max_best']:.3g} | {r['evaluations']:.0f} "
            f"| {r['generations']:.0f} | {r['overhead_ms_per_generation']:.2f} |"
        )
    obj = ", ".join(f"{c} {1e3 * s:.1f} ms" for c, s in objective_s.items())
    lines += [
        "",
        f"Objective alone ({BUDGET // POPULATION} batches of {POPULATION}): {obj}. "
        f"Overhead = (wall time - objective time) / (generations + 1, the initial population). "
        f"Seeds: {seeds}; population {POPULATION}, {BUDGET} evaluations per run.",
        "",
        f"Python {env['python']}, numpy {env['numpy']}, pymoo {env['pymoo']} "
        f"(compiled extensions: {env['pymoo_compiled']}), tcbench {env['tcbench']}; "
        f"{env['platform']}, {env['cpus']} CPUs.",
        "",
        f"Command: `{command}`",
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--seeds", type=int, default=5, help="number of seeds (>= 5), 0..N-1")
    parser.add_argument("--cases", nargs="+", default=list(DEFAULT_CASES),
                        help="function-dimension pairs, e.g. rastrigin-10 sphere-30")
    parser.add_argument("--json", type=Path, default=DEFAULT_JSON, help="where to write results")
    args = parser.parse_args(argv)
    if args.seeds < 5:
        parser.error("--seeds must be >= 5")
    for case in args.cases:
        try:
            parse_case(case)
        except ValueError as err:
            parser.error(str(err))
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    command = shlex.join(["python", *sys.argv]) if argv is None else shlex.join(argv)
    runs: list[RunResult] = []
    for case in args.cases:
        for seed in range(args.seeds):
            trio = [run_tcbench(case, seed), run_pymoo(case, seed, False),
                    run_pymoo(case, seed, True)]
            runs += trio
            print(f"{case} seed {seed}: " + " | ".join(
                f"{r.method} {r.seconds:.3f}s f={r.best:.4g} ({r.evaluations} ev)" for r in trio
            ), file=sys.stderr, flush=True)
    objective_s = {case: objective_alone(case) for case in args.cases}
    rows = summarise(runs, objective_s)
    env = environment()
    print(markdown(rows, objective_s, env, command, args.seeds))
    report = {
        "benchmark": "ga_vs_pymoo",
        "domain": [LOWER, UPPER],
        "population": POPULATION,
        "budget": BUDGET,
        "operators": {"eta_c": ETA_C, "eta_m": ETA_M, "crossover_prob": CROSSOVER_PROB,
                      "crossover_var_prob": CROSSOVER_VAR_PROB, "mutation_prob": "1/d",
                      "elite": ELITE},
        "seeds": list(range(args.seeds)),
        "command": command,
        "environment": env,
        "objective_seconds": objective_s,
        "summary": rows,
        "runs": [asdict(r) for r in runs],
    }
    args.json.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
