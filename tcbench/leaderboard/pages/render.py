"""The board pages, made from the committed files under ``leaderboards/`` alone: one page per
compensation board (its tier, its verdict, its table with the references marked, a plot of the
methods against the limits, its own figures), a page per optimisation folder (its ECDFs and
tables), the real-IMU board, and a summary that ranks the methods across the compensation tasks.
:func:`build_site` returns every file as bytes, a committed file to copy, or a plot made when
written, under the paths they take in the output folder (or ``docs/leaderboards/``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

import pandas as pd

from tcbench.leaderboard.compensation import SPLIT_LINES
from tcbench.leaderboard.labels import METRICS
from tcbench.leaderboard.pages import html, verdicts
from tcbench.leaderboard.pages.boards import (
    CompensationBoard,
    compensation_boards,
    md_paragraphs,
    md_section,
    read_csv,
)
from tcbench.leaderboard.pages.catalogue import (
    BASELINES,
    FAMILIES,
    NOT_PAGED,
    REFERENCES,
    Family,
    readme_url,
)
from tcbench.leaderboard.pages.plots import reference_plot
from tcbench.leaderboard.pages.summary import ranking

Content = bytes | Path | Callable[[], bytes]  # a file's bytes, a committed file copied, or a plot made when written
SUMMARY = "index.md"
WIDE = ["---", "hide:", "  - toc", "---", ""]  # front matter: no table of contents beside a wide table


class UnknownBoardError(LookupError):
    """A board asked for by name that the committed folders do not hold."""


@dataclass
class Page:
    """One page: where it goes, how the navigation names it, its markdown."""

    page_id: str  # how boards= names it: a folder, or <folder>/<stem>
    path: PurePosixPath  # relative to the output folder
    nav: str
    family: str  # its folder ("" for the summary)
    text: str = ""
    files: dict[PurePosixPath, Content] = field(default_factory=dict)  # the figures and plots it shows


@dataclass
class Site:
    """Every page and every file the pages need, by path relative to the output folder."""

    pages: list[Page] = field(default_factory=list)
    files: dict[PurePosixPath, Content] = field(default_factory=dict)

    def nav(self, prefix: str = "leaderboards") -> list[object]:
        """The pages as MkDocs navigation entries (paths under ``prefix`` in the docs folder): the
        summary first, then a section per study in the catalogue's order."""
        entries: list[object] = []
        sections: dict[str, list[object]] = {}
        for page in self.pages:
            item = {page.nav: f"{prefix}/{page.path}"}
            if page.family:
                sections.setdefault(page.family, []).append(item)
            else:
                entries.append(item)
        for folder, items in sections.items():
            entries.append({FAMILIES[folder].nav: items} if len(items) > 1 else {FAMILIES[folder].nav: list(items[0].values())[0]})  # type: ignore[union-attr]
        return entries


def _roles(family: Family) -> dict[str, str]:
    """How the rows of a compensation board are marked, by method."""
    roles = {"oracle": "limit", "oracle_thermometer": "limit", "memoriser": "memoriser", "raw": "baseline"}
    return {**roles, **{m: "paper" for m in family.paper_methods}}


def _admonition(kind: str, title: str, lines: list[str]) -> list[str]:
    """A Material admonition: each line a paragraph inside it."""
    out = [f'!!! {kind} "{title}"', ""]
    for i, line in enumerate(lines):
        out += ([""] if i else []) + [f"    {line}"]
    return out + [""]


def _head(family: Family, subtitle: str = "") -> list[str]:
    """The title naming the paper and the sensor, the citation and the study's README."""
    lines = [f"# {family.title}", ""]
    if subtitle:
        lines += [subtitle, ""]
    if family.paper:
        lines += [f"**Paper:** {family.paper}.", ""]
    lines += [f"**Study:** [{family.readme}]({readme_url(family.readme)}) (how it was run, what it found).", ""]
    return lines


def _image(path: PurePosixPath, page: PurePosixPath, alt: str) -> str:
    rel = path.relative_to(page.parent) if page.parent != PurePosixPath(".") else path
    return f"![{alt}]({rel})"


def _copied(files: dict[PurePosixPath, Content], root: Path, family: Family, images: list[Path]) -> list[PurePosixPath]:
    """The committed figures as files of a page (same paths under the family's folder)."""
    out = []
    for image in images:
        rel = PurePosixPath(family.folder) / PurePosixPath(image.relative_to(root / family.folder).as_posix())
        files[rel] = image
        out.append(rel)
    return out


