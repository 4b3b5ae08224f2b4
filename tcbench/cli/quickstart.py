"""``tcbench quickstart``: the main job in about a minute.

1. Compensation: the paper's IFA-BP (seed 000 §3) on the simulated MSRA zero-bias task, a few
   trainings (``tcbench run -m experiment=quickstart``), beside raw, the memoriser, the polynomial
   (pooled and within runs), the lag-aware polynomial and the oracle (the physical limit) — every job through the normal runner, one MLflow run each —
   then a small leaderboard.
2. Diagnosis: a simulated MSRA recording with one effect hidden under the noise
   (:func:`~tcbench.datasets.concealed.concealed_recording`), diagnosed as ``tcbench diagnose``
   does; the report and plots are written and logged as an MLflow run.

Its parameters are :class:`tcbench.commands.schemas.QuickstartConfig` (``conf/quickstart.yaml``);
the test suite runs it with two short trainings. Run again, it replaces the files an earlier
quickstart wrote into ``out`` and says which (every file moved into place only when complete); a
link out of ``out`` is refused, as by every command.
"""

from __future__ import annotations

import io
import sys
import textwrap
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager, redirect_stdout
from pathlib import Path
from typing import Any

from tcbench.cli.app import hydra_string
from tcbench.commands.schemas import QuickstartConfig
from tcbench.diagnose.select.significance import ROBUST_WALD, SURROGATE
from tcbench.errors import ConfigError
from tcbench.papers import SEED_000
from tcbench.staging import REPLACED

HEADER = """\
tcbench: a benchmark for temperature compensation of MEMS inertial sensors. It simulates sensors
(a micromachined silicon resonant accelerometer, MSRA; a dual-mass MEMS gyroscope; an ordinary
MEMS accelerometer) in temperature chambers, compensates them (learners and their weight searches,
against the polynomial flight stacks ship and the physical limit), and diagnoses what a model or
simulator leaves out of a recording. Every job is a run in MLflow."""
NEXT_STEPS = """\
Next steps (the full experiments, from the repository root with the environment active; the paper's
studies compare with CMA-ES from the peers plugin: pip install -e plugins/tcbench-peers):
  bash experiments/paper_ifa_bp/run.sh     seed 000 Tables 1-2: 30 trainings per method on both MSRA tasks,
                                           with raw, poly, the oracle and the paper's tables
  tcbench run -m task=msra_fulltemp learner=bp optimiser=fa,ifa seed='range(30)'   the full-temperature task
  tcbench simulate sensor=msra out=rec     a simulated recording with every effect of the device; then
  tcbench diagnose recording=rec/msra-fulltemp-dev0-seed0.csv out=diagnosis   (tcbench import: your CSV)
  python experiments/diagnose-concealed/run.py --workers 2   every hidden effect and controls, 80 recordings
  tcbench run -m experiment=paper_fa_ifa   FA against IFA on the paper's benchmark functions
  tcbench --help                           every command; tcbench <command> --help for its parameters"""
# the quickstart's leaderboard: the names its table shows that the paragraph above it does not explain
TABLE_LEGEND = """\
  IFA-BP-gd = the paper's method: a backpropagation (BP) network whose initial weights the improved
  firefly algorithm (IFA) searches, then trained by gradient descent (gd); raw = the uncompensated
  output. Training i and every other row's run i meet the same draw i of power-ons (4 to train, 2
  to test). 95% CI = bootstrap interval of the median over the draws; x physical limit = median over
  the draws of this row ÷ the oracle on the same draw; gain over raw = median over the draws of
  raw ÷ this row."""
# what each significance test a diagnosis names in its evidence means (tcbench.diagnose.select.significance)
TEST_LEGEND = {
    ROBUST_WALD: "the effect's coefficients against their uncertainty, estimated from blocks of the record "
                 "(clusters) so that slow, correlated noise is not taken for an effect",
    SURROGATE: "the gain compared with the gains of simulated records that have the residual's spectrum and "
               "no effect",
}


