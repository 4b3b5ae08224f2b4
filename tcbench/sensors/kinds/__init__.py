"""Sensor kinds: what a kind of sensor measures, in which units, and how it is simulated.

A kind is one :class:`SensorKind`, declared in one module. The built-in kinds are
:mod:`~tcbench.sensors.kinds.msra` (seed 000's resonant accelerometer, output in Hz),
:mod:`~tcbench.sensors.kinds.gyro` (seed 001's dual-mass gyroscope, deg/s) and
:mod:`~tcbench.sensors.kinds.accel` (a capacitive MEMS accelerometer, g). A package adds a kind
with an entry point in the group ``tcbench.sensor_kinds`` naming its ``SensorKind`` object
(``mykind = "mypkg.kind:KIND"``), or at run time with :func:`register`. Everything else in
tcbench (the recording schema, the importer, ``simulate``, ``metrics``, ``diagnose``,
``calibrate``) asks this registry instead of naming kinds.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any

BUILTIN = ("msra", "gyro", "accel")
DEFAULT = BUILTIN[0]  # the kind a simulation makes when it names none
ENTRY_POINT_GROUP = "tcbench.sensor_kinds"
INPUT_FIELDS = ("accel_g", "rate_dps")  # the Profile/Signals field a kind's input is
REPORTS = ("inertial", "zero_bias", "rate")  # the metrics ``tcbench metrics`` reads off a run (SensorKind.report)


@dataclass(frozen=True)
class SensorKind:
    """One kind of sensor.

    name: its id in sidecars, configs and commands (``sensor=accel``).
    title: what it is, in words.
    input_unit, output_unit: the recording schema's units of ``input`` and ``output`` (units
        :mod:`tcbench.sensors.units` can convert to: ``g``, ``deg/s``, ``Hz``).
    input_field: which applied input the simulator feeds it: ``accel_g`` (acceleration along
        the sensitive axis, with ``cross_g`` across it) or ``rate_dps``.
    input_range, output_range: plausible values in the schema units; beyond them a value is a
        unit mistake, not a measurement.
    device: device seed -> simulated :class:`~tcbench.sensors.models.Unit`.
    protocols: protocol name -> profile builder (:mod:`tcbench.sensors.protocols`).
    positions: whether recordings may carry position labels (+0g, +1g, -0g, -1g): the unit can be
        turned through gravity (a test may cycle its input through +1, 0, -1 g).
    input_step: the input step (input unit) of the truth's sensitivity difference.
    noise_unit, noise_scale: the unit bias and noise figures are reported in, and the factor
        from the output unit to it (``°/h``, 3600 for a gyro in deg/s).
    ulog_topic, ulog_unit: PX4's topic of this kind and the unit it logs the axes in.
    px4_letter: the letter of PX4's thermal-calibration parameters (``TC_G*``, ``TC_A*``).
    px4_cal: the kind's name in PX4's sensor-calibration parameters (``CAL_GYROn_ID``, ``CAL_ACCn_ID``).
    ardupilot_letters: the letters of ArduPilot's temperature-calibration parameters
        (``INS_TCALn_GYR*``, ``INS_TCALn_ACC*``); None: ArduPilot calibrates no such kind.
    report: the metrics ``tcbench metrics`` reads off a run without complete four-position groups
        (:data:`REPORTS`): ``inertial``, the bias (output less the applied input) in ``noise_unit``:
        its stability, noise density, bias instability, slope against temperature and hysteresis;
        ``zero_bias``, seed 000's zero-bias stability in µg through the device's scale factor;
        ``rate``, seed 001's Allan read-offs in °/h, the 60 → -40 °C drift and the rate against
        temperature.
    nominal_scale_factor: the output per input unit assumed when a recording's sidecar gives none
        (``scale_factor_hz_per_g``): 1 for a kind whose output is in its input's unit.
    default_protocol: the protocol ``tcbench simulate`` runs when none is given (None: the first
        of ``protocols``).
    power_on: what a new power-on changes in a unit's model, ``(model, rng) -> (model as it runs,
        {draw: value})`` (turn-on bias and scale factor, docs/concepts/split-tiers.md; :mod:`tcbench.sensors.runs`);
        None: the model is the same at every power-on (the chamber timing and the thermometer
        still vary).
    """

    name: str
    title: str
    input_unit: str
    output_unit: str
    input_field: str
    input_range: tuple[float, float]
    output_range: tuple[float, float]
    device: Callable[[int], Any]
    protocols: Mapping[str, Callable[..., Any]]
    positions: bool = False
    input_step: float = 1e-3
    noise_unit: str = ""
    noise_scale: float = 1.0
    ulog_topic: str | None = None
    ulog_unit: str | None = None
    px4_letter: str | None = None
    px4_cal: str | None = None
    ardupilot_letters: str | None = None
    report: str = "inertial"
    nominal_scale_factor: float = 1.0
    extra: Mapping[str, Any] = field(default_factory=dict)
    default_protocol: str | None = None
    power_on: Callable[[Any, Any], tuple[Any, dict[str, float]]] | None = None

    def __post_init__(self) -> None:
        if self.input_field not in INPUT_FIELDS:
            raise ValueError(f"sensor kind {self.name!r}: input_field must be one of {', '.join(INPUT_FIELDS)}, "
                             f"got {self.input_field!r}")
        if not self.protocols:
            raise ValueError(f"sensor kind {self.name!r} has no protocol")
        if self.report not in REPORTS:
            raise ValueError(f"sensor kind {self.name!r}: report must be one of {', '.join(REPORTS)}, "
                             f"got {self.report!r}")
        if self.default_protocol is None:
            object.__setattr__(self, "default_protocol", next(iter(self.protocols)))
        elif self.default_protocol not in self.protocols:
            raise ValueError(f"sensor kind {self.name!r}: default_protocol {self.default_protocol!r} is not one of its "
                             f"protocols ({', '.join(self.protocols)})")

    @property
    def scaled(self) -> bool:
        """Whether its output is in another unit than its input (an MSRA's Hz for g): read as the
        input, it needs the device's scale factor (a recording's ``scale_factor_hz_per_g``)."""
        return self.input_unit != self.output_unit

    @property
    def units(self) -> dict[str, str]:
        """The schema units of its recordings' numeric columns."""
        return {"time_s": "s", "temperature_c": "degC", "input": self.input_unit, "output": self.output_unit}


