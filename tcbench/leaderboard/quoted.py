"""Numbers quoted in prose, read from the board CSV that defines them: one definition per number.

A page quotes a board's number as a link to the CSV whose title names the cell::

    the thermometer-limited oracle, [30.1](../../leaderboards/paper-ifa-bp/msra_fulltemp-dev0.csv "oracle_thermometer | median_bias_ug")

The title is ``ROW | COLUMN``: ROW is the value of the CSV's ``method`` column (else its first), or
``key=value & key=value`` for CSVs keyed by several columns; COLUMN is the column. The link's text is
the cell as a board shows it (three significant digits; an interval column as written). A page of
the documentation site, whose links must stay inside the site, writes the number followed by the
same locator in a comment: ``30.1<!-- ../../leaderboards/x.csv "oracle_thermometer | median_bias_ug" -->``.
``python -m tcbench.leaderboard.quoted FILE ...`` rewrites every such text from its CSV after the
boards are regenerated; ``--check`` changes nothing and lists every quoted number that differs
(exit 1), as the repository's test does for every page.
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

_CELL = r'(?P<path>[^)\s]+\.csv) "(?P<row>[^"|]+?) \| (?P<column>[^"]+?)"'
# a link, or (on a site page, whose links must stay inside the site) the number followed by a comment
QUOTE = re.compile(r'\[(?P<text>[^\]]*)\]\(' + _CELL + r'\)|(?P<bare>[^\s<>\[\](]+)<!-- ' + _CELL.replace("?P<", "?P<c_")
                   + r' -->')


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


def shown(value: object) -> str:
    """A cell as a board shows it: three significant digits, ∞ and – for inf and NaN, text as is."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(value)
    if isinstance(value, (float, np.floating)):
        if np.isinf(value):
            return "∞"
        return "–" if np.isnan(value) else f"{value:.3g}"
    return str(value)


def _cell(table: pd.DataFrame, row: str, column: str, where: str) -> object:
    if column not in table.columns:
        raise QuoteError(f"{where}: no column {column!r} (it has: {', '.join(map(str, table.columns))})")
    if "=" in row:
        mask = np.ones(len(table), bool)
        for part in row.split("&"):
            key, _, value = (p.strip() for p in part.partition("="))
            if key not in table.columns:
                raise QuoteError(f"{where}: no column {key!r} to select the row by")
            mask &= table[key].astype(str).to_numpy() == value
    else:
        key = "method" if "method" in table.columns else table.columns[0]
        mask = table[key].astype(str).to_numpy() == row.strip()
    hits = np.flatnonzero(mask)
    if hits.size != 1:
        raise QuoteError(f"{where}: {hits.size} rows match {row!r} (one needed)")
    return table[column].iloc[int(hits[0])]


def _parts(m: re.Match[str]) -> tuple[str, str, str, str]:
    """A quote's text, CSV path, row and column, whichever form it takes."""
    if m["text"] is not None:
        return m["text"], m["path"], m["row"].strip(), m["column"].strip()
    return m["bare"], m["c_path"], m["c_row"].strip(), m["c_column"].strip()


def quotes(page: Path) -> list[Quote]:
    """Every quoted number of ``page``, each with its CSV's value; :class:`QuoteError` naming the
    page, line and what is missing when a CSV, row or column does not exist."""
    tables: dict[Path, pd.DataFrame] = {}
    found = []
    for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), start=1):
        for m in QUOTE.finditer(line):
            text, path, row, column = _parts(m)
            csv = (page.parent / path).resolve()
            where = f"{page}:{n}: {path}"
            if csv not in tables:
                if not csv.is_file():
                    raise QuoteError(f"{where}: no such CSV")
                tables[csv] = pd.read_csv(csv, keep_default_na=True)
            value = shown(_cell(tables[csv], row, column, where))
            found.append(Quote(page, n, text, value, csv, row, column))
    return found


def rewrite(page: Path) -> int:
    """Set every quoted number of ``page`` to its CSV's value; how many changed."""
    stale = {(q.line, q.row, q.column): q.value for q in quotes(page) if q.stale}
    if not stale:
        return 0
    lines = page.read_text(encoding="utf-8").splitlines(keepends=True)

    def fix(n: int, m: re.Match[str]) -> str:
        text, _, row, column = _parts(m)
        value = stale.get((n, row, column))
        if value is None:
            return m[0]
        return f"[{value}]" + m[0][len(text) + 2:] if m["text"] is not None else value + m[0][len(text):]

    out = [QUOTE.sub(lambda m, n=n: fix(n, m), line) for n, line in enumerate(lines, start=1)]
    page.write_text("".join(out), encoding="utf-8")
    return len(stale)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tcbench.leaderboard.quoted", description=__doc__.split("\n\n")[0])
    parser.add_argument("pages", nargs="+", type=Path, help="markdown pages to check or rewrite")
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 listing every stale quote")
    args = parser.parse_args(argv)
    stale = 0
    try:
        for page in args.pages:
            if args.check:
                for q in (q for q in quotes(page) if q.stale):
                    print(f"{q.page}:{q.line}: quotes {q.text!r}, {q.csv.name} says {q.value!r} ({q.row} | {q.column})")
                    stale += 1
            else:
                changed = rewrite(page)
                print(f"{page}: {changed} quoted number{'s' if changed != 1 else ''} rewritten")
    except (QuoteError, OSError) as exc:
        print(f"quoted: {exc}", file=sys.stderr)
        return 2
    return 1 if stale else 0


if __name__ == "__main__":
    raise SystemExit(main())
