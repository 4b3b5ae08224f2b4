"""COCO-style runtime ECDFs: the fraction of (function, target) pairs solved against evaluations.

For every finished single-objective run, the best-so-far error history (``best_f - f_opt``,
logged per generation) gives the first evaluation at which each target ``10^2 ... 10^-8``
(51 log-spaced values, as in COCO) is reached. Pooled over the functions, targets and seeds of
one dimension, the fraction reached by ``b`` evaluations is the method's ECDF at ``b``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

TARGETS = 10.0 ** np.linspace(2.0, -8.0, 51)


def hitting_evaluations(steps: np.ndarray, errors: np.ndarray, targets: np.ndarray = TARGETS) -> np.ndarray:
    """First evaluation at which ``errors`` (best so far, non-increasing) reach each target;
    ``inf`` where never."""
    order = np.argsort(steps)
    steps, errors = steps[order], np.minimum.accumulate(errors[order])
    reached = errors[None, :] <= targets[:, None]  # (targets, records)
    first = np.where(reached.any(axis=1), reached.argmax(axis=1), -1)
    return np.where(first >= 0, steps[np.maximum(first, 0)], np.inf)


def runtime_table(client, runs: pd.DataFrame) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """One row per (run, target): method, dimension, task, evaluations to hit (inf = never)."""
    done = runs[(runs["status"] == "FINISHED") & runs["f_opt"].notna() & runs["hypervolume"].isna()]
    rows = []
    for r in done.itertuples():
        hist = client.get_metric_history(r.run_id, "best_f")
        if not hist:
            continue
        steps = np.array([h.step for h in hist], dtype=float)
        errors = np.array([h.value for h in hist]) - r.f_opt
        hits = hitting_evaluations(steps, errors)
        rows.append(pd.DataFrame({
            "method": r.method, "dim": r.dim, "task": r.task, "seed": r.seed,
            "target": TARGETS, "evaluations": hits, "budget": r.budget,
        }))
    return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame()


def ecdf_curves(table: pd.DataFrame, grid: np.ndarray) -> dict[int, dict[str, np.ndarray]]:
    """Per dimension, per method, the fraction of (task, seed, target) triples hit by each
    evaluation count in ``grid``."""
    out: dict[int, dict[str, np.ndarray]] = {}
    for (dim, method), g in table.groupby(["dim", "method"], sort=True):
        hits = np.sort(g["evaluations"].to_numpy())
        out.setdefault(int(dim), {})[str(method)] = np.searchsorted(hits, grid, side="right") / hits.size
    return out


def write_ecdf_plots(client, runs: pd.DataFrame, out_dir: Path) -> list[Path]:  # type: ignore[no-untyped-def]
    """One ``ecdf_<d>d.png`` per dimension into ``out_dir``; the paths written."""
    from tcbench import plots

    table = runtime_table(client, runs)
    if table.empty:
        return []
    budget = int(table["budget"].max())
    grid = np.unique(np.geomspace(1, budget, 300).round())
    paths = []
    for dim, curves in ecdf_curves(table, grid).items():
        n_tasks = table.loc[table["dim"] == dim, "task"].nunique()
        path = out_dir / f"ecdf_{dim}d.png"
        plots.ecdf_plot(path, grid, curves,
                        f"{dim}-D: {n_tasks} functions x 51 targets 1e2..1e-8, pooled over seeds")
        paths.append(path)
    return paths
