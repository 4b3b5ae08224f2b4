"""How IFA's unstated constants (k of eq. 6, epsilon of eq. 8, the subset size) move the
paper's Rastrigin result: final best and population mean after 50 iterations, 30 seeds.

Run: python experiments/paper_fa_ifa/sensitivity.py   (no tracking; prints a markdown table)
"""

from __future__ import annotations

import itertools

import numpy as np

from tcbench.runner.loop import run_optimisation

TASK = {"name": "rastrigin", "dim": 2, "target_precision": 1e-3}
SEEDS = range(30)
GRID = {
    "k": [0.9, 1.0],
    "epsilon": [0.001, 0.01, 0.1, 1.0],
    "subset_fraction": [0.3, 1.0],
}


def main() -> None:
    print("| conventions | k | epsilon | subset | best @50 median | pop. mean @50 median | best < 1e-3 |")
    print("|---|---|---|---|---|---|---|")
    for yang in (False, True):
        for k, eps, sub in itertools.product(*GRID.values()):
            opt = {"name": "ifa", "k": k, "epsilon": eps, "subset_fraction": sub}
            if yang:
                opt |= {"beta_min": 0.2, "alpha_relative": True}
            runs = [run_optimisation(TASK, opt, 510, s) for s in SEEDS]
            best = np.array([r.best_f for r in runs])
            mean = np.array([r.trace.mean_f[-1] for r in runs])
            print(
                f"| {'yang' if yang else 'eq. 4-5'} | {k} | {eps} | {sub} | {np.median(best):.3g} | "
                f"{np.median(mean):.3g} | {np.mean(best < 1e-3):.0%} |"
            )


if __name__ == "__main__":
    main()
