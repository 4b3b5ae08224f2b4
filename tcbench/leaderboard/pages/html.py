"""A board's table as HTML for the pages: every header a human label beside the raw column key,
every numeric cell its number in ``data-value`` (so ``docs/javascripts/boards.js`` sorts it as a
number), reference rows (the limits, the memoriser, raw) and the paper's rows marked, a text box
that filters the rows. No script or style here: the site's ``boards.js`` and ``boards.css``."""

from __future__ import annotations

import html
import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from tcbench.leaderboard.files import STAT_PREFIXES
from tcbench.leaderboard.labels import column_label, metric_of
from tcbench.leaderboard.pages.boards import interval

# how a marked row's role is shown beside its method
BADGES = {"limit": "limit", "memoriser": "reference", "baseline": "baseline", "paper": "paper's method"}


def _esc(value: object) -> str:
    return html.escape(str(value), quote=True)


def _number(value: float) -> str:
    """A number as the boards print it (three significant digits)."""
    return f"{value:.3g}"


def _data_value(value: float) -> str:
    """A number as ``data-value`` holds it (JavaScript's ``Number()`` reads it back); NaN: empty."""
    if math.isnan(value):
        return ""
    if math.isinf(value):
        return "Infinity" if value > 0 else "-Infinity"
    return repr(float(value))


def _numeric(column: pd.Series) -> pd.Series | None:
    """The column as numbers (an interval ``a–b`` as its low end), or None when it is text."""
    given = column.notna() & (column.astype(str).str.strip() != "")
    if not given.any():
        return None
    numbers = pd.to_numeric(column, errors="coerce")
    if bool((numbers.notna() | ~given).all()):
        return numbers.astype(float)
    if column.name and str(column.name).startswith("ci95_"):
        low = column.map(lambda v: interval(v)[0] if isinstance(v, str) else math.nan)
        return low.astype(float)
    return None


def _cell(raw: object, number: float | None, column: str, integer: bool) -> str:
    """One ``<td>``: the shown text and, for a numeric column, its number."""
    if number is None:
        text = "" if raw is None or (isinstance(raw, float) and math.isnan(raw)) else str(raw)
        return f"<td>{_esc(text)}</td>"
    if isinstance(raw, str) and not _plain_number(raw):  # an interval: shown as written, sorted by its low end
        return f'<td class="tcb-num" data-value="{_data_value(number)}">{_esc(raw)}</td>'
    if math.isnan(number):
        shown = "–"
    elif math.isinf(number):
        shown = "failed" if column.startswith(STAT_PREFIXES) and number > 0 else ("∞" if number > 0 else "−∞")
    else:
        shown = str(int(number)) if integer else _number(number)
    full = "" if math.isnan(number) or math.isinf(number) or integer else f' title="{_esc(repr(float(number)))}"'
    return f'<td class="tcb-num" data-value="{_data_value(number)}"{full}>{_esc(shown)}</td>'


def _plain_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def header(column: str, numeric: bool, label: str | None = None) -> str:
    """One ``<th>``: the label (``label``, else :func:`~tcbench.leaderboard.labels.column_label`),
    the raw key beside it; the metric's own name in its tooltip."""
    label = label or column_label(column)
    metric = metric_of(column)
    tip = f' title="metric {_esc(metric)}"' if metric and metric != column else ""
    kind = "num" if numeric else "text"
    raw = f"<code>{_esc(column)}</code>"
    shown = raw if label == column else f'<span class="tcb-label">{_esc(label)}</span> {raw}'
    return f'<th scope="col" data-type="{kind}" aria-sort="none"{tip}>{shown}</th>'


def table(frame: pd.DataFrame, table_id: str, caption: str, roles: Mapping[str, str] | None = None,
          key: str = "method", labels: Mapping[str, str] | None = None) -> str:
    """The HTML of a sortable, filterable board table: one line per row, no blank line (a raw HTML
    block of Python-Markdown). ``roles`` marks rows by the value of their ``key`` column
    (``limit``, ``memoriser``, ``baseline``, ``paper``); ``labels`` overrides column labels."""
    roles, labels = roles or {}, labels or {}
    columns = [str(c) for c in frame.columns]
    numbers = {c: _numeric(frame[c]) for c in columns}
    integer = {c: pd.api.types.is_integer_dtype(frame[c].dtype) for c in columns}
    lines = [f'<div class="tcb-board" data-table="{_esc(table_id)}">',
             f'<div class="tcb-tools"><input type="search" class="tcb-filter" aria-controls="{_esc(table_id)}" '
             f'aria-label="Filter the rows of {_esc(caption)}" placeholder="Filter rows (method, note …)"> '
             f'<span class="tcb-count" aria-live="polite">{len(frame)} of {len(frame)} rows</span></div>',
             f'<div class="tcb-scroll"><table class="tcb-table" id="{_esc(table_id)}">',
             f"<caption>{_esc(caption)}</caption>",
             "<thead><tr>" + "".join(header(c, numbers[c] is not None, labels.get(c)) for c in columns) + "</tr></thead>",
             "<tbody>"]
    values = frame.to_numpy(dtype=object)
    for i in range(len(frame)):
        row = values[i]
        name = str(row[columns.index(key)]) if key in columns else ""
        role = roles.get(name, "")
        cells = []
        for j, c in enumerate(columns):
            num = numbers[c]
            cell = _cell(row[j], None if num is None else float(num.iloc[i]), c, integer[c])
            if c == key and role:
                cell = cell.replace("</td>", f' <span class="tcb-badge tcb-badge-{role}">{BADGES[role]}</span></td>', 1)
            cells.append(cell)
        attrs = f' class="tcb-ref tcb-{role}" data-ref="{role}"' if role else ""
        lines.append(f"<tr{attrs}>" + "".join(cells) + "</tr>")
    lines += ["</tbody>", "</table></div>", "</div>"]
    return "\n".join(lines)


def column_legend(frame: pd.DataFrame) -> list[str]:
    """Markdown lines naming every column: the raw key, its label and, for a statistic of a metric,
    the metric's own name (``median_zb0_ug``: median zero-bias stability from power-on, µg
    (``zb_zero_start_ug``))."""
    out = []
    for column in map(str, frame.columns):
        metric = metric_of(column)
        own = f" (`{metric}`)" if metric and metric != column else ""
        out.append(f"- `{column}`: {column_label(column)}{own}")
    return out


def finite(values: pd.Series) -> np.ndarray:
    """The finite numbers of a column."""
    x = pd.to_numeric(values, errors="coerce").to_numpy(float)
    return x[np.isfinite(x)]
