"""Benchmark tcbench's particle swarm (``pso``) against ``pyswarms.single.GlobalBestPSO``.

Both minimise Rastrigin and sphere on [-5.12, 5.12]^d, d = 10 and 30, with 40 particles for
500 iterations, once per seed, in this one process. Both evaluate the whole swarm once per
iteration and both call the same vectorised tcbench function (``tcbench.tasks.functions``) on
each (40, d) batch, so equal iterations are equal evaluations: 20 000 per run (counted by a
wrapper around the objective, not taken from the libraries). For each run we record the wall
time (``time.perf_counter`` around construction + optimisation), the best objective value and
the evaluation count. tcbench is driven through its ask/tell loop; pyswarms through
``optimize(f, iters=500, verbose=False)`` (no progress bar, no log lines).

Parameter mapping (checked against pyswarms 1.3.0: ``single/global_best.py``,
``backend/operators.py``, ``backend/handlers.py``, ``backend/generators.py``)
----------------------------------------------------------------------------------------------

=======================  ==========================================  ===========================
quantity                 pyswarms ``GlobalBestPSO``                  tcbench ``pso`` (``PSOParams``)
=======================  ==========================================  ===========================
swarm size               ``n_particles=40``                          ``population=40``
update                   ``v = w v + c1 r1 (p - x) + c2 r2 (g - x)``  eq. 21, ``chi = 1``
                         (``r1, r2`` per particle and coordinate)    (same)
coefficients             ``options={"w": 0.7298, "c1": 1.49618,      ``w=0.7298, c1=c2=1.49618``
                         "c2": 1.49618}``                            (tcbench defaults)
velocity clamp           ``velocity_clamp=(-2.048, 2.048)``          ``v_max_fraction=0.2``
                         (0.2 x domain width 10.24)                  (0.2 x width, per axis)
bounds                   ``bounds=(lower, upper)``,                  clamp to the bound
                         ``bh_strategy="nearest"`` (clamp)
best updates             synchronous, after the whole swarm          synchronous
evaluations              500 iterations x 40                         budget 20 000 = 500 x 40
=======================  ==========================================  ===========================

What differs and cannot be set equal:

- **Initial velocity.** pyswarms draws it uniformly in the clamp range ``[-2.048, 2.048)``;
  tcbench starts from zero velocity (seed 001 step B).
- **Wall.** tcbench zeroes the velocity component of a coordinate it clamps ("absorbing
  wall"); pyswarms' ``nearest`` clamps the position but keeps the velocity, so the particle
  keeps pushing outward until its velocity turns (its ``vh_strategy="zero"`` tests the position
  *before* the move, which is always inside, so it cannot express this).
- **Default boundary handling.** pyswarms' default is ``bh_strategy="periodic"`` (a particle
  leaving one side re-enters on the other); it is replaced by ``"nearest"`` above because that
  is what tcbench does. Both test functions have their optimum at the centre.
- **Random numbers.** pyswarms draws from numpy's global legacy generator (seeded here with
  ``np.random.seed(seed)``); tcbench from the ``Generator`` it is given. So runs with the same
  seed are not the same run, only the same distribution.

pyswarms' ``GlobalBestPSO`` configures the root logger at construction (a stream handler and a
``report.log`` file handler in the working directory) unless the ``LOG_CFG`` environment
variable names a logging YAML file. This script points ``LOG_CFG`` at a minimal config so that
no ``report.log`` is written; that file is read and applied once per construction, inside the
timed region, as pyswarms' own default config would be.

Usage::

    python benchmarks/pso_vs_pyswarms.py --seeds 5
"""

from __future__ import annotations

import argparse
import os
import tempfile
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
    environment,
    footer,
    groups,
    median_of,
    objective_list,
    objective_seconds,
    parse_case,
    parse_case_args,
    run_cases,
    spread,
    table_head,
    table_row,
    write_report,
)

from tcbench.optimisers import create
from tcbench.tasks.functions import rastrigin, sphere

LOWER, UPPER = -5.12, 5.12
PARTICLES = 40
ITERATIONS = 500
W, C1, C2 = 0.7298, 1.49618, 1.49618
V_MAX_FRACTION = 0.2
FUNCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "rastrigin": rastrigin,
    "sphere": sphere,
}
DEFAULT_JSON = Path(__file__).with_name("pso_vs_pyswarms.json")
METHODS = {"tcbench": "tcbench `pso`", "pyswarms": "pyswarms `GlobalBestPSO`"}
_LOG_CFG = Path(tempfile.gettempdir()) / "tcbench_pyswarms_logging.yaml"


def quiet_pyswarms() -> None:
    """Point pyswarms' Reporter at a logging config that adds no handler (no report.log)."""
    _LOG_CFG.write_text("version: 1\ndisable_existing_loggers: false\n")
    os.environ["LOG_CFG"] = str(_LOG_CFG)


