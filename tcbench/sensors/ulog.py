"""PX4 ULog files (``.ulg``, read with pyulog) as recordings: the sensor topic of a kind
(``sensor_gyro`` for a gyro, ``sensor_accel`` for an accelerometer), every instance (one per
physical sensor), each axis a recording with the topic's own clock and temperature.

A topic instance is a table of fields (``timestamp``, ``timestamp_sample`` in µs since boot,
``x``, ``y``, ``z``, ``temperature`` in °C, ...); the default column map reads the sample clock,
the temperature and the three axes in PX4's units (rad/s for ``sensor_gyro``, m/s^2 for
``sensor_accel``), and any field can be named instead, with a unit, as for a CSV file
(:func:`tcbench.sensors.importer.import_table`). The fields ``x``, ``y``, ``z`` are the sensor's
axes: :func:`field_axis` names the axis a field is.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tcbench.errors import file_problem
from tcbench.sensors import kinds
from tcbench.sensors.recording import AXES, RecordingError


@dataclass(frozen=True)
class TopicInstance:
    """One instance of a sensor topic: its fields as pyulog read them (each in its logged type: the
    import converts the columns it uses, so no field is held twice), and the ``device_id`` PX4 logged."""

    topic: str
    instance: int
    fields: dict[str, np.ndarray]
    device_id: int | None


def default_columns(fields: list[str]) -> dict[str, str]:
    """The column map of a topic in PX4's units: the sample clock (else the publication clock),
    the temperature; the axes are :func:`default_axes`."""
    clock = "timestamp_sample" if "timestamp_sample" in fields else "timestamp"
    return {"time_s": f"{clock}:us", "temperature_c": "temperature:degC"}


def topics() -> dict[str, tuple[str, str]]:
    """Sensor kind -> its PX4 topic and the unit PX4 logs the axes in (kinds that have one)."""
    return {k.name: (k.ulog_topic, k.ulog_unit or k.output_unit) for k in kinds.registry().values() if k.ulog_topic}


def default_axes(sensor: str) -> list[str]:
    """``x:UNIT``, ``y:UNIT``, ``z:UNIT`` in the unit PX4 logs the sensor's topic in."""
    unit = topics()[sensor][1]
    return [f"{a}:{unit}" for a in AXES]


def field_axis(field: str) -> str | None:
    """The sensor axis of a topic field (``x``, ``y`` or ``z``), None for any other field."""
    return field if field in AXES else None


def read_topic(path: str | Path, sensor: str) -> list[TopicInstance]:
    """Every instance of ``sensor``'s topic in the ULog file ``path``, in instance order;
    :class:`RecordingError` (one line, the file named) when the file cannot be read or holds none."""
    path = Path(path)
    known = topics()
    if sensor not in known:
        raise RecordingError(f"a PX4 log has no topic tcbench reads for sensor {sensor!r} "
                             f"(it reads: {', '.join(f'{k} from {v[0]}' for k, v in known.items())})", file=str(path))
    topic = known[sensor][0]
    if path.is_dir():
        raise RecordingError("is a directory, not a ULog file", file=str(path))
    if problem := file_problem(path):
        raise RecordingError(problem, file=str(path))
    from pyulog import ULog

    try:
        log = ULog(str(path), [topic])
    except Exception as exc:  # noqa: BLE001 - pyulog raises many kinds for a file that is not a ULog
        raise RecordingError(f"cannot read the file as a PX4 ULog ({type(exc).__name__}: {exc})", file=str(path)) from None
    found = sorted((d for d in log.data_list if d.name == topic), key=lambda d: d.multi_id)
    if not found:
        raise RecordingError(f"the log has no {topic} topic", file=str(path))
    out = []
    for d in found:
        ids = d.data.get("device_id")
        device_id = int(ids[0]) if ids is not None and len(ids) else None
        out.append(TopicInstance(topic, int(d.multi_id), dict(d.data), device_id))
    return out
