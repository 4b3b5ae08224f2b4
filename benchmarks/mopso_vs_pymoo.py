"""Benchmark tcbench's MOPSO and its GA in NSGA-II mode against pymoo's NSGA-II and MOPSO-CD.

Every method gets the same problem function and exactly 10 000 evaluations per run: ZDT1, ZDT2,
ZDT3 (30 variables, 2 objectives) and DTLZ2 (12 variables, 3 objectives) from
``tcbench.tasks.multiobjective``. tcbench's optimisers call ``get_problem(key).evaluate`` in an
ask/tell loop; pymoo gets a ``pymoo.core.problem.Problem`` whose ``_evaluate`` calls the same
function, so no method uses pymoo's own ZDT/DTLZ code. pymoo runs through
``minimize(problem, algorithm, ("n_eval", 10000), seed=seed)``; with 100 individuals per
generation the budget ends on a generation boundary for every method. The wrapper counts the
evaluated rows (the table reports that count, not the libraries') and keeps every objective
vector evaluated, so that the non-dominated set of *all* evaluations can be scored for pymoo
too (outside the timed region).

Indicators, for each method's final set: hypervolume with tcbench's exact
``tcbench.metrics.multiobjective.hypervolume`` against the problem's ``ref_point`` ((1.1, 1.1),
(1.1, 1.1, 1.1)), divided by the problem's ``front_hypervolume`` (1 = the true front), and IGD
against ``true_front(1000)``. Two sets are scored per method, labelled in the table:

- *returned set*: what the method hands back. tcbench ``mopso``: its bounded external archive
  (``opt.archive``, at most ``archive_size`` = 100). tcbench ``ga``: the non-dominated rows of
  its final population. pymoo NSGA-II: ``res.opt`` (the final population's first front). pymoo
  MOPSO-CD: ``res.opt`` (its archive, at most ``archive_size``).
- *all evaluated*: the non-dominated set of every point evaluated during the run (unbounded).
  For tcbench this is ``opt.front``; for pymoo it is computed from the wrapper's log with
  tcbench's ``merge_front``.

Wall time is ``time.perf_counter`` around construction + optimisation (one value per run).

Settings (population/swarm 100 for every method)
------------------------------------------------

*tcbench ``ga`` (NSGA-II survival) vs pymoo ``NSGA2``* (checked against pymoo 0.6.2
``algorithms/moo/nsga2.py``, ``operators/crossover/sbx.py``, ``operators/mutation/pm.py``):
population 100; SBX ``eta_c = 15``, crossover probability 0.9 per pair, 0.5 per variable,
children exchange a variable with probability 1/2 (pymoo ``SBX(eta=15, prob=0.9,
prob_var=0.5)``); polynomial mutation ``eta_m = 20`` on every child with probability 1/d per
variable (pymoo ``PM(eta=20, prob=1.0, prob_var=1/d)``; pymoo's default mutates only 90 % of
the children); no duplicate elimination (pymoo ``eliminate_duplicates=False``; its default
removes duplicates, tcbench never does); binary tournament on rank, then crowding distance
(pymoo ``tournament_type = "comp_by_rank_and_crowding"``; its default compares by Pareto
dominance first). Survival is (mu + lambda) with rank and crowding distance in both. Left
different: pymoo draws tournament contestants from permutations, tcbench with replacement.

*tcbench ``mopso`` vs pymoo ``MOPSO_CD``* (``pymoo.algorithms.moo.mopso_cd``, present in 0.6.2).
These are different algorithms: tcbench's is Coello, Pulido & Lechuga's (2004) MOPSO (adaptive
hypergrid, leaders by cell-density roulette, eq. 23 grid truncation of the archive, random
personal-best replacement between non-dominated points, Coello's decaying mutation, velocity
reversed at a wall); MOPSO-CD picks leaders by a crowding-distance binary tournament, truncates
the archive by crowding-distance tournaments, keeps the position clamped at a wall with its
velocity unchanged, and clamps velocities. The shared parameters are set equal: swarm 100,
archive 100, ``w = 0.4``, ``c1 = c2 = 1.5`` (tcbench's defaults, seed 001 §4) and pymoo's
``max_velocity_rate = 1.0`` (a velocity limit of one domain width, i.e. none, as in tcbench).
Two more rows show each library at its own wall/setting: tcbench ``mopso`` with
``bound_velocity="zero"`` (a documented parameter; Coello's default is ``"reverse"``), and
``MOPSO_CD()`` with all of pymoo's defaults (``w = 0.6, c1 = c2 = 2, max_velocity_rate = 0.5,
archive_size = 200``; swarm 100).

pymoo 0.6.2's MOPSO-CD, as read in its source and so not something this script changes:
``_setup`` evaluates one random swarm that ``_initialize_infill`` then replaces by a new one,
so 100 of its 10 000 evaluations are never used; when neither the new point nor the personal
best dominates the other it compares their crowding distance within that pair of two points,
which is always (inf, inf), so the personal best is then never replaced; and it recomputes the
archive's crowding distances once per particle per generation, which dominates its run time.

Usage::

    python benchmarks/mopso_vs_pymoo.py --seeds 5
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from common import (
    add_json,
    add_seeds,
    check_each,
    check_seeds,
    command_line,
    footer,
    groups,
    median_of,
    parser_for,
    progress,
    pymoo_environment,
    pymoo_versions,
    spread,
    table_head,
    table_row,
    write_report,
)
from pymoo.algorithms.moo.mopso_cd import MOPSO_CD
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.core.problem import Problem
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.optimize import minimize

from tcbench.metrics.multiobjective import hypervolume, igd
from tcbench.optimisers import create
from tcbench.pareto import merge_front, nondominated
from tcbench.tasks.multiobjective import MultiObjectiveProblem, get_problem

BUDGET = 10_000
POPULATION = 100
ARCHIVE = 100
MOPSO_W, MOPSO_C1, MOPSO_C2 = 0.4, 1.5, 1.5
ETA_C, ETA_M = 15.0, 20.0
CROSSOVER_PROB, CROSSOVER_VAR_PROB = 0.9, 0.5
IGD_POINTS = 1000
DEFAULT_PROBLEMS = ("zdt1", "zdt2", "zdt3", "dtlz2")
DEFAULT_JSON = Path(__file__).with_name("mopso_vs_pymoo.json")
METHODS = {
    "tcbench-mopso": ("tcbench `mopso` (Coello; wall: reverse)", "archive (<= 100)"),
    "tcbench-mopso-zero": ("tcbench `mopso`, `bound_velocity=\"zero\"`", "archive (<= 100)"),
    "pymoo-mopso-cd": ("pymoo `MOPSO_CD`, shared parameters = tcbench's",
                       "`res.opt` = archive (<= 100)"),
    "pymoo-mopso-cd-defaults": ("pymoo `MOPSO_CD()`, pymoo defaults",
                                "`res.opt` = archive (<= 200)"),
    "tcbench-ga": ("tcbench `ga`, NSGA-II survival", "final population, rank 0"),
    "pymoo-nsga2": ("pymoo `NSGA2`", "`res.opt` = final population, rank 0"),
}
ALL_EVALUATED = "all evaluated, non-dominated (unbounded)"


@dataclass
class RunResult:
    """One run: its time, evaluation count and the two scored sets."""

    problem: str
    method: str
    seed: int
    seconds: float
    evaluations: int
    returned_size: int
    returned_hv: float
    returned_igd: float
    all_size: int
    all_hv: float
    all_igd: float


class LoggedProblem(Problem):
    """A pymoo problem calling a tcbench problem's formulas; counts rows and keeps every F."""

    def __init__(self, problem: MultiObjectiveProblem) -> None:
        d = problem.default_dim
        super().__init__(n_var=d, n_obj=problem.n_objectives, xl=np.full(d, problem.lower),
                         xu=np.full(d, problem.upper))
        self.tc = problem
        self.count = 0
        self.log: list[tuple[np.ndarray, np.ndarray]] = []

    def _evaluate(self, x, out, *args, **kwargs):  # noqa: ANN001 - pymoo's signature
        f = self.tc.evaluate(x)
        self.count += x.shape[0]
        self.log.append((x, f))
        out["F"] = f

    def all_nondominated(self) -> np.ndarray:
        """Non-dominated objective vectors of everything evaluated (merged batch by batch)."""
        fx, ff = np.empty((0, self.n_var)), np.empty((0, self.n_obj))
        for x, f in self.log:
            fx, ff = merge_front(fx, ff, x, f)
        return ff


