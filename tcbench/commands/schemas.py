"""Config schemas of the key=value commands (``tcbench run``'s is :mod:`tcbench.runner.schema`):
each is the structured base of its primary config ``conf/<command>.yaml``, named by the command's
spec (:mod:`tcbench.commands.registry`) and registered with Hydra's ConfigStore as
``<command>_schema`` so types and known keys are checked at composition. ``kind`` names the job
kind that runs it (:mod:`tcbench.runner.kinds`)."""

from __future__ import annotations

import dataclasses
import re
import typing
from dataclasses import dataclass, field
from typing import Any

from tcbench.diagnose.settings import DiagnoseSettings
from tcbench.sensors import kinds
from tcbench.tracking.config import TrackingConfig


@dataclass
class SimulateConfig:
    """``tcbench simulate``. ``protocol_params.<name>=`` overrides a protocol keyword
    (``protocol_params.duration_s=3600``); ``effects.<id>.<param>=`` changes or adds an effect
    (``effects.hysteresis.amplitude=0.02``); ``without=[white_noise]`` drops some. ``model=PATH``
    simulates a fitted-model file (:mod:`tcbench.diagnose.model_file`) instead of a device: the
    sensor comes from the file (``sensor`` null), effect changes and ``without`` still apply.
    ``protocol`` null is the sensor kind's default (:attr:`~tcbench.sensors.kinds.SensorKind.default_protocol`)."""

    kind: str = "simulate"
    sensor: str | None = None  # null: msra, or the model file's sensor
    protocol: str | None = None  # null: the sensor kind's default (msra fulltemp, gyro oven, accel chamber)
    device_seed: int = 0
    seed: int = 0
    power_on: int | None = None  # null: the run's own power-on; N: run N's power-on, this run's noise (a replay)
    out: str = "recordings"
    format: str = "csv"
    name: str | None = None
    overwrite: bool = False  # replace files of the same name in out= (false: refuse them)
    protocol_params: dict[str, Any] = field(default_factory=dict)
    effects: dict[str, dict[str, Any]] = field(default_factory=dict)
    without: list[str] = field(default_factory=list)
    metrics: bool = True
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="simulations"))
    model: str | None = None


@dataclass
class MetricsConfig:
    """``tcbench metrics``: ``recording=PATH`` and options."""

    kind: str = "metrics"
    recording: str = ""
    out: str | None = None
    overwrite: bool = False
    scale_factor_hz_per_g: float | None = None
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="recordings"))


@dataclass
class ImportUnits:
    """``tcbench import``'s ``units=``: the unit of a column named without one (``units={output:rad/s}``)."""

    time: str | None = None
    temperature: str | None = None
    output: str | None = None
    input: str | None = None


@dataclass
class ImportConfig:
    """``tcbench import``: the CSV, the sensor kind, the column map (``time=COL:unit`` ...), the
    units of columns given without one (``units={output:rad/s,time:us}``), the sensor axis of each
    output column (``axes=x,y,z``), rows to drop (``drop=flag`` or ``drop=a,b``: rows where a
    column is nonzero) and the output directory; ``name`` is the recording's stem (default: the CSV's)."""

    kind: str = "import"
    csv: str = ""
    sensor: str = ""
    time: str = ""
    temperature: str = ""
    output: str = ""
    input: str | None = None
    units: ImportUnits = field(default_factory=lambda: ImportUnits())
    axes: str | None = None
    drop: str | None = None
    out: str = ""
    name: str | None = None
    overwrite: bool = False
    device_id: str | None = None
    sample_rate_hz: float | None = None
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="recordings"))


# the most rows tcbench diagnose takes by default: about 8 min of one core and 3 GB (tcbench.diagnose.rate.cost)
DIAGNOSE_MAX_ROWS = 1_000_000


def _mutable(cls: type) -> type:
    """A plain dataclass with the fields, types and defaults of the frozen settings section
    ``cls`` (a tuple as a list): OmegaConf makes a frozen dataclass read-only, so no ``key=value``
    could change it. Made once here, named ``<Section>Config`` in this module (a sweep's configs
    are pickled by name)."""
    hints = typing.get_type_hints(cls)
    fields: list[tuple[str, Any, Any]] = []
    for f in dataclasses.fields(cls):
        kind = hints[f.name]
        if dataclasses.is_dataclass(kind):
            sub = _mutable(kind)  # type: ignore[arg-type]
            fields.append((f.name, sub, field(default_factory=sub)))
        elif typing.get_origin(kind) is tuple:
            fields.append((f.name, list[float], field(default_factory=lambda d=f.default: list(d))))
        else:
            fields.append((f.name, kind, field(default=f.default)))
    made = dataclasses.make_dataclass(f"{cls.__name__}Config", fields)
    made.__module__, made.__doc__ = __name__, cls.__doc__
    globals()[made.__name__] = made
    return made


# ``tcbench diagnose settings.<section>.<key>=``: the statistics of tcbench.diagnose.settings.DiagnoseSettings
DiagnoseSettingsConfig = _mutable(DiagnoseSettings)


@dataclass
class DiagnoseConfig:
    """``tcbench diagnose``: the recording, the output directory, the sensor kind for a recording
    without a sidecar, the model file of effects already modelled, the most rows diagnosed
    (:mod:`tcbench.diagnose.rate.cost`) and the statistics of the diagnosis (``settings``, checked by
    :func:`tcbench.diagnose.settings.from_mapping`)."""

    kind: str = "diagnose"
    recording: str = ""
    out: str = "diagnosis"
    overwrite: bool = False
    sensor: str | None = None
    model: str | None = None
    max_rows: int | None = DIAGNOSE_MAX_ROWS  # null: no limit
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="diagnoses"))
    settings: DiagnoseSettingsConfig = field(default_factory=DiagnoseSettingsConfig)  # type: ignore[valid-type]


