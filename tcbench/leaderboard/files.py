"""What every leaderboard shares, optimisation (:mod:`tcbench.leaderboard.optimisation`) and compensation
(:mod:`tcbench.leaderboard.compensation`): the MLflow runs of a kind, one run per job and the board
files (markdown tables: :mod:`tcbench.tables`). A leaf module (numpy and pandas only)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

# Why a board's p_vs_next is "–" (tcbench.stats.paired_p_value), said in its key and on its page
P_DASH = ("p_vs_next is – where the row and the next share fewer than 6 pairs (runs paired by seed; on a "
          "compensation board by draw of power-ons, by seed within one draw): with fewer no difference could reach "
          "p < 0.05, a method run once has one, and one over draws shares at most one with one restarted on a single "
          "draw; and on the last row.")
# How every board counts failed runs in its statistics (:func:`tcbench.stats.with_failures`), said in its key
FAILED_RULE = ("Every median, quartile and ci95 counts a failed run as worse than any finished one: "
               "\"failed\" where the statistic falls on failed runs (a method that failed half its runs or "
               "more has median \"failed\"); p_vs_next pairs finished runs only. " + P_DASH)
STAT_PREFIXES = ("median_", "ci95_", "iqr_", "x_")  # the columns a failed run can make "failed"


def experiment_ids(client, experiments: list[str]) -> list[str]:  # type: ignore[no-untyped-def]
    """The ids of the experiments; ``LookupError`` naming the first the store does not hold, and
    those it does."""
    found = {name: client.get_experiment_by_name(name) for name in experiments}
    if missing := [name for name, e in found.items() if e is None]:
        from tcbench.errors import unknown_name

        held = sorted(e.name for e in client.search_experiments())
        raise LookupError(unknown_name("experiment", missing[0], held, f" in {client.tracking_uri}"))
    return [e.experiment_id for e in found.values()]


def search_runs(client, experiments: list[str], kind: str | None, sweep: str | None = None) -> Iterator[Any]:  # type: ignore[no-untyped-def]
    """Every MLflow run of ``kind`` (``optimisation``, ``compensation``; None: every tcbench run)
    in the experiments, optionally of one sweep, page by page; ``LookupError`` naming the first
    experiment the store does not hold, and those it does."""
    ids = experiment_ids(client, experiments)
    terms = [f"tags.`tcbench.kind` = '{kind}'" if kind else "tags.`tcbench.kind` != ''"]
    if sweep:
        terms.append(f"tags.`tcbench.sweep_id` = '{sweep}'")
    query = " and ".join(terms)
    token = None
    while True:
        page = client.search_runs(ids, filter_string=query, max_results=1000, page_token=token)
        yield from page
        token = page.token
        if not token:
            break


def one_run_per_job(runs: pd.DataFrame, keys: tuple[str, ...] = ("task", "method", "config_hash", "seed")
                    ) -> pd.DataFrame:
    """Keep one run per job (task, method, config, seed): the latest FINISHED one, else the
    latest attempt, so a resumed or repeated sweep does not count a seed twice. ``keys`` without
    ``config_hash`` keeps one run per method and seed even when configs sharing a method name differ
    (e.g. the gyro oracle, the same whatever the pipeline settings beside it)."""
    if runs.empty:
        return runs
    order = runs.assign(_ok=runs["status"] == "FINISHED").sort_values(["_ok", "start_time"])
    keys = list(keys)
    return order.drop_duplicates(keys, keep="last").drop(columns="_ok").sort_index()


def failed_as_text(table: pd.DataFrame) -> pd.DataFrame:
    """The board's table as shown: an infinite median, quartile, interval end or ratio to a limit
    (one that falls on failed runs) reads "failed"; the CSV keeps the number (``inf``)."""
    shown = table.copy()
    for column in [c for c in table.columns if str(c).startswith(STAT_PREFIXES)]:
        values = pd.to_numeric(table[column], errors="coerce")
        if np.isinf(values).any():
            shown[column] = table[column].astype(object).where(~np.isinf(values), "failed")
    return shown


def failed_lines(failed: pd.DataFrame) -> list[str]:
    """Markdown lines listing failed or unfinished runs (none when there are none)."""
    if not len(failed):
        return []
    return ["Failed or unfinished runs:", "",
            *[f"- {r.method} seed {r.seed}: {r.status} {r.error_message}".rstrip() for r in failed.itertuples()], ""]


def write_board_files(lines: list[str], table: pd.DataFrame, paths: dict[str, Path]) -> None:
    """Write the markdown ``lines`` and the ``table`` CSV, each renamed into place when complete."""
    tmp_md, tmp_csv = paths["md"].with_suffix(".md.tmp"), paths["csv"].with_suffix(".csv.tmp")
    tmp_md.write_text("\n".join(lines))
    table.to_csv(tmp_csv, index=False)
    tmp_md.replace(paths["md"])
    tmp_csv.replace(paths["csv"])
