"""The leaderboard pages (tcbench.leaderboard.pages) made from the committed boards: a page per
board whose table holds the CSV's rows, labels beside the raw keys, the references marked, verdicts
that agree with the CSV; ``tcbench pages``' one-line errors and that it writes nothing outside
out=; the MkDocs hook's navigation and its generated folder."""

from __future__ import annotations

import html as html_lib
import importlib.util
import math
import re
from pathlib import Path, PurePosixPath

import numpy as np
import pandas as pd
import pytest

from tcbench.cli import main
from tcbench.leaderboard import labels
from tcbench.leaderboard.pages import html, verdicts
from tcbench.leaderboard.pages.boards import compensation_boards, is_compensation_csv
from tcbench.leaderboard.pages.catalogue import FAMILIES, NOT_PAGED
from tcbench.leaderboard.pages.output import sync_files
from tcbench.leaderboard.pages.plots import reference_plot
from tcbench.leaderboard.pages.render import build_site
from tcbench.leaderboard.pages.summary import ranking

REPO = Path(__file__).resolve().parents[1]
BOARDS = REPO / "leaderboards"
ONE = "paper-ifa-bp/msra_zerobias-dev0"


@pytest.fixture(scope="module")
def site():  # type: ignore[no-untyped-def]
    return build_site(BOARDS)


def _pages(site) -> dict[str, str]:  # type: ignore[no-untyped-def]
    return {p.page_id: p.text for p in site.pages}


def _tables(text: str) -> dict[str, str]:
    """Each board table of a page by its id."""
    return dict(re.findall(r'<table class="tcb-table" id="([^"]+)">(.*?)</table>', text, flags=re.S))


def _body_rows(table: str) -> list[str]:
    body = table.split("<tbody>", 1)[1]
    return re.findall(r"<tr[^>]*>.*?</tr>", body, flags=re.S)


def _compensation_csvs() -> list[Path]:
    return sorted(p for f in FAMILIES.values() if f.kind == "compensation"
                  for p in (BOARDS / f.folder).glob("*.csv") if is_compensation_csv(p))


def test_every_committed_folder_has_pages_or_says_why_not() -> None:
    folders = {p.name for p in BOARDS.iterdir() if p.is_dir()}
    assert folders == set(FAMILIES) | set(NOT_PAGED)


def test_a_page_per_compensation_board_whose_table_holds_the_csv_rows(site) -> None:  # type: ignore[no-untyped-def]
    pages = _pages(site)
    csvs = _compensation_csvs()
    assert len(csvs) >= 18
    for csv in csvs:
        page_id = f"{csv.parent.name}/{csv.stem}"
        assert page_id in pages, page_id
        frame = pd.read_csv(csv)
        (table,) = _tables(pages[page_id]).values()
        rows = _body_rows(table)
        assert len(rows) == len(frame)
        methods = [html_lib.unescape(re.search(r"<td>(.*?)(?: <span|</td>)", r).group(1))  # type: ignore[union-attr]
                   for r in rows]
        assert methods == frame["method"].astype(str).tolist()
        header = table.split("<tbody>", 1)[0]
        assert re.findall(r"<code>(.*?)</code>", header) == list(frame.columns)
        assert PurePosixPath(f"{page_id}.md") in site.files and PurePosixPath(f"{page_id}.limits.svg") in site.files


def test_every_table_of_every_page_has_as_many_rows_as_its_csv(site) -> None:  # type: ignore[no-untyped-def]
    pages = _pages(site)
    expected = {"bbob": {"board-bbob-solved": BOARDS / "bbob/solved.csv",
                         "board-bbob-functions": BOARDS / "bbob/per_function.csv"},
                "real-imu": {"board-real-imu": BOARDS / "real-imu/board.csv"},
                "accel-chamber/devices": {"board-devices": BOARDS / "accel-chamber/devices.csv"},
                "paper-ifa-bp/claims": {"board-claims": BOARDS / "paper-ifa-bp/claims.csv"},
                "paper-movmd-tfpf/claims": {"board-claims": BOARDS / "paper-movmd-tfpf/claims.csv"},
                "optim-suite": {f"board-{p.stem}".replace(".", "-"): p for p in (BOARDS / "optim-suite").glob("*.csv")},
                "paper-fa-ifa": {f"board-{p.stem}".replace(".", "-"): p for p in (BOARDS / "paper-fa-ifa").glob("*.csv")}}
    for page_id, tables in expected.items():
        found = _tables(pages[page_id])
        for table_id, csv in tables.items():
            assert len(_body_rows(found[table_id])) == len(pd.read_csv(csv)), (page_id, table_id)


