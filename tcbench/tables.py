"""Tables as GitHub markdown: a leaf module (numpy, pandas and tabulate only), shared by the
leaderboards and the commands that write tables of their own."""

from __future__ import annotations

import numpy as np
import pandas as pd
from tabulate import DataRow, TableFormat

# tabulate's "github" format with cells as given (no padding to the column's width) and a rule
# of three dashes per column: the tables tcbench has always written, byte for byte.
_GITHUB = TableFormat(lineabove=None, linebelowheader=lambda widths, _aligns: "|" + "|".join("---" for _ in widths) + "|",
                      linebetweenrows=None, linebelow=None, headerrow=DataRow("|", "|", "|"),
                      datarow=DataRow("|", "|", "|"), padding=1, with_header_hide=None)


def cell_text(value: object) -> str:
    """A cell as a table shows it: floats to three significant digits, ``inf`` as ∞, NaN as –,
    everything else as ``str`` gives it."""
    if isinstance(value, (float, np.floating)):
        if np.isinf(value):
            return "∞"
        if np.isnan(value):
            return "–"
        return f"{value:.3g}"
    return str(value)


def markdown_table(table: pd.DataFrame) -> str:
    """A pandas table as a GitHub markdown table (floats to three significant digits, ``inf`` as
    ∞, NaN as –; every other cell as ``str`` gives it)."""
    cells = table.astype(object).map(cell_text)
    return cells.to_markdown(index=False, tablefmt=_GITHUB, disable_numparse=True, stralign=None, numalign=None)
