"""The verdict of each board page, computed from its committed CSV (so it cannot drift from the
table beside it): where the paper's method ranks among the methods (the limits and the memoriser
left out), what beats it, how far the best is from the limits; and the paper's claims as the
board's own files state them (``claims.csv``: seed 000's per tier and selection, seed 001's per device and
tier; ``fig19.md`` of seed 001 where its folder has no ``claims.csv``)."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from tcbench.leaderboard.labels import METRICS
from tcbench.leaderboard.pages.boards import CompensationBoard, md_section, read_csv
from tcbench.leaderboard.pages.catalogue import REFERENCES

SHOWN_RIVALS = 3  # the methods named that beat the paper's


def ordinal(n: int) -> str:
    """1st, 2nd, 3rd, 4th ..."""
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def value(v: float, unit: str = "") -> str:
    """A median as a verdict quotes it."""
    if math.isinf(v):
        return "failed"
    if math.isnan(v):
        return "–"
    return f"{v:.3g}{' ' + unit if unit else ''}"


def unit_of(metric: str) -> str:
    """The unit of a metric, as its label ends (``…, µg``)."""
    return METRICS[metric].rsplit(", ", 1)[-1] if ", " in METRICS[metric] else ""


def method_ranks(board: CompensationBoard) -> pd.DataFrame:
    """The board's methods (no limit, no memoriser) with their rank on the primary metric's median
    (ties share the better rank; a failed median is last), median and ratios to the limits."""
    table = board.table
    rows = table[~table["method"].isin(list(REFERENCES))].copy()
    medians = pd.to_numeric(rows[board.primary_column], errors="coerce")
    rows["median"] = medians.to_numpy(float)
    rows["place"] = medians.rank(method="min", na_option="bottom").astype(int).to_numpy()
    keep = ["method", "place", "median"] + [c for c in ("x_oracle", "x_thermo", "note") if c in rows]
    return rows[keep].sort_values(["place", "method"], kind="stable").reset_index(drop=True)


def _limits(board: CompensationBoard, x_oracle: float, x_thermo: float) -> str:
    parts = []
    if math.isfinite(x_thermo):
        parts.append(f"{x_thermo:.3g}× the thermometer-limited oracle")
    if math.isfinite(x_oracle):
        parts.append(f"{x_oracle:.3g}× the physical limit")
    return ", ".join(parts)


def compensation_verdict(board: CompensationBoard) -> list[str]:
    """The verdict sentences of a compensation board (markdown)."""
    ranks = method_ranks(board)
    if ranks.empty:
        return ["The board holds no method beside the limits."]
    unit, label = unit_of(board.primary), METRICS[board.primary].rsplit(", ", 1)[0]
    n = len(ranks)
    by_name = ranks.set_index("method")
    best = ranks.iloc[0]
    paper = [m for m in board.family.paper_methods if m in by_name.index]
    out = []
    if board.family.paper_methods and not paper:
        out.append(f"The paper's methods ({', '.join(board.family.paper_methods)}) were not run on this board.")
    for m in paper:
        row = by_name.loc[m]
        place, median = int(row["place"]), float(row["median"])
        limits = _limits(board, float(row.get("x_oracle", math.nan)), float(row.get("x_thermo", math.nan)))
        if place == 1:
            rival = ranks[ranks["method"] != m].iloc[0] if n > 1 else None
            nxt = f"; next: {rival['method']} ({value(float(rival['median']), unit)})" if rival is not None else ""
            out.append(f"**The paper's {m} ranks first** of {n} methods on the median {label} "
                       f"({value(median, unit)}{'; ' + limits if limits else ''}){nxt}.")
        else:
            better = ranks[ranks["place"] < place]
            named = ", ".join(f"{r.method} ({value(float(r.median), unit)})" for r in better.head(SHOWN_RIVALS).itertuples())
            more = f" and {len(better) - SHOWN_RIVALS} more" if len(better) > SHOWN_RIVALS else ""
            raw = " — worse than raw, no compensation at all" if "raw" in better["method"].tolist() else ""
            out.append(f"**The paper's {m} loses**: {ordinal(place)} of {n} methods on the median {label} "
                       f"({value(median, unit)}{'; ' + limits if limits else ''}){raw}; better: {named}{more}.")
        note = str(row.get("note", "") or "")
        if note and note != "nan":
            out.append(f"Its note on the board: {note}.")
    best_limits = _limits(board, float(best.get("x_oracle", math.nan)), float(best.get("x_thermo", math.nan)))
    out.append(f"Best method: {best['method']} ({value(float(best['median']), unit)}"
               f"{'; ' + best_limits if best_limits else ''}). The limits and the memoriser are references, "
               "not ranked.")
    if not board.held_out:
        out.append("This tier replays the training runs' power-on: a diagnostic, not a benchmark — the held-out "
                   "verdict is on the next_run board.")
    return out + claims(board)


def claims(board: CompensationBoard) -> list[str]:
    """The paper's claims on this board as its folder's committed files state them."""
    folder = board.folder
    if (folder / "claims.csv").is_file():
        return _claims_csv(board, read_csv(folder / "claims.csv"))
    if board.tier == "next_run" and (folder / "fig19.md").is_file():
        return md_section(folder / "fig19.md", f"## {board.stem}", start="**Claim")
    return []


def _claims_csv(board: CompensationBoard, table: pd.DataFrame) -> list[str]:
    """One sentence per claim of ``claims.csv`` on the board's tier and metrics."""
    from tcbench.compensation.scoring import METRIC_NAMES

    mine = table[(table["tier"] == board.tier) & table["metric"].isin(METRIC_NAMES[board.protocol])]
    if "task" in table:  # a file over several devices (seed 001's): this board's device only
        mine = mine[mine["task"] == board.task]
    out = []
    for claim, rows in mine.groupby("claim", sort=False):
        said = rows["reproduced"].astype(str)
        yes = int((said == "yes").sum())
        partly = int(said.str.startswith("yes on").sum())
        undecided = int(said.str.startswith("undecided").sum())
        n = len(rows)
        if yes == n:
            verdict = "**reproduced**"
        elif undecided == n:
            verdict = "**undecided**: the interval spans the paper's factor"
        elif yes == 0 and partly == 0:
            verdict = "**not reproduced**" + (f" (undecided in {undecided} of {n} rows)" if undecided else "")
        elif yes == 0:
            verdict = (f"**not reproduced as a compensation**: {partly} of {n} rows reach it on the table while "
                       "failing the ±0.5 g probe, none otherwise")
        else:
            verdict = f"**partly reproduced**: in {yes} of {n} rows" + (
                f", {partly} more on the table only (failing the ±0.5 g probe)" if partly else "")
        counted = f"{n} row{'s' if n != 1 else ''} of claims.csv"
        out.append(f"Claim “{claim}” on this tier: {verdict} ({counted}; {_evidence(rows)}).")
    return out


