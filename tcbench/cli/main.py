"""``tcbench`` command line: the commands of :mod:`tcbench.commands.registry`, their usage and
their dispatch."""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import sys
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tcbench.cli.argv import (
    UserError,
    app_words,
    asks_info,
    command_words,
    configs_elsewhere,
    given,
    leaderboard_words,
    run_flags,
    shows_run_help,
)
from tcbench.commands.registry import SPECS, CommandSpec, load

if TYPE_CHECKING:
    from tcbench.cli.app import Plan


def _usage() -> str:
    """``tcbench --help``: every registered command with its summary."""
    width = max(len(name) for name in SPECS) + 2
    return "\n".join([
        "usage: tcbench <command> [args]", "", "commands:",
        *(f"  {name:{width}s}{spec.summary}" for name, spec in SPECS.items()), "",
        "Every command is a Hydra app: `tcbench <command> --help` (or -h) shows its parameters, their",
        "defaults, examples and where its output goes; `--cfg job` prints the config a command would run",
        "with, and runs nothing; -m sweeps.", ""])


USAGE = _usage()
# Hydra's own log lines (a sweep's launch, each job's line, its progress) go to stderr, never between
# the results a command prints on stdout (conf/hydra/hydra_logging/); the quickstart's go to its log
HYDRA_LOGGING = "tcbench_stderr"


def _fail(message: str, code: int = 2) -> int:
    print(f"tcbench: error: {message}", file=sys.stderr)
    return code


@contextlib.contextmanager
def _quiet_job_log() -> Iterator[None]:
    """The runner's own failure log line off: one job's command reports its error itself."""
    logger = logging.getLogger("tcbench.runner.job")
    disabled, logger.disabled = logger.disabled, True
    try:
        yield
    finally:
        logger.disabled = disabled


def _app_command(command: str, argv: list[str]) -> int:
    """A key=value command: a Hydra app on its primary config ``conf/<command>.yaml``, its command
    line read by :func:`tcbench.cli.argv.app_words`. One job runs here (no Hydra output folder);
    ``-m`` sweeps run through Hydra's launcher like ``tcbench run``'s, but those of a command whose
    spec has ``runs_here`` one after another here. Every job is checked before the first starts."""
    words = app_words(command, argv)
    if words.help:
        from tcbench.cli import help as cli_help

        print(cli_help.usage(command))
        return 0
    spec = SPECS[command]
    if words.sweeps and spec.runs_here:
        return _in_turn(command, list(words.overrides))
    if words.sweeps:
        checked = _run_sweep(["-m", *words.overrides], spec.config)
        assert checked is not None
        if not checked.tracking_enabled:
            return _failures_report(checked.jobs)
        return _sweep_report(checked.sweep_id, checked.experiment, checked.tracking_uri,
                             None if checked.resume else checked.jobs)
    c = _one_job(list(words.overrides), spec, words.cfg)
    if c is None:
        return 0
    if spec.runs_here:
        from tcbench.errors import ConfigError

        check, work = _runs_here(spec)
        try:
            check(c)
            return work(c)
        except ConfigError as exc:
            raise UserError(str(exc)) from None
    return _run_one(command, c)


def _one_job(args: list[str], spec: CommandSpec, cfg: str | None) -> dict[str, Any] | None:
    """The config of one job composed from the overrides ``args``, its input files checked to
    exist; with ``cfg`` (``--cfg job``) printed instead (None)."""
    from hydra import initialize_config_module

    from tcbench.cli.app import compose_job
    from tcbench.commands.inputs import check_inputs_exist
    from tcbench.config_dir import CONFIG_MODULE
    from tcbench.errors import ConfigError
    from tcbench.runner.schema import as_dict

    try:
        with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
            composed = compose_job(args, spec.config)
        if cfg is not None:
            from omegaconf import OmegaConf

            print(OmegaConf.to_yaml(composed), end="")
            return None
        c = as_dict(composed)  # one job: its work makes the checks once (run_job), no check ahead
        check_inputs_exist(c)  # but a missing input file is named before its readers are imported
    except ConfigError as exc:
        raise UserError(str(exc)) from None
    return c


