"""Numbers a page quotes from a board are links to the CSV cell that defines them, and its tables
are generated from the CSV (:mod:`tcbench.leaderboard.quoted`): every page of the repository agrees
with its boards, and a stale number or table is found, named and rewritten."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from tcbench.leaderboard.quoted import QuoteError, main, quotes, render_table, rewrite, tables

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "experiments").glob("*/README.md")),
         *sorted(p for p in (ROOT / "docs").rglob("*.md") if "leaderboards" not in p.parts)]
REAL_IMU = ROOT / "experiments" / "real-imu" / "README.md"
BOARD = ROOT / "leaderboards" / "real-imu"


def test_every_quoted_number_of_every_page_is_its_board_s() -> None:
    found = [q for page in PAGES for q in quotes(page)]
    assert any(q.page.name == "README.md" and "paper_ifa_bp" in str(q.page) for q in found)
    stale = [f"{q.page.relative_to(ROOT)}:{q.line}: {q.text} but {q.csv.name} says {q.value}" for q in found if q.stale]
    assert not stale, "\n".join(stale)


def test_no_quoted_number_follows_a_digit_group() -> None:
    """A number written with a space between its thousands ("1 780") and quoted bare keeps its first
    group when rewritten: "1 1.78e+03" read as its board's 1.78e+03 and showed a stray 1."""
    import re

    split = re.compile(r"\d [^\s<>\[\](]+<!-- [^>]*\.csv ")
    found = [f"{page.relative_to(ROOT)}: {m.group(0)}" for page in PAGES
             for m in split.finditer(page.read_text(encoding="utf-8"))]
    assert not found, "\n".join(found)


def test_every_table_of_every_page_is_its_board_s() -> None:
    found = [t for page in PAGES for t in tables(page)]
    assert sum(t.page == REAL_IMU for t in found) == 3
    stale = [f"{t.page.relative_to(ROOT)}:{t.line}: {t.first_difference()}" for t in found if t.stale]
    assert not stale, "\n".join(stale)


def test_a_table_is_the_board_s_own_markdown() -> None:
    """Every row and column of ``splits.csv`` renders as ``board.md``'s table, byte for byte."""
    splits = pd.read_csv(BOARD / "splits.csv")
    table = render_table(splits, "*", list(splits.columns), "splits.csv")
    assert table.count("\n") == len(splits) + 1 and table in (BOARD / "board.md").read_text(encoding="utf-8")


def _real_imu_copy(tmp_path: Path) -> Path:
    """The real-IMU README and its boards' CSVs, copied with their relative paths kept."""
    page = tmp_path / "experiments" / "real-imu" / "README.md"
    page.parent.mkdir(parents=True)
    shutil.copy(REAL_IMU, page)
    (tmp_path / "leaderboards" / "real-imu").mkdir(parents=True)
    for name in ("board.csv", "splits.csv", "cross_part_tally.csv"):
        shutil.copy(BOARD / name, tmp_path / "leaderboards" / "real-imu" / name)
    return page