def _evidence(rows: pd.DataFrame) -> str:
    """What a claim's rows measured: seed 000's first two selections and their worst-test gains, or
    seed 001's median gain over restarts with its interval and draws."""
    if "selection" in rows:
        return "e.g. " + "; ".join(f"{sel}: {gain}" for sel, gain in zip(rows["selection"].head(2),
                                                                          rows["worst-test gain"].head(2), strict=True))
    return "; ".join(f"{r.metric}: ×{value(float(r.gain))} [{r.ci95_gain}] over {int(r.draws)} draws"
                     for r in rows.itertuples())


def optimisation_verdict(table: pd.DataFrame, paper: tuple[str, ...]) -> str:
    """Where the papers' optimisers rank on one optimisation board."""
    if table.empty:
        return "No runs."
    n = len(table)
    top = table.iloc[0]
    theirs = table[table["method"].isin(paper)]
    head = f"rank 1 of {n}: {top['method']} (success {value(float(top['success_rate']))}, median error " \
           f"{value(float(top['median_error']))})"
    if theirs.empty:
        return f"{head[0].upper()}{head[1:]}; the papers' optimisers did not run here."
    mine = theirs.iloc[0]
    if int(mine["rank"]) == 1:
        return f"**The papers' {mine['method']} ranks first** of {n} (success {value(float(mine['success_rate']))}, " \
               f"median error {value(float(mine['median_error']))})."
    return (f"**The papers' optimisers lose**: their best, {mine['method']}, ranks {ordinal(int(mine['rank']))} of {n} "
            f"(success {value(float(mine['success_rate']))}, median error {value(float(mine['median_error']))}); "
            f"{head}.")


def bbob_verdict(folder: Path) -> list[str]:
    """The board's own paragraphs on where the seed papers' methods stand (its README, written with it)."""
    return md_section(folder / "README.md", "## Where the seed papers' methods stand")


def calibration_verdict(table: pd.DataFrame, paper: tuple[str, ...]) -> list[str]:
    """Which offset model is best, per record and split, on the real-IMU board."""
    place = table.groupby(["record", "split"], sort=False)["held_out_drift"].rank(method="min")
    firsts = table[place == 1]
    wins = firsts["method"].value_counts()
    pairs = len(table.groupby(["record", "split"], sort=False))
    line = f"Best held-out drift per record and split ({pairs} of them; ties counted for each): " \
           f"{', '.join(f'{m} {k}' for m, k in wins.items())}."
    for m in paper:
        mine = place[table["method"] == m]
        if len(mine):
            line += (f" The seed paper's gradient-descent BP ({m}) is best on {int((mine == 1).sum())} of {len(mine)}; "
                     f"its median place {float(mine.median()):.3g}.")
    return [line]


def devices_verdict(table: pd.DataFrame) -> list[str]:
    """Which method is best across the simulated devices of the chamber study."""
    wins = table["best"].value_counts()
    counted = ", ".join(f"{m} on {k}" for m, k in wins.items())
    ran = [c[2:] for c in table.columns if c.startswith("x_") and table[c].notna().sum() == 1]
    line = f"Best method per device ({len(table)} devices): {counted}."
    if ran:
        line += f" Run on one device only: {', '.join(ran)}."
    return [line]