def _run_one(command: str, c: dict[str, Any]) -> int:
    """One job of ``command`` run through the runner (:func:`tcbench.runner.job.run_job`): 0, or
    its user error as a :class:`UserError`, or 1 with its failure said."""
    from tcbench.runner.job import FAILURES, JobFailure, run_job

    c["tracking"]["sweep_id"] = c["tracking"].get("sweep_id") or uuid.uuid4().hex[:12]
    FAILURES.clear()
    with _quiet_job_log():
        outcome = run_job(c, record_user_errors=False)
    if isinstance(outcome, JobFailure):
        if outcome.user:
            raise UserError(outcome.error)
        return _fail(f"{command} failed: {outcome.error}", 1)
    return 0


def _prepare_store(uri: str | None, experiment: str) -> None:
    """The MLflow store and experiment made before any job runs (a store that cannot be made is
    one line, and leaves no half-made database)."""
    from tcbench.tracking import store as tracking

    try:
        tracking.check_store(uri, create=True)
        tracking.prepare_store(uri, experiment)
    except tracking.StoreError as exc:
        raise UserError(str(exc)) from None


def _run_sweep(args: list[str], config_name: str = "config") -> Plan | None:
    """Validate every job of the Hydra app ``config_name`` (``config``: ``tcbench run``), then run
    them through Hydra; the plan, or None if not checked."""
    from hydra.errors import HydraException
    from omegaconf.errors import OmegaConfBaseException

    from tcbench.cli.app import deferred_to_the_jobs, hydra_app, plan, sweep_dir, with_overrides
    from tcbench.errors import ConfigError
    from tcbench.runner.job import FAILURES

    FAILURES.clear()  # this sweep's failed jobs only (main() may run again in one process)

    info = asks_info(args)
    if not info and not any(a.startswith("tracking.sweep_id=") for a in args):
        args = with_overrides(args, [f"tracking.sweep_id={uuid.uuid4().hex[:12]}"])
    elsewhere = configs_elsewhere(args)
    if not elsewhere and not given(args, "hydra/hydra_logging"):  # Hydra's lines never between the results
        args = with_overrides(args, [f"hydra/hydra_logging={HYDRA_LOGGING}"])
    checked: Plan | None = None
    if elsewhere:
        from tcbench.cli.app import check_command_line_size

        try:  # counted from the overrides alone: Hydra would list every job first
            check_command_line_size(args)
        except ConfigError as exc:
            raise UserError(str(exc)) from None
        print("tcbench: configs from elsewhere: each job validates its own config", file=sys.stderr)
    elif not info:
        try:
            checked = plan(args, config_name)
        except ConfigError as exc:
            raise UserError(str(exc)) from None
        if checked.tracking_enabled:  # create the store and experiment once, before parallel jobs
            from tcbench.tracking import store as tracking

            _prepare_store(checked.tracking_uri, checked.experiment)
            try:
                dead = tracking.mark_dead_runs(checked.tracking_uri, checked.experiment,
                                               checked.sweep_id) if checked.resume else 0
            except tracking.StoreError as exc:
                raise UserError(str(exc)) from None
            if dead:
                print(f"tcbench: {dead} run{'s' * (dead != 1)} of sweep {checked.sweep_id} left RUNNING by a "
                      "process that is gone marked KILLED; their jobs run again", file=sys.stderr)
        n = checked.jobs
        print(f"tcbench: {n} job{'s' if n != 1 else ''} to run", file=sys.stderr)
        if (where := sweep_dir(checked.outs)) is not None and not given(args, "hydra.sweep.dir"):
            args = with_overrides(args, [f"hydra.sweep.dir={where}"])  # Hydra's record of the sweep under out=
        args = deferred_to_the_jobs(args, checked.swept)  # task.split=replay beside task=a,b: set in each job
    saved, full_error = sys.argv, os.environ.get("HYDRA_FULL_ERROR")
    sys.argv = ["tcbench", *args]
    os.environ["HYDRA_FULL_ERROR"] = "1"  # Hydra's errors reach us whole instead of as its traceback
    try:
        hydra_app(config_name)()
    except KeyboardInterrupt:
        if checked is not None and checked.tracking_enabled:
            _mark_interrupted(checked)
        raise
    except OSError as exc:  # a job folder or Hydra's own files cannot be written (a full disk)
        where = f" {exc.filename}" if exc.filename else ""
        raise UserError(f"cannot write{where} ({exc.strerror or exc}); nothing more was run") from None
    except (HydraException, OmegaConfBaseException, ValueError) as exc:  # usage: "Only one of --run, --cfg ..."
        raise UserError(str(exc).strip().splitlines()[0]) from None
    finally:
        sys.argv = saved
        if full_error is None:
            os.environ.pop("HYDRA_FULL_ERROR", None)
        else:
            os.environ["HYDRA_FULL_ERROR"] = full_error
    return checked


