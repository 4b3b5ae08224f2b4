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
    """The checks made before reading any run: the experiment names, the output folder, an
    existing store holding every experiment named; the store's resolved URI."""
    from tcbench.leaderboard.files import experiment_ids
    from tcbench.outputs import folder_problem
    from tcbench.tracking import store as tracking

    experiments = experiments_of(experiment)
    if problem := folder_problem(out):
        raise ConfigError(f"out={out}: {problem}")
    try:
        resolved = tracking.check_store(uri, create=False)
        experiment_ids(tracking.client(resolved), experiments)
    except tracking.StoreError as exc:
        raise ConfigError(str(exc)) from None
    except LookupError as exc:
        raise ConfigError(str(exc)) from None
    except Exception as exc:  # noqa: BLE001 - a store that cannot be read: one line, as every store problem
        raise ConfigError(f"tracking store {resolved} cannot be read ({tracking.first_line(exc)})") from None
    return resolved


def make_leaderboards(experiment: Any, sweep: str | None, out: str, uri: str | None,
                      ecdf: bool = False, overwrite: bool = False) -> list[Path]:
    """Write and print the boards of the runs in ``experiment`` (optionally of one ``sweep``)
    into ``out``; the files written. Every board is written to a temporary folder and moved into
    ``out`` at the end, files already there replaced only with ``overwrite`` (and said).
    ConfigError (one line) when there is nothing to rank or an output is refused."""
    from tcbench.leaderboard import calibration as cal_board
    from tcbench.leaderboard import compensation as comp_board
    from tcbench.leaderboard import optimisation as leaderboard
    from tcbench.staging import OutputRefusedError, refusal_line, replaced_line, staged_dir
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
        raise ConfigError(str(exc)) from None
    if runs.empty and comp.empty and cals.empty:
        where = f", sweep {sweep}" if sweep else ""
        raise ConfigError(f"no tcbench runs in experiment {', '.join(experiments)}{where}")
    source = f"MLflow experiment {', '.join(experiments)}" + (f", sweep {sweep}" if sweep else "")
    sections: list[tuple[str, list[Path]]] = []  # each board's text and files, printed once they are in place
    replaced: list[Path] = []
    try:
        with staged_dir(out, (), overwrite, replaced) as tmp:
            for board in leaderboard.boards(runs) if not runs.empty else []:
                paths = leaderboard.write(board, tmp, client, source)
                sections.append((f"\n## {board.task}  (target precision {board.target_precision:g})\n\n"
                                 + leaderboard.markdown_table(board.table), list(paths.values())))
            for cboard in comp_board.boards(comp, protocols()) if not comp.empty else []:
                paths = comp_board.write(cboard, tmp, source)
                sections.append((f"\n## {cboard.task}  (compensation)\n\n" + leaderboard.markdown_table(cboard.table),
                                 list(paths.values())))
            for calboard in cal_board.boards(cals) if not cals.empty else []:
                paths = cal_board.write(calboard, tmp, source)
                table = leaderboard.markdown_table(calboard.table) if not calboard.table.empty else "no finished calibration"
                sections.append((f"\n## {calboard.recording}  (calibration, content {calboard.data_hash})\n\n" + table,
                                 list(paths.values())))
            plots = None
            if ecdf and not runs.empty:
                from tcbench.leaderboard.ecdf import write_ecdf_plots

                plots = write_ecdf_plots(client, leaderboard.one_run_per_job(runs), tmp)
    except OutputRefusedError as exc:
        raise ConfigError(refusal_line(exc)) from None
    written: list[Path] = []
    for text, files in sections:
        final = [Path(out) / Path(p).relative_to(tmp) for p in files]
        print(text)
        print(f"\nwritten: {', '.join(str(p) for p in final)}")
        written += final
    if plots is not None:
        final = [Path(out) / Path(p).relative_to(tmp) for p in plots]
        print(f"\nECDF plots: {', '.join(map(str, final)) or 'none (no single-objective runs)'}")
        written += final
    if replaced:
        print(replaced_line(replaced))
    return written
