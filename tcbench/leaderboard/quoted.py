"""Numbers and tables quoted in prose, read from the board CSV that defines them: one definition per number.

A page quotes a board's number as a link to the CSV whose title names the cell::

    the thermometer-limited oracle, [30.1](../../leaderboards/paper-ifa-bp/msra_fulltemp-dev0.csv "oracle_thermometer | median_bias_ug")

The title is ``ROW | COLUMN``: ROW is the value of the CSV's ``method`` column (else its first), or
``key=value & key=value`` for CSVs keyed by several columns; COLUMN is the column. The link's text is
the cell as a board shows it (three significant digits; an interval column as written). A page of
the documentation site, whose links must stay inside the site, writes the number followed by the
same locator in a comment: ``30.1<!-- ../../leaderboards/x.csv "oracle_thermometer | median_bias_ug" -->``
(a ``×`` written before it stays outside the quote).

A page holds a table of a CSV between two markers, each alone on its line,
``<!-- table: CSV "ROWS | COLUMNS" -->`` and ``<!-- /table -->``::

    <!-- table: ../../leaderboards/real-imu/splits.csv "fit on → scored on=0 → 1,2 | record, raw, best" -->
    | record | raw | best |
    ...
    <!-- /table -->

ROWS selects rows as ROW does (``*``: every row; any number of rows), in the CSV's order; COLUMNS
names the columns, in the table's order, by their CSV names. The body is the markdown table the
boards write (:func:`tcbench.tables.markdown_table`), a blank line either side of it.

``python -m tcbench.leaderboard.quoted FILE ...`` rewrites every such number and table from its CSV
after the boards are regenerated; ``--check`` changes nothing and lists every quoted number and
table that differs (exit 1), as the repository's test does for every page.
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.tables import cell_text, markdown_table

_CELL = r'(?P<path>[^)\s]+\.csv) "(?P<row>[^"|]+?) \| (?P<column>[^"]+?)"'
# a link (its text without brackets: an interval is [[lo](…), [hi](…)]), or (on a site page, whose links
# must stay inside the site) the number followed by a comment
QUOTE = re.compile(r'\[(?P<text>[^\[\]]*)\]\(' + _CELL + r'\)|(?P<bare>[^\s<>\[\](×]+)<!-- ' + _CELL.replace("?P<", "?P<c_")
                   + r' -->')
TABLE = re.compile(r'^\s*<!-- table: ' + _CELL + r' -->\s*$')
TABLE_END = "<!-- /table -->"
shown = cell_text  # a cell as a board shows it


class QuoteError(ValueError):
    """A quote whose CSV, row or column does not exist."""


@dataclass(frozen=True)
class Quote:
    """One quoted number: where it is, what it says and what its CSV says."""

    page: Path
    line: int
    text: str
    value: str
    csv: Path
    row: str
    column: str

    @property
    def stale(self) -> bool:
        """Whether the page's text differs from the CSV's value."""
        return self.text != self.value


@dataclass(frozen=True)
class Table:
    """One quoted table: its markers' lines (1-based, the opening and the closing one), its body as
    written and as its CSV renders it."""

    page: Path
    line: int
    end: int
    text: str
    value: str
    csv: Path
    rows: str
    columns: tuple[str, ...]

    @property
    def stale(self) -> bool:
        """Whether the page's table differs from its CSV's."""
        return self.text != self.value

    def first_difference(self) -> str:
        """The first line where the page's table and the CSV's differ, both ways."""
        written, wanted = self.text.splitlines(), self.value.splitlines()
        for k in range(max(len(written), len(wanted))):
            a = written[k] if k < len(written) else "(nothing)"
            b = wanted[k] if k < len(wanted) else "(nothing)"
            if a != b:
                return f"line {k + 1} of the table reads {a!r}, the CSV gives {b!r}"
        return "no difference"


def _rows(table: pd.DataFrame, row: str, where: str) -> np.ndarray:
    """The indices of the rows ``row`` selects: ``*`` every row, ``key=value & ...`` those whose
    cells are these values, else those whose ``method`` (else first) column is ``row``."""
    row = row.strip()
    if row == "*":
        return np.arange(len(table))
    if "=" in row:
        mask = np.ones(len(table), bool)
        for part in row.split("&"):
            key, _, value = (p.strip() for p in part.partition("="))
            if key not in table.columns:
                raise QuoteError(f"{where}: no column {key!r} to select the row by")
            mask &= table[key].astype(str).to_numpy() == value
    else:
        key = "method" if "method" in table.columns else table.columns[0]
        mask = table[key].astype(str).to_numpy() == row
    return np.flatnonzero(mask)


def _column(table: pd.DataFrame, column: str, where: str) -> None:
    if column not in table.columns:
        raise QuoteError(f"{where}: no column {column!r} (it has: {', '.join(map(str, table.columns))})")


def _cell(table: pd.DataFrame, row: str, column: str, where: str) -> object:
    _column(table, column, where)
    hits = _rows(table, row, where)
    if hits.size != 1:
        raise QuoteError(f"{where}: {hits.size} rows match {row!r} (one needed)")
    return table[column].iloc[int(hits[0])]


def render_table(table: pd.DataFrame, rows: str, columns: list[str], where: str) -> str:
    """The markdown table of ``table``'s ``rows`` (a ROW selector, ``*`` for all) and ``columns``,
    as the boards write it; :class:`QuoteError` when a column is missing or no row is selected."""
    for column in columns:
        _column(table, column, where)
    hits = _rows(table, rows, where)
    if hits.size == 0:
        raise QuoteError(f"{where}: no row matches {rows.strip()!r}")
    return markdown_table(table.iloc[hits][columns])


class _Csvs:
    """The CSVs a page quotes, each read once."""

    def __init__(self, page: Path) -> None:
        self.page = page
        self.read: dict[Path, pd.DataFrame] = {}

    def __call__(self, path: str, where: str) -> tuple[Path, pd.DataFrame]:
        csv = (self.page.parent / path).resolve()
        if csv not in self.read:
            if not csv.is_file():
                raise QuoteError(f"{where}: no such CSV")
            self.read[csv] = pd.read_csv(csv, keep_default_na=True)
        return csv, self.read[csv]


def _parts(m: re.Match[str]) -> tuple[str, str, str, str]:
    """A quote's text, CSV path, row and column, whichever form it takes."""
    if m["text"] is not None:
        return m["text"], m["path"], m["row"].strip(), m["column"].strip()
    return m["bare"], m["c_path"], m["c_row"].strip(), m["c_column"].strip()


