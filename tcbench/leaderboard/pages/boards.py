"""The committed boards as the pages read them: every compensation board of a folder (its CSV,
the text of its markdown, its tier, its protocol and primary metric, its figures), read from
``leaderboards/`` alone (no MLflow store)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from tcbench.compensation.data import DEFAULT_TIER
from tcbench.compensation.scoring import METRIC_NAMES, PRIMARY
from tcbench.leaderboard.compensation import SHORT, SPLIT_LINES
from tcbench.leaderboard.pages.catalogue import Family

COMPENSATION_HEAD = ("rank", "method", "runs")  # how a compensation board's CSV starts (then draws, if paired, and failed)
TIER_HEADING = re.compile(r"^# Compensation leaderboard: (?P<task>.+?)(?: — split (?P<tier>.+))?$")


@dataclass(frozen=True)
class CompensationBoard:
    """One committed compensation board: ``<folder>/<stem>.csv`` and ``.md``."""

    family: Family
    folder: Path  # leaderboards/<family>/
    stem: str
    task: str
    tier: str
    protocol: str
    table: pd.DataFrame
    text: list[str]  # the paragraphs of its markdown before the table (its heading and tier line left out)
    images: list[Path]  # its committed figures: its own plot first

    @property
    def page_id(self) -> str:
        """``<folder>/<stem>``: how ``boards=`` names this board."""
        return f"{self.family.folder}/{self.stem}"

    @property
    def primary(self) -> str:
        """The metric the board ranks by (:data:`tcbench.compensation.scoring.PRIMARY`)."""
        return PRIMARY[self.protocol]

    @property
    def primary_column(self) -> str:
        """The CSV column of the primary metric's median."""
        return f"median_{SHORT[self.primary]}"

    @property
    def held_out(self) -> bool:
        """True when the tier tests on runs the training never saw (not a replay, not made before tiers)."""
        return self.tier not in ("replay", "before tiers")


def read_csv(path: Path) -> pd.DataFrame:
    """A committed CSV as written, every column as the board wrote it (``inf`` kept as a number)."""
    return pd.read_csv(path, keep_default_na=True)


def is_compensation_csv(path: Path) -> bool:
    """True when ``path`` is a compensation board's table (its columns start as the boards' do)."""
    with path.open(encoding="utf-8") as f:
        head = f.readline().strip().split(",")
    return tuple(head[:3]) == COMPENSATION_HEAD and "failed" in head and "x_thermo" in head


def protocol_of(table: pd.DataFrame) -> str:
    """The protocol whose metrics the table's median columns are (fulltemp, roomtemp, chamber, gyro)."""
    for protocol, metrics in METRIC_NAMES.items():
        if all(f"median_{SHORT[m]}" in table.columns for m in metrics):
            return protocol
    raise ValueError(f"no protocol has the metrics of columns {', '.join(map(str, table.columns))}")


def board_text(md: Path) -> tuple[str, str, list[str]]:
    """The task, the tier and the paragraphs before the table of a board's markdown."""
    lines = md.read_text(encoding="utf-8").splitlines()
    m = TIER_HEADING.match(lines[0]) if lines else None
    task, tier = (m["task"], m["tier"] or "") if m else ("", "")
    paragraphs = []
    for line in lines[1:]:
        if line.startswith("|"):
            break
        if line.strip() and line.strip() not in SPLIT_LINES.values():
            paragraphs.append(line.strip())
    return task, tier, paragraphs


def split_stem(stem: str) -> tuple[str, str]:
    """``task.tier`` of a board's file stem (the default tier is left out of it)."""
    for tier in SPLIT_LINES:
        if stem.endswith(f".{tier}"):
            return stem[: -len(tier) - 1], tier
    return stem, DEFAULT_TIER


def figures(family: Family, folder: Path, stem: str, task: str, tier: str) -> list[Path]:
    """The board's own plot, then the family's further figures of it (on the default tier only)."""
    own = [folder / f"{stem}.png"] if (folder / f"{stem}.png").is_file() else []
    if tier != DEFAULT_TIER:
        return own
    names = {"stem": stem, "task": task, "family_task": task.split("-dev")[0]}
    more: list[Path] = []
    for pattern in family.figures:
        more += sorted(p for p in folder.glob(pattern.format(**names)) if p.is_file() and p not in own + more)
    return own + more


def compensation_boards(family: Family, root: Path) -> list[CompensationBoard]:
    """Every compensation board of ``family`` under ``root`` (the leaderboards folder), in name order."""
    folder = root / family.folder
    out = []
    for csv in sorted(folder.glob("*.csv")):
        if not is_compensation_csv(csv):
            continue
        stem = csv.stem
        task, tier = split_stem(stem)
        md = csv.with_suffix(".md")
        heading_task, heading_tier, text = board_text(md) if md.is_file() else ("", "", [])
        tier = heading_tier or tier
        table = read_csv(csv)
        out.append(CompensationBoard(family, folder, stem, heading_task or task, tier, protocol_of(table), table, text,
                                     figures(family, folder, stem, task, tier)))
    return sorted(out, key=lambda b: _order(family, b))


def _order(family: Family, board: CompensationBoard) -> tuple[int, list[object], bool]:
    """Boards in the order of the family's tasks, devices in number order, the default tier first."""
    place = next((i for i, p in enumerate(family.tasks) if re.fullmatch(p, board.task)), len(family.tasks))
    natural = [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", board.task)]
    return place, natural, board.tier != DEFAULT_TIER


def interval(text: object) -> tuple[float, float]:
    """The two ends of a board's ``ci95_`` cell (``6.84–7.18``; "failed" is infinite; ``–``: none)."""
    parts = str(text).split("–")
    if len(parts) != 2 or not all(p.strip() for p in parts):
        return math.nan, math.nan

    def end(p: str) -> float:
        p = p.strip()
        return math.inf if p == "failed" else float(p)

    try:
        return end(parts[0]), end(parts[1])
    except ValueError:
        return math.nan, math.nan


def md_paragraphs(path: Path) -> list[str]:
    """The text of a committed markdown file before its first table (its heading left out)."""
    if not path.is_file():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").splitlines()[1:]:
        if line.startswith("|"):
            break
        if line.strip():
            out.append(line.strip())
    return out


def md_section(path: Path, heading: str, start: str = "") -> list[str]:
    """The paragraphs under ``heading`` (a whole heading line) of a committed markdown file, up to the
    next heading; with ``start``, only the paragraphs that begin with it."""
    if not path.is_file():
        return []
    lines = path.read_text(encoding="utf-8").splitlines()
    try:
        first = lines.index(heading) + 1
    except ValueError:
        return []
    out = []
    for line in lines[first:]:
        if line.startswith("#"):
            break
        if line.strip() and line.strip().startswith(start) and not line.startswith(("|", "![")):
            out.append(line.strip())
    return out
