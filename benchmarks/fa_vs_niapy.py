"""Benchmark tcbench's firefly algorithm (FA) against NiaPy's ``FireflyAlgorithm``.

Both optimisers minimise 30-D Rastrigin on [-5.12, 5.12]^30 with 40 fireflies for 500
generations, once per seed, in this one process. For each run we record the wall time
(``time.perf_counter`` around construction + optimisation), the best objective value found and
the number of objective evaluations. tcbench is driven through its ask/tell protocol, calling the
vectorised ``tcbench.tasks.functions.rastrigin`` on each (n, d) batch; NiaPy runs its own loop
on its built-in ``rastrigin`` problem (same formula), one point per call.

Parameter mapping (checked against the source of NiaPy 2.7.1, ``niapy/algorithms/basic/fa.py``)
-------------------------------------------------------------------------------------------------
NiaPy 2.7.1 moves ``x_i += beta0 exp(-gamma r^2) (x_j - x_i) + alpha (rand(d) - 0.5) * range``.
It has no ``beta_min`` (the attractiveness is eq. 4 as printed) and it decays alpha by a free
factor ``theta`` (default 0.97) at the *start* of every generation, so generation g uses
``alpha theta^g``. (The schedule ``(1e-4/0.9)^(1/generations)`` and the floored attractiveness
``(1 - beta_min) exp(-gamma r^2) + beta_min`` belong to Yang's reference code, not to this NiaPy
version.) The mapping is therefore:

=====================  ===========================  =================================
quantity               NiaPy ``FireflyAlgorithm``   tcbench ``fa`` (``FAParams``)
=====================  ===========================  =================================
population             ``population_size=40``       ``population=40``
attractiveness         ``beta0=1``                  ``beta0=1, beta_min=0``
absorption             ``gamma``                    ``gamma`` (same value)
random step scale      ``alpha * range``            ``alpha_relative=True``
step at generation g   ``alpha theta^g`` (g >= 1)   ``alpha0 decay^(g-1)``, so
                                                    ``alpha0 = alpha theta``, ``decay = theta``
bounds                 clip (``limit`` repair)      clip
stopping               ``Task(max_iters=500)``      ``max_generations=500``
=====================  ===========================  =================================

Defaults are NiaPy's own: ``alpha=1, gamma=0.01, theta=0.97``. ``gamma = 0.01`` is close to
``1/width^2 = 0.0095`` for the width 10.24, i.e. attraction fades over about one domain width.
Use ``--alpha/--gamma/--theta`` to try other settings (always applied to both libraries).

What cannot be matched: NiaPy evaluates the objective after *every* pairwise move (firefly i
toward each j with ``f_i >= f_j``, j = i included) and moves in place, so later pairs see
already-moved fireflies and updated values. One generation therefore costs up to
``n (n + 1) / 2`` evaluations (about 760 measured for n = 40), not ``n``. tcbench composes the
chain of moves of one generation in closed form from the start-of-generation positions and
evaluates each firefly once (``n`` evaluations per generation, plus ``n`` for the initial
population). Both libraries run the same 500 generations, so NiaPy spends roughly 19x more
evaluations; the report gives both counts, the per-evaluation cost, and an extra NiaPy row
capped at tcbench's evaluation count (``Task(max_evals=...)``) to compare fitness at equal
evaluations.

Usage::

    python benchmarks/fa_vs_niapy.py --seeds 5
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from common import (
    add_json,
    add_seeds,
    check_seeds,
    command_line,
    environment,
    footer,
    median_of,
    parser_for,
    progress,
    table_head,
    table_row,
    write_report,
)
from niapy.algorithms.basic import FireflyAlgorithm as NiaPyFA
from niapy.task import Task

from tcbench.optimisers import create
from tcbench.tasks.functions import rastrigin

DIM = 30
LOWER, UPPER = -5.12, 5.12
POPULATION = 40
GENERATIONS = 500
DEFAULT_JSON = Path(__file__).with_name("fa_vs_niapy.json")


@dataclass(frozen=True)
class Setting:
    """FA parameters shared by both libraries (NiaPy's naming)."""

    alpha: float
    gamma: float
    theta: float
    beta0: float = 1.0


@dataclass(frozen=True)
class RunResult:
    """One optimisation run."""

    library: str
    seed: int
    seconds: float
    best: float
    evaluations: int
    generations: int


def run_tcbench(seed: int, setting: Setting) -> RunResult:
    """tcbench FA on an ask/tell loop; budget = initial population + 500 generations."""
    lower, upper = np.full(DIM, LOWER), np.full(DIM, UPPER)
    params = {
        "population": POPULATION,
        "alpha0": setting.alpha * setting.theta,  # NiaPy decays before its first move
        "alpha_decay": setting.theta,
        "alpha_relative": True,
        "beta0": setting.beta0,
        "beta_min": 0.0,
        "gamma": setting.gamma,
        "max_generations": GENERATIONS,
    }
    budget = POPULATION + GENERATIONS * POPULATION
    start = time.perf_counter()
    opt = create("fa", lower, upper, budget, np.random.default_rng(seed), params)
    while not opt.done:
        x = opt.ask()
        opt.tell(x, rastrigin(x))
    seconds = time.perf_counter() - start
    return RunResult("tcbench", seed, seconds, opt.best.f, opt.evaluations, opt.generation)


def run_niapy(seed: int, setting: Setting, max_evals: float = np.inf) -> RunResult:
    """NiaPy FA for 500 generations (``max_iters``), optionally capped at ``max_evals``."""
    start = time.perf_counter()
    task = Task(
        problem="rastrigin", dimension=DIM, lower=LOWER, upper=UPPER,
        max_iters=GENERATIONS, max_evals=max_evals,
    )
    algo = NiaPyFA(
        population_size=POPULATION, alpha=setting.alpha, beta0=setting.beta0,
        gamma=setting.gamma, theta=setting.theta, seed=seed,
    )
    _, best = algo.run(task)
    seconds = time.perf_counter() - start
    label = "niapy" if np.isinf(max_evals) else "niapy-equal-evals"
    return RunResult(label, seed, seconds, float(best), int(task.evals), int(task.iters))


def summarise(runs: list[RunResult]) -> dict[str, dict[str, float]]:
    """Per-library medians of wall time, best fitness and evaluation count."""
    out: dict[str, dict[str, float]] = {}
    for library in dict.fromkeys(r.library for r in runs):
        mine = [r for r in runs if r.library == library]
        seconds = median_of(mine, "seconds")
        evals = median_of(mine, "evaluations")
        out[library] = {
            "median_seconds": seconds,
            "median_best": median_of(mine, "best"),
            "mean_best": statistics.fmean(r.best for r in mine),
            "median_evaluations": evals,
            "median_generations": median_of(mine, "generations"),
            "microseconds_per_evaluation": 1e6 * seconds / evals,
        }
    return out


def markdown(summary: dict[str, dict[str, float]], ratios: dict[str, float],
             env: dict[str, str | int | None], command: str, seeds: int) -> str:
    """The report as a markdown table plus versions and command."""
    titles = {
        "tcbench": "tcbench `fa`",
        "niapy": "NiaPy `FireflyAlgorithm`",
        "niapy-equal-evals": "NiaPy, capped at tcbench's evaluations",
    }
    lines = table_head(
        ["library", "median wall time (s)", "median final best", "mean final best",
         "evaluations (median)", "generations", "µs / evaluation"],
        "lrrrrrr",
    )
    for library, s in summary.items():
        lines.append(table_row([
            titles[library], f"{s['median_seconds']:.3f}", f"{s['median_best']:.2f}",
            f"{s['mean_best']:.2f}", f"{s['median_evaluations']:.0f}",
            f"{s['median_generations']:.0f}", f"{s['microseconds_per_evaluation']:.1f}",
        ]))
    lines += [
        "",
        f"Speed ratio (NiaPy median time / tcbench median time, 500 generations each): "
        f"**{ratios['per_run']:.1f}x**; per evaluation: {ratios['per_evaluation']:.1f}x. "
        f"Seeds: {seeds}.",
        *footer(env, f"NiaPy {env['niapy']}", command),
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = parser_for(__doc__)
    add_seeds(parser)
    parser.add_argument("--alpha", type=float, default=1.0, help="random step, fraction of width")
    parser.add_argument("--gamma", type=float, default=0.01, help="absorption coefficient")
    parser.add_argument("--theta", type=float, default=0.97, help="alpha decay per generation")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args(argv)
    check_seeds(parser, args.seeds)
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    setting = Setting(alpha=args.alpha, gamma=args.gamma, theta=args.theta)
    command = command_line(argv)
    runs: list[RunResult] = []
    for seed in range(args.seeds):
        ours = run_tcbench(seed, setting)
        theirs = run_niapy(seed, setting)
        capped = run_niapy(seed, setting, max_evals=ours.evaluations)
        runs += [ours, theirs, capped]
        progress(
            f"seed {seed}: tcbench {ours.seconds:.3f}s f={ours.best:.2f} ({ours.evaluations} ev) | "
            f"niapy {theirs.seconds:.3f}s f={theirs.best:.2f} ({theirs.evaluations} ev) | "
            f"niapy@{capped.evaluations} ev f={capped.best:.2f}"
        )
    summary = summarise(runs)
    t, n = summary["tcbench"], summary["niapy"]
    ratios = {
        "per_run": n["median_seconds"] / t["median_seconds"],
        "per_evaluation": n["microseconds_per_evaluation"] / t["microseconds_per_evaluation"],
    }
    env = environment("niapy")
    print(markdown(summary, ratios, env, command, args.seeds))
    setup = {
        "problem": {"function": "rastrigin", "dim": DIM, "lower": LOWER, "upper": UPPER},
        "population": POPULATION,
        "generations": GENERATIONS,
        "setting": asdict(setting),
    }
    write_report(args.json, "fa_vs_niapy", setup, args.seeds, command, env,
                 {"summary": summary, "speed_ratio": ratios}, runs)


if __name__ == "__main__":
    main()
