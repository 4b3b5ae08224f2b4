"""Paired comparisons of the accelerometer chamber boards: for two methods on one device, the draws
both finished, on how many the first drifts less, and the Wilcoxon signed-rank p-value over those
draws (the statistic the boards' ``p_vs_next`` uses, for rows that are not adjacent).

Usage (from the repository root, after run.sh): ``python experiments/accel_chamber/pairs.py
[--sweep ID] [DEVICE:A:B ...]``; without pairs, the ones experiments/accel_chamber/README.md quotes.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.leaderboard.compensation import load_runs
from tcbench.leaderboard.files import one_run_per_job
from tcbench.leaderboard.paired import draw_column, pairing_index
from tcbench.stats import paired_p_value
from tcbench.tracking import store as tracking

HERE = Path(__file__).resolve().parent
QUOTED = ["0:poly3_rate:IFA-BP-gd", "0:IFA-BP-gd:random-BP-gd", "0:memoriser:poly3",
          *[f"{d}:diagnosed:{other}" for d in (2, 3, 4, 7) for other in ("poly3_rate", "lagpoly")],
          "8:diagnosed:poly3_rate", *[f"{d}:memoriser:poly3" for d in (1, 3, 5, 7)]]


def drifts(sweep: str, uri: str) -> pd.DataFrame:
    """The finished next_run runs of the sweep (:func:`tcbench.leaderboard.compensation.load_runs`),
    one per job as the boards keep them (a repeated job's latest), each with its draw."""
    runs = load_runs(tracking.client(uri), ["accel-chamber"], sweep)
    if runs.empty:
        raise SystemExit(f"no runs of sweep {sweep} in {uri}: run experiments/accel_chamber/run.sh first")
    runs = one_run_per_job(runs[(runs["status"] == "FINISHED") & (runs["split"] == "next_run")]).copy()
    runs["draw"] = draw_column(runs)
    return runs


def compare(runs: pd.DataFrame, device: int, a: str, b: str) -> str:
    """Row ``a`` against row ``b`` on one device, paired as the board pairs ``p_vs_next``."""
    on = runs[runs["task"] == f"accel_chamber-dev{device}"]
    x, y = (on[on["method"] == m] for m in (a, b))
    if x.empty or y.empty:
        return f"device {device}: no runs of {a if x.empty else b}"
    xs, ys = (pd.Series(r["drift_ug"].to_numpy(float), index=pairing_index(r)) for r in (x, y))
    both = pd.concat([xs, ys], axis=1, join="inner").dropna()
    below = int(np.sum(both.iloc[:, 0] < both.iloc[:, 1]))
    return (f"device {device}: {a} below {b} on {below} of {len(both)} draws, "
            f"Wilcoxon p = {paired_p_value(xs, ys):.2g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", default="accel-chamber-instances")
    parser.add_argument("pairs", nargs="*", default=QUOTED, help="DEVICE:A:B")
    args = parser.parse_args()
    uri = os.environ.get("MLFLOW_TRACKING_URI", f"sqlite:///{HERE / 'mlflow.db'}")
    runs = drifts(args.sweep, uri)
    for pair in args.pairs:
        device, a, b = pair.split(":")
        print(compare(runs, int(device), a, b))


if __name__ == "__main__":
    main()