def test_the_real_imu_page_follows_its_csvs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    page = _real_imu_copy(tmp_path)
    assert main(["--check", str(page)]) == 0
    csvs = tmp_path / "leaderboards" / "real-imu"
    # a regenerated board: gyro y's raw drift in the first split (a table cell) and the memoriser's
    # ratio to the best there (a number of the text) change
    splits = pd.read_csv(csvs / "splits.csv")
    row = (splits["record"] == "tofupilot-imu.gyro.y") & (splits["fit on → scored on"] == "0 → 1,2")
    assert row.sum() == 1
    splits.loc[row, "raw"] = 2.5
    splits.to_csv(csvs / "splits.csv", index=False)
    board = pd.read_csv(csvs / "board.csv")
    row = ((board["record"] == "tofupilot-imu.gyro.y") & (board["split"] == "0 → 1,2")
           & (board["method"] == "memoriser"))
    board.loc[row, "pooled_over_best"] = 12.0
    board.to_csv(csvs / "board.csv", index=False)
    assert main(["--check", str(page)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2, out
    assert "quotes '13.8', board.csv says '12'" in out[0]
    assert "the table of splits.csv (fit on → scored on=0 → 1,2) is stale" in out[1]
    assert "| tofupilot-imu.gyro.y | deg/s | 2.5 | model |" in out[1]
    before = page.read_text(encoding="utf-8")
    assert rewrite(page) == 2 and main(["--check", str(page)]) == 0
    after = page.read_text(encoding="utf-8")
    assert "| tofupilot-imu.gyro.y | deg/s | 2.5 | model |" in after
    assert "| tofupilot-imu.gyro.y | deg/s | 1.18 |" not in after
    # only the changed number and table row differ; a second rewrite changes nothing
    changed = [(a, b) for a, b in zip(before.splitlines(), after.splitlines(), strict=True) if a != b]
    assert len(changed) == 2 and rewrite(page) == 0


def _page(tmp_path: Path, text: str) -> Path:
    (tmp_path / "board.csv").write_text("rank,method,median_ug,ci95_ug,runs\n1,oracle,5.8164,5.26–6.14,30\n"
                                        "2,poly3,39.2,35–44,30\n")
    (tmp_path / "parts.csv").write_text("record,split,method,ratio\nx,a,bp,0.5\nx,b,bp,0.25\n")
    page = tmp_path / "page.md"
    page.write_text(text)
    return page


def test_a_stale_number_is_found_named_and_rewritten(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    page = _page(tmp_path, 'the limit [5.9](board.csv "oracle | median_ug") [23–36](board.csv "oracle | ci95_ug"),\n'
                           'n = [30](board.csv "poly3 | runs"), ratio [0.25](parts.csv "split=b & method=bp | ratio")\n')
    found = quotes(page)
    assert [q.stale for q in found] == [True, True, False, False]
    assert main(["--check", str(page)]) == 1
    out = capsys.readouterr().out
    assert "page.md:1: quotes '5.9', board.csv says '5.82' (oracle | median_ug)" in out
    assert rewrite(page) == 2
    assert page.read_text().startswith('the limit [5.82](board.csv "oracle | median_ug") [5.26–6.14](board.csv')
    assert main(["--check", str(page)]) == 0


def test_one_cell_of_two_boards_on_one_line_gets_each_board_s_value(tmp_path: Path) -> None:
    """A replay board and a next_run board quote the same row and column on one table line: each
    quote is rewritten from its own CSV, not both from whichever was read first."""
    page = _page(tmp_path, '| 1<!-- replay.csv "oracle | median_ug" --> | 1<!-- board.csv "oracle | median_ug" --> |\n')
    (tmp_path / "replay.csv").write_text("rank,method,median_ug\n1,oracle,44.1\n")
    assert rewrite(page) == 2
    assert page.read_text() == ('| 44.1<!-- replay.csv "oracle | median_ug" --> | '
                                '5.82<!-- board.csv "oracle | median_ug" --> |\n')


@pytest.mark.parametrize(("quote", "says"), [
    ('[1](nowhere.csv "oracle | median_ug")', "no such CSV"),
    ('[1](board.csv "oracle | mean_ug")', "no column 'mean_ug'"),
    ('[1](board.csv "lagpoly | median_ug")', "0 rows match 'lagpoly'"),
    ('[1](parts.csv "method=bp | ratio")', "2 rows match"),
])
def test_a_quote_of_nothing_is_one_line_naming_the_page_and_line(tmp_path: Path, quote: str, says: str,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    page = _page(tmp_path, f"text\nsee {quote}\n")
    with pytest.raises(QuoteError, match=says):
        quotes(page)
    assert main(["--check", str(page)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "page.md:2:" in err and says in err


def test_a_site_page_quotes_with_a_comment_and_is_rewritten_alike(tmp_path: Path) -> None:
    page = _page(tmp_path, 'limit 5.9<!-- board.csv "oracle | median_ug" --> and (8<!-- board.csv "poly3 | runs" -->),'
                           ' gain ×1<!-- board.csv "poly3 | median_ug" -->\n')
    assert [(q.text, q.value) for q in quotes(page)] == [("5.9", "5.82"), ("8", "30"), ("1", "39.2")]
    assert rewrite(page) == 3
    assert page.read_text() == ('limit 5.82<!-- board.csv "oracle | median_ug" --> and '
                                '(30<!-- board.csv "poly3 | runs" -->), gain ×39.2<!-- board.csv "poly3 | median_ug" -->\n')


def test_a_table_is_written_checked_and_rewritten(tmp_path: Path) -> None:
    page = _page(tmp_path, 'before\n<!-- table: board.csv "* | method, median_ug" -->\n<!-- /table -->\nafter\n'
                           '<!-- table: parts.csv "split=b | method, ratio" -->\n| old |\n<!-- /table -->\n')
    assert [t.stale for t in tables(page)] == [True, True]
    assert rewrite(page) == 2
    assert page.read_text() == ('before\n<!-- table: board.csv "* | method, median_ug" -->\n\n'
                                '| method | median_ug |\n|---|---|\n| oracle | 5.82 |\n| poly3 | 39.2 |\n\n'
                                '<!-- /table -->\nafter\n<!-- table: parts.csv "split=b | method, ratio" -->\n\n'
                                '| method | ratio |\n|---|---|\n| bp | 0.25 |\n\n<!-- /table -->\n')
    assert main(["--check", str(page)]) == 0 and rewrite(page) == 0


@pytest.mark.parametrize(("table", "says"), [
    ('<!-- table: board.csv "* | method, mean_ug" -->\n<!-- /table -->', "no column 'mean_ug'"),
    ('<!-- table: board.csv "method=lagpoly | method" -->\n<!-- /table -->', "no row matches 'method=lagpoly'"),
    ('<!-- table: board.csv "* | method" -->\n| method |', "no closing <!-- /table -->"),
    ('<!-- table: nowhere.csv "* | method" -->\n<!-- /table -->', "no such CSV"),
])
def test_a_table_of_nothing_is_one_line_naming_the_page_and_line(tmp_path: Path, table: str, says: str,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    page = _page(tmp_path, f"text\n{table}\n")
    with pytest.raises(QuoteError, match=says):
        tables(page)
    assert main(["--check", str(page)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "page.md:2:" in err and says in err