FOLDERS = ("diagnosis", "leaderboard", "recordings", "multirun")  # the quickstart's, inside its out=
LOG = "quickstart.log"  # Hydra's log lines of the quickstart's sweeps and diagnosis, inside its out=


def activate_command(prefix: Path, cwd: Path) -> str:
    """``source <prefix>/bin/activate`` (relative to ``cwd`` where it lies inside it), which puts the
    virtual environment ``prefix``'s ``tcbench`` on the path; empty when ``prefix`` has no such script."""
    script = prefix / "bin" / "activate"
    if not script.is_file():
        return ""
    return f"source {script.relative_to(cwd) if script.is_relative_to(cwd) else script}"


def _rule(title: str) -> str:
    return f"\n== {title} " + "=" * max(0, 90 - len(title))


def _say(text: str) -> None:
    """Print a paragraph wrapped to 100 columns."""
    print(textwrap.fill(text, width=100))


def _fmt(x: Any) -> str:
    return f"{x:.3g}" if isinstance(x, float) else str(x)


def _print_table(header: list[str], rows: list[list[Any]]) -> None:
    cells = [header, *[[_fmt(v) for v in r] for r in rows]]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    for k, r in enumerate(cells):
        print("  " + "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True))))
        if k == 0:
            print("  " + "  ".join("-" * w for w in widths))


def check(cfg: QuickstartConfig) -> None:
    """The quickstart's own parameters, checked before anything runs (the compensation sweep's
    are checked by ``tcbench run``): ConfigError with one line."""
    from tcbench.datasets.concealed import EFFECTS_BY_SENSOR
    from tcbench.errors import unknown_name

    for key in ("seeds", "budget", "epochs"):
        if getattr(cfg, key) < 1:
            raise ConfigError(f"{key}={getattr(cfg, key)}: must be at least 1")
    if cfg.diagnose_sensor not in EFFECTS_BY_SENSOR:
        raise ConfigError(f"diagnose_sensor={cfg.diagnose_sensor}: "
                          + unknown_name("sensor", cfg.diagnose_sensor, EFFECTS_BY_SENSOR))
    if cfg.diagnose_effect not in EFFECTS_BY_SENSOR[cfg.diagnose_sensor]:
        raise ConfigError(f"diagnose_effect={cfg.diagnose_effect}: " + unknown_name(
            "effect", cfg.diagnose_effect, EFFECTS_BY_SENSOR[cfg.diagnose_sensor],
            f" to hide in a {cfg.diagnose_sensor} recording"))
    if cfg.diagnose_seed < 0:
        raise ConfigError(f"diagnose_seed={cfg.diagnose_seed}: must be a non-negative integer")
    if not str(cfg.tracking.experiment).strip():
        raise ConfigError("tracking.experiment: give the MLflow experiment a name")
    from tcbench.outputs import folder_problem
    from tcbench.staging import OutputRefusedError, check_targets, refusal_line

    if problem := folder_problem(cfg.out):
        raise ConfigError(f"out={cfg.out}: {problem}")
    try:
        check_targets(cfg.out, [(folder, True) for folder in FOLDERS], overwrite=True)
    except OutputRefusedError as exc:
        raise ConfigError(refusal_line(exc)) from None


def work(cfg: QuickstartConfig) -> int:
    """``tcbench quickstart`` (:attr:`~tcbench.commands.registry.CommandSpec.runs_here`): :func:`run`
    on the command line's sweep launcher and end-of-sweep report."""
    from tcbench.cli.main import _run_sweep, _sweep_report

    return run(_run_sweep, _sweep_report, cfg)


def run(run_sweep: Callable[[list[str]], Any], sweep_report: Callable[..., int], cfg: QuickstartConfig) -> int:
    """Run the quickstart ``cfg`` from the working directory with the command line's sweep
    launcher ``run_sweep`` and end-of-sweep report ``sweep_report`` (:func:`work` passes the command
    line's); 0 if every job finished."""
    check(cfg)
    started = time.monotonic()
    sweep = cfg.tracking.sweep_id or uuid.uuid4().hex[:12]
    out = Path(cfg.out)
    log_path = out / LOG
    out.mkdir(parents=True, exist_ok=True)
    log_path.write_text("")  # this quickstart's log: Hydra's lines go here, not between the results
    tracked = [f"tracking.sweep_id={sweep}", f"tracking.experiment={hydra_string(cfg.tracking.experiment)}",
               *([f"tracking.uri={hydra_string(cfg.tracking.uri)}"] if cfg.tracking.uri else []),
               "hydra/hydra_logging=tcbench_file",
               f"hydra.hydra_logging.handlers.file.filename={hydra_string(str(log_path.resolve()))}"]
    print(HEADER)

    print(_rule("1. Compensating a sensor: MSRA zero-bias stability (seed 000 §3, Table 1)"))
    _say(f"Seed 000 is {SEED_000.names()}.")
    n_bp = cfg.seeds
    _say(f"Sizes (a demonstration, not the paper's result): IFA-BP trained {n_bp} times (seeds 0-{n_bp - 1}; "
          f"the paper: 30), each with {cfg.budget} evaluations of IFA's weight search (population 10) and "
          f"{cfg.epochs} gradient-descent epochs; one simulated device, 4 recordings to train and 2 to test, a new draw of power-ons for each "
          f"training, and every baseline and the limit on the same {n_bp} draws.")
    _say(f"Running; each job's line and the sweep's progress go to {log_path}.")
    def sweep_dir(name: str) -> str:  # Hydra's record of each of its sweeps, under out=
        from tcbench.commands.schemas import literal

        return f"hydra.sweep.dir={hydra_string(literal(str(out / 'multirun' / name)))}"

    checked = run_sweep(["-m", "experiment=quickstart", *tracked, sweep_dir("ifa-bp"), f"budget={cfg.budget}",
                         f"learner.epochs={cfg.epochs}", f"seed=range({n_bp})"])
    assert checked is not None
    baselines = ("raw", "memoriser", "poly", "lagpoly", "oracle")
    # the baselines and the limit on the same draws of power-ons as the trainings (restart i on draw i)
    run_sweep(["-m", "experiment=quickstart", f"learner={','.join(baselines)}", "optimiser=none", f"seed=range({n_bp})",
               *tracked, sweep_dir("baselines")])
    run_sweep(["-m", "experiment=quickstart", "learner=poly", "learner.offsets=per_run", "optimiser=none",
               f"seed=range({n_bp})", *tracked, sweep_dir("poly-per-run")])
    status = sweep_report(sweep, checked.experiment, checked.tracking_uri)
    board_paths = _leaderboard(checked.experiment, sweep, checked.tracking_uri, out / "leaderboard")
    compensation_s = time.monotonic() - started

    print(_rule("2. Diagnosing a recording: what does the model leave out?"))
    diag_paths, run_id = _diagnosis(cfg, sweep, checked.experiment, checked.tracking_uri, out / "diagnosis")
    diagnosis_s = time.monotonic() - started - compensation_s

    from tcbench.tracking import store as tracking

    uri = tracking.tracking_uri(checked.tracking_uri)
    print(_rule("Where everything is"))
    if activate := activate_command(Path(sys.prefix), Path.cwd()):
        print(f"The commands below run in tcbench's environment; activate it once per shell: {activate}")
    print(f"MLflow store: {uri} (experiment {checked.experiment!r}, sweep {sweep}: "
          f"{n_bp * (len(baselines) + 2)} compensation runs and the diagnosis run {run_id})")
    print(f"  browse: mlflow ui --backend-store-uri {uri}")
    print(f"Leaderboard: {', '.join(str(p.resolve()) for p in board_paths)}")
    print(f"Diagnosis report and plots: {', '.join(str(p.resolve()) for p in diag_paths)}")
    print("Per-run figures (the paper's Fig. 7 for each test recording), scores.json and the training curves are")
    print("  artifacts of each compensation run in MLflow.")
    print(f"Log of the sweeps and the diagnosis: {log_path.resolve()}; each job's resolved config: "
          f"{(out / 'multirun').resolve()}/")
    print(f"Took {compensation_s:.0f} s (compensation) + {diagnosis_s:.0f} s (diagnosis).")
    print()
    print(NEXT_STEPS)
    return status


def _leaderboard(experiment: str, sweep: str, uri: str | None, out: Path) -> list[Path]:
    """Print the small table and write the full board; the paths written."""
    from tcbench.tracking import store as tracking
    from tcbench.leaderboard import compensation as comp_board
    from tcbench.tasks.specs import protocols

    runs = comp_board.load_runs(tracking.client(uri), [experiment], sweep)
    boards = comp_board.boards(runs, protocols())
    written: list[Path] = []
    replaced: list[Path] = []
    with _staged(out, replaced) as tmp:
        for board in boards:
            paths = comp_board.write(board, tmp, f"MLflow experiment {experiment}, sweep {sweep} (tcbench quickstart)")
            written += [out / p.relative_to(tmp) for p in paths.values()]
    _say_replaced(replaced)
    for board in boards:
        primary = comp_board.PRIMARY[board.protocol]
        s = comp_board.SHORT[primary]
        t = board.table
        print()
        _say(f"Leaderboard {board.task}: zero-bias stability from power-on (1σ of 10 s means of the compensated "
              f"0 g output, mean of the 2 test recordings, µg; lower is better; {primary} in MLflow and the log). "
              "oracle = the simulator's own model at the true die temperature: noise alone, the physical limit; "
              "lagpoly = a straight line or low polynomial in the thermometer passed through a first-order lag "
              "(the die trails the thermometer), its lag chosen by leave-one-recording-out error; poly3 = a cubic "
              "in the thermometer, poly3_runs the same fitted within runs (a constant per power-on); memoriser = "
              "the training runs' mean output at the same time since power-on (no temperature at all). The test "
              "runs are new power-ons of the device (task.split=next_run).")
        rows = [[r.rank, r.method, r.runs, r.failed, getattr(r, f"median_{s}"), getattr(r, f"ci95_{s}"),
                 r.x_oracle, getattr(r, f"gain_{s}")]
                for r in t.itertuples(index=False)]
        _print_table(["rank", "method", "runs", "failed", "median (µg)", "95% CI (µg)", "x physical limit",
                      "gain over raw"], rows)
        print(TABLE_LEGEND)
    return written


@contextmanager
def _staged(out: Path, replaced: list[Path]) -> Iterator[Path]:
    """:func:`tcbench.staging.staged_dir` into the quickstart's own folder: files of an earlier
    quickstart replaced (listed in ``replaced``), a refusal one line."""
    from tcbench.staging import OutputRefusedError, refusal_line, staged_dir

    try:
        with staged_dir(out, overwrite=True, replaced=replaced) as tmp:
            yield tmp
    except OutputRefusedError as exc:
        raise ConfigError(refusal_line(exc)) from None


def _say_replaced(replaced: list[Path]) -> None:
    from tcbench.staging import replaced_line

    if replaced:
        print(replaced_line(replaced))


def _where(where: dict[str, Any]) -> str:
    parts = []
    for k, v in where.items():
        if isinstance(v, (list, tuple)) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v):
            name, unit = {"temperature_c": ("temperature", " °C"), "time_s": ("time", " s")}.get(k, (k, ""))
            parts.append(f"{name} {v[0]:.3g}..{v[1]:.3g}{unit}")
        else:
            parts.append(f"{k} {v}")
    return ", ".join(parts) or "the whole record"