@dataclass
class CalibrateConfig:
    """``tcbench calibrate``: offset models of a static recording fitted on some of its parts
    (``train_branches``: temperature branches or time blocks, numbered from 0 in time order; null:
    of several branches, the consecutive ones whose temperatures span the held-out ones', or the
    even ones of five time blocks when there is one branch)
    and scored on the others."""

    kind: str = "calibrate"
    recording: str = ""
    out: str = "calibration"
    overwrite: bool = False
    train_branches: list[int] | None = None
    methods: list[str] = field(default_factory=lambda: ["raw", "poly3", "poly3_rate", "bp", "bp_gd", "elman", "model"])
    seed: int = 0
    restarts: int = 1  # networks per learner method (seeds seed, seed+1, ...): the board gives their median
    min_swing_c: float = 5.0
    drift_window_s: float = 60.0
    blocks: int | None = None  # cut into this many time blocks instead of temperature branches
    test_recordings: list[str] = field(default_factory=list)  # more records to score on, every part held out
    true_input: str | None = None  # VALUE[:unit]: the static record's true input (an axis along gravity: -1:g)
    axis: str | None = None  # x, y or z: the recording's axis when its sidecar does not say (for tcbench export)
    screen: bool = True  # drop the training parts' bursts, spikes and thermometer glitches before any fit
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="calibrations"))


@dataclass
class ExportConfig:
    """``tcbench export``: the autopilots' parameter files of some ``tcbench calibrate`` outputs
    (one per axis and sensor kind of one IMU)."""

    calibrations: list[str] = field(default_factory=list)
    runs: list[str] = field(default_factory=list)  # tcbench run ids (or their device.json) whose network formats=[c] writes
    out: str = "export"
    overwrite: bool = False
    formats: list[str] = field(default_factory=lambda: ["px4", "ardupilot"])
    device_id: Any = None  # PX4's TC_*_ID: a number, or {gyro: N, accel: M}; null: the log's
    px4_instance: int = 0
    ardupilot_imu: int = 1


@dataclass
class LeaderboardConfig:
    """``tcbench leaderboard``: the boards of the runs in ``experiments`` (a name, or a list
    ``[a,b]``), optionally of one ``sweep``, written into ``out``. It reads the store
    ``tracking.uri``; ``tracking.enabled=true`` also files the board files as a run there."""

    kind: str = "leaderboard"
    experiments: Any = "tcbench"
    sweep: str | None = None
    out: str = "leaderboards"
    overwrite: bool = False
    ecdf: bool = False
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(enabled=False, experiment="leaderboards"))


@dataclass
class PagesConfig:
    """``tcbench pages``: the leaderboard pages of the committed boards in ``leaderboards`` (all of
    them, or the folders and boards named in ``boards``) written into ``out``."""

    out: str = ""
    leaderboards: str = "leaderboards"
    boards: list[str] = field(default_factory=list)
    overwrite: bool = False


LISTS = ("all", "tasks", "optimisers", "learners", "sensors", "terms")


@dataclass
class ListConfig:
    """``tcbench list``: what to list (one of :data:`LISTS`)."""

    what: str = "all"


@dataclass
class QuickstartTracking:
    """Where the quickstart's runs go (it is tracked whole: its leaderboard reads them back)."""

    uri: str | None = None
    experiment: str = "quickstart"
    sweep_id: str | None = None


@dataclass
class QuickstartConfig:
    """``tcbench quickstart``: the sizes of its compensation sweep (``tcbench run -m
    experiment=quickstart``), the hidden effect of its diagnosis and where its files go."""

    seeds: int = 5
    budget: int = 510
    epochs: int = 1000
    diagnose_sensor: str = kinds.DEFAULT
    diagnose_effect: str = "thermal_lag"
    diagnose_seed: int = 0
    out: str = "tcbench-quickstart"
    tracking: QuickstartTracking = field(default_factory=QuickstartTracking)


def register() -> None:
    """Register the resolver ``stem``: ``${stem:KEY}`` is the file stem of the path at config key
    ``KEY`` (``out=diagnoses/${stem:recording}``: a folder per recording of a sweep). The schemas
    are registered by :func:`tcbench.runner.schema.register_schema`."""
    from pathlib import PurePath

    from omegaconf import OmegaConf

    if not OmegaConf.has_resolver("stem"):
        OmegaConf.register_new_resolver("stem", lambda key, _root_: PurePath(str(OmegaConf.select(_root_, key))).stem)


def literal(text: str) -> str:
    """``text`` escaped so that OmegaConf reads it as it is: every ``${`` is part of the text,
    never an interpolation (``\\${``; the backslashes before one are doubled)."""
    return re.sub(r"(\\*)\$\{", lambda m: m.group(1) * 2 + "\\${", text)


def _literal_values(value: Any) -> Any:
    """Every string inside ``value`` (dicts and lists) as :func:`literal` text."""
    if isinstance(value, str):
        return literal(value)
    if isinstance(value, dict):
        return {k: _literal_values(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_literal_values(v) for v in value]
    return value


def as_schema(c: dict[str, Any], schema: type) -> Any:
    """A composed config (plain dict, already resolved) as the schema's dataclass, types checked.
    Its values are taken as they are: a ``${...}`` left in one after the composition resolved the
    config is text (a file named ``${HOME}.csv``), not resolved a second time."""
    from omegaconf import OmegaConf

    return OmegaConf.to_object(OmegaConf.merge(OmegaConf.structured(schema), _literal_values(c)))
