"""Sensor recordings, schema v1: a CSV or Parquet table plus a JSON sidecar, validated on I/O.

Table columns: ``time_s`` (strictly increasing, counted from the power-on: never negative),
``temperature_c`` (the sensor's thermometer), ``input`` (applied acceleration in g, or applied
rate in deg/s), ``output`` (in the kind's unit: an MSRA's frequency difference in Hz, a gyro's
rate in deg/s, an accelerometer's g) and, for accelerometer kinds, an optional ``position`` (``+0g``, ``+1g``, ``-0g``, ``-1g``, or empty outside
a four-position test). Other columns are rejected. The kinds are :mod:`tcbench.sensors.kinds`.
The sidecar ``<stem>.json`` holds the sensor kind, units, sample rate, device id and a free-form
``extra`` object; it is optional when reading and always written. One key of ``extra`` has a
contract: ``axis``, the sensor axis a single-axis recording measures (``x``, ``y`` or ``z``), or
absent when unknown (:func:`recording_axis`).

Every problem raises :class:`RecordingError` with one line naming the file and, where it applies,
the row and column. Rows are numbered like a user counts data rows: the first row below the
header is row 1, so CSV row ``n`` is line ``n + 1`` of the file.

The schema and its checks live in :mod:`tcbench.sensors.recording_schema`, the file formats in
:mod:`tcbench.sensors.recording_files`; this module is the public API and re-exports the schema's
public names.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tcbench.errors import file_problem

from tcbench.sensors.recording_files import (
    _atomic_write,
    _format,
    _json_default,
    _load_json,
    _read_csv,
    _read_parquet,
    _write_json,
    _write_table,
)
from tcbench.sensors.recording_schema import (
    COLUMNS,
    FORMATS,
    NUMERIC_COLUMNS,
    POSITIONS,
    RATE_TOLERANCE,
    SCHEMA_VERSION,
    RecordingError,
    RecordingMeta,
    _check_consistency,
    _check_table,
    _in_file,
    _meta_from_dict,
    _normalise,
    _positions,
    check_sensor,
    known_units,
    standard_units,
)

__all__ = [
    "AXES",
    "COLUMNS",
    "FORMATS",
    "NUMERIC_COLUMNS",
    "POSITIONS",
    "RATE_TOLERANCE",
    "SCHEMA_VERSION",
    "Recording",
    "RecordingError",
    "RecordingMeta",
    "check_axis",
    "check_sensor",
    "known_units",
    "make_recording",
    "read_recording",
    "recording_axis",
    "sidecar_path",
    "standard_units",
    "write_recording",
]


@dataclass
class Recording:
    """A recording table (columns of :data:`COLUMNS`, row order = time order) and its metadata."""

    data: pd.DataFrame
    meta: RecordingMeta = field(default_factory=RecordingMeta)

    @property
    def samples(self) -> int:
        """Number of rows (samples)."""
        return len(self.data)

    @property
    def time_s(self) -> np.ndarray:
        """Sample times in s."""
        return self.data["time_s"].to_numpy(dtype=np.float64)

    @property
    def temperature_c(self) -> np.ndarray:
        """Thermometer reading in degC."""
        return self.data["temperature_c"].to_numpy(dtype=np.float64)

    @property
    def input(self) -> np.ndarray:
        """Applied stimulus in the kind's input unit: acceleration in g, or rate in deg/s."""
        return self.data["input"].to_numpy(dtype=np.float64)

    @property
    def output(self) -> np.ndarray:
        """Sensor output in the kind's output unit: Hz (MSRA), deg/s (gyro), g (accel)."""
        return self.data["output"].to_numpy(dtype=np.float64)

    @property
    def position(self) -> np.ndarray | None:
        """Position labels (object array of str, ``None`` where empty), or ``None`` without the column."""
        if "position" not in self.data:
            return None
        return _positions(self.data["position"])

    def validate(self) -> None:
        """Raise :class:`RecordingError` unless the recording can be written as schema v1."""
        _checked(self, None, None)