def test_metric_columns_carry_a_human_label_beside_the_raw_key(site) -> None:  # type: ignore[no-untyped-def]
    text = _pages(site)[ONE]
    assert labels.unlabelled_metrics() == []
    assert labels.column_label("median_zb0_ug") == "median zero-bias stability from power-on, µg"
    assert '<span class="tcb-label">median zero-bias stability from power-on, µg</span> <code>median_zb0_ug</code>' in text
    assert "- `median_zb0_ug`: median zero-bias stability from power-on, µg (`zb_zero_start_ug`)" in text
    for csv in _compensation_csvs():
        for column in pd.read_csv(csv, nrows=0).columns:
            assert labels.column_label(column) != column or column in {"rank", "method", "note"}, (csv.name, column)


def test_the_limits_and_the_memoriser_are_marked_reference_rows(site) -> None:  # type: ignore[no-untyped-def]
    checked = 0
    for page_id, text in _pages(site).items():
        if page_id.count("/") != 1 or not any(page_id == f"{c.parent.name}/{c.stem}" for c in _compensation_csvs()):
            continue
        (table,) = _tables(text).values()
        marked = {html_lib.unescape(re.search(r"<td>(.*?) <span", r).group(1)): re.search(r'data-ref="(\w+)"', r).group(1)  # type: ignore[union-attr]
                  for r in _body_rows(table) if "data-ref" in r}
        assert marked["oracle"] == "limit" and marked["oracle_thermometer"] == "limit", page_id
        assert marked["memoriser"] == "memoriser", page_id
        assert "## Methods against the limits" in text and "Split tier: " in text and '!!! abstract "Verdict"' in text
        checked += 1
    assert checked == len(_compensation_csvs())


def test_the_verdict_says_where_the_papers_method_loses() -> None:
    judged = 0
    for family in (f for f in FAMILIES.values() if f.kind == "compensation"):
        for board in compensation_boards(family, BOARDS):
            said = " ".join(verdicts.compensation_verdict(board))
            rows = board.table[~board.table["method"].isin(["oracle", "oracle_thermometer", "memoriser"])]
            medians = dict(zip(rows["method"], pd.to_numeric(rows[board.primary_column]), strict=True))
            for m in family.paper_methods:
                if m not in medians:
                    continue
                beaten = any(v < medians[m] for k, v in medians.items() if k != m)
                assert (f"The paper's {m} loses" in said) == beaten, (board.stem, m)
                assert (f"The paper's {m} ranks first" in said) == (not beaten), (board.stem, m)
                judged += 1
            if not any(m in medians for m in family.paper_methods):
                assert "were not run on this board" in said
    assert judged >= 10
    zero = next(b for b in compensation_boards(FAMILIES["paper-ifa-bp"], BOARDS) if b.stem == "msra_zerobias-dev0")
    said = " ".join(verdicts.compensation_verdict(zero))
    assert "The paper's IFA-BP-gd loses" in said and "not reproduced" in said


