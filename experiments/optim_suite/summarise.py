"""One table over all suite leaderboards: median final error per task and method, best in bold,
and ranks a paired test cannot separate marked ≈. Writes ``summary.md`` beside this file.

Run from the repository root: python experiments/optim_suite/summarise.py
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
BOARDS = HERE.parents[1] / "leaderboards" / "optim-suite"


def main() -> None:
    rows = []
    for csv in sorted(BOARDS.glob("*.csv")):
        table = pd.read_csv(csv)
        first = table.iloc[0]
        tie = first["p_vs_next"] >= 0.05 if pd.notna(first["p_vs_next"]) else False
        cells = {}
        for r in table.itertuples():
            value = f"{r.median_error:.3g}"
            cells[r.method] = f"**{value}**" if r.rank == 1 else value
        rows.append({"task": csv.stem, "best": first["method"] + (" ≈ " + table.iloc[1]["method"] if tie else ""),
                     **cells})
    summary = pd.DataFrame(rows).fillna("–")
    methods = [c for c in summary.columns if c not in {"task", "best"}]
    lines = ["| task | rank 1 | " + " | ".join(methods) + " |", "|---|---|" + "---|" * len(methods)]
    lines += ["| " + " | ".join(str(r[c]) for c in ["task", "best", *methods]) + " |" for _, r in summary.iterrows()]
    wins = summary["best"].str.split(" ").str[0].value_counts()
    text = ("Median final error (best − f*; for ZDT/DTLZ2 the hypervolume gap 1 − HV/HV*) over 15 seeds, "
            "5000 evaluations, from `leaderboards/optim-suite/*.csv`. ≈: the rank-1 method is not "
            "separated from rank 2 by a paired Wilcoxon test (p ≥ 0.05).\n\n" + "\n".join(lines) +
            "\n\nRank-1 counts: " + ", ".join(f"{m} {n}" for m, n in wins.items()) + ".\n")
    (HERE / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