def score(
    f: np.ndarray, problem: MultiObjectiveProblem, reference: np.ndarray
) -> tuple[int, float, float]:
    """Number of distinct points, normalised hypervolume and IGD of the objective vectors ``f``
    (a set may hold copies of one point: pymoo's archives keep identical points)."""
    hv = hypervolume(f, problem.ref_point) / problem.front_hypervolume
    return int(np.unique(f, axis=0).shape[0]), float(hv), float(igd(f, reference))


def run_tcbench(key: str, method: str, seed: int, reference: np.ndarray) -> RunResult:
    problem = get_problem(key)
    d, m = problem.default_dim, problem.n_objectives
    if method == "tcbench-ga":
        name = "ga"
        params = {"population": POPULATION, "crossover_prob": CROSSOVER_PROB,
                  "crossover_var_prob": CROSSOVER_VAR_PROB, "eta_c": ETA_C,
                  "mutation_prob": None, "eta_m": ETA_M}
    else:
        name = "mopso"
        params = {"population": POPULATION, "archive_size": ARCHIVE, "w": MOPSO_W,
                  "c1": MOPSO_C1, "c2": MOPSO_C2,
                  "bound_velocity": "zero" if method == "tcbench-mopso-zero" else "reverse"}
    count = 0
    start = time.perf_counter()
    opt = create(name, np.full(d, problem.lower), np.full(d, problem.upper), BUDGET,
                 np.random.default_rng(seed), params, m)
    while not opt.done:
        x = opt.ask()
        opt.tell(x, problem.evaluate(x))
        count += x.shape[0]
    seconds = time.perf_counter() - start
    if name == "ga":
        pop_f = opt.population_fitness
        returned = pop_f[nondominated(pop_f)]
    else:
        returned = opt.archive.f
    return RunResult(key, method, seed, seconds, count, *score(returned, problem, reference),
                     *score(opt.front.f, problem, reference))