def _tier_box(tier: str) -> list[str]:
    text = SPLIT_LINES.get(tier, f"**Split {tier}.**")
    body = text.split(":** ", 1)[1] if ":** " in text else text
    return _admonition("info", f"Split tier: {tier}", [body[:1].upper() + body[1:]])


def compensation_page(root: Path, board: CompensationBoard) -> Page:
    """The page of one compensation board."""
    family = board.family
    path = PurePosixPath(family.folder) / f"{board.stem}.md"
    plot = PurePosixPath(family.folder) / f"{board.stem}.limits.svg"
    files: dict[PurePosixPath, Content] = {plot: lambda board=board: reference_plot(board)}
    images = _copied(files, root, family, board.images)
    primary = board.primary
    label = METRICS[primary]
    table_id = f"board-{board.stem}".replace(".", "-").replace("=", "-")
    lines = [*WIDE, *_head(family, f"**Board:** {family.task_line(board.task)} — `{board.stem}`, split **{board.tier}**.")]
    lines += _tier_box(board.tier)
    lines += _admonition("abstract", "Verdict", verdicts.compensation_verdict(board))
    marked = "; ".join(f"{name}, {short} ({full})" for name, (short, full) in {**REFERENCES, **BASELINES}.items())
    lines += [f"**Primary metric:** {label} (`{primary}`); the rows are ordered by its median over restarts. "
              f"Marked rows: {marked}; and the paper's methods. Click a header to sort; type to filter the rows.", "",
              html.table(board.table, table_id, f"{board.stem}: every method, split {board.tier}", _roles(family)), "",
              "## Methods against the limits", "",
              _image(plot, path, f"{board.stem}: median {primary} per method with the limits, the memoriser and raw"),
              ""]
    if images:
        lines += ["## The board's figures", ""]
        lines += [_image(p, path, p.name) + "\n" for p in images]
    lines += ["## How to read this board", "", *[f"{p}\n" for p in board.text],
              "??? note \"Columns\"", "", *[f"    {c}" for c in html.column_legend(board.table)], "",
              f"Made from the committed `leaderboards/{family.folder}/{board.stem}.csv` and `.md`.", ""]
    return Page(board.page_id, path, f"{family.task_line(board.task, short=True)} · {board.tier}", family.folder,
                "\n".join(lines), files)


def devices_page(root: Path, family: Family) -> Page | None:
    """The chamber study's page across devices (``devices.csv``), when committed."""
    folder = root / family.folder
    if not (folder / "devices.csv").is_file():
        return None
    table = read_csv(folder / "devices.csv")
    path = PurePosixPath(family.folder) / "devices.md"
    files: dict[PurePosixPath, Content] = {}
    lines = WIDE + _head(family, "**Across devices:** every method's median drift over the thermometer-limited oracle's, "
                          "per simulated device (split next_run).")
    lines += _admonition("abstract", "Verdict", verdicts.devices_verdict(table))
    lines += [*[f"{p}\n" for p in md_paragraphs(folder / "devices.md")],
              html.table(table, "board-devices", "every device", key="device"), ""]
    lines += [_image(p, path, p.name) + "\n" for p in _copied(files, root, family, sorted(folder.glob("devices.png")))]
    lines += ["??? note \"Columns\"", "", *[f"    {c}" for c in html.column_legend(table)], ""]
    return Page(f"{family.folder}/devices", path, "across devices", family.folder, "\n".join(lines), files)


