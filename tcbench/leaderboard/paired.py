"""A method and its limits on the same draws of runs, compared per draw (as COCO scores an
algorithm over a function's instances).

A simulated compensation run trains and tests on one **draw** of power-ons: the recordings seed
it used (``task.recordings_seed``; ``null`` draws them from the run seed, so restart *i* is draw
*i*, :func:`tcbench.runner.compensation_job.draw_of`). A limit (the oracle) run on draw *d* is the
limit *of draw d*: a method's ratio to it is taken run by run against the limit on the run's own
draw, then summarised (median, bootstrap interval); a run on a draw the limit was not run on has
no ratio. A method run 30 times on one draw is compared with the limit on that draw only, and
the board's ``draws`` column says it met one.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from tcbench.stats import bootstrap_median_ci, with_failures


UNKNOWN_DRAW = -1  # the user's recordings (every run on the same files) or runs from before draws were tagged


def draw_column(runs: pd.DataFrame) -> pd.Series:
    """Each run's draw: the ``tcbench.draw`` tag, else a numeric ``task.recordings_seed`` param,
    else :data:`UNKNOWN_DRAW` — one draw shared by every run that names none (runs on the same
    files meet the same data; runs from before draws were tagged are compared as they were)."""
    tagged = pd.to_numeric(runs["draw_tag"], errors="coerce") if "draw_tag" in runs else pd.Series(np.nan, runs.index)
    if "params" not in runs:
        return tagged.fillna(UNKNOWN_DRAW)
    fixed = pd.to_numeric(runs["params"].map(lambda p: p.get("task.recordings_seed") if isinstance(p, dict) else None),
                          errors="coerce")
    return tagged.fillna(fixed).fillna(UNKNOWN_DRAW)


def limit_by_draw(runs: pd.DataFrame, limit: str, metric: str) -> pd.Series:
    """The limit's finished value of ``metric`` on each draw (the median where it ran twice on one)."""
    ok = runs[(runs["method"] == limit) & (runs["status"] == "FINISHED")]
    if ok.empty or metric not in ok or "draw" not in ok:
        return pd.Series(dtype=float)
    ok = ok[ok[metric].notna()]
    return ok.groupby("draw")[metric].median()


def paired_ratios(method_runs: pd.DataFrame, limit: pd.Series, metric: str) -> np.ndarray:
    """Each of a method's runs over the limit on its own draw: finished runs' ratios, a failed
    run on a draw the limit ran on as ``+inf`` (worse than any); runs on other draws left out."""
    if limit.empty or "draw" not in method_runs:
        return np.array([])
    on = method_runs[method_runs["draw"].isin(limit.index)]
    ok = on[on["status"] == "FINISHED"]
    value = ok[metric].to_numpy(float) if metric in ok else np.full(len(ok), np.nan)
    ratio = value / limit.reindex(ok["draw"]).to_numpy(float)
    return with_failures(ratio, int(len(on) - len(ok)))


def ratio_summary(ratios: np.ndarray) -> tuple[float, float, float]:
    """Median of paired ratios and the bootstrap 95 % interval of it (NaN without ratios)."""
    if ratios.size == 0:
        return float("nan"), float("nan"), float("nan")
    low, high = bootstrap_median_ci(ratios)
    return float(np.median(ratios)), low, high


def pairing_index(runs: pd.DataFrame) -> pd.MultiIndex:
    """The key two methods' runs are paired on: (draw, seed). Two methods over draws pair draw by
    draw (restart *i* is draw *i*); two on one draw pair restart by restart; a method on one draw
    and one over draws share one pair at most, so no paired test between them."""
    draw = runs["draw"].astype(int) if "draw" in runs else pd.Series(UNKNOWN_DRAW, runs.index)
    return pd.MultiIndex.from_arrays([draw.to_numpy(), runs["seed"].to_numpy()], names=["draw", "seed"])


def paired_gain(ok: pd.DataFrame, metric: str, failed: int) -> float:
    """Median over runs of raw ÷ the method on the run's own test runs (a failed run: gain 0): one
    definition for every row, the limits' and the methods'."""
    raw = f"raw_{metric}"
    if metric not in ok or raw not in ok:
        return float("nan")
    gain = ok[raw].to_numpy(float) / ok[metric].to_numpy(float)
    gain = np.concatenate([gain[~np.isnan(gain)], np.zeros(failed)])
    return float(np.median(gain)) if gain.size else float("nan")


def n_draws(runs: pd.DataFrame) -> int:
    """How many distinct draws of power-ons a method met (0 where its draws are unknown)."""
    return int(runs.loc[runs["draw"] != UNKNOWN_DRAW, "draw"].nunique()) if "draw" in runs else 0
