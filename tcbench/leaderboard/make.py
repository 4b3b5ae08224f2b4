"""What ``tcbench leaderboard`` does: read the finished runs of some MLflow experiments, write
every board (optimisation, compensation and calibration; ``OUT/<task>.md/.csv`` and plots) and
print the tables. Reads the store, never writes to it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tcbench.errors import ConfigError


def experiments_of(experiment: Any) -> list[str]:
    """The ``experiments=`` value as a list of names: one name, or a list of them."""
    names = [experiment] if isinstance(experiment, str) else list(experiment or [])
    names = [str(n) for n in names]
    if not names or not all(n.strip() for n in names):
        raise ConfigError("experiments: name an MLflow experiment (experiments=NAME, or experiments=[a,b])")
    return names


def check_leaderboard(experiment: Any, out: str, uri: str | None) -> str:
    """The checks made before reading anything: the experiment names, the output folder and an
    existing store; the store's resolved URI."""
    from tcbench.outputs import folder_problem
    from tcbench.tracking import store as tracking

    experiments_of(experiment)
    if problem := folder_problem(out):
        raise ConfigError(f"out={out}: {problem}")
    try:
        return tracking.check_store(uri, create=False)
    except tracking.StoreError as exc:
        raise ConfigError(str(exc)) from None


def make_leaderboards(experiment: Any, sweep: str | None, out: str, uri: str | None,
                      ecdf: bool = False) -> list[Path]:
    """Write and print the boards of the runs in ``experiment`` (optionally of one ``sweep``)
    into ``out``; the files written. ConfigError (one line) when there is nothing to rank."""
    from tcbench.leaderboard import calibration as cal_board
    from tcbench.leaderboard import compensation as comp_board
    from tcbench.leaderboard import optimisation as leaderboard
    from tcbench.tasks.specs import protocols
    from tcbench.tracking import store as tracking

    experiments = experiments_of(experiment)
    resolved = check_leaderboard(experiments, out, uri)
    client = tracking.client(resolved)
    try:
        runs = leaderboard.load_runs(client, experiments, sweep)
        comp = comp_board.load_runs(client, experiments, sweep)
        cals = cal_board.load_runs(client, experiments, sweep)
    except LookupError as exc:
        raise ConfigError(f"{exc} in {resolved}") from None
    if runs.empty and comp.empty and cals.empty:
        where = f", sweep {sweep}" if sweep else ""
        raise ConfigError(f"no tcbench runs in experiment {', '.join(experiments)}{where}")
    source = f"MLflow experiment {', '.join(experiments)}" + (f", sweep {sweep}" if sweep else "")
    written: list[Path] = []
    for board in leaderboard.boards(runs) if not runs.empty else []:
        paths = leaderboard.write(board, Path(out), client, source)
        print(f"\n## {board.task}  (target precision {board.target_precision:g})\n")
        print(leaderboard.markdown_table(board.table))
        print(f"\nwritten: {', '.join(str(p) for p in paths.values())}")
        written += list(paths.values())
    for cboard in comp_board.boards(comp, protocols()) if not comp.empty else []:
        paths = comp_board.write(cboard, Path(out), source)
        print(f"\n## {cboard.task}  (compensation)\n")
        print(leaderboard.markdown_table(cboard.table))
        print(f"\nwritten: {', '.join(str(p) for p in paths.values())}")
        written += list(paths.values())
    for calboard in cal_board.boards(cals) if not cals.empty else []:
        paths = cal_board.write(calboard, Path(out), source)
        print(f"\n## {calboard.recording}  (calibration, content {calboard.data_hash})\n")
        print(leaderboard.markdown_table(calboard.table) if not calboard.table.empty else "no finished calibration")
        print(f"\nwritten: {', '.join(str(p) for p in paths.values())}")
        written += list(paths.values())
    if ecdf and not runs.empty:
        from tcbench.leaderboard.ecdf import write_ecdf_plots

        plots = write_ecdf_plots(client, leaderboard.one_run_per_job(runs), Path(out))
        print(f"\nECDF plots: {', '.join(map(str, plots)) or 'none (no single-objective runs)'}")
        written += list(plots)
    return [Path(p) for p in written]