def claims_page(root: Path, family: Family) -> Page | None:
    """The paper's claims per tier (``claims.csv``) and, for seed 000, its verdict against the training budget."""
    folder = root / family.folder
    if not (folder / "claims.csv").is_file():
        return None
    claims = read_csv(folder / "claims.csv")
    said = claims["reproduced"].astype(str)
    probe = said.str.startswith("yes on").any()  # seed 000's rows that reach a gain on the table only
    per_tier = [f"Tier {tier}: {int((said[claims['tier'] == tier] == 'yes').sum())} of "
                f"{int((claims['tier'] == tier).sum())} rows reproduced"
                + (f", {int(said[claims['tier'] == tier].str.startswith('yes on').sum())} on the table only (failing "
                   "the ±0.5 g probe)." if probe else ".") for tier in dict.fromkeys(claims["tier"])]
    path = PurePosixPath(family.folder) / "claims.md"
    how = ("worse of the two test datasets" if "worst-test gain" in claims else
           "the median over restarts of each restart's gain on its own draw, with its 95 % interval")
    lines = WIDE + _head(family, f"**The paper's claims, per tier:** gains against raw, {how}.")
    lines += _admonition("abstract", "Verdict", per_tier)
    caption = "every claim, tier and selection" if "selection" in claims else "every claim, device and tier"
    lines += [html.table(claims, "board-claims", caption, key="tier"), ""]
    if (folder / "gd_budget.csv").is_file():
        budget = read_csv(folder / "gd_budget.csv")
        lines += ["## Table 2's verdict against the gradient-descent budget", "",
                  *[f"{p}\n" for p in md_section(folder / "tables.md",
                                                 "## Table 2's verdict as a function of the training budget "
                                                 "(IFA-BP-gd-300000ep)")],
                  html.table(budget, "board-gd-budget", "gains per number of epochs", key="epochs"), ""]
    return Page(f"{family.folder}/claims", path, "the paper's claims", family.folder, "\n".join(lines))


def optimisation_page(root: Path, family: Family) -> Page:
    """One page for a folder of optimisation boards: the ECDFs, a line per board, every table."""
    folder = root / family.folder
    path = PurePosixPath(family.folder) / "index.md"
    files: dict[PurePosixPath, Content] = {}
    tables = [(csv.stem, read_csv(csv)) for csv in sorted(folder.glob("*.csv"))]
    tables = [(stem, t) for stem, t in tables if {"rank", "method", "success_rate", "median_error"} <= set(t.columns)]
    firsts = [(stem, t) for stem, t in tables if t["method"].isin(family.paper_methods).any()]
    won = [stem for stem, t in firsts if int(t.loc[t["method"].isin(family.paper_methods), "rank"].min()) == 1]
    top = pd.Series([str(t["method"].iloc[0]) for _, t in tables]).value_counts() if tables else pd.Series(dtype=int)
    summary = [f"The papers' optimisers ({', '.join(m for m in family.paper_methods)}) rank first on {len(won)} of "
               f"{len(firsts)} boards they ran on{': ' + ', '.join(won) if won else ''}. Rank 1 per board: "
               + ", ".join(f"{m} {k}" for m, k in top.items()) + "."]
    lines = _head(family)
    lines += _admonition("abstract", "Verdict", summary)
    ecdfs = _copied(files, root, family, sorted(folder.glob("ecdf*.png")))
    if ecdfs:
        lines += ["## Runtime ECDFs", "", *[_image(p, path, p.name) + "\n" for p in ecdfs]]
    glance = pd.DataFrame([_glance(stem, t, family) for stem, t in tables])
    lines += ["## Every board at a glance", "",
              html.table(glance, f"board-{family.folder}-glance", "rank 1 and the papers' best per board",
                         key="board"), ""]
    for stem, t in tables:
        lines += [f"## {stem}", "", verdicts.optimisation_verdict(t, family.paper_methods), "",
                  *[f"{p}\n" for p in md_paragraphs(folder / f"{stem}.md")],
                  html.table(t, f"board-{stem}".replace(".", "-"), stem,
                             {m: "paper" for m in family.paper_methods}), ""]
        figures = sorted(folder.glob(f"{stem}_*.png"))
        lines += [_image(p, path, p.name) + "\n" for p in _copied(files, root, family, figures)]
    if tables:
        lines += ["??? note \"Columns\"", "", *[f"    {c}" for c in html.column_legend(max((t for _, t in tables),
                                                                                       key=lambda t: t.shape[1]))], ""]
    return Page(family.folder, path, family.nav, family.folder, "\n".join(lines), files)


def _glance(stem: str, table: pd.DataFrame, family: Family) -> dict[str, object]:
    theirs = table[table["method"].isin(family.paper_methods)]
    return {"board": stem, "methods": len(table), "rank_1": str(table["method"].iloc[0]),
            "papers_best": str(theirs["method"].iloc[0]) if len(theirs) else "",
            "papers_rank": int(theirs["rank"].iloc[0]) if len(theirs) else math.nan,
            "papers_success_rate": float(theirs["success_rate"].iloc[0]) if len(theirs) else math.nan,
            "papers_median_error": float(theirs["median_error"].iloc[0]) if len(theirs) else math.nan,
            "rank_1_median_error": float(table["median_error"].iloc[0])}