_added: dict[str, SensorKind] = {}


@functools.cache
def _installed() -> dict[str, SensorKind]:
    """The built-in kinds, then those of installed packages (entry points)."""
    found = {name: importlib.import_module(f"{__name__}.{name}").KIND for name in BUILTIN}
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in found:
            continue  # a built-in name is never replaced
        kind = ep.load()
        if not isinstance(kind, SensorKind) or kind.name != ep.name:
            raise TypeError(f"entry point {ep.name} = {ep.value} in {ENTRY_POINT_GROUP} must name a SensorKind "
                            f"called {ep.name!r}")
        found[ep.name] = kind
    return found


def registry() -> dict[str, SensorKind]:
    """Every kind by name: built-in, installed, then registered at run time."""
    return {**_installed(), **_added}


def register(kind: SensorKind) -> SensorKind:
    """Add ``kind`` for this process (a name already known is refused)."""
    if kind.name in registry():
        raise ValueError(f"sensor kind {kind.name!r} already exists")
    _added[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Remove a kind added with :func:`register` (tests and notebooks)."""
    _added.pop(name, None)


def names() -> list[str]:
    """The known kinds' names."""
    return list(registry())


def known(name: object) -> bool:
    """Whether ``name`` is a known kind's name."""
    return isinstance(name, str) and name in registry()


def get(name: str) -> SensorKind:
    """The kind ``name``, or a ``ValueError`` listing the known ones."""
    kinds = registry()
    if name not in kinds:
        from tcbench.errors import unknown_name

        raise ValueError(unknown_name("sensor", name, kinds))
    return kinds[name]


def unit(sensor: str, device_seed: int) -> Any:
    """The unit ``device_seed`` of sensor kind ``sensor`` (a :class:`~tcbench.sensors.models.Unit`)."""
    return get(sensor).device(device_seed)


def profile_input(profile: Any) -> Any:
    """The recorded ``input`` column of a :class:`~tcbench.sensors.protocols.Profile`: the applied
    input its sensor kind measures (acceleration in g, or rate in deg/s)."""
    return getattr(profile, get(profile.sensor).input_field)