def _diagnosis(cfg: QuickstartConfig, sweep: str, experiment: str, uri: str | None, out: Path) -> tuple[list[Path], str]:
    """Simulate a recording with a hidden effect, write it, diagnose it as ``tcbench diagnose``
    does (:func:`tcbench.runner.job.run_job`: the report, and a run in MLflow) and print what was found;
    the paths written and the run id."""
    from omegaconf import OmegaConf

    from tcbench.tracking import store as tracking
    from tcbench.commands.schemas import DiagnoseConfig
    from tcbench.runner.config import as_dict
    from tcbench.datasets.concealed import concealed_recording
    from tcbench.runner.job import JobFailure, run_job
    from tcbench.sensors.recording import write_recording

    rec, hidden = concealed_recording(cfg.diagnose_sensor, cfg.diagnose_effect, cfg.diagnose_seed)
    length = f"{(rec.time_s[-1] - rec.time_s[0]) / 3600:.1f} h"
    _say(f"A simulated {hidden.sensor.upper()} chamber recording ({length} at 1 Hz, seed {hidden.seed}) with one "
          f"effect hidden under the noise: {hidden.effect} ({', '.join(f'{k} {v:.4g}' for k, v in hidden.params.items())}). "
          "The diagnosis is not told which; it starts from the minimal model (bias and scale factor "
          "quadratic in the thermometer temperature, white noise) and tests the library's effects.")
    folder = out.parent / "recordings"
    path = folder / f"concealed-{hidden.sensor}-{hidden.effect}-{hidden.seed}.csv"
    replaced: list[Path] = []
    with _staged(folder, replaced) as tmp:
        write_recording(rec, tmp / path.name)
    _say_replaced(replaced)
    # the job tcbench diagnose runs (its report, and its run in MLflow), over an earlier quickstart's report
    c = as_dict(OmegaConf.structured(DiagnoseConfig(recording=str(path), out=str(out), overwrite=True)))
    c["tracking"] |= {"uri": uri, "experiment": experiment, "sweep_id": sweep}
    said = io.StringIO()
    with redirect_stdout(said):  # its summary lines go to the log (the quickstart prints its own) ...
        outcome = run_job(c)
    with (out.parent / LOG).open("a") as log:
        log.write(said.getvalue())
    for line in said.getvalue().splitlines():  # ... but not what it replaced of an earlier quickstart
        if line.startswith(REPLACED):
            print(line)
    if isinstance(outcome, JobFailure):
        if outcome.user:
            raise ConfigError(outcome.error)
        raise RuntimeError(f"the diagnosis failed: {outcome.error}")
    diag, written = outcome.diagnosis, outcome.written
    sigma = float(diag.noise.white_sigma)
    before, after = float(diag.baseline.rmse_heldout), float(diag.final.rmse_heldout)
    print(f"\nVerdict: {diag.verdict}")
    for e in diag.effects:
        params = ", ".join(f"{k} {v:.4g}" for k, v in e.params.items())
        ev = e.evidence
        evidence = (f"dropping it raises the held-out squared error by {ev['gain_sigma2']:.4g} sigma^2 "
                    f"(threshold {ev.get('threshold_sigma2', float('nan')):g}; {ev.get('test', 'test')})"
                    if "gain_sigma2" in ev else ", ".join(f"{k} {_fmt(v)}" for k, v in ev.items()))
        print(f"  found {e.id} ({e.shape}){': ' + params if params else ''}")
        print(f"    where: {_where(e.where)}")
        print(f"    evidence: {evidence}")
    for test in dict.fromkeys(e.evidence.get("test") for e in diag.effects):
        if test in TEST_LEGEND:
            print(textwrap.fill(f"({test}: {TEST_LEGEND[test]})", width=100, initial_indent="  ",
                                subsequent_indent="   "))
    hit = cfg.diagnose_effect in diag.effect_ids
    print(f"  the hidden effect was {hidden.effect}: {'found' if hit else 'NOT found'}")
    print(f"Held-out RMSE (white noise sigma {sigma:.4g} {diag.unit}; a model that misses nothing reaches ~1 sigma):")
    _print_table(["model", f"RMSE held-out ({diag.unit})", "in sigma"],
                 [[" + ".join(diag.baseline.model), before, before / sigma],
                  [" + ".join(diag.final.model), after, after / sigma]])
    paths = list(written.values())
    client = tracking.client(uri)
    exp = client.get_experiment_by_name(experiment)
    (run,) = client.search_runs([exp.experiment_id], filter_string=(
        f"tags.`tcbench.kind` = 'diagnosis' and tags.`tcbench.sweep_id` = '{sweep}'"), max_results=1)
    run_id = run.info.run_id
    return paths, run_id