GLANCE_LABELS = {"methods": "methods on the board", "rank_1": "rank 1", "papers_best": "the papers' best optimiser",
                 "papers_rank": "its rank", "papers_success_rate": "its success rate",
                 "papers_median_error": "its median error", "rank_1_median_error": "rank 1's median error"}


def bbob_page(root: Path, family: Family) -> Page:
    """The BBOB page: where the papers' methods stand, the functions solved, the ECDFs, every function."""
    folder = root / family.folder
    path = PurePosixPath(family.folder) / "index.md"
    files: dict[PurePosixPath, Content] = {}
    lines = _head(family)
    lines += _admonition("abstract", "Verdict", verdicts.bbob_verdict(folder) or ["(the board's README says none)"])
    roles = {m: "paper" for m in family.paper_methods}
    if (folder / "solved.csv").is_file():
        lines += ["## Functions solved", "", *[f"{p}\n" for p in md_section(folder / "README.md", "## Functions solved")],
                  html.table(read_csv(folder / "solved.csv"), "board-bbob-solved", "functions solved per method",
                             roles), ""]
    ecdfs = _copied(files, root, family, sorted(folder.glob("ecdf*.png")))
    if ecdfs:
        lines += ["## Runtime ECDFs", "", *[_image(p, path, p.name) + "\n" for p in ecdfs]]
    if (folder / "per_function.csv").is_file():
        lines += ["## Every method on every function", "",
                  "One row per method, dimension and function (filter e.g. `ifa`, or a function number).", "",
                  html.table(read_csv(folder / "per_function.csv"), "board-bbob-functions",
                             "every method, dimension and function", roles), ""]
    return Page(family.folder, path, family.nav, family.folder, "\n".join(lines), files)


def calibration_page(root: Path, family: Family) -> Page | None:
    """The real-IMU board: every offset model on every record and split, held out."""
    folder = root / family.folder
    if not (folder / "board.csv").is_file():
        return None
    table = read_csv(folder / "board.csv")
    path = PurePosixPath(family.folder) / "index.md"
    files: dict[PurePosixPath, Content] = {}
    lines = WIDE + _head(family)
    lines += _admonition("abstract", "Verdict", verdicts.calibration_verdict(table, family.paper_methods))
    lines += [*[f"{p}\n" for p in md_paragraphs(folder / "board.md")],
              html.table(table, "board-real-imu", "every record, split and method",
                         {"raw": "baseline", **{m: "paper" for m in family.paper_methods}}), ""]
    lines += [_image(p, path, p.name) + "\n" for p in _copied(files, root, family, sorted(folder.glob("board.png")))]
    lines += ["??? note \"Columns\"", "", *[f"    {c}" for c in html.column_legend(table)], ""]
    return Page(family.folder, path, family.nav, family.folder, "\n".join(lines), files)


