"""Tables as GitHub markdown: a leaf module (numpy and pandas only), shared by the leaderboards
and the commands that write tables of their own."""

from __future__ import annotations

import numpy as np
import pandas as pd


def _fmt(value: object) -> str:
    if isinstance(value, (float, np.floating)):
        if np.isinf(value):
            return "∞"
        if np.isnan(value):
            return "–"
        return f"{value:.3g}"
    return str(value)


def markdown_table(table: pd.DataFrame) -> str:
    """A pandas table as a GitHub markdown table (floats to three significant digits)."""
    head = "| " + " | ".join(table.columns) + " |"
    rule = "|" + "|".join("---" for _ in table.columns) + "|"
    body = ["| " + " | ".join(_fmt(v) for v in row) + " |" for row in table.itertuples(index=False)]
    return "\n".join([head, rule, *body])
