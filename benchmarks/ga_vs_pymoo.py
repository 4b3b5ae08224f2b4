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
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from common import (
    add_time_ratio,
    case_cells,
    case_columns,
    command_line,
    footer,
    groups,
    median_of,
    objective_list,
    objective_seconds,
    parse_case,
    parse_case_args,
    pymoo_environment,
    pymoo_versions,
    run_cases,
    spread,
    table_head,
    table_row,
    write_report,
)
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


def run_tcbench(case: str, seed: int) -> RunResult:
    name, dim = parse_case(case, FUNCTIONS)
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
    name, dim = parse_case(case, FUNCTIONS)
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
    name, dim = parse_case(case, FUNCTIONS)
    fn = FUNCTIONS[name]
    x = np.random.default_rng(0).uniform(LOWER, UPPER, size=(POPULATION, dim))
    return objective_seconds(fn, x, BUDGET // POPULATION, repeats)


def summarise(runs: list[RunResult], objective_s: dict[str, float]) -> list[dict]:
    rows = []
    for case, method, mine in groups(runs, "case", METHODS):
        seconds = median_of(mine, "seconds")
        gens = median_of(mine, "generations")
        rows.append({
            "case": case, "method": method,
            "median_seconds": seconds,
            **spread([r.best for r in mine], "best"),
            "evaluations": median_of(mine, "evaluations"),
            "generations": gens,
            "overhead_ms_per_generation": 1e3 * (seconds - objective_s[case]) / (gens + 1),
        })
    return add_time_ratio(rows)


def markdown(rows: list[dict], objective_s: dict[str, float], env: dict, command: str,
             seeds: int) -> str:
    lines = table_head([*case_columns("method"), "generations", "overhead ms / generation"],
                       "llrrrrrrr")
    for r in rows:
        lines.append(table_row([*case_cells(r, METHODS), f"{r['generations']:.0f}",
                                f"{r['overhead_ms_per_generation']:.2f}"]))
    obj = objective_list(objective_s)
    lines += [
        "",
        f"Objective alone ({BUDGET // POPULATION} batches of {POPULATION}): {obj}. "
        f"Overhead = (wall time - objective time) / (generations + 1, the initial population). "
        f"Seeds: {seeds}; population {POPULATION}, {BUDGET} evaluations per run.",
        *footer(env, pymoo_versions(env), command),
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    return parse_case_args(__doc__, DEFAULT_JSON, FUNCTIONS, argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    command = command_line(argv)
    runs = run_cases(args.cases, args.seeds, lambda case, seed: [
        run_tcbench(case, seed), run_pymoo(case, seed, False), run_pymoo(case, seed, True),
    ])
    objective_s = {case: objective_alone(case) for case in args.cases}
    rows = summarise(runs, objective_s)
    env = pymoo_environment()
    print(markdown(rows, objective_s, env, command, args.seeds))
    setup = {
        "domain": [LOWER, UPPER],
        "population": POPULATION,
        "budget": BUDGET,
        "operators": {"eta_c": ETA_C, "eta_m": ETA_M, "crossover_prob": CROSSOVER_PROB,
                      "crossover_var_prob": CROSSOVER_VAR_PROB, "mutation_prob": "1/d",
                      "elite": ELITE},
    }
    write_report(args.json, "ga_vs_pymoo", setup, args.seeds, command, env,
                 {"objective_seconds": objective_s, "summary": rows}, runs)


if __name__ == "__main__":
    main()