def summary_page(pages: list[Page], boards: list[CompensationBoard]) -> Page:
    """The summary: methods ranked across the compensation tasks, every board, the other pages."""
    path = PurePosixPath(SUMMARY)
    lines = [*WIDE, "# Leaderboards", "",
             "Every page here is made from the committed files under `leaderboards/` when the site is built "
             "(`tcbench pages out=DIR` writes the same pages), so the numbers are the boards' own. Each board "
             "ranks the methods of one task on its primary metric, over restarts, on one split tier; the limits "
             "(the oracle, the thermometer-limited oracle) and the memoriser are references beside them.", ""]
    held = [b for b in boards if b.held_out]
    if held:
        table = ranking(boards)
        labels = {b.page_id: f"place on {b.family.task_line(b.task, short=True)}" for b in held}
        lines += ["## Methods across the compensation tasks", "",
                  f"Each method's place on every held-out board it ran on ({len(held)} boards: the replay tiers "
                  "are diagnostics, left out), by that board's primary metric, with the limits and the memoriser "
                  "left out; its mean place over the boards counted, its first places, and its median ratio to the "
                  "thermometer-limited oracle, which every board shares. The boards hold different methods (the "
                  "chamber's devices 1–9 ran the baselines only), so compare mean places of methods counted on "
                  "the same boards.", "",
                  html.table(table, "board-ranking", "methods across the held-out compensation boards",
                             {m: "paper" for b in boards for m in b.family.paper_methods}, labels=labels), ""]
    if boards:
        rows = []
        for b in boards:
            ranks = verdicts.method_ranks(b)
            mine = ranks[ranks["method"].isin(b.family.paper_methods)]
            best = ranks.iloc[0] if len(ranks) else None
            rows.append({"board": b.page_id, "study": b.family.nav, "tier": b.tier, "methods": len(ranks),
                         "primary": b.primary, "best_method": str(best["method"]) if best is not None else "",
                         "best_x_thermo_board": float(best["x_thermo"]) if best is not None else math.nan,
                         "paper_place": float(mine["place"].min()) if len(mine) else math.nan})
        lines += ["## Every compensation board", "",
                  html.table(pd.DataFrame(rows), "board-every", "every compensation board", key="board",
                             labels={"methods": "methods (no limit, no memoriser)"}), ""]
    lines += ["## The pages", ""]
    for page in pages:
        lines.append(f"- [{FAMILIES[page.family].nav}: {page.nav}]({page.path})" if page.family != page.page_id
                     else f"- [{page.nav}]({page.path})")
    lines += ["", "Not here, being no ranking of methods: "
              + "; ".join(f"`leaderboards/{k}/` ({v})" for k, v in NOT_PAGED.items()) + ".", ""]
    return Page("summary", path, "Summary", "", "\n".join(lines))


def family_pages(root: Path, family: Family) -> tuple[list[Page], list[CompensationBoard]]:
    """The pages of one folder, and its compensation boards: by its kind (:data:`KIND_PAGES`)."""
    return KIND_PAGES[family.kind](root, family)


def _compensation_pages(root: Path, family: Family) -> tuple[list[Page], list[CompensationBoard]]:
    """A page per compensation board, the devices' and the claims' pages; and the boards."""
    boards = compensation_boards(family, root)
    pages = [compensation_page(root, b) for b in boards]
    pages += [p for p in (devices_page(root, family), claims_page(root, family)) if p is not None]
    return pages, boards


def _calibration_pages(root: Path, family: Family) -> tuple[list[Page], list[CompensationBoard]]:
    page = calibration_page(root, family)
    return ([page] if page else []), []


# The pages of a folder of each kind (Family.kind), and its compensation boards
KIND_PAGES: dict[str, Callable[[Path, Family], tuple[list[Page], list[CompensationBoard]]]] = {
    "compensation": _compensation_pages,
    "optimisation": lambda root, family: ([optimisation_page(root, family)], []),
    "bbob": lambda root, family: ([bbob_page(root, family)], []),
    "calibration": _calibration_pages,
}


def known(root: Path) -> list[str]:
    """Every name ``boards=`` takes: the folders with a page, then ``<folder>/<stem>`` of each page."""
    folders = [f for f in FAMILIES if (root / f).is_dir()]
    ids = [p.page_id for f in folders for p in family_pages(root, FAMILIES[f])[0] if p.page_id != f]
    return folders + ids


def build_site(root: Path, select: list[str] | None = None) -> Site:
    """Every page of the committed boards under ``root`` (``leaderboards/``), or of those named in
    ``select`` (folders, or ``<folder>/<stem>`` of one board), and the summary; an
    :class:`UnknownBoardError` naming the first name that is none of them."""
    wanted = set(select or [])
    pages: list[Page] = []
    chosen: list[CompensationBoard] = []
    found: set[str] = set()
    for folder, family in FAMILIES.items():
        if not (root / folder).is_dir() or (wanted and not any(w.split("/")[0] == folder for w in wanted)):
            continue  # every name of a folder's pages starts with the folder
        made, boards = family_pages(root, family)
        found |= {folder} | {p.page_id for p in made}
        keep = [p for p in made if not wanted or folder in wanted or p.page_id in wanted]
        pages += keep
        chosen += [b for b in boards if b.page_id in {p.page_id for p in keep}]
    if unknown := sorted(wanted - found):
        raise UnknownBoardError(unknown[0])
    site = Site([summary_page(pages, chosen), *pages])
    for page in site.pages:
        site.files.update(page.files)
        site.files[page.path] = page.text.encode("utf-8")
    return site
