"""Markdown tables (tcbench.tables): tcbench's cell formatting laid out by tabulate, the same
bytes the committed boards hold."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from tcbench.leaderboard.files import failed_as_text
from tcbench.tables import markdown_table

ROOT = Path(__file__).resolve().parents[1]


def test_cells_are_formatted_and_not_padded() -> None:
    table = pd.DataFrame({"method": ["ifa", "a longer name"], "error": [0.000123456, np.inf],
                          "ci": [np.nan, 1234567.0], "seeds": [5, 30], "note": ["1e+03", ""]})
    assert markdown_table(table) == (
        "| method | error | ci | seeds | note |\n"
        "|---|---|---|---|---|\n"
        "| ifa | 0.000123 | – | 5 | 1e+03 |\n"
        "| a longer name | ∞ | 1.23e+06 | 30 |  |"
    )
    assert markdown_table(table.iloc[:0]) == "| method | error | ci | seeds | note |\n|---|---|---|---|---|"


def test_committed_optimisation_boards_are_reproduced_from_their_csv() -> None:
    """Each committed optimisation board's .md holds the table its CSV gives, byte for byte."""
    boards = [p for p in sorted((ROOT / "leaderboards").glob("*/*.csv"))
              if p.with_suffix(".md").is_file() and p.read_text().startswith("rank,method,seeds,")]
    assert len(boards) >= 10
    for csv in boards:
        assert markdown_table(failed_as_text(pd.read_csv(csv))) in csv.with_suffix(".md").read_text(), csv


# A cell's text is what a UTF-8 board can hold: no lone surrogates (pandas' string columns refuse them).
_cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**6, 10**6),
                   st.text(st.characters(codec="utf-8", exclude_characters="|\n\r"), max_size=6))


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 4).flatmap(lambda cols: st.lists(st.lists(_cells, min_size=cols, max_size=cols), max_size=5)
                                 .map(lambda rows, cols=cols: (cols, rows))))
def test_rows_hold_each_cell_as_formatted(shape: tuple[int, list[list[object]]]) -> None:
    cols, rows = shape
    names = [f"c{j}" for j in range(cols)]
    lines = markdown_table(pd.DataFrame(rows, columns=names, dtype=object)).split("\n")
    assert lines[0] == "| " + " | ".join(names) + " |" and lines[1] == "|" + "|".join(["---"] * cols) + "|"
    assert len(lines) == 2 + len(rows)
    for line, row in zip(lines[2:], rows, strict=True):
        want = ["∞" if isinstance(v, float) and np.isinf(v) else "–" if isinstance(v, float) and np.isnan(v)
                else f"{v:.3g}" if isinstance(v, float) else str(v) for v in row]
        assert line == "| " + " | ".join(want) + " |"