@dataclass(frozen=True)
class RunResult:
    """One optimisation run."""

    case: str
    method: str
    seed: int
    seconds: float
    best: float
    evaluations: int


class Counted:
    """The objective with a count of evaluated rows."""

    def __init__(self, fn: Callable[[np.ndarray], np.ndarray]) -> None:
        self.fn = fn
        self.count = 0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self.count += x.shape[0]
        return self.fn(x)


def run_tcbench(case: str, seed: int) -> RunResult:
    name, dim = parse_case(case, FUNCTIONS)
    f = Counted(FUNCTIONS[name])
    params = {"population": PARTICLES, "w": W, "c1": C1, "c2": C2, "constriction": False,
              "v_max_fraction": V_MAX_FRACTION}
    start = time.perf_counter()
    opt = create("pso", np.full(dim, LOWER), np.full(dim, UPPER), PARTICLES * ITERATIONS,
                 np.random.default_rng(seed), params)
    while not opt.done:
        x = opt.ask()
        opt.tell(x, f(x))
    seconds = time.perf_counter() - start
    return RunResult(case, "tcbench", seed, seconds, opt.best.f, f.count)


def run_pyswarms(case: str, seed: int) -> RunResult:
    from pyswarms.single import GlobalBestPSO

    name, dim = parse_case(case, FUNCTIONS)
    f = Counted(FUNCTIONS[name])
    v_max = V_MAX_FRACTION * (UPPER - LOWER)
    np.random.seed(seed)  # pyswarms uses numpy's global generator
    start = time.perf_counter()
    opt = GlobalBestPSO(
        n_particles=PARTICLES, dimensions=dim, options={"c1": C1, "c2": C2, "w": W},
        bounds=(np.full(dim, LOWER), np.full(dim, UPPER)), velocity_clamp=(-v_max, v_max),
        bh_strategy="nearest",
    )
    best, _ = opt.optimize(f, iters=ITERATIONS, verbose=False)
    seconds = time.perf_counter() - start
    return RunResult(case, "pyswarms", seed, seconds, float(best), f.count)


def objective_alone(case: str, repeats: int = 5) -> float:
    """Best-of-``repeats`` time of ``ITERATIONS`` calls of the objective on one (40, d) batch."""
    name, dim = parse_case(case, FUNCTIONS)
    fn = FUNCTIONS[name]
    x = np.random.default_rng(0).uniform(LOWER, UPPER, size=(PARTICLES, dim))
    return objective_seconds(fn, x, ITERATIONS, repeats)


def summarise(runs: list[RunResult], objective_s: dict[str, float]) -> list[dict]:
    rows = []
    for case, method, mine in groups(runs, "case", METHODS):
        seconds = median_of(mine, "seconds")
        rows.append({
            "case": case, "method": method,
            "median_seconds": seconds,
            **spread([r.best for r in mine], "best"),
            "evaluations": median_of(mine, "evaluations"),
            "overhead_us_per_iteration": 1e6 * (seconds - objective_s[case]) / ITERATIONS,
        })
    return add_time_ratio(rows)


def markdown(rows: list[dict], objective_s: dict[str, float], env: dict, command: str,
             seeds: int) -> str:
    lines = table_head([*case_columns("library"), "overhead µs / iteration"], "llrrrrrr")
    for r in rows:
        lines.append(table_row([*case_cells(r, METHODS), f"{r['overhead_us_per_iteration']:.0f}"]))
    obj = objective_list(objective_s)
    lines += [
        "",
        f"Objective alone ({ITERATIONS} calls on {PARTICLES} points): {obj}. Overhead = "
        f"(wall time - objective time) / {ITERATIONS} iterations. Seeds: {seeds}; "
        f"{PARTICLES} particles x {ITERATIONS} iterations = {PARTICLES * ITERATIONS} evaluations.",
        *footer(env, f"pyswarms {env['pyswarms']}", command),
    ]
    return "\n".join(lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    return parse_case_args(__doc__, DEFAULT_JSON, FUNCTIONS, argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    quiet_pyswarms()
    command = command_line(argv)
    runs = run_cases(args.cases, args.seeds, lambda case, seed: [
        run_tcbench(case, seed), run_pyswarms(case, seed),
    ])
    objective_s = {case: objective_alone(case) for case in args.cases}
    rows = summarise(runs, objective_s)
    env = environment("pyswarms")
    print(markdown(rows, objective_s, env, command, args.seeds))
    setup = {
        "domain": [LOWER, UPPER],
        "particles": PARTICLES,
        "iterations": ITERATIONS,
        "setting": {"w": W, "c1": C1, "c2": C2, "v_max_fraction": V_MAX_FRACTION,
                    "pyswarms_bh_strategy": "nearest"},
    }
    write_report(args.json, "pso_vs_pyswarms", setup, args.seeds, command, env,
                 {"objective_seconds": objective_s, "summary": rows}, runs)


if __name__ == "__main__":
    main()
