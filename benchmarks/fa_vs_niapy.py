"""Benchmark tcbench's firefly algorithm (FA) against NiaPy's ``FireflyAlgorithm``.

Both optimisers minimise 30-D Rastrigin on [-5.12, 5.12]^30 with 40 fireflies for 500
generations, once per seed, in this one process, after one untimed warm-up run of each. For each
run we record the wall time (``time.perf_counter`` around construction + optimisation, objective
included), the process CPU time, the best objective value found and the number of objective
evaluations. A tcbench run lasts about 0.1 s, so it is timed ``--repeats`` times (same seed, same
result) and the median kept; a NiaPy run lasts several seconds and is timed once. tcbench is
driven through its ask/tell protocol, calling the vectorised ``tcbench.tasks.functions.rastrigin``
on each (n, d) batch; NiaPy runs its own loop on its built-in ``rastrigin`` problem (same
formula), one point per call.

The headline is the speed at equal work: wall time per objective evaluation, NiaPy's over
tcbench's (from the medians over seeds; the per-seed ratios give the spread), next to the fitness
each reaches at equal evaluations (NiaPy capped at tcbench's count). The per-run ratio at equal
generations is reported too, but it is not equal work (see below). The report states the BLAS
libraries and their thread counts as the process found them (nothing is forced).

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
evaluations. Because NiaPy evaluates after every pairwise move, its time per evaluation includes
one pairwise move and one scalar objective call, while tcbench's includes 1/n of a vectorised
generation (n - 1 moves composed per firefly) and 1/n of a batched objective call.

Usage::

    python benchmarks/fa_vs_niapy.py --seeds 5
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from common import (
    add_json,
    add_seeds,
    blas_threads,
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
    """One optimisation run: wall and CPU (process) seconds, the median over ``repeat_seconds``
    when the same run was timed more than once."""

    library: str
    seed: int
    seconds: float
    cpu_seconds: float
    best: float
    evaluations: int
    generations: int
    repeat_seconds: tuple[float, ...]


def run_tcbench(seed: int, setting: Setting, repeats: int = 1) -> RunResult:
    """tcbench FA on an ask/tell loop; budget = initial population + 500 generations. The run is
    repeated ``repeats`` times (same seed, same result) and the median times are kept: one run
    lasts about 0.1 s, short enough for a moment of load on a shared machine to skew it."""
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
    walls, cpus, results = [], [], set()
    for _ in range(repeats):
        start, cpu = time.perf_counter(), time.process_time()
        opt = create("fa", lower, upper, budget, np.random.default_rng(seed), params)
        while not opt.done:
            x = opt.ask()
            opt.tell(x, rastrigin(x))
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
        results.add((opt.best.f, opt.evaluations, opt.generation))
    if len(results) != 1:
        raise RuntimeError(f"seed {seed}: repeated tcbench runs disagree: {results}")
    return RunResult("tcbench", seed, statistics.median(walls), statistics.median(cpus),
                     opt.best.f, opt.evaluations, opt.generation, tuple(walls))


def run_niapy(seed: int, setting: Setting, max_evals: float = np.inf) -> RunResult:
    """NiaPy FA for 500 generations (``max_iters``), optionally capped at ``max_evals``."""
    start, cpu = time.perf_counter(), time.process_time()
    task = Task(
        problem="rastrigin", dimension=DIM, lower=LOWER, upper=UPPER,
        max_iters=GENERATIONS, max_evals=max_evals,
    )
    algo = NiaPyFA(
        population_size=POPULATION, alpha=setting.alpha, beta0=setting.beta0,
        gamma=setting.gamma, theta=setting.theta, seed=seed,
    )
    _, best = algo.run(task)
    seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - cpu
    label = "niapy" if np.isinf(max_evals) else "niapy-equal-evals"
    return RunResult(label, seed, seconds, cpu_seconds, float(best), int(task.evals),
                     int(task.iters), (seconds,))


def warm_up(setting: Setting) -> None:
    """One untimed run of each library (imports, caches and first-call costs), results dropped."""
    run_tcbench(0, setting)
    run_niapy(0, setting, max_evals=POPULATION + GENERATIONS * POPULATION)


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
            "cpu_microseconds_per_evaluation": 1e6 * median_of(mine, "cpu_seconds") / evals,
        }
    return out


def speed_ratios(runs: list[RunResult], summary: dict[str, dict[str, float]]) -> dict[str, Any]:
    """NiaPy's time per evaluation over tcbench's (wall time: medians and per seed; CPU time:
    medians), and the per-run wall-time ratio at equal generations."""
    t, n = summary["tcbench"], summary["niapy"]
    by_seed = {r.seed: r for r in runs if r.library == "tcbench"}
    per_seed = [
        (r.seconds / r.evaluations) / (by_seed[r.seed].seconds / by_seed[r.seed].evaluations)
        for r in runs if r.library == "niapy"
    ]
    return {
        "per_evaluation": n["microseconds_per_evaluation"] / t["microseconds_per_evaluation"],
        "per_evaluation_by_seed": per_seed,
        "per_evaluation_cpu": (n["cpu_microseconds_per_evaluation"]
                               / t["cpu_microseconds_per_evaluation"]),
        "per_run_equal_generations": n["median_seconds"] / t["median_seconds"],
    }


def equal_evaluations(runs: list[RunResult]) -> dict[str, Any]:
    """Final best of tcbench and of NiaPy capped at tcbench's evaluations, per seed."""
    ours = {r.seed: r.best for r in runs if r.library == "tcbench"}
    theirs = {r.seed: r.best for r in runs if r.library == "niapy-equal-evals"}
    return {
        "tcbench_median_best": statistics.median(ours.values()),
        "niapy_median_best": statistics.median(theirs.values()),
        "seeds_tcbench_better": sum(ours[s] < theirs[s] for s in ours),
        "seeds": len(ours),
    }


