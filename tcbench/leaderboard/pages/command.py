"""``tcbench pages``: the leaderboard pages of the committed boards written into ``out=``. Its jobs
run in the command line's process (:attr:`~tcbench.commands.registry.CommandSpec.runs_here`); the
config is :class:`tcbench.commands.schemas.PagesConfig` (``out``, ``leaderboards``, ``boards``,
``overwrite``). Every argument is checked before anything is written, and nothing is written
outside ``out=``: no temporary folder beside it, no store."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from tcbench.errors import ConfigError, meant
from tcbench.leaderboard.pages.catalogue import FAMILIES
from tcbench.leaderboard.pages.render import Site, UnknownBoardError, build_site, known


def _leaderboards(cfg: Any) -> Path:
    """The folder of committed boards, checked."""
    root = Path(str(cfg.leaderboards))
    if not root.is_dir():
        raise ConfigError(f"leaderboards={cfg.leaderboards}: no such folder (the repository's leaderboards/: run "
                          "from the repository's root or give leaderboards=PATH)")
    if not any((root / folder).is_dir() for folder in FAMILIES):
        raise ConfigError(f"leaderboards={cfg.leaderboards}: holds none of the board folders "
                          f"({', '.join(FAMILIES)})")
    return root


def _out(cfg: Any, root: Path) -> Path:
    """The output folder, checked: given, usable, not inside the committed boards."""
    from tcbench.outputs import folder_problem

    if not str(cfg.out or "").strip():
        raise ConfigError("out=DIR is required: the folder the pages are written into")
    out = Path(str(cfg.out))
    if problem := folder_problem(out):
        raise ConfigError(f"out={cfg.out}: {problem}")
    boards, target = os.path.realpath(root), os.path.realpath(out)
    if target == boards or target.startswith(boards + os.sep):
        raise ConfigError(f"out={cfg.out}: inside leaderboards={cfg.leaderboards}, the committed boards the pages "
                          "are made from; choose another out=")
    return out


_MADE: dict[tuple[str, tuple[str, ...]], Site] = {}  # the last site made: a job's check and work make it once


def _site(cfg: Any, root: Path) -> Site:
    """The pages of the boards asked for; one line naming an unknown board."""
    select = [str(b) for b in (cfg.boards or [])]
    key = (os.path.realpath(root), tuple(select))
    if key in _MADE:
        return _MADE[key]
    try:
        site = build_site(root, select)
        _MADE.clear()
        _MADE[key] = site
        return site
    except UnknownBoardError as exc:
        names = known(root)
        folders = [n for n in names if "/" not in n]
        raise ConfigError(f"boards: unknown {exc.args[0]!r}; known: {', '.join(folders)} (a folder), or one board "
                          f"as FOLDER/STEM, e.g. {next((n for n in names if '/' in n), 'paper-ifa-bp/claims')}"
                          + meant(exc.args[0], names)) from None
    except (OSError, ValueError, KeyError) as exc:
        raise ConfigError(f"leaderboards={cfg.leaderboards}: a committed board cannot be read ({exc})") from None


def check(cfg: Any) -> None:
    """Every argument of ``tcbench pages`` before anything is written: the boards' folder, the
    names in ``boards=``, ``out=`` and the files already there (replaced only with overwrite=true)."""
    root = _leaderboards(cfg)
    out = _out(cfg, root)
    site = _site(cfg, root)
    _free(cfg, out, site)


def _free(cfg: Any, out: Path, site: Site) -> list[Path]:
    """The existing files the pages would replace; one line when not allowed."""
    from tcbench.staging import OutputRefusedError, check_targets, refusal_line

    try:
        return check_targets(out, sorted((rel, False) for rel in site.files), bool(cfg.overwrite))
    except OutputRefusedError as exc:
        raise ConfigError(refusal_line(exc)) from None


def work(cfg: Any) -> int:
    """Write the pages into ``out=``; exit code 0."""
    from tcbench.leaderboard.pages.output import write_files
    from tcbench.outputs import write_problem
    from tcbench.staging import replaced_line

    root = _leaderboards(cfg)
    out = _out(cfg, root)
    site = _site(cfg, root)
    replaced = _free(cfg, out, site)
    try:
        written = write_files(site.files, out)
    except OSError as exc:
        raise ConfigError(f"out={cfg.out}: cannot write the pages ({write_problem(exc)})") from None
    if replaced:
        print(replaced_line(replaced))
    pages = len(site.pages)
    print(f"tcbench: wrote {pages} page{'s' * (pages != 1)} and {len(written) - pages} figures into {out} "
          f"(summary: {out / 'index.md'}); tables sort and filter in the site (docs/javascripts/boards.js)")
    return 0
