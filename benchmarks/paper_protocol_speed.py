"""Time seed 000's whole full-temperature protocol: 30 x FA-BP and 30 x IFA-BP.

Each training is what ``tcbench run task=msra_fulltemp learner=bp optimiser=fa|ifa seed=S``
computes, without tracking: the weight search (population 10, 50 iterations = 510 evaluations
of the training error, batched per generation), BP training from the best vector (gradient
descent, 1000 epochs by default; or ``--training lm``), and the Table 2 metrics and the
+-0.5 g probe on the two test recordings. The five recordings are simulated once per worker
process (included in the time). Jobs are spread over ``--workers`` processes (joblib/loky),
each with one BLAS thread so the workers do not oversubscribe the cores. Target of the issue:
under 60 s on 2 cores.

    python benchmarks/paper_protocol_speed.py --workers 2
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

from common import (
    add_json,
    command_line,
    environment,
    environment_line,
    parser_for,
    write_json,
)
from joblib import Parallel, delayed
from threadpoolctl import threadpool_info, threadpool_limits

DEFAULT_JSON = Path(__file__).with_name("paper_protocol_speed.json")


def one(optimiser: str, seed: int, training: str) -> dict[str, float | str | int]:
    with threadpool_limits(1):
        from tcbench.runner.loop import run_compensation

        t0 = time.perf_counter()
        r = run_compensation({"name": "msra_fulltemp"}, {"name": "bp", "training": training},
                             {"name": optimiser}, 510, seed)
        s = r.score.summary()
        return {"optimiser": optimiser, "seed": seed, "seconds": time.perf_counter() - t0,
                "search_s": r.seconds_search, "train_s": r.seconds_train,
                "bias_variation_ug": s["bias_variation_ug"], "sf_variation_ppm": s["sf_variation_ppm"],
                "pid": os.getpid()}


def main() -> None:
    ap = parser_for(__doc__)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--training", default="gd", choices=("gd", "lm"))
    add_json(ap, DEFAULT_JSON)
    ns = ap.parse_args()
    env = environment("scipy", "joblib")
    blas = sorted({f"{i['internal_api']} {i['version']} ({i['num_threads']} threads by default)"
                   for i in threadpool_info()})
    jobs = [(o, s) for o in ("fa", "ifa") for s in range(ns.seeds)]
    t0 = time.perf_counter()
    rows = Parallel(n_jobs=ns.workers)(delayed(one)(o, s, ns.training) for o, s in jobs)
    wall = time.perf_counter() - t0
    print(f"# Seed 000 protocol: {len(jobs)} trainings (FA-BP, IFA-BP x {ns.seeds}), BP {ns.training}\n")
    print(f"Command: `{command_line()}`\n")
    libs = f"scipy {env['scipy']}, joblib {env['joblib']}"
    print(environment_line(env, libs) + f" BLAS: {'; '.join(blas)}, 1 thread per worker.\n")
    print("| optimiser | runs | median run (s) | median search (s) | median training (s) | median bias var. (µg) |")
    print("|---|---:|---:|---:|---:|---:|")
    for o in ("fa", "ifa"):
        g = [r for r in rows if r["optimiser"] == o]
        med = {k: statistics.median(float(r[k]) for r in g)
               for k in ("seconds", "search_s", "train_s", "bias_variation_ug")}
        print(f"| {o.upper()}-BP | {len(g)} | {med['seconds']:.2f} | {med['search_s']:.2f} | {med['train_s']:.2f} "
              f"| {med['bias_variation_ug']:.4g} |")
    verdict = "met" if wall < 60.0 else "not met"
    print(f"\nWall time, {ns.workers} workers: **{wall:.1f} s** (target < 60 s: {verdict}); "
          f"sum of run times {sum(float(r['seconds']) for r in rows):.1f} s.")
    write_json(ns.json, {"wall_s": wall, "workers": ns.workers, "training": ns.training, "env": env,
                         "blas": blas, "runs": rows})


if __name__ == "__main__":
    main()