def test_a_gyro_board_states_the_claims_of_its_own_device_and_tier() -> None:
    table = pd.read_csv(BOARDS / "paper-movmd-tfpf/claims.csv")
    stated = 0
    for board in compensation_boards(FAMILIES["paper-movmd-tfpf"], BOARDS):
        said = verdicts.claims(board)
        mine = table[(table["task"] == board.task) & (table["tier"] == board.tier)].groupby("claim", sort=False)
        assert len(said) == len(mine), board.stem  # a sentence per claim judged on this device and tier, no other
        for sentence, (claim, rows) in zip(said, mine, strict=True):
            verdicts_said = set(rows["reproduced"].str.split(" ").str[0])
            verdict = {"yes": "**reproduced**", "no": "**not reproduced**"}.get(next(iter(verdicts_said)), "**undecided**")
            assert claim in sentence and all(f"[{ci}]" in sentence for ci in rows["ci95_gain"]), board.stem
            assert len(verdicts_said) > 1 or verdict in sentence, (board.stem, claim)
            stated += 1
    assert stated >= 12
    board = next(b for b in compensation_boards(FAMILIES["paper-movmd-tfpf"], BOARDS) if b.tier == "new_device")
    spans = table.assign(reproduced="undecided (interval spans ×102)")
    assert all("**undecided**: the interval spans" in s for s in verdicts._claims_csv(board, spans))
    mixed = table.assign(reproduced=(["no", "undecided (interval spans ×102)"] * len(table))[:len(table)])
    assert any("**not reproduced** (undecided in" in s for s in verdicts._claims_csv(board, pd.concat([mixed, table])))


def test_the_ranking_across_tasks_is_the_mean_of_each_boards_places() -> None:
    boards = [b for f in FAMILIES.values() if f.kind == "compensation" for b in compensation_boards(f, BOARDS)]
    table = ranking(boards).set_index("method")
    held = [b for b in boards if b.held_out]
    assert len(held) < len(boards)  # the replay tiers are left out
    for method in ("poly3", "IFA-BP-gd", "raw"):
        places = []
        for b in held:
            ranks = verdicts.method_ranks(b).set_index("method")
            if method in ranks.index:
                places.append(int(ranks.loc[method, "place"]))
        assert table.loc[method, "boards"] == len(places)
        assert table.loc[method, "mean_rank"] == pytest.approx(np.mean(places))
        assert table.loc[method, "wins"] == places.count(1)
    assert "oracle" not in table.index and "memoriser" not in table.index
    assert list(table["mean_rank"]) == sorted(table["mean_rank"])


def test_the_plot_is_the_same_bytes_every_time_with_the_references_as_lines() -> None:
    board = next(b for b in compensation_boards(FAMILIES["paper-ifa-bp"], BOARDS) if b.stem == "msra_zerobias-dev0")
    svg = reference_plot(board)
    assert svg == reference_plot(board)
    text = svg.decode()
    for line in ("oracle (physical limit)", "thermometer-limited oracle", "memoriser (no physics)",
                 "raw (no compensation)"):
        assert line in text
    assert "IFA-BP-gd" in text and len(svg) < 200_000


def test_a_cell_shows_failed_and_sorts_by_its_number() -> None:
    frame = pd.DataFrame({"method": ["a", "oracle", "b"], "median_zb0_ug": [2.5, 1.0, math.inf],
                          "ci95_zb0_ug": ["2.1–3", "0.9–1.1", "4–failed"], "runs": [3, 30, 3]})
    out = html.table(frame, "t", "caption", {"oracle": "limit"})
    assert '<td class="tcb-num" data-value="Infinity">failed</td>' in out
    assert '<td class="tcb-num" data-value="2.1">2.1–3</td>' in out  # an interval sorts by its low end
    assert 'data-ref="limit"' in out and out.count("<tr") == 4
    assert "\n\n" not in out  # one raw HTML block for Python-Markdown


def _run(*args: str) -> int:
    return main(["pages", f"leaderboards={BOARDS}", *args])


