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

import mlflow
import numpy as np
import pandas as pd
from scipy.stats import wilcoxon

HERE = Path(__file__).resolve().parent
QUOTED = ["0:poly3_rate:IFA-BP-gd", "0:IFA-BP-gd:random-BP-gd", "0:memoriser:poly3",
          *[f"{d}:diagnosed:{other}" for d in (2, 3, 4, 7) for other in ("poly3_rate", "lagpoly")],
          "8:diagnosed:poly3_rate", *[f"{d}:memoriser:poly3" for d in (1, 3, 5, 7)]]


def drifts(sweep: str, uri: str) -> pd.DataFrame:
    """drift_ug of every finished next_run run of the sweep: device task, method, draw."""
    client = mlflow.MlflowClient(uri)
    exp = client.get_experiment_by_name("accel-chamber")
    if exp is None:
        raise SystemExit(f"no experiment accel-chamber in {uri}: run experiments/accel_chamber/run.sh first")
    runs = client.search_runs([exp.experiment_id], f"tags.`tcbench.sweep_id` = '{sweep}' and "
                              "attributes.status = 'FINISHED'", max_results=50_000)
    rows = [{"task": r.data.tags["tcbench.task"], "method": r.data.tags["tcbench.method"],
             "draw": r.data.tags.get("tcbench.draw"), "drift_ug": r.data.metrics.get("drift_ug")}
            for r in runs if r.data.tags.get("tcbench.split", "next_run") == "next_run"]
    return pd.DataFrame(rows).dropna()


def compare(table: pd.DataFrame, device: int, a: str, b: str) -> str:
    runs = table[table["task"] == f"accel_chamber-dev{device}"].pivot_table(
        index="draw", columns="method", values="drift_ug", aggfunc="last")
    if a not in runs or b not in runs:
        return f"device {device}: no runs of {a if a not in runs else b}"
    both = runs[[a, b]].dropna()
    x, y = both[a].to_numpy(), both[b].to_numpy()
    p = wilcoxon(x, y).pvalue if len(both) >= 6 else float("nan")
    return f"device {device}: {a} below {b} on {int(np.sum(x < y))} of {len(both)} draws, Wilcoxon p = {p:.2g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", default="accel-chamber-instances")
    parser.add_argument("pairs", nargs="*", default=QUOTED, help="DEVICE:A:B")
    args = parser.parse_args()
    uri = os.environ.get("MLFLOW_TRACKING_URI", f"sqlite:///{HERE / 'mlflow.db'}")
    table = drifts(args.sweep, uri)
    for pair in args.pairs:
        device, a, b = pair.split(":")
        print(compare(table, int(device), a, b))


if __name__ == "__main__":
    main()