def run_pymoo(key: str, method: str, seed: int, reference: np.ndarray) -> RunResult:
    problem = get_problem(key)
    wrapped = LoggedProblem(problem)
    d = problem.default_dim
    start = time.perf_counter()
    if method == "pymoo-nsga2":
        algo = NSGA2(
            pop_size=POPULATION,
            crossover=SBX(eta=ETA_C, prob=CROSSOVER_PROB, prob_var=CROSSOVER_VAR_PROB),
            mutation=PM(eta=ETA_M, prob=1.0, prob_var=1.0 / d),
            eliminate_duplicates=False,
        )
        algo.tournament_type = "comp_by_rank_and_crowding"
    elif method == "pymoo-mopso-cd":
        algo = MOPSO_CD(pop_size=POPULATION, w=MOPSO_W, c1=MOPSO_C1, c2=MOPSO_C2,
                        max_velocity_rate=1.0, archive_size=ARCHIVE)
    else:
        algo = MOPSO_CD(pop_size=POPULATION)
    res = minimize(wrapped, algo, ("n_eval", BUDGET), seed=seed, verbose=False)
    seconds = time.perf_counter() - start
    returned = np.atleast_2d(res.F)
    return RunResult(key, method, seed, seconds, wrapped.count,
                     *score(returned, problem, reference),
                     *score(wrapped.all_nondominated(), problem, reference))


