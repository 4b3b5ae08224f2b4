"""The registry of tcbench's commands: one :class:`CommandSpec` per command, from which the
command line derives its usage text, its dispatch and each command's ``--help``, Hydra its
schemas, and the runner its job kinds. A new command is one entry in :data:`SPECS` and its module.

It sits on the commands layer, below the runner and the command line, so every one of them reads
it. What it names above that layer (run's schema, the job kinds, the command line's parsers and
in-process entries) it names as ``module:attribute`` paths, imported by their own layer when used
(:func:`load`); importing this module imports nothing of tcbench, so ``tcbench --help`` stays fast.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any

# meanings of keys several commands share, for their --help
TRACKING = {
    "tracking.enabled": "log the results to MLflow (false: files only)",
    "tracking.uri": "MLflow store (null: $MLFLOW_TRACKING_URI, else sqlite:///mlflow.db in the cwd); a SQLite store "
                    "keeps the runs' files in mlartifacts/ and its lock file <db>.lock beside its database",
    "tracking.experiment": "MLflow experiment the run is filed under",
    "tracking.sweep_id": "the sweep's id in MLflow (null: a new one per command)",
    "tracking.resume": "skip a job whose config already FINISHED in the experiment (re-run a killed sweep)",
}
RUN_PARAMS = {
    "task": "the task, an option of the group task (task.<key>=VALUE sets one of its keys)",
    "optimiser": "the optimiser, an option of the group optimiser (optimiser.<key>=VALUE sets one of its keys)",
    "learner": "compensation tasks: the learner, an option of the group learner (default: the task's, bp)",
    "experiment": "a whole study in one file, an option of the group experiment (experiment=paper_fa_ifa)",
    "seed": "run seed: the task instance and the optimiser's streams derive from it",
    "budget": "objective evaluations per run, initial population included",
    "progress": "a progress bar per run",
    **TRACKING,
    "tracking.plots": "a figure per run (null: for single runs and compensation runs, not in optimisation sweeps)",
    "tracking.ioh_dir": "also write each run in IOHprofiler's format into this folder (null: no)",
}
OVERWRITE = ("replace files of the same name already in out= and say which (false: refuse, naming the first; "
             "a link out of out= or a folder where a file goes is refused either way)")


@dataclass(frozen=True)
class CommandSpec:
    """One ``tcbench`` command. Its jobs run either as job kinds of :mod:`tcbench.runner.kinds`
    (``kinds``: one job per config, on the launcher for a sweep) or in the command line's process
    (``runs_here``: a module whose ``check(cfg)`` and ``work(cfg) -> int`` take the schema's
    dataclass; for work that needs no worker: a listing, two small files, a quickstart that runs
    sweeps of its own), never both. ``params`` gives the meaning of every key of the schema (dotted
    for nested dataclasses; a dict-valued key is one entry), or ``more_params`` (a ``module:function``
    returning ``{key: meaning}``) for keys documented where they are defined."""

    name: str
    summary: str  # its line in ``tcbench --help``
    schema: str  # ``module:Class`` of its primary config's dataclass schema
    description: str = ""  # the paragraph of ``tcbench NAME --help`` (run: conf/config.yaml's hydra.help)
    params: dict[str, str] = field(default_factory=dict)
    examples: tuple[str, ...] = ()
    output: str = ""  # where its output goes, for its --help
    # ``tcbench metrics PATH`` means ``recording=PATH``; None: ``recording`` for every command reading one
    positional: str | None = None
    required: tuple[str, ...] = ()
    options: tuple[str, ...] = ()  # further lines of the options section (flags kept as aliases)
    sweep: str = ""  # what the -m line of its --help adds about its sweeps
    config: str = ""  # its primary config, conf/<config>.yaml (empty: its name)
    schema_node: str = ""  # the schema's name in Hydra's ConfigStore, as the config's defaults list names it
    parser: str | None = None  # ``module:function`` reading its arguments (None: key=value pairs of its schema)
    kinds: dict[str, str] = field(default_factory=dict)  # job kind -> ``module:Class`` of its JobKind
    runs_here: str | None = None  # the module running its jobs in this process, one after another
    inputs: tuple[str, ...] = ()  # keys naming the files its jobs read (checked to exist before any work)
    more_params: str | None = None  # ``module:function`` -> {key: meaning} of keys documented where defined

    def __post_init__(self) -> None:
        object.__setattr__(self, "config", self.config or self.name)
        object.__setattr__(self, "schema_node", self.schema_node or f"{self.config}_schema")
        if self.positional is None and "recording" in self.inputs:  # one rule: a recording is also the first argument
            object.__setattr__(self, "positional", "recording")
        if bool(self.kinds) == bool(self.runs_here):
            raise ValueError(f"command {self.name}: give its job kinds or the module that runs it here, one of them")

    def schema_class(self) -> type:
        """The dataclass schema of its primary config (imported now)."""
        return load(self.schema)  # type: ignore[no-any-return]

    def meanings(self) -> dict[str, str]:
        """The meaning of every key: :attr:`params` and those of :attr:`more_params` (imported now)."""
        return {**self.params, **(load(self.more_params)() if self.more_params else {})}


def load(path: str) -> Any:
    """The object a ``module:attribute`` path names, its module imported now."""
    module, _, attribute = path.partition(":")
    return getattr(importlib.import_module(module), attribute)


def by_config(config: str) -> CommandSpec | None:
    """The command whose primary config is ``conf/<config>.yaml``, or None."""
    return next((spec for spec in SPECS.values() if spec.config == config), None)


def job_kinds() -> dict[str, str]:
    """Every job kind of every command: kind name -> ``module:Class`` of its JobKind."""
    return {kind: path for spec in SPECS.values() for kind, path in spec.kinds.items()}


SPECS: dict[str, CommandSpec] = {
    "run": CommandSpec(
        name="run",
        summary="one job, or a Hydra sweep with -m (e.g. tcbench run -m optimiser=fa,ifa seed='range(30)')",
        schema="tcbench.runner.schema:JobConfig",
        config="config",
        schema_node="base_config",
        parser="tcbench.cli.main:cmd_run",
        # the job kinds of the tasks' specs (tcbench.tasks.specs)
        kinds={"optimisation": "tcbench.runner.kinds.optimisation:OptimisationKind",
               "compensation": "tcbench.runner.kinds.compensation:CompensationKind"},
        params=RUN_PARAMS,
    ),
    "leaderboard": CommandSpec(
        name="leaderboard",
        summary="aggregate finished runs into leaderboards/<task>.md/.csv/.png (experiments=NAME out=DIR)",
        description="Aggregate the finished runs of MLflow experiments into leaderboards (optimisation and "
                    "compensation): tables, convergence plots, ECDFs.",
        schema="tcbench.commands.schemas:LeaderboardConfig",
        kinds={"leaderboard": "tcbench.runner.kinds.leaderboards:LeaderboardKind"},
        parser="tcbench.cli.main:cmd_leaderboard",
        params={
            "experiments": "MLflow experiment whose runs are ranked; several: experiments=[a,b]",
            "sweep": "only the runs of this sweep id (null: every run of the experiment)",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "ecdf": "also write COCO-style ECDF plots per dimension",
            "tracking.uri": "MLflow store to read (null: $MLFLOW_TRACKING_URI, else sqlite:///mlflow.db in the cwd)",
            "tracking.enabled": "also file the board files as a run in the store (false: files only)",
            "tracking.experiment": "experiment that run is filed under",
            "tracking.sweep_id": TRACKING["tracking.sweep_id"],
            "tracking.resume": TRACKING["tracking.resume"],
        },
        examples=(
            "tcbench leaderboard                                         all runs of experiment tcbench",
            "tcbench leaderboard experiments=quickstart sweep=SWEEP_ID out=lb ecdf=true",
            "tcbench leaderboard --experiment quickstart --sweep SWEEP_ID --out lb --ecdf   (the same)",
            "tcbench leaderboard -m experiments=paper-fa-ifa,paper-ifa-bp 'out=lb/${experiments}'   (a board per experiment)",
        ),
        output="OUT/<task>.md, OUT/<task>.csv and OUT/<task>_convergence.png per task (compensation tasks too), "
               "the tables also printed; ecdf=true adds OUT/ecdf_<d>d.png. Reads the MLflow store and writes "
               "nothing to it unless tracking.enabled=true",
        options=("  --experiment NAME   experiments=NAME (repeatable: experiments=[a,b])",
                 "  --sweep ID          sweep=ID",
                 "  --tracking-uri URI  tracking.uri=URI",
                 "  --ecdf              ecdf=true"),
    ),
    "pages": CommandSpec(
        name="pages",
        summary="the leaderboard pages of the committed boards, for the documentation site (out=DIR)",
        description="Write the leaderboard pages of the documentation site from the committed boards under "
                    "leaderboards/ alone (no MLflow store): a page per compensation board (its paper and sensor, "
                    "its split tier, its verdict, a sortable and filterable table with the limits and the "
                    "memoriser marked, its methods against the limits as a plot, its own figures), a page per "
                    "optimisation folder (ECDFs and tables), the real-IMU board, and a summary ranking the methods "
                    "across the compensation tasks. `mkdocs build` makes the same pages into docs/leaderboards/.",
        schema="tcbench.commands.schemas:PagesConfig",
        runs_here="tcbench.leaderboard.pages.command",
        params={
            "out": "output folder (markdown pages for MkDocs, their plots and the boards' figures)",
            "leaderboards": "the folder of committed boards (the repository's leaderboards/)",
            "boards": "only these: board folders (boards=[paper-ifa-bp,bbob]) or single boards as FOLDER/STEM "
                      "(boards=[paper-ifa-bp/msra_zerobias-dev0]); empty: every board. The summary page is "
                      "always written, over the boards chosen",
            "overwrite": OVERWRITE,
        },
        examples=(
            "tcbench pages out=board-pages",
            "tcbench pages out=board-pages 'boards=[paper-ifa-bp,accel-chamber/accel_chamber-dev0]'",
            "tcbench pages out=board-pages overwrite=true      (again, replacing the pages written before)",
        ),
        output="OUT/index.md (the summary), OUT/<folder>/<board>.md per compensation board with its plot "
               "OUT/<folder>/<board>.limits.svg, OUT/<folder>/index.md per optimisation folder, and the boards' "
               "committed figures beside them; nothing outside OUT",
        required=("out",),
        sweep=", each writing its own out=",
    ),
    "quickstart": CommandSpec(
        name="quickstart",
        summary="the main job in a minute: compensate a simulated MSRA, diagnose a recording",
        description="The main job in about a minute (2 cores), at demonstration sizes, not the paper's: "
                    "1. compensation: the paper's IFA-BP on the simulated MSRA zero-bias task (`tcbench run -m "
                    "experiment=quickstart`, conf/experiment/quickstart.yaml: seed: range(5), budget: 510), beside "
                    "raw, poly and the oracle (the physical limit), then a small leaderboard; 2. diagnosis: a "
                    "simulated recording with one hidden effect (thermal_lag by default), what the diagnosis finds, "
                    "where, and the held-out RMSE before and after in noise sigmas. Deterministic: same "
                    "parameters, same numbers.",
        schema="tcbench.commands.schemas:QuickstartConfig",
        runs_here="tcbench.cli.quickstart",
        params={
            "seeds": "IFA-BP trainings (seeds 0..seeds-1; the paper: 30)",
            "budget": "evaluations of IFA's weight search per training (the paper's search: 510)",
            "epochs": "BP gradient-descent epochs per training",
            "diagnose_sensor": "msra or gyro: the simulated recording diagnosed",
            "diagnose_effect": "the effect hidden in it (an effect of tcbench.datasets.concealed, e.g. hysteresis)",
            "diagnose_seed": "its draw",
            "out": "output folder (leaderboard/, diagnosis/, recordings/); a quickstart run again replaces the "
                   "files the earlier one wrote there and says which",
            "tracking.uri": TRACKING["tracking.uri"],
            "tracking.experiment": "MLflow experiment the quickstart's runs are filed under",
            "tracking.sweep_id": "the quickstart's sweep id in MLflow (null: a new one)",
        },
        examples=("tcbench quickstart",
                  "tcbench quickstart seeds=30             the paper's 30 trainings (about 5 min)",
                  "tcbench quickstart -m diagnose_effect=thermal_lag,hysteresis 'out=qs/${diagnose_effect}'",
                  "tcbench run -m experiment=quickstart 'seed=range(30)' learner.epochs=3000   the sweep alone"),
        output="runs in MLflow (./mlflow.db, experiment quickstart: one per compensation job and one for the "
               "diagnosis), the leaderboard in OUT/leaderboard/, the diagnosis report and plots in "
               "OUT/diagnosis/, Hydra's log lines in OUT/quickstart.log and each job's resolved config in OUT/multirun/",
        sweep=" (each quickstart runs its own sweeps on tcbench run's launcher)",
    ),
    "list": CommandSpec(
        name="list",
        summary="registered tasks, optimisers, learners, sensors and terms (what=all|tasks|optimisers|learners|sensors|terms)",
        description="Print the registered tasks (their gymnasium env id and task= name), optimisers (with the "
                    "package that provides them: tcbench or a plugin), learners and broken plugins.",
        schema="tcbench.commands.schemas:ListConfig",
        runs_here="tcbench.commands.listing",
        params={"what": "which list: all, tasks, optimisers, learners, sensors or terms"},
        examples=("tcbench list", "tcbench list what=optimisers", "tcbench list -m what=tasks,learners"),
        output="stdout only",
        sweep=", each list printed in turn",
    ),
    "simulate": CommandSpec(
        name="simulate",
        summary="simulate a recording (sensor=msra|gyro|accel protocol=... device_seed=N seed=N out=DIR) and its metrics",
        description="Simulate a recording of one device under a test protocol, then compute its metrics.",
        schema="tcbench.commands.schemas:SimulateConfig",
        kinds={"simulate": "tcbench.runner.kinds.recordings:SimulateKind"},
        inputs=("model",),
        params={
            "sensor": "msra (resonant accelerometer), gyro or accel (capacitive accelerometer); `tcbench list what=sensors` "
                      "(null: msra, or the model file's)",
            "protocol": "test protocol: msra roomtemp|fulltemp, gyro oven|static, accel chamber|multipos|static "
                        "(null: the sensor's default, msra fulltemp, gyro oven, accel chamber)",
            "device_seed": "which unit of the device population (integer >= 0)",
            "seed": "which run of the device (integer >= 0): a new power-on (turn-on bias and scale factor, hysteresis "
                    "state, chamber timing within tolerance, the thermometer's offset and gradient) and new noise",
            "power_on": "null: the run's own power-on; N: replay run N's power-on with this run's noise (only the noise "
                        "differs: the replay tier)",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "format": "csv or parquet",
            "name": "file stem (null: <sensor>-<protocol>-dev<device_seed>-seed<seed>[-poweron<N>])",
            "protocol_params": "protocol_params.<keyword>=VALUE overrides a protocol keyword (duration_s=3600)",
            "effects": "effects.<effect>.<param>=VALUE changes or adds an effect (effects.hysteresis.amplitude=0.02)",
            "without": "effects to drop, e.g. 'without=[white_noise]'",
            "metrics": "also compute the metrics, plots and tables",
            **TRACKING,
            "model": "simulate a fitted-model file (model.yaml of tcbench diagnose) instead of a device",
        },
        examples=(
            "tcbench simulate sensor=msra protocol=fulltemp device_seed=0 out=recordings",
            "tcbench simulate sensor=gyro protocol=oven seed=1 format=parquet tracking.enabled=false",
            "tcbench simulate -m device_seed='range(100)' out=population   (a population, one job per device)",
        ),
        output="OUT/NAME.csv (or .parquet) with its sidecar OUT/NAME.json, and with metrics=true "
               "OUT/NAME_metrics/ (metrics.json, plots); MLflow experiment 'simulations' when tracking is on",
    ),
    "import": CommandSpec(
        name="import",
        summary="your own CSV as a recording (csv=PATH sensor=msra|gyro|accel time=COL:unit ... out=DIR)",
        description="Import your own CSV file as a tcbench recording (validated, with its sidecar).",
        schema="tcbench.commands.schemas:ImportConfig",
        kinds={"import": "tcbench.runner.kinds.recordings:ImportKind"},
        inputs=("csv",),
        params={
            "csv": "the table to import (fields separated by commas, tabs or semicolons), or a PX4 log (.ulg: "
                   "every instance and axis of the sensor's topic, sensor_gyro for a gyro, sensor_accel for accel); also the first argument",
            "sensor": "msra, gyro or accel (any kind `tcbench list what=sensors` shows)",
            "time": "time column, COL:unit (any time unit pint knows: s, ms, us, ns, min, h)",
            "temperature": "temperature column, COL:unit (degC, K, degF)",
            "output": "sensor output column, COL:unit (gyro: deg/s, rad/s, mrad/s, mdps ...; accel: g, mg, m/s^2 ...; "
                      "msra: Hz, kHz ...); "
                      "several axes: COL:unit,COL:unit,... (one recording each, NAME-COL)",
            "input": "optional true-input column, COL:unit",
            "units.time": "the unit of time= when it names its column without one (units={time:us,output:rad/s} "
                          "sets several): a unit is never assumed; say it after the column's colon, here, or import "
                          "a tcbench recording whose sidecar states it",
            "units.temperature": "the unit of temperature= when it names its column without one",
            "units.output": "the unit of every output= column named without one (units.output=m/s^2)",
            "units.input": "the unit of input= when it names its column without one",
            "axes": "the sensor axis of each output column, x, y or z (axes=y, or axes=x,y,z for three), written to "
                    "the sidecar's extra.axis; null: not recorded (never guessed from a name; a PX4 log's x, y, z "
                    "fields are their axes)",
            "drop": "drop rows where these columns are nonzero (drop=flag or drop=a,b)",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "name": "file stem (null: the CSV's)",
            "device_id": "device id for the sidecar (null: the CSV's stem)",
            "sample_rate_hz": "sample rate (null: one over the median interval of the time column)",
            **TRACKING,
        },
        examples=(
            "tcbench import csv=log.csv sensor=gyro time=time_s:s temperature=temp_c:degC "
            "output=gyro_x_dps:deg/s axes=x out=recordings",
            "tcbench import csv=flight.ulg sensor=gyro out=recordings   (NAME-sensor_gyro-<instance>-<axis>.csv)",
            "tcbench import csv=imu.tsv sensor=accel time=t temperature=temp output=ax,ay,az "
            "units={time:us,temperature:degC} units.output=m/s^2 axes=x,y,z out=recordings",
        ),
        output="OUT/NAME.csv and its sidecar OUT/NAME.json; MLflow experiment 'recordings' when tracking is on",
        positional="csv",
        required=("csv", "sensor", "time", "temperature", "output", "out"),
    ),
    "metrics": CommandSpec(
        name="metrics",
        summary="validate a recording and compute the papers' metrics, with plots (tcbench metrics PATH)",
        description="Validate a recording and compute the papers' metrics, with plots.",
        schema="tcbench.commands.schemas:MetricsConfig",
        kinds={"metrics": "tcbench.runner.kinds.recordings:MetricsKind"},
        inputs=("recording",),
        params={
            "recording": "the recording (.csv or .parquet with its .json sidecar); also the first argument",
            "out": "output folder (null: <recording stem>_metrics next to the recording)",
            "overwrite": OVERWRITE,
            "scale_factor_hz_per_g": "MSRA scale factor in Hz/g (null: the sidecar's, else the nominal one)",
            **TRACKING,
        },
        examples=(
            "tcbench metrics recordings/msra-fulltemp-dev0-seed0.csv",
            "tcbench metrics recording=run.csv out=run_metrics tracking.enabled=false",
        ),
        output="OUT/ (metrics.json, overview and Allan deviation plots, nodes.csv for a four-position "
               "test); MLflow experiment 'recordings' when tracking is on",
        required=("recording",),
    ),
    "diagnose": CommandSpec(
        name="diagnose",
        summary="find the physics a model leaves out of a recording: report, plots, model.yaml",
        description="Find the physics a model leaves out of a recording: a report, plots and a model file.",
        schema="tcbench.commands.schemas:DiagnoseConfig",
        kinds={"diagnose": "tcbench.runner.kinds.diagnosis:DiagnoseKind"},
        inputs=("recording", "model"),
        params={
            "recording": "the recording to diagnose; also the first argument",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "sensor": "the sensor kind (msra, gyro, accel), for a recording without a sidecar (null: from the sidecar)",
            "model": "model file of the effects already modelled (null: none)",
            "max_rows": "the most rows diagnosed (null: no limit). A record of more rows than settings.rate.max_rows "
                        "is diagnosed on bin means (its noise terms on every sample); this refuses what would still "
                        "be longer. Measured on one core (benchmarks/diagnose_scaling.py), a diagnosis takes about "
                        "49 s and 550 MB at 100 000 rows, 8 min and 3.2 GB at the default 1 000 000, 1.2 h and 30 GB "
                        "at 10^7: a longer record is refused before it is read (or, averaged, once its bins are "
                        "known), with its estimate; one estimated over 30 s says so when it starts and shows the "
                        "time spent on a terminal",
            **TRACKING,
        },
        more_params="tcbench.diagnose.settings:meanings",  # settings.<section>.<key>: the statistics
        examples=(
            "tcbench diagnose recordings/msra-fulltemp-dev0-seed0.csv --out diagnosis",
            "tcbench diagnose recording=run.csv out=diag2 model=diagnosis/model.yaml",
            "tcbench diagnose recording=run.csv settings.selection.wald_threshold=30 settings.locate.false_alarm=0.05",
            "tcbench diagnose -m recording=a.csv,b.csv 'out=diagnoses/${stem:recording}' hydra.launcher.n_jobs=2",
        ),
        output="OUT/report.json, OUT/report.md, plots and OUT/model.yaml; MLflow experiment 'diagnoses' "
               "(effects found, held-out RMSEs, the report) when tracking is on",
        required=("recording",),
    ),
    "calibrate": CommandSpec(
        name="calibrate",
        summary="fit offset models on some temperature branches of a static recording, score them on the others",
        description="Calibrate a static recording on its own temperature branches: each offset model (raw, "
                    "PX4's cubic in the thermometer, the cubic with a temperature-rate term, BP and Elman networks, "
                    "the diagnosed model) fitted on some parts and ranked on the others, held out, with a "
                    "block-bootstrap interval.",
        schema="tcbench.commands.schemas:CalibrateConfig",
        kinds={"calibrate": "tcbench.runner.kinds.calibration:CalibrateKind"},
        inputs=("recording", "test_recordings"),
        params={
            "recording": "the static recording (its true input in the input column: 0 for a gyro at rest); also the "
                         "first argument",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "train_branches": "the temperature branches (or time blocks) to fit on, numbered from 0 in time order; "
                              "null: of several branches, the fewest consecutive ones whose temperatures span the others' "
                              "(the held-out score is then interpolation), or blocks 0, 2, 4 of five when there is one",
            "blocks": "cut the record into this many time blocks of equal duration instead of temperature branches "
                      "(a record that only cools: train_branches=[0,2,4] blocks=5)",
            "methods": "offset models: raw, poly3 (PX4's cubic), poly3_rate (cubic + temperature rate), bp (trained by "
                       "Levenberg-Marquardt when the rows allow), bp_gd (gradient descent, 1000 epochs), elman (Adam) "
                       "(the seed papers' networks on [T, dT/dt]), model (the diagnosed physics without its "
                       "clock-keyed terms); not by default: memoriser (a control, no physics: the fitted parts' mean "
                       "offset against the time since their start, at the same time in each held-out part)",
            "seed": "the networks' initial weights",
            "restarts": "networks per learner method, seeds seed, seed+1, ...: the board gives the median of their "
                        "scores (the plot shows the first)",
            "min_swing_c": "a turning point of the temperature stands out by at least this (degC)",
            "drift_window_s": "the drift score's running mean (s)",
            "screen": "drop the training parts' handling bursts, spikes and thermometer glitches before any model is "
                      "fitted (reported); false: fit every sample",
            "axis": "x, y or z: the recording's axis when its sidecar does not say (tcbench import axes= records it)",
            "test_recordings": "other recordings of the same kind and unit to score the fitted models on, every "
                               "part of them held out: train on one record, test on others",
            "true_input": "the static record's true input, VALUE[:unit] (an accelerometer axis along gravity: "
                          "-1:g); null: the recording's input column",
            **TRACKING,
        },
        examples=(
            "tcbench calibrate recordings/tofupilot/imu-imu.gyro.y.csv --out cal/gyro-y",
            "tcbench calibrate recording=run.csv 'train_branches=[0,1]' 'methods=[poly3]'",
            "tcbench calibrate -m recording=a.csv,b.csv 'out=cal/${stem:recording}'",
            "tcbench calibrate recording=recordings/tofupilot/imu-imu.acc.z.csv true_input=-1:g out=cal/acc-z",
        ),
        output="the held-out ranking (printed); OUT/calibration.md and .csv (one row per method and part: drift and "
               "RMS), OUT/residuals.png, OUT/calibration.json (the ranking and the cubic for tcbench export); MLflow "
               "experiment 'calibrations' when tracking is on",
        required=("recording",),
    ),
    "export": CommandSpec(
        name="export",
        summary="PX4 and ArduPilot thermal-calibration parameters of calibrations (calibrations=[DIR,...])",
        description="Write the thermal-calibration parameters of one IMU for PX4 (TC_G*/TC_A*, a param-set "
                    "script) and ArduPilot (INS_TCALn_*, a .parm file) from tcbench calibrate's outputs, one per "
                    "axis and sensor kind, every axis in its slot (the axis from the recording's sidecar or "
                    "calibrate axis=). As PX4's own fit, an accelerometer's TC_A* leave out its static level "
                    "(the median reading, gravity included), which stays with CAL_ACCn_*.",
        schema="tcbench.commands.schemas:ExportConfig",
        runs_here="tcbench.commands.export",
        params={
            "calibrations": "the out= folders of tcbench calibrate (their calibration.json): one per axis and kind",
            "runs": "tcbench run compensation runs (their ids in $MLFLOW_TRACKING_URI, or their device.json) whose "
                    "trained network formats=[c] writes as C",
            "out": "output folder",
            "overwrite": OVERWRITE,
            "formats": "px4, ardupilot, c (C99 of every method a device runs), or several",
            "device_id": "PX4's TC_*_ID: the sensor's device id (CAL_GYROn_ID / CAL_ACCn_ID), one number or "
                         "{gyro: N, accel: M}; null: the id the PX4 log gave (required for px4 otherwise)",
            "px4_instance": "the TC_G<i> / TC_A<i> instance (0..3)",
            "ardupilot_imu": "the INS_TCAL<n> IMU (1..3)",
        },
        examples=(
            "tcbench export 'calibrations=[cal/x,cal/y,cal/z]' device_id=2293768 out=params",
            "tcbench export 'calibrations=[cal/gx,cal/gy,cal/gz,cal/ax,cal/ay,cal/az]' formats=[ardupilot] out=params",
        ),
        output="OUT/px4_tc_params.txt and OUT/ardupilot_tcal.parm",
        required=("calibrations",),
    ),
}