def _mark_interrupted(checked: Plan) -> None:
    """After Ctrl-C: every run of the sweep left RUNNING by this process or its ended workers is
    marked KILLED (a store that cannot be written is said in one line)."""
    from tcbench.tracking import store as tracking

    try:
        n = tracking.mark_dead_runs(checked.tracking_uri, checked.experiment, checked.sweep_id,
                                    frozenset({os.getpid()}), reason=tracking.INTERRUPTED)
    except Exception as exc:  # noqa: BLE001 - the store cannot be written or read: said, then the interrupt
        print(f"tcbench: error: {_first_line(str(exc))}", file=sys.stderr)
        return
    if n:
        print(f"tcbench: {n} run{'s' * (n != 1)} of sweep {checked.sweep_id} marked KILLED", file=sys.stderr)


def _sweep_report(sweep: str, experiment: str, uri: str | None, expected: int | None = None) -> int:
    """Print how the jobs of a sweep ended (the latest run of each job: a resumed sweep's re-run
    replaces the attempt it repeats); 1 if any job's latest run did not finish, when ``expected``
    is given if fewer jobs than planned left a run, or if the store could not be written (said
    in one line)."""
    from tcbench.leaderboard import optimisation as leaderboard
    from tcbench.tracking import store as tracking

    unwritable = None
    try:
        tracking.mark_dead_runs(uri, experiment, sweep, frozenset({os.getpid()}))
    except tracking.StoreError as exc:
        unwritable = str(exc)
    try:
        runs = leaderboard.sweep_runs(tracking.client(uri), [experiment], sweep)
    except Exception as exc:  # noqa: BLE001 - a store that cannot be read either
        unread = f"tracking store {tracking.tracking_uri(uri)} cannot be read ({tracking.first_line(exc)})"
        print(f"tcbench: error: {unwritable or unread}", file=sys.stderr)
        return 1
    latest = leaderboard.one_run_per_job(runs)
    failed = latest[latest["status"] != "FINISHED"]
    running = int((failed["status"] == "RUNNING").sum())
    repeated = len(runs) - len(latest)
    print(
        f"tcbench: {len(latest)} job{'s' if len(latest) != 1 else ''} recorded in {tracking.tracking_uri(uri)} "
        f"(experiment {experiment!r}, sweep {sweep}): {len(latest) - len(failed)} finished, "
        f"{len(failed)} failed" + (f" ({running} still RUNNING in another live process or on another host)"
                                   if running and not unwritable else "")
        + (f"; {repeated} earlier attempt{'s' * (repeated != 1)} replaced by a re-run" if repeated else ""),
    )
    for r in failed.itertuples():
        print(f"  {r.status} {r.method} on {r.task} seed {r.seed}: {_first_line(r.error_message)}")
    missing = (expected - len(latest)) if expected is not None else 0
    if missing > 0:
        from tcbench.runner.job import FAILURES

        print(f"  {missing} job{'s' if missing != 1 else ''} left no run in MLflow "
              f"(skipped by resume, or the tracking store failed: see the job logs)")
        for error in dict.fromkeys(_first_line(f.error) for f in FAILURES):
            print(f"  a job's error: {error}")
    if unwritable:
        print(f"tcbench: error: {unwritable}", file=sys.stderr)
    return 1 if len(failed) or missing > 0 or unwritable else 0


def _first_line(text: str) -> str:
    from tcbench.errors import error_line

    return error_line(text)


def _failures_report(jobs: int) -> int:
    """Untracked jobs: print the failures this process saw; 1 if any."""
    from tcbench.runner.job import FAILURES

    if not FAILURES:
        return 0
    print(f"tcbench: {len(FAILURES)} of {jobs} job{'s' * (jobs != 1)} failed (tracking off: nothing recorded)")
    for f in FAILURES:
        print(f"  FAILED {f.name}: {f.error}")
    return 1


def cmd_run(args: list[str]) -> int:
    """``tcbench run``: Hydra's own command line (:func:`tcbench.cli.argv.run_flags`), every job
    checked, then run through Hydra."""
    if shows_run_help(run_flags(args)):  # configs from elsewhere: Hydra's help
        from tcbench.cli import help as cli_help

        print(cli_help.run_usage())
        return 0
    from tcbench.runner.job import FAILURES

    checked = _run_sweep(args)
    if checked is None:
        return 1 if FAILURES else 0
    if not checked.tracking_enabled:
        return _failures_report(checked.jobs)
    expected = None if checked.resume else checked.jobs
    return _sweep_report(checked.sweep_id, checked.experiment, checked.tracking_uri, expected)