def markdown(summary: dict[str, dict[str, float]], ratios: dict[str, Any],
             equal: dict[str, Any], env: dict[str, str | int | None], blas: str, command: str,
             seeds: int) -> str:
    """The report: headline at equal work, the table, versions, BLAS threads and command."""
    titles = {
        "tcbench": "tcbench `fa`",
        "niapy": "NiaPy `FireflyAlgorithm`",
        "niapy-equal-evals": "NiaPy, capped at tcbench's evaluations",
    }
    evals = summary["tcbench"]["median_evaluations"]
    per_seed = ratios["per_evaluation_by_seed"]
    headline = (
        f"Per objective evaluation (equal work): **{ratios['per_evaluation']:.1f}x** "
        f"(NiaPy {summary['niapy']['microseconds_per_evaluation']:.1f} µs / tcbench "
        f"{summary['tcbench']['microseconds_per_evaluation']:.2f} µs per evaluation, medians; "
        f"per seed {min(per_seed):.1f}x .. {max(per_seed):.1f}x; in CPU time "
        f"{ratios['per_evaluation_cpu']:.1f}x). "
        f"At equal evaluations ({evals:.0f}): median final best tcbench "
        f"{equal['tcbench_median_best']:.2f}, NiaPy {equal['niapy_median_best']:.2f} "
        f"(tcbench better on {equal['seeds_tcbench_better']} of {equal['seeds']} seeds)."
    )
    lines = [headline, ""]
    lines += table_head(
        ["library", "median wall time (s)", "median final best", "mean final best",
         "evaluations (median)", "generations", "µs / evaluation"],
        "lrrrrrr",
    )
    for library, s in summary.items():
        lines.append(table_row([
            titles[library], f"{s['median_seconds']:.3f}", f"{s['median_best']:.2f}",
            f"{s['mean_best']:.2f}", f"{s['median_evaluations']:.0f}",
            f"{s['median_generations']:.0f}", f"{s['microseconds_per_evaluation']:.2f}",
        ]))
    lines += [
        "",
        (
            f"Per run at equal generations (500 each; not equal work, NiaPy makes about "
            f"{summary['niapy']['median_evaluations'] / evals:.0f}x more evaluations): "
            f"{ratios['per_run_equal_generations']:.1f}x. Seeds: {seeds}."
        ),
        "",
        f"BLAS (default thread settings, nothing forced): {blas}.",
        *footer(env, f"NiaPy {env['niapy']}", command),
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = parser_for(__doc__)
    add_seeds(parser)
    parser.add_argument("--alpha", type=float, default=1.0, help="random step, fraction of width")
    parser.add_argument("--gamma", type=float, default=0.01, help="absorption coefficient")
    parser.add_argument("--theta", type=float, default=0.97, help="alpha decay per generation")
    parser.add_argument("--repeats", type=int, default=5,
                        help="timed tcbench runs per seed (median kept); NiaPy runs once")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args(argv)
    check_seeds(parser, args.seeds)
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    setting = Setting(alpha=args.alpha, gamma=args.gamma, theta=args.theta)
    command = command_line(argv)
    warm_up(setting)
    runs: list[RunResult] = []
    for seed in range(args.seeds):
        ours = run_tcbench(seed, setting, args.repeats)
        theirs = run_niapy(seed, setting)
        capped = run_niapy(seed, setting, max_evals=ours.evaluations)
        runs += [ours, theirs, capped]
        progress(
            f"seed {seed}: tcbench {ours.seconds:.3f}s f={ours.best:.2f} ({ours.evaluations} ev, "
            f"{1e6 * ours.seconds / ours.evaluations:.2f} us/ev) | "
            f"niapy {theirs.seconds:.3f}s f={theirs.best:.2f} ({theirs.evaluations} ev, "
            f"{1e6 * theirs.seconds / theirs.evaluations:.2f} us/ev) | "
            f"niapy@{capped.evaluations} ev f={capped.best:.2f}"
        )
    summary = summarise(runs)
    ratios = speed_ratios(runs, summary)
    equal = equal_evaluations(runs)
    env = environment("niapy")
    blas = blas_threads()
    print(markdown(summary, ratios, equal, env, blas, command, args.seeds))
    setup = {
        "problem": {"function": "rastrigin", "dim": DIM, "lower": LOWER, "upper": UPPER},
        "population": POPULATION,
        "generations": GENERATIONS,
        "setting": asdict(setting),
    }
    write_report(args.json, "fa_vs_niapy", setup, args.seeds, command, {**env, "blas": blas},
                 {"summary": summary, "speed_ratio": ratios, "equal_evaluations": equal}, runs)


if __name__ == "__main__":
    main()
