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
import json
import os
import platform
import shlex
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from importlib.metadata import version
from pathlib import Path

import numpy as np

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
DEFAULT_CASES = ("rastrigin-10", "rastrigin-30", "sphere-10", "sphere-30")
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


def parse_case(case: str) -> tuple[str, int]:
    name, dim = case.rsplit("-", 1)
    if name not in FUNCTIONS:
        raise ValueError(f"unknown function {name!r}; known: {', '.join(FUNCTIONS)}")
    return name, int(dim)


def run_tcbench(case: str, seed: int) -> RunResult:
    name, dim = parse_case(case)
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

    name, dim = parse_case(case)
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
    name, dim = parse_case(case)
    fn = FUNCTIONS[name]
    x = np.random.default_rng(0).uniform(LOWER, UPPER, size=(PARTICLES, dim))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(ITERATIONS):
            fn(x)
        best = min(best, time.perf_counter() - t0)
    return best


def summarise(runs: list[RunResult], objective_s: dict[str, float]) -> list[dict]:
    rows = []
    for case in dict.fromkeys(r.case for r in runs):
        for method in METHODS:
            mine = [r for r in runs if r.case == case and r.method == method]
            seconds = statistics.median(r.seconds for r in mine)
            rows.append({
                "case": case, "method": method,
                "median_seconds": seconds,
                "median_best": statistics.median(r.best for r in mine),
                "min_best": min(r.best for r in mine),
                "max_best": max(r.best for r in mine),
                "evaluations": statistics.median(r.evaluations for r in mine),
                "overhead_us_per_iteration": 1e6 * (seconds - objective_s[case]) / ITERATIONS,
            })
    tc = {row["case"]: row["median_seconds"] for row in rows if row["method"] == "tcbench"}
    for row in rows:
        row["time_ratio_vs_tcbench"] = row["median_seconds"] / tc[row["case"]]
    return rows


def environment() -> dict[str, str | int | None]:
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "pyswarms": version("pyswarms"),
        "tcbench": version("tcbench"),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
    }


def markdown(rows: list[dict], objective_s: dict[str, float], env: dict, command: str,
             seeds: int) -> str:
    lines = [
        "| problem | library | median wall time (s) | time / tcbench | median final best "
        "| best .. worst seed | evaluations | overhead µs / iteration |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {METHODS[r['method']]} | {r['median_seconds']:.3f} "
            f"| {r['time_ratio_vs_tcbench']:.1f}x | {r['median_best']:.4g} "
            f"| {r['min_best']:.3g} .. {r['max_best']:.3g} | {r['evaluations']:.0f} "
            f"| {r['overhead_us_per_iteration']:.0f} |"
        )
    obj = ", ".join(f"{c} {1e3 * s:.1f} ms" for c, s in objective_s.items())
    lines += [
        "",
        f"Objective alone ({ITERATIONS} calls on {PARTICLES} points): {obj}. Overhead = "
        f"(wall time - objective time) / {ITERATIONS} iterations. Seeds: {seeds}; "
        f"{PARTICLES} particles x {ITERATIONS} iterations = {PARTICLES * ITERATIONS} evaluations.",
        "",
        f"Python {env['python']}, numpy {env['numpy']}, pyswarms {env['pyswarms']}, "
        f"tcbench {env['tcbench']}; {env['platform']}, {env['cpus']} CPUs.",
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
    quiet_pyswarms()
    command = shlex.join(["python", *sys.argv]) if argv is None else shlex.join(argv)
    runs: list[RunResult] = []
    for case in args.cases:
        for seed in range(args.seeds):
            pair = [run_tcbench(case, seed), run_pyswarms(case, seed)]
            runs += pair
            print(f"{case} seed {seed}: " + " | ".join(
                f"{r.method} {r.seconds:.3f}s f={r.best:.4g} ({r.evaluations} ev)" for r in pair
            ), file=sys.stderr, flush=True)
    objective_s = {case: objective_alone(case) for case in args.cases}
    rows = summarise(runs, objective_s)
    env = environment()
    print(markdown(rows, objective_s, env, command, args.seeds))
    report = {
        "benchmark": "pso_vs_pyswarms",
        "domain": [LOWER, UPPER],
        "particles": PARTICLES,
        "iterations": ITERATIONS,
        "setting": {"w": W, "c1": C1, "c2": C2, "v_max_fraction": V_MAX_FRACTION,
                    "pyswarms_bh_strategy": "nearest"},
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
