"""Numbers a page quotes from a board are links to the CSV cell that defines them
(:mod:`tcbench.leaderboard.quoted`): every page of the repository agrees with its boards, and a
stale number is found, named and rewritten."""

from __future__ import annotations

from pathlib import Path

import pytest

from tcbench.leaderboard.quoted import QuoteError, main, quotes, rewrite

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "experiments").glob("*/README.md")),
         *sorted(p for p in (ROOT / "docs").rglob("*.md") if "leaderboards" not in p.parts)]


def test_every_quoted_number_of_every_page_is_its_board_s() -> None:
    found = [q for page in PAGES for q in quotes(page)]
    assert any(q.page.name == "README.md" and "paper_ifa_bp" in str(q.page) for q in found)
    stale = [f"{q.page.relative_to(ROOT)}:{q.line}: {q.text} but {q.csv.name} says {q.value}" for q in found if q.stale]
    assert not stale, "\n".join(stale)


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
    page = _page(tmp_path, 'limit 5.9<!-- board.csv "oracle | median_ug" --> and (8<!-- board.csv "poly3 | runs" -->)\n')
    assert [(q.text, q.value) for q in quotes(page)] == [("5.9", "5.82"), ("8", "30")]
    assert rewrite(page) == 2
    assert page.read_text() == ('limit 5.82<!-- board.csv "oracle | median_ug" --> and '
                                '(30<!-- board.csv "poly3 | runs" -->)\n')