def _in_turn(command: str, args: list[str]) -> int:
    """A ``-m`` sweep of a command whose jobs run here: every job checked, then each run here in
    turn; the worst exit code."""
    from tcbench.cli.app import claim_outputs, expand
    from tcbench.errors import ConfigError

    spec = SPECS[command]
    check, work = _runs_here(spec)
    try:
        jobs = expand(["-m", *args], spec.config)
        written: dict[Path, int] = {}
        for i, (_, c) in enumerate(jobs):
            check(c)
            claim_outputs([Path(str(c["out"]))] if "out" in c else [], written, i)
    except ConfigError as exc:
        raise UserError(str(exc)) from None
    status = 0
    for i, (overrides, c) in enumerate(jobs):
        print(f"tcbench: job {i + 1}/{len(jobs)}: {' '.join(overrides) or '(defaults)'}", file=sys.stderr)
        try:
            status = max(status, work(c))
        except ConfigError as exc:
            raise UserError(f"job {i + 1}: {exc}") from None
    return status


def _runs_here(spec: CommandSpec) -> tuple[Callable[[dict[str, Any]], None], Callable[[dict[str, Any]], int]]:
    """The check and the work of a command whose jobs run in this process (the ``check`` and
    ``work`` of its spec's ``runs_here`` module), each taking a composed job config."""
    import importlib

    from tcbench.commands.schemas import as_schema

    assert spec.runs_here is not None
    module, schema = importlib.import_module(spec.runs_here), spec.schema_class()
    return (lambda c: module.check(as_schema(c, schema))), (lambda c: int(module.work(as_schema(c, schema))))


def cmd_leaderboard(argv: list[str]) -> int:
    """``tcbench leaderboard``: its key=value (``conf/leaderboard.yaml``), or the flags
    ``--experiment`` (repeatable), ``--sweep``, ``--tracking-uri`` and ``--ecdf`` (``--out``: as
    every command's, :data:`~tcbench.cli.flags.KEY_FLAGS`), read by
    :func:`tcbench.cli.argv.leaderboard_words`."""
    return _app_command("leaderboard", leaderboard_words(argv))


def _handler(spec: CommandSpec) -> Callable[[list[str]], int]:
    """What runs ``tcbench NAME ARGS...``: the spec's own argument parser, imported when called,
    else the key=value app on its primary config."""
    if spec.parser is None:
        return functools.partial(_app_command, spec.name)
    parser = spec.parser
    return lambda argv: int(load(parser)(argv))


COMMANDS: dict[str, Callable[[list[str]], int]] = {name: _handler(spec) for name, spec in SPECS.items()}


def main(argv: list[str] | None = None) -> int:
    try:
        code = _main(list(sys.argv[1:] if argv is None else argv))
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading: not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # so that the interpreter's last flush does not fail again
        return 0
    if code == INTERRUPTED and argv is None:  # the command itself, not a call from Python
        _exit_now(code)
    return code


INTERRUPTED = 130  # the exit code of a command ended by Ctrl-C


def _exit_now(code: int) -> None:
    """End the process at once after a Ctrl-C, its runs marked and its workers reaped: the
    interpreter's teardown (collecting every object of MLflow, Hydra, pandas) took seconds, and
    on a loaded machine a minute, after the user asked it to stop."""
    import logging

    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


def _main(argv: list[str]) -> int:
    argv = command_words(argv, COMMANDS)
    if not argv or argv[0] in {"-h", "--help", "help"}:
        print(USAGE)
        return 0 if argv else 2
    command, rest = argv[0], argv[1:]
    if command not in COMMANDS:
        from tcbench.errors import unknown_name

        return _fail(unknown_name("command", command, COMMANDS))
    try:
        return COMMANDS[command](rest)
    except UserError as exc:
        return _fail(str(exc))
    except SystemExit as exc:  # Hydra's --help, --cfg and --info end with sys.exit
        if exc.code is None or isinstance(exc.code, int):
            return exc.code or 0
        raise
    except KeyboardInterrupt:
        return _fail("interrupted", INTERRUPTED)

if __name__ == "__main__":
    sys.exit(main())
