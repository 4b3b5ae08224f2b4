"""Leaderboards: finished and failed runs from MLflow aggregated over seeds with pandas.

Per task and method: seeds (one run each), failed runs, median final best, median and IQR of
the final error (best - optimum),
success rate at the task's target precision, expected running time (ERT) to that target, and a
rank. ERT = (evaluations spent by all runs, counting a successful run only up to its first hit
and a failed run at its full budget) / (number of successful runs); infinite when none succeed.
Rank orders methods by success rate (higher first), then ERT, then median final error; where
those tie (a median "failed"), the smaller share of failed runs, then the median of the finished
runs, ranks higher, and a method without any finished run ranks last. A failed
run is a failure to reach the target: it counts in the success rate, in ERT at its full budget,
and in every median, quartile and interval as worse than any finished run (:func:`tcbench.stats.with_failures`:
``+inf``, shown "failed"; ``-inf`` for the hypervolume), so a method that failed on half its runs
or more has median "failed", and one that failed on a few has its interval widened by them;
``failed`` says how many did not finish.
``ci95_low``/``ci95_high``: percentile-bootstrap 95 % interval of the median error over seeds;
``p_vs_next``: two-sided Wilcoxon signed-rank p-value of the final errors of this method and
the next-ranked one, paired by seed (and BBOB instance; finished runs both have; NaN below 6
shared seeds).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.leaderboard.files import (
    FAILED_RULE,
    failed_as_text,
    failed_lines,
    one_run_per_job,
    search_runs,
    write_board_files,
)
from tcbench.tables import markdown_table
from tcbench.stats import (
    TIE_BREAK_KEYS,
    bootstrap_median_ci,
    failure_tie_break,
    paired_p_value,
    percentiles,
    with_failures,
)

COLUMNS = [
    "rank", "method", "seeds", "failed", "median_best", "median_error", "ci95_low", "ci95_high",
    "iqr_error", "success_rate", "ert_evals", "median_evals", "p_vs_next",
]
# Several objectives: error = hypervolume gap 1 - HV/HV*; median HV and IGD instead of best.
MO_COLUMNS = [
    "rank", "method", "seeds", "failed", "median_hv", "median_igd", "median_error", "ci95_low",
    "ci95_high", "iqr_error", "success_rate", "ert_evals", "median_evals", "p_vs_next",
]


@dataclass
class Board:
    """Leaderboard of one task: the table and what it was computed from."""

    task: str
    table: pd.DataFrame
    runs: pd.DataFrame
    target_precision: float
    f_opt: float


def sweep_runs(client, experiments: list[str], sweep: str) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """Status, method, task, seed and error of every run of one sweep, of every job kind (what the
    end-of-sweep report needs, without any board's columns)."""
    columns = ["status", "method", "task", "seed", "config_hash", "start_time", "error_message"]
    rows = [{"status": r.info.status, "method": t.get("tcbench.method"), "task": t.get("tcbench.task"),
             "seed": int(t.get("tcbench.seed", -1)), "config_hash": t.get("tcbench.config_hash"),
             "start_time": r.info.start_time, "error_message": t.get("tcbench.error", "")}
            for r in search_runs(client, experiments, None, sweep) for t in (r.data.tags,)]
    return pd.DataFrame(rows, columns=columns)


def load_runs(client, experiments: list[str], sweep: str | None = None) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """One row per tcbench optimisation run (finished, failed or unfinished)."""
    rows = []
    for r in search_runs(client, experiments, "optimisation", sweep):
        m, p, t = r.data.metrics, r.data.params, r.data.tags
        rows.append({
            "run_id": r.info.run_id,
            "status": r.info.status,
            "task": t.get("tcbench.task"),
            "method": t.get("tcbench.method"),
            "seed": int(t.get("tcbench.seed", -1)),
            "instance": int(p.get("task.instance") or 0),  # BBOB: runs pair by (instance, seed)
            "sweep": t.get("tcbench.sweep_id"),
            "config_hash": t.get("tcbench.config_hash"),
            "start_time": r.info.start_time,
            "error_message": t.get("tcbench.error", ""),
            "budget": int(p.get("budget", 0)),
            "dim": int(p.get("task.dim", 0) or 0),
            "target_precision": float(p.get("task.target_precision", "nan")),
            "final_error": m.get("final_error", np.nan),
            "final_best": m.get("final_best", np.nan),
            "f_opt": m.get("f_opt", np.nan),
            "evaluations": m.get("evaluations", np.nan),
            "target_hit": m.get("target_hit", 0.0) > 0,
            "evals_to_target": m.get("evals_to_target", np.nan),
            "hypervolume": m.get("hypervolume", np.nan),
            "igd": m.get("igd", np.nan),
            "task_name": t.get("tcbench.task_name"),
        })
    return pd.DataFrame(rows)


def expected_running_time(evaluations: np.ndarray, hit_at: np.ndarray, hit: np.ndarray) -> float:
    """ERT over runs: evaluations spent until success (or in total when not) / successes."""
    spent = np.where(hit, hit_at, evaluations).sum()
    n_hit = int(np.count_nonzero(hit))
    return float(spent / n_hit) if n_hit else float("inf")


def summarise(runs: pd.DataFrame) -> pd.DataFrame:
    """Leaderboard table of one task's runs (all methods)."""
    rows, errors = [], {}
    for method, g in runs.groupby("method", sort=True):
        ok = g["status"] == "FINISHED"
        n_failed = int((~ok).sum())
        err = g.loc[ok, "final_error"].to_numpy(float)
        pairs = g.loc[ok, ["instance", "seed"]] if "instance" in g else g.loc[ok, ["seed"]]
        errors[method] = pd.Series(err, index=pd.MultiIndex.from_frame(pairs))
        hit = (g["target_hit"] & ok).to_numpy(bool)
        evals = np.where(ok, g["evaluations"].fillna(0), g["budget"]).astype(float)
        scored = with_failures(err, n_failed)
        q25, q50, q75 = percentiles(scored, [25, 50, 75]) if scored.size else (np.nan,) * 3
        low, high = bootstrap_median_ci(scored)
        rows.append({
            "method": method,
            "seeds": len(g),
            "failed": n_failed,
            "median_best": _median(g.loc[ok, "final_best"], n_failed),
            "median_error": q50,
            "ci95_low": low,
            "ci95_high": high,
            "iqr_error": q75 - q25 if np.isfinite(q75) else np.inf,
            "success_rate": hit.mean(),
            "ert_evals": expected_running_time(evals, g["evals_to_target"].to_numpy(float), hit),
            "median_evals": float(np.median(evals)),
            "median_hv": _median(g.loc[ok, "hypervolume"], n_failed, higher_is_better=True) if "hypervolume" in g
            else np.nan,
            "median_igd": _median(g.loc[ok, "igd"], n_failed) if "igd" in g else np.nan,
            "_rank_error": q50,
            **failure_tie_break(err, n_failed),
        })
    table = pd.DataFrame(rows)
    columns = MO_COLUMNS if is_multiobjective(runs) else COLUMNS
    if table.empty:
        return pd.DataFrame(columns=columns)
    keys = ["_no_finished", "success_rate", "ert_evals", "_rank_error", *TIE_BREAK_KEYS, "median_error"]
    table = table.sort_values(
        keys, ascending=[k != "success_rate" for k in keys], na_position="last", kind="stable",
    ).reset_index(drop=True)
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    methods = table["method"].tolist()
    table["p_vs_next"] = [
        paired_p_value(errors[m], errors[n]) for m, n in zip(methods, methods[1:], strict=False)
    ] + [np.nan]
    return table[columns]


def _median(finished: pd.Series, failed: int, higher_is_better: bool = False) -> float:
    """Median of the finished runs' values with the failed runs counted as the worst (NaN without
    any value)."""
    x = with_failures(finished.to_numpy(float), failed, higher_is_better)
    return float(np.median(x)) if x.size else np.nan


def is_multiobjective(runs: pd.DataFrame) -> bool:
    """True when the runs carry hypervolumes (a multi-objective task)."""
    return "hypervolume" in runs and bool(runs["hypervolume"].notna().any())


def boards(runs: pd.DataFrame) -> list[Board]:
    """One :class:`Board` per task in ``runs`` (one run per job, see :func:`one_run_per_job`)."""
    out = []
    for task, g in one_run_per_job(runs).groupby("task", sort=True):
        finite = g["f_opt"].dropna()
        out.append(Board(
            task=str(task),
            table=summarise(g),
            runs=g,
            target_precision=float(g["target_precision"].dropna().iloc[0]) if g["target_precision"].notna().any() else float("nan"),
            f_opt=float(finite.iloc[0]) if len(finite) else float("nan"),
        ))
    return out


def step_curves(
    client, runs: pd.DataFrame, metric: str, grid: np.ndarray  # type: ignore[no-untyped-def]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per method, each finished run's ``metric`` held piecewise-constant on ``grid`` (evaluations)."""
    curves: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for method, g in runs[runs["status"] == "FINISHED"].groupby("method", sort=True):
        ys = []
        for run_id in g["run_id"]:
            hist = sorted((m.step, m.value) for m in client.get_metric_history(run_id, metric))
            if not hist:
                continue
            steps, values = np.array(hist).T
            idx = np.searchsorted(steps, grid, side="right") - 1
            ys.append(np.where(idx >= 0, values[np.maximum(idx, 0)], np.nan))
        if ys:
            curves[str(method)] = (grid, np.vstack(ys))
    return curves


def _front_plot(board: Board, client, path: Path) -> bool:  # type: ignore[no-untyped-def]
    """Each method's front from its median-IGD run against the true front; False if none."""
    import tempfile

    from tcbench.tasks.multiobjective import get_problem

    done = board.runs[(board.runs["status"] == "FINISHED") & board.runs["igd"].notna()]
    if done.empty:
        return False
    fronts = {}
    with tempfile.TemporaryDirectory() as tmp:
        for method, g in done.groupby("method", sort=True):
            median_run = g.iloc[(g["igd"] - g["igd"].median()).abs().argsort().iloc[0]]
            local = client.download_artifacts(median_run["run_id"], "front.csv", tmp)
            fronts[str(method)] = np.loadtxt(local, delimiter=",", skiprows=1, ndmin=2)
    problem = get_problem(str(done["task_name"].iloc[0]))
    from tcbench import plots

    plots.front_plot(path, fronts, problem.true_front(400), f"{board.task}: final fronts (median-IGD run)")
    return True


def write(board: Board, out_dir: Path, client, source: str) -> dict[str, Path]:  # type: ignore[no-untyped-def]
    """Write ``<task>.md``, ``<task>.csv`` and ``<task>_convergence.png`` into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {
        "md": out_dir / f"{board.task}.md",
        "csv": out_dir / f"{board.task}.csv",
        "png": out_dir / f"{board.task}_convergence.png",
    }
    budget = int(board.runs["budget"].max())
    grid = np.unique(np.linspace(1, budget, 200).round().astype(int))
    multi = is_multiobjective(board.runs)
    curves = step_curves(client, board.runs, "hv_gap" if multi else "best_f", grid)
    if curves:
        from tcbench import plots

        plots.band_convergence(
            paths["png"], curves, board.f_opt,
            f"{board.task}: {'hypervolume gap' if multi else 'best so far'} (median, IQR over seeds)",
            ylabel="1 - HV/HV*" if multi else "best so far - optimum",
        )
    if multi:
        paths["front"] = out_dir / f"{board.task}_front.png"
        if not _front_plot(board, client, paths["front"]):
            del paths["front"]
    failed = board.runs[board.runs["status"] != "FINISHED"]
    lines = [
        f"# Leaderboard: {board.task}",
        "",
        f"Source: {source}. Optimum value f* = {board.f_opt:g}; error = final best − f*; "
        f"target precision {board.target_precision:g}; budget {budget} evaluations.",
        "Rank: success rate, then ERT (expected evaluations to reach the target), then median "
        "error, then the smaller share of failed runs and the median of the finished ones (a method "
        "without a finished run last). ci95 = bootstrap 95 % interval of the median error; IQR = inter-quartile range of "
        "the final error over seeds; p_vs_next = Wilcoxon signed-rank p-value against the next "
        "row, paired by seed (p ≥ 0.05: the two are not told apart by these seeds). Failed runs "
        f"count as unsuccessful runs that used their whole budget. {FAILED_RULE}",
        "",
        markdown_table(failed_as_text(board.table)),
        "",
    ]
    if curves:
        lines += [f"![convergence]({paths['png'].name})", ""]
    if "front" in paths:
        lines += [f"![front]({paths['front'].name})", ""]
    write_board_files(lines + failed_lines(failed), board.table, paths)
    return paths
