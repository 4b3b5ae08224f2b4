"""The leaderboard job kind: ``tcbench leaderboard`` (:mod:`tcbench.leaderboard.make`). It reads
the store and writes board files; with ``tracking.enabled=true`` the files are also filed as the
artifacts of a run in the experiment ``tracking.experiment`` (``leaderboards``), so a sweep over
experiments or sweeps (``-m experiments=a,b``) keeps its boards in MLflow beside the runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tcbench.commands.schemas import LeaderboardConfig, as_schema
from tcbench.leaderboard.make import check_leaderboard, experiments_of, make_leaderboards
from tcbench.runner.kinds import JobKind, JobNames, announce


class LeaderboardKind(JobKind):
    opens_run_after_work = True  # nothing to rank leaves no run, as it leaves no file

    def config(self, c: dict[str, Any]) -> LeaderboardConfig:
        return as_schema(c, LeaderboardConfig)

    def check(self, c: dict[str, Any]) -> None:
        cfg = self.config(c)
        check_leaderboard(cfg.experiments, cfg.out, cfg.tracking.uri)

    def names(self, c: dict[str, Any]) -> JobNames:
        cfg = self.config(c)
        source = "+".join(experiments_of(cfg.experiments))
        return JobNames(f"leaderboard-{source}" + (f"-{cfg.sweep}" if cfg.sweep else ""), source, "leaderboard",
                        tags={"tcbench.board_sweep": str(cfg.sweep or "")})

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        return [Path(str(c.get("out")))]

    def execute(self, c: dict[str, Any]) -> list[Path]:
        cfg = self.config(c)
        return make_leaderboards(cfg.experiments, cfg.sweep, cfg.out, cfg.tracking.uri, cfg.ecdf, cfg.overwrite)

    def record(self, run: Any, outcome: list[Path], c: dict[str, Any], where: Path) -> list[Path]:
        announce(run, c)
        return [p for p in outcome if p.is_file()]

    def summary(self, outcome: list[Path], c: dict[str, Any]) -> str:
        return f"leaderboard of {c.get('experiments')}: {len(outcome)} files in {c.get('out')}"
