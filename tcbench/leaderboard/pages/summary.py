"""Methods ranked across the compensation boards: each method's place on every held-out board it
ran on (by the board's primary metric, the limits and the memoriser left out), its mean place,
the boards counted, its wins, and its median ratio to the thermometer-limited oracle, the one
relative quantity every board shares."""

from __future__ import annotations

import numpy as np
import pandas as pd

from tcbench.leaderboard.pages.boards import CompensationBoard
from tcbench.leaderboard.pages.verdicts import method_ranks


def ranking(boards: list[CompensationBoard]) -> pd.DataFrame:
    """One row per method over the held-out boards (``next_run`` and the other new-run tiers):
    ``boards`` counted, ``mean_rank``, ``wins`` (first places), ``median_x_thermo`` and its place
    on each board (a column per board, empty where it did not run); best mean place first."""
    held = [b for b in boards if b.held_out]
    places: dict[str, dict[str, float]] = {}
    ratios: dict[str, list[float]] = {}
    for board in held:
        for row in method_ranks(board).itertuples(index=False):
            places.setdefault(str(row.method), {})[board.page_id] = float(row.place)
            x = float(getattr(row, "x_thermo", np.nan))
            if np.isfinite(x):
                ratios.setdefault(str(row.method), []).append(x)
    rows = []
    for method, on in places.items():
        ranks = np.array(list(on.values()))
        rows.append({"method": method, "boards": len(on), "mean_rank": float(ranks.mean()),
                     "wins": int((ranks == 1).sum()),
                     "median_x_thermo": float(np.median(ratios[method])) if ratios.get(method) else np.nan,
                     **{b.page_id: on.get(b.page_id, np.nan) for b in held}})
    table = pd.DataFrame(rows, columns=["method", "boards", "mean_rank", "wins", "median_x_thermo",
                                        *[b.page_id for b in held]])
    return table.sort_values(["mean_rank", "boards", "method"], ascending=[True, False, True],
                             kind="stable").reset_index(drop=True)
