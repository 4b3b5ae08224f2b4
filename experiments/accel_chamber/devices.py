"""The accelerometer chamber task across devices: from the per-device boards ``tcbench leaderboard``
wrote (``<board dir>/accel_chamber-dev<N>.csv``), one table of every method's median drift per
device, its ratio to the thermometer-limited oracle, the best method that is not a limit (and the rows
the board's paired test ties with it), and the device's drawn lag and hysteresis (what decides which
method wins).

Usage: python experiments/accel_chamber/devices.py --boards DIR (run.sh calls it); writes
``DIR/devices.md``, ``DIR/devices.csv`` and ``DIR/devices.png``.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from tcbench.sensors.kinds.accel import accel_unit  # noqa: E402
from tcbench.tables import markdown_table  # noqa: E402

LIMITS = ("oracle", "oracle_thermometer")


def device_table(boards: Path) -> pd.DataFrame:
    """One row per device: the drawn physics, then each method's drift over the thermometer-limited
    oracle's on the same draws (the board's ``x_thermo``)."""
    rows = []
    next_run = [p for p in boards.glob("accel_chamber-dev*.csv") if "." not in p.stem]  # tier boards: <task>.<tier>
    for path in sorted(next_run, key=lambda p: int(re.findall(r"dev(\d+)", p.stem)[0])):
        device = int(re.findall(r"dev(\d+)", path.stem)[0])
        board = pd.read_csv(path).set_index("method")
        drift = board["median_drift_ug"]
        draws = accel_unit(device).draws
        row: dict[str, object] = {"device": device, "lag_s": draws["lag_tau_s"],
                                  "hysteresis_mg": draws["hysteresis_mg"],
                                  "raw_ug": drift.get("raw"), "thermo_limit_ug": drift.get("oracle_thermometer")}
        methods = [m for m in drift.index if m not in LIMITS and m != "raw"]
        for m in methods:  # the board's ratio, taken draw by draw (tcbench.leaderboard.paired)
            row[f"x_{m}"] = board.loc[m, "x_thermo"]
        best = drift[methods].idxmin()
        row["best"] = best
        row["best_x_thermo"] = board.loc[best, "x_thermo"]
        row["tied_with_best"] = ", ".join(tied(board, best))
        rows.append(row)
    return pd.DataFrame(rows)


def tied(board: pd.DataFrame, best: str, alpha: float = 0.05) -> list[str]:
    """The methods ranked right after ``best`` that the board's paired test does not tell from the
    row above them (``p_vs_next`` >= ``alpha``: Wilcoxon signed-rank over the draws), down to the
    first that it does or to a limit."""
    ranked = board.sort_values("rank")
    names = list(ranked.index)
    out = []
    for above, below in zip(names[names.index(best):], names[names.index(best) + 1:]):
        p = ranked.loc[above, "p_vs_next"]
        if below in LIMITS or pd.isna(p) or p < alpha:
            break
        out.append(below)
    return out


def plot(table: pd.DataFrame, path: Path) -> None:
    ratios = [c for c in table.columns if c.startswith("x_") and table[c].notna().all()]  # on every device
    fig, ax = plt.subplots(figsize=(8, 4))
    for c in ratios:
        ax.plot(table["device"], table[c], marker="o", label=c[2:])
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("simulated device")
    ax.set_ylabel("median drift / thermometer-limited oracle's")
    ax.set_title("accel_chamber: every device, the baselines")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--boards", type=Path, required=True)
    args = parser.parse_args()
    table = device_table(args.boards)
    if table.empty:
        raise SystemExit(f"no accel_chamber-dev*.csv board in {args.boards}")
    table.to_csv(args.boards / "devices.csv", index=False)
    plot(table, args.boards / "devices.png")
    text = ["# accel_chamber across devices", "",
            "Median drift of each method over the thermometer-limited oracle's (x_*, 1 = the limit), per simulated "
            "device; lag_s and hysteresis_mg are the device's drawn thermal lag and half loop; best = the lowest "
            "median drift that is not a limit, tied_with_best = the rows below it the board's paired test (p_vs_next "
            ">= 0.05, Wilcoxon signed-rank over the draws) does not tell from the row above. Source: the boards "
            "beside this file (`bash experiments/accel_chamber/run.sh`).", "",
            markdown_table(table.round(3)), "", "![ratios per device](devices.png)", ""]
    (args.boards / "devices.md").write_text("\n".join(text))
    print(f"written: {args.boards / 'devices.md'}")


if __name__ == "__main__":
    main()
