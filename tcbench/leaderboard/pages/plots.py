"""The plot of a board page: each method's median of the primary metric with its 95 % interval,
best at the top, beside reference lines at the oracle (the physical limit), the
thermometer-limited oracle, the memoriser and raw. An SVG, byte for byte the same for the same
board (no date, a fixed id salt), so a rebuilt site rewrites nothing."""

from __future__ import annotations

import io
import math

import numpy as np

from tcbench.leaderboard.labels import METRICS
from tcbench.leaderboard.pages.boards import CompensationBoard, interval
from tcbench.leaderboard.pages.catalogue import BASELINES, REFERENCES

# reference line per row: colour, line style, legend text
LINES = {
    "oracle": ("#1b7837", "-", "oracle (physical limit)"),
    "oracle_thermometer": ("#5aae61", "--", "thermometer-limited oracle"),
    "memoriser": ("#c51b7d", ":", "memoriser (no physics)"),
    "raw": ("#636363", "-.", "raw (no compensation)"),
}
PAPER_COLOUR, OTHER_COLOUR = "#d73027", "#4575b4"


def reference_plot(board: CompensationBoard, fmt: str = "svg") -> bytes:
    """The plot (an SVG; ``fmt``: another of matplotlib's formats) of the board's methods, the limits,
    the memoriser and raw as lines, on its primary metric."""
    import matplotlib

    from matplotlib.figure import Figure

    table = board.table
    column, ci = board.primary_column, board.primary_column.replace("median_", "ci95_", 1)
    rows = table[~table["method"].isin(list(REFERENCES) + list(BASELINES))]
    medians = rows[column].to_numpy(float)
    ends = np.array([interval(v) for v in rows[ci]]) if ci in rows else np.full((len(rows), 2), np.nan)
    names = rows["method"].astype(str).tolist()
    height = 1.4 + 0.26 * max(len(names), 1)
    with matplotlib.rc_context({"svg.hashsalt": "tcbench-board", "svg.fonttype": "none", "font.size": 8}):
        fig = Figure(figsize=(7.0, height))
        ax = fig.subplots()
        y = np.arange(len(names))[::-1]
        shown = np.where(np.isfinite(medians), medians, np.nan)
        low = np.where(np.isfinite(ends[:, 0]), shown - ends[:, 0], 0.0) if len(names) else np.array([])
        high = np.where(np.isfinite(ends[:, 1]), ends[:, 1] - shown, 0.0) if len(names) else np.array([])
        colours = [PAPER_COLOUR if n in board.family.paper_methods else OTHER_COLOUR for n in names]
        for yi, m, lo, hi, c in zip(y, shown, low, high, colours, strict=True):
            if np.isfinite(m):
                ax.errorbar(m, yi, xerr=[[max(lo, 0.0)], [max(hi, 0.0)]], fmt="o", color=c, ms=4, capsize=2, lw=1)
        positive = [v for v in shown if np.isfinite(v) and v > 0]
        for name, (colour, style, text) in LINES.items():
            ref = table.loc[table["method"] == name, column]
            value = float(ref.iloc[0]) if len(ref) else math.nan
            if np.isfinite(value):
                ax.axvline(value, color=colour, ls=style, lw=1.2, label=f"{text}: {value:.3g}")
                lo, hi = interval(table.loc[table["method"] == name, ci].iloc[0]) if ci in table else (math.nan,) * 2
                if np.isfinite(lo) and np.isfinite(hi) and hi > lo:  # a limit drawn over runs: its interval
                    ax.axvspan(lo, hi, color=colour, alpha=0.12, lw=0)
                positive += [value] if value > 0 else []
        if positive and min(positive) > 0 and max(positive) / min(positive) > 20:
            ax.set_xscale("log")
        ax.set_yticks(y, names)
        for tick, c in zip(ax.get_yticklabels(), colours, strict=True):
            tick.set_color(c)
        ax.set_ylim(-0.7, len(names) - 0.3)
        ax.set_xlabel(f"median {METRICS[board.primary]} (dot) and its 95 % interval (bar)")
        paper = " (red: the paper's method)" if PAPER_COLOUR in colours else ""
        ax.set_title(f"{board.stem}: methods against the limits{paper}", fontsize=9)
        ax.grid(True, axis="x", which="both", alpha=0.25)
        if ax.get_legend_handles_labels()[0]:
            below = 0.5 / (0.77 * height)  # the x label's height in axes fractions (default subplot margins)
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -below), ncol=2, frameon=False, fontsize=7)
        buf = io.BytesIO()
        fig.savefig(buf, format=fmt, metadata={"Date": None} if fmt == "svg" else None, bbox_inches="tight")
    return buf.getvalue()