def make_recording(
    time_s: np.ndarray,
    temperature_c: np.ndarray,
    input: np.ndarray,  # noqa: A002 - the schema's column name
    output: np.ndarray,
    *,
    sensor: str,
    sample_rate_hz: float,
    device_id: str,
    position: np.ndarray | list[str | None] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> Recording:
    """Build and validate a recording from arrays, with the standard units of ``sensor``.

    Contiguous float64 arrays become the table's columns without a copy (the recording then
    shares them with the caller); anything else, broadcast views included, is copied once."""
    check_sensor(sensor)
    columns: dict[str, Any] = {"time_s": time_s, "temperature_c": temperature_c, "input": input, "output": output}
    columns = {k: np.ascontiguousarray(v, dtype=np.float64).reshape(-1) for k, v in columns.items()}
    if position is not None:
        columns["position"] = pd.Series(np.asarray(position, dtype=object).reshape(-1), dtype=object)
    meta = RecordingMeta(sensor, standard_units(sensor), float(sample_rate_hz), device_id,
                         extra=dict(extra or {}))
    rec = Recording(pd.DataFrame(columns, copy=False), meta)
    rec.data = _checked(rec, None, None)[0]
    return rec


AXES = ("x", "y", "z")


def check_axis(axis: Any) -> str:
    """``axis`` if it names a sensor axis (x, y or z), else one line saying what it must be."""
    if not isinstance(axis, str) or axis not in AXES:
        raise RecordingError(f"axis must be x, y or z, got {axis!r}")
    return axis


def recording_axis(meta: RecordingMeta) -> str | None:
    """The sensor axis (x, y or z) a recording's sidecar states in ``extra.axis``; None when it
    states none. Any other value is a :class:`RecordingError`."""
    if "axis" not in meta.extra:
        return None
    try:
        return check_axis(meta.extra["axis"])
    except RecordingError as err:
        raise RecordingError(f"extra.axis: {err.problem}") from None


def sidecar_path(path: str | Path) -> Path:
    """The sidecar of a table: ``rec.csv`` and ``rec.parquet`` both map to ``rec.json``."""
    return Path(path).with_suffix(".json")


def sidecar_present(side: Path) -> bool:
    """True when the sidecar ``side`` is there to be read, False when there is none (it is
    optional); a :class:`RecordingError` when something else is in its place (a folder, a
    broken link, a device): a sidecar the user may think is read."""
    if side.is_file():
        return True
    if not os.path.lexists(side):
        return False
    what = "a directory" if side.is_dir() else "a broken link" if side.is_symlink() and not side.exists() else \
        "not a regular file"
    raise RecordingError(f"is {what}, not a sidecar (the recording's sidecar is optional: remove it, or put the "
                         "sidecar there)")


def write_recording(rec: Recording, path: str | Path) -> Path:
    """Validate ``rec`` and write it to ``path`` (``.csv`` or ``.parquet``) plus its sidecar.

    Both files are written to temporary files in the target directory and renamed into place only
    once both are complete, so an invalid recording or a failed write leaves any earlier recording
    intact and no stray files (the two renames are not one atomic step; a crash between them leaves
    a new table with the old sidecar). CSV floats are written in shortest round-trip form.
    """
    path = Path(path)
    with _in_file(str(path)):
        fmt = _format(path)
    side = sidecar_path(path)
    data, doc = _checked(rec, str(path), str(side))
    try:
        text = json.dumps(doc, indent=2, allow_nan=False, default=_json_default) + "\n"
    except (TypeError, ValueError) as exc:
        raise RecordingError(f"extra is not JSON-serialisable ({exc})", file=str(side)) from None
    _atomic_write({path: lambda f: _write_table(data, f, fmt), side: lambda f: _write_json(text, f)})
    return path


def read_recording(path: str | Path) -> Recording:
    """Load and validate a recording and its sidecar (if present); raise :class:`RecordingError`.

    Row numbers in messages count data rows from 1 (the header is not a row): CSV row ``n`` is
    line ``n + 1`` of the file, Parquet row ``n`` is the ``n``-th record.
    """
    path, name = Path(path), str(path)
    with _in_file(name):
        if path.is_dir():
            raise RecordingError("is a directory, not a recording (give the .csv or .parquet file inside it)")
        fmt = _format(path)
        if problem := file_problem(path):
            raise RecordingError(problem)
        data = _read_csv(path) if fmt == ".csv" else _read_parquet(path)
        _check_table(data)
    side = sidecar_path(path)
    meta = RecordingMeta()
    with _in_file(str(side)):
        if sidecar_present(side):
            meta = _meta_from_dict(_load_json(side))
    _check_consistency(data, meta, name, str(side))
    return Recording(data, meta)


# -- validation shared by reading and writing ----------------------------------------------------
def _checked(rec: Recording, table: str | None, side: str | None) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Normalised table and sidecar document of ``rec``, after every check of reading."""
    with _in_file(table):
        data = _normalise(rec.data)
        _check_table(data)
    doc = {"schema_version": rec.meta.schema_version, "sensor": rec.meta.sensor, "units": dict(rec.meta.units),
           "sample_rate_hz": rec.meta.sample_rate_hz, "device_id": rec.meta.device_id, "extra": dict(rec.meta.extra)}
    with _in_file(side):
        meta = _meta_from_dict(doc)
    _check_consistency(data, meta, table, side)
    return data, doc