def quotes(page: Path) -> list[Quote]:
    """Every quoted number of ``page``, each with its CSV's value; :class:`QuoteError` naming the
    page, line and what is missing when a CSV, row or column does not exist."""
    csvs = _Csvs(page)
    found = []
    for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), start=1):
        for m in QUOTE.finditer(line):
            text, path, row, column = _parts(m)
            where = f"{page}:{n}: {path}"
            csv, table = csvs(path, where)
            found.append(Quote(page, n, text, shown(_cell(table, row, column, where)), csv, row, column))
    return found


def tables(page: Path) -> list[Table]:
    """Every quoted table of ``page``, each with its CSV's rendering; :class:`QuoteError` naming the
    page and line when a CSV, column or row does not exist or a table has no closing marker."""
    csvs = _Csvs(page)
    lines = page.read_text(encoding="utf-8").splitlines()
    found = []
    n = 0
    while n < len(lines):
        m = TABLE.match(lines[n])
        n += 1
        if m is None:
            continue
        where = f"{page}:{n}: {m['path']}"
        end = next((k for k in range(n, len(lines)) if lines[k].strip() == TABLE_END), None)
        if end is None:
            raise QuoteError(f"{where}: the table has no closing {TABLE_END}")
        csv, table = csvs(m["path"], where)
        columns = [c.strip() for c in m["column"].split(",")]
        value = render_table(table, m["row"], columns, where)
        found.append(Table(page, n, end + 1, "\n".join(lines[n:end]).strip(), value, csv, m["row"].strip(),
                           tuple(columns)))
        n = end + 1
    return found


def rewrite(page: Path) -> int:
    """Set every quoted number and table of ``page`` to its CSV's; how many changed."""
    stale = {(q.line, q.csv, q.row, q.column): q.value for q in quotes(page) if q.stale}
    lines = page.read_text(encoding="utf-8").splitlines(keepends=True)

    def fix(n: int, m: re.Match[str]) -> str:
        text, path, row, column = _parts(m)
        value = stale.get((n, (page.parent / path).resolve(), row, column))
        if value is None:
            return m[0]
        return f"[{value}]" + m[0][len(text) + 2:] if m["text"] is not None else value + m[0][len(text):]

    if stale:
        lines = [QUOTE.sub(lambda m, n=n: fix(n, m), line) for n, line in enumerate(lines, start=1)]
    stale_tables = [t for t in tables(page) if t.stale]
    for t in reversed(stale_tables):  # from the bottom, so the lines above keep their numbers
        lines[t.line:t.end - 1] = ["\n", t.value + "\n", "\n"]  # blank lines: the markers are blocks of their own
    if stale or stale_tables:
        page.write_text("".join(lines), encoding="utf-8")
    return len(stale) + len(stale_tables)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tcbench.leaderboard.quoted", description=__doc__.split("\n\n")[0])
    parser.add_argument("pages", nargs="+", type=Path, help="markdown pages to check or rewrite")
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 listing every stale quote and table")
    args = parser.parse_args(argv)
    stale = 0
    try:
        for page in args.pages:
            if args.check:
                for q in (q for q in quotes(page) if q.stale):
                    print(f"{q.page}:{q.line}: quotes {q.text!r}, {q.csv.name} says {q.value!r} ({q.row} | {q.column})")
                    stale += 1
                for t in (t for t in tables(page) if t.stale):
                    print(f"{t.page}:{t.line}: the table of {t.csv.name} ({t.rows}) is stale: {t.first_difference()}")
                    stale += 1
            else:
                changed = rewrite(page)
                print(f"{page}: {changed} quoted number{'s' if changed != 1 else ''} or "
                      f"table{'s' if changed != 1 else ''} rewritten")
    except (QuoteError, OSError) as exc:
        print(f"quoted: {exc}", file=sys.stderr)
        return 2
    return 1 if stale else 0


if __name__ == "__main__":
    raise SystemExit(main())
