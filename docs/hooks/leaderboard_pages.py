"""MkDocs hook: the leaderboard pages, made from the committed boards under ``leaderboards/`` every
time the site is built (``tcbench.leaderboard.pages``), so they cannot drift from the CSVs. They
are written into ``docs/leaderboards/`` (git-ignored; a file is rewritten only when it changes, so
``mkdocs serve`` settles), and the navigation entry ``Leaderboards`` of mkdocs.yml is replaced by
their tree: the summary, then a section per study."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

log = logging.getLogger("mkdocs.hooks.leaderboard_pages")

GENERATED = "leaderboards"  # docs/<GENERATED>/, made here, never committed
NAV_ENTRY = "Leaderboards"  # the entry of mkdocs.yml's nav that the pages' tree replaces


def on_config(config: Any) -> Any:
    """Write the pages into the docs folder and put their tree into the navigation."""
    from tcbench.leaderboard.pages.output import sync_files
    from tcbench.leaderboard.pages.render import build_site

    root = Path(config.config_file_path).parent
    site = build_site(root / "leaderboards")
    written, removed = sync_files(site.files, Path(config.docs_dir) / GENERATED)
    log.info(f"leaderboard pages: {len(site.pages)} pages, {written} files written, {removed} removed "
             f"in {Path(config.docs_dir) / GENERATED}")
    config.nav = with_pages(config.nav, site.nav(GENERATED))
    return config


def with_pages(nav: list[Any] | None, pages: list[Any]) -> list[Any] | None:
    """``nav`` with its ``Leaderboards`` entry holding the pages' tree (added last when it has
    none; None, MkDocs's own navigation of every page, stays None)."""
    if nav is None:
        return None
    out, placed = [], False
    for entry in nav:
        if isinstance(entry, dict) and NAV_ENTRY in entry:
            out.append({NAV_ENTRY: pages})
            placed = True
        else:
            out.append(entry)
    return out if placed else [*out, {NAV_ENTRY: pages}]