def test_the_command_writes_the_pages_into_out_and_nothing_beside(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "made" / "pages"
    assert _run(f"out={out}", f"boards=[{ONE}]") == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["made"]
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert "index.md" in written and f"{ONE}.md" in written and f"{ONE}.limits.svg" in written
    assert f"{ONE}.png" in written and not any(n.startswith("bbob") for n in written)
    assert f"({ONE}.md)" in (out / "index.md").read_text()
    assert _run(f"out={out}", f"boards=[{ONE}]") == 2  # again: refused, one line
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already exists" in err[0] and "overwrite=true" in err[0]
    assert _run(f"out={out}", f"boards=[{ONE}]", "overwrite=true") == 0
    assert "replaced" in capsys.readouterr().out


@pytest.mark.parametrize(("args", "words"), [
    ([], ["out=DIR is required"]),
    (["out={tmp}/file"], ["is not a folder"]),
    (["out={tmp}/p", "boards=[nope]"], ["boards: unknown 'nope'", "paper-ifa-bp", "FOLDER/STEM"]),
    (["out={tmp}/p", "boards=[paper-ifa-bp/msra_zerobias-dev7]"], ["unknown 'paper-ifa-bp/msra_zerobias-dev7'"]),
    ([f"out={BOARDS}/paper-ifa-bp"], ["inside leaderboards=", "choose another out="]),
    (["out={tmp}/p", "leaderboards={tmp}/none"], ["leaderboards=", "no such folder"]),
])
def test_a_bad_argument_is_one_line_and_writes_nothing(args: list[str], words: list[str], tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file").write_text("x")
    before = sorted(BOARDS.rglob("*"))
    assert main(["pages", f"leaderboards={BOARDS}", *[a.format(tmp=tmp_path) for a in args]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    assert sorted(BOARDS.rglob("*")) == before


def _hook():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("leaderboard_pages_hook", REPO / "docs" / "hooks" / "leaderboard_pages.py")
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_the_hook_puts_the_pages_tree_in_place_of_the_nav_entry(site) -> None:  # type: ignore[no-untyped-def]
    hook = _hook()
    tree = site.nav("leaderboards")
    nav = hook.with_pages([{"Home": "index.md"}, {"Leaderboards": "leaderboards/index.md"}, {"API": "api.md"}], tree)
    assert nav[0] == {"Home": "index.md"} and nav[2] == {"API": "api.md"} and nav[1] == {"Leaderboards": tree}
    assert tree[0] == {"Summary": "leaderboards/index.md"}
    paths = re.findall(r"'(leaderboards/[^']+\.md)'", repr(tree))
    assert sorted(paths) == sorted(f"leaderboards/{p.path}" for p in site.pages)
    assert hook.with_pages(None, tree) is None


def test_the_generated_folder_is_rewritten_only_where_it_changed(tmp_path: Path) -> None:
    files = {PurePosixPath("a.md"): b"a", PurePosixPath("sub/b.svg"): lambda: b"b"}
    assert sync_files(files, tmp_path) == (2, 0)
    stamp = (tmp_path / "a.md").stat().st_mtime_ns
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "gone.md").write_text("stale")
    assert sync_files(files, tmp_path) == (0, 1)
    assert (tmp_path / "a.md").stat().st_mtime_ns == stamp and not (tmp_path / "old").exists()
    assert sync_files({**files, PurePosixPath("a.md"): b"A"}, tmp_path) == (1, 0)
    assert (tmp_path / "a.md").read_bytes() == b"A"


def test_a_board_paired_by_draw_is_a_compensation_board(tmp_path: Path) -> None:
    """Boards over draws carry a ``draws`` column after ``runs``; the pages take them as the others."""
    from tcbench.leaderboard.pages.boards import is_compensation_csv

    paired, single, other = tmp_path / "p.csv", tmp_path / "s.csv", tmp_path / "o.csv"
    paired.write_text("rank,method,runs,draws,failed,median_drift_ug,x_oracle,x_thermo\n1,raw,30,30,0,5,9,3\n")
    single.write_text("rank,method,runs,failed,median_drift_ug,x_oracle,x_thermo\n1,raw,1,0,5,9,3\n")
    other.write_text("rank,method,runs,median_f\n1,fa,30,0.1\n")
    assert is_compensation_csv(paired) and is_compensation_csv(single) and not is_compensation_csv(other)