def summarise(runs: list[RunResult]) -> list[dict]:
    rows = []
    for key, method, mine in groups(runs, "problem", METHODS):
        seconds = median_of(mine, "seconds")
        for which, label in (("returned", METHODS[method][1]), ("all", ALL_EVALUATED)):
            rows.append({
                "problem": key, "method": method, "set": which, "set_label": label,
                "median_size": median_of(mine, f"{which}_size"),
                **spread([getattr(r, f"{which}_hv") for r in mine], "hv"),
                "median_igd": median_of(mine, f"{which}_igd"),
                "median_seconds": seconds,
                "evaluations": median_of(mine, "evaluations"),
            })
    return rows


def markdown(rows: list[dict], env: dict, command: str, seeds: int) -> str:
    lines = table_head(
        ["problem", "method", "set scored", "median distinct points",
         "median HV / HV(true front)", "HV worst .. best seed", "median IGD",
         "median wall time (s)", "evaluations"],
        "lllrrrrrr",
    )
    for r in rows:
        lines.append(table_row([
            get_problem(r["problem"]).name, METHODS[r["method"]][0], r["set_label"],
            f"{r['median_size']:.0f}", f"{r['median_hv']:.4f}",
            f"{r['min_hv']:.3f} .. {r['max_hv']:.3f}", f"{r['median_igd']:.4f}",
            f"{r['median_seconds']:.3f}", f"{r['evaluations']:.0f}",
        ]))
    lines += [
        "",
        f"Seeds: {seeds}; {BUDGET} evaluations per run; population/swarm {POPULATION}; "
        f"IGD against `true_front({IGD_POINTS})`. The wall time belongs to the run, so both "
        "sets of a method show the same value.",
        *footer(env, pymoo_versions(env), command),
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = parser_for(__doc__)
    add_seeds(parser)
    parser.add_argument("--problems", nargs="+", default=list(DEFAULT_PROBLEMS),
                        help="problem keys (zdt1 zdt2 zdt3 dtlz2)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS),
                        help="methods to run (default: all)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args(argv)
    check_seeds(parser, args.seeds)
    check_each(parser, args.problems, get_problem, errors=(KeyError,))
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    command = command_line(argv)
    runs: list[RunResult] = []
    for key in args.problems:
        reference = get_problem(key).true_front(IGD_POINTS)
        for seed in range(args.seeds):
            for method in args.methods:
                run = run_tcbench if method.startswith("tcbench") else run_pymoo
                r = run(key, method, seed, reference)
                runs.append(r)
                progress(
                    f"{key} seed {seed} {method}: {r.seconds:.3f}s, {r.evaluations} ev, "
                    f"returned {r.returned_size} HV {r.returned_hv:.4f} IGD {r.returned_igd:.4f}, "
                    f"all {r.all_size} HV {r.all_hv:.4f} IGD {r.all_igd:.4f}"
                )
    rows = summarise(runs)
    env = pymoo_environment()
    print(markdown(rows, env, command, args.seeds))
    setup = {
        "budget": BUDGET,
        "population": POPULATION,
        "archive": ARCHIVE,
        "mopso": {"w": MOPSO_W, "c1": MOPSO_C1, "c2": MOPSO_C2},
        "ga": {"eta_c": ETA_C, "eta_m": ETA_M, "crossover_prob": CROSSOVER_PROB,
               "crossover_var_prob": CROSSOVER_VAR_PROB, "mutation_prob": "1/d"},
        "igd_points": IGD_POINTS,
    }
    write_report(args.json, "mopso_vs_pymoo", setup, args.seeds, command, env,
                 {"summary": rows}, runs)


if __name__ == "__main__":
    main()
