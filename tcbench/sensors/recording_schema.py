"""Recording schema v1: its constants, :class:`RecordingError`, :class:`RecordingMeta` and the checks.

Validation shared by reading and writing: column names, normalisation to the canonical table,
row-level table checks, sidecar parsing, units and sidecar-against-table consistency. The file
layout itself is described in :mod:`tcbench.sensors.recording`.
"""

from __future__ import annotations

import contextlib
import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tcbench.errors import listed, unknown_name
from tcbench.sensors import kinds

SCHEMA_VERSION = 1
POSITIONS = ("+0g", "+1g", "-0g", "-1g")
NUMERIC_COLUMNS = ("time_s", "temperature_c", "input", "output")
COLUMNS = (*NUMERIC_COLUMNS, "position")
FORMATS = (".csv", ".parquet")
RATE_TOLERANCE = 0.01
TIME_LIMIT_S = 1.0e10  # |time_s| beyond this (317 years) is a unit mistake or a glitch, not a clock
GAP_LIMIT = 1.0e4  # a step longer than this many times the time all samples cover is a clock glitch
_SIDECAR_KEYS = ("schema_version", "sensor", "units", "sample_rate_hz", "device_id")


class RecordingError(ValueError):
    """A recording breaks schema v1; ``str(err)`` is one line: ``file: row r, column 'c': problem``."""

    def __init__(self, problem: str, *, file: str | None = None, row: int | None = None,
                 column: str | None = None) -> None:
        self.problem, self.file, self.row, self.column = problem, file, row, column
        where = ", ".join(p for p in (row and f"row {row}", column and f"column {column!r}") if p)
        message = ": ".join(p for p in (file, where, problem) if p)
        super().__init__(" ".join(message.splitlines()))

    def located(self, file: str) -> RecordingError:
        """The same error attributed to ``file`` (kept if it already names one)."""
        return self if self.file else RecordingError(self.problem, file=file, row=self.row, column=self.column)


@dataclass(frozen=True)
class RecordingMeta:
    """Sidecar contents; ``RecordingMeta()`` (sensor ``None``) stands for "no sidecar, unknown"."""

    sensor: str | None = None
    units: dict[str, str] = field(default_factory=dict)
    sample_rate_hz: float | None = None
    device_id: str | None = None
    schema_version: int = SCHEMA_VERSION
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def known(self) -> bool:
        """True when the sensor kind (and so the units) is known."""
        return self.sensor is not None


# -- validation shared by reading and writing ----------------------------------------------------
@contextlib.contextmanager
def _in_file(name: str | None) -> Iterator[None]:
    """Attribute :class:`RecordingError` raised inside the block to file ``name``."""
    try:
        yield
    except RecordingError as err:
        if name is None:
            raise
        raise err.located(name) from None


def _check_columns(names: list[str]) -> None:
    """Required columns present, no unknown or duplicate ones."""
    dup = sorted(c for c, n in Counter(names).items() if n > 1)
    if dup:
        raise RecordingError(f"duplicate column {dup[0]!r}")
    unknown = [c for c in names if c not in COLUMNS]
    missing = [c for c in NUMERIC_COLUMNS if c not in names]
    if missing:
        also = f" (found unknown {listed(unknown)})" if unknown else ""
        raise RecordingError(f"missing column {missing[0]!r}{also}")
    if unknown:
        allowed = ", ".join(COLUMNS)
        raise RecordingError(f"unknown column {listed(unknown)} (schema v1 allows only {allowed})")


def _normalise(data: pd.DataFrame) -> pd.DataFrame:
    """Canonical table: columns in schema order, float64 numbers, object positions (str or None).
    Float64 columns are shared with ``data``, not copied."""
    _check_columns([str(c) for c in data.columns])
    out = {}
    for c in NUMERIC_COLUMNS:
        if data[c].dtype.kind not in "iuf":
            raise RecordingError(f"holds {data[c].dtype} values, expected numbers", column=c)
        out[c] = data[c].to_numpy(dtype=np.float64, na_value=np.nan)
    if "position" in data:
        out["position"] = pd.Series(_positions(data["position"]), dtype=object)
    return pd.DataFrame(out, copy=False)


def _positions(col: pd.Series) -> np.ndarray:
    """Position labels as an object array, with ``None`` for missing or empty cells."""
    labels = col.to_numpy(dtype=object, na_value=None, copy=True)
    labels[labels == ""] = None
    return labels


def _check_table(data: pd.DataFrame) -> None:
    """Row-level checks of a normalised table: rows present, finite numbers, positions, time."""
    if len(data) == 0:
        raise RecordingError("no data rows")
    columns = {c: data[c].to_numpy(dtype=np.float64) for c in NUMERIC_COLUMNS}  # views, column by column
    rows = [int(np.argmin(np.isfinite(x))) for x in columns.values()]
    first = [(i, c) for i, (c, x) in zip(rows, columns.items(), strict=True) if not np.isfinite(x[i])]
    if first:
        i, c = min(first)  # the first bad row; within it, the first column in schema order
        raise RecordingError(f"{columns[c][i]} is not finite", row=i + 1, column=c)
    if "position" in data:
        labels = pd.Series(data["position"].to_numpy(dtype=object), dtype=object)
        wrong = ~(labels.isna() | labels.isin(POSITIONS)).to_numpy()
        if wrong.any():
            i = int(np.argmax(wrong))
            raise RecordingError(f"{labels[i]!r} is not a position (expected one of {', '.join(POSITIONS)} or empty)",
                                 row=i + 1, column="position")
    t = columns["time_s"]
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0])
        prev, cur = float(t[i]), float(t[i + 1])
        problem = (f"duplicate time_s {cur!r} (same as row {i + 1})" if cur == prev
                   else f"time_s goes back from {prev!r} to {cur!r}")
        raise RecordingError(problem, row=i + 2, column="time_s")
    _check_clock(t)


def _check_clock(t_s: np.ndarray) -> None:
    """An increasing clock that a sample rate can describe: every time within
    :data:`TIME_LIMIT_S` and none negative (the clock counts from the power-on), and no gap longer than :data:`GAP_LIMIT` times the time the samples
    cover at the median step (``n * step``). A logger's bursts pass: their gaps are minutes
    between seconds of data, not years after a minute; a uniform grid over the clock then stays
    within ``GAP_LIMIT`` times the samples per gap."""
    far = np.abs(t_s) > TIME_LIMIT_S
    if far.any():
        i = int(np.argmax(far))
        raise RecordingError(f"{t_s[i]:g} s is not a plausible time (beyond ±{TIME_LIMIT_S:g} s, 317 years; "
                             "ms or µs given as s?)", row=i + 1, column="time_s")
    if t_s.size and t_s[0] < 0.0:  # the clock increases: the first time is the earliest
        raise RecordingError(f"{t_s[0]:g} s is before the power-on: time_s counts from it (the warm-up and "
                             "ageing of a sensor model are functions of it), so no time may be negative; "
                             "shift the clock to start at 0 or later", row=1, column="time_s")
    if t_s.size < 3:
        return
    dt = np.diff(t_s)
    i = int(np.argmax(dt))
    gap_s = float(dt[i])
    step_s = float(np.median(dt, overwrite_input=True))  # reorders dt, read before
    covered_s = t_s.size * step_s
    if gap_s > GAP_LIMIT * covered_s:
        raise RecordingError(f"a gap of {gap_s:.3g} s after {step_s:.3g} s steps: more than {GAP_LIMIT:g} times the "
                             f"{covered_s:.3g} s the {t_s.size} samples cover at that step (a clock glitch?)",
                             row=i + 2, column="time_s")


def _meta_from_dict(doc: Any) -> RecordingMeta:
    """Validate a sidecar document (parsed JSON) and build its :class:`RecordingMeta`."""
    if not isinstance(doc, dict):
        raise RecordingError("the sidecar must hold a JSON object")
    if "schema_version" not in doc:
        raise RecordingError("missing key 'schema_version'")
    version = doc["schema_version"]
    if version != SCHEMA_VERSION or isinstance(version, bool):
        raise RecordingError(f"unknown schema_version {version!r} (this tcbench reads {SCHEMA_VERSION})")
    for key in _SIDECAR_KEYS:
        if key not in doc:
            raise RecordingError(f"missing key {key!r}")
    unknown = [k for k in doc if k not in (*_SIDECAR_KEYS, "extra")]
    if unknown:
        raise RecordingError(f"unknown key {unknown[0]!r} (free-form data goes under 'extra')")
    sensor = doc["sensor"]
    check_sensor(sensor)
    units = _check_units(doc["units"], sensor)
    rate = doc["sample_rate_hz"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
        raise RecordingError(f"sample_rate_hz must be a positive number, got {rate!r}")
    device = doc["device_id"]
    if not isinstance(device, str) or not device:
        raise RecordingError(f"device_id must be a non-empty string, got {device!r}")
    extra = doc.get("extra", {})
    if not isinstance(extra, dict):
        raise RecordingError(f"extra must be a JSON object, got {extra!r}")
    return RecordingMeta(sensor, units, float(rate), device, SCHEMA_VERSION, extra)


def check_sensor(sensor: Any) -> None:
    """A known sensor kind, or one line naming the known ones."""
    if not kinds.known(sensor):
        raise RecordingError(unknown_name("sensor", sensor, kinds.names()))


def standard_units(sensor: str) -> dict[str, str]:
    """The schema units of a ``sensor`` recording's numeric columns."""
    check_sensor(sensor)
    return kinds.get(sensor).units


def known_units(column: str) -> tuple[str, ...]:
    """Every schema unit ``column`` has in some kind."""
    return tuple(dict.fromkeys(kind.units[column] for kind in kinds.registry().values()))


def _check_units(units: Any, sensor: str) -> dict[str, str]:
    """Every column's unit known to the schema and the one of ``sensor``."""
    if not isinstance(units, dict):
        raise RecordingError(f"units must be a JSON object, got {units!r}")
    extra = [c for c in units if c not in NUMERIC_COLUMNS]
    if extra:
        raise RecordingError(f"units for unknown column {extra[0]!r} (expected {', '.join(NUMERIC_COLUMNS)})")
    for c in NUMERIC_COLUMNS:
        if c not in units:
            raise RecordingError("no unit given", column=c)
        unit, expected = units[c], standard_units(sensor)[c]
        if unit not in known_units(c):
            raise RecordingError(f"unknown unit {unit!r}; accepted: {', '.join(known_units(c))}", column=c)
        if unit != expected:
            raise RecordingError(f"unit {unit!r} does not fit a {sensor} recording (expected {expected!r})", column=c)
    return {c: units[c] for c in NUMERIC_COLUMNS}


# Plausible temperatures (test chambers run -70..+180 degC); beyond them a value is a unit mistake
# (kelvin labelled degC) rather than a measurement. Each kind states its input's and output's.
PLAUSIBLE_TEMPERATURE_C = (-100.0, 200.0)


def plausible_ranges(sensor: str | None) -> dict[str, tuple[float, float, str]]:
    """Column -> (low, high, unit) beyond which a value is a unit mistake (mdps labelled deg/s,
    mg labelled g, ...), not a measurement."""
    ranges = {"temperature_c": (*PLAUSIBLE_TEMPERATURE_C, "degC")}
    if kinds.known(sensor):
        kind = kinds.get(str(sensor))
        ranges |= {"input": (*kind.input_range, kind.input_unit), "output": (*kind.output_range, kind.output_unit)}
    return ranges


def _check_plausible(data: pd.DataFrame, sensor: str | None, table: str | None) -> None:
    """Every value within :func:`plausible_ranges` for its column's unit; the first outside
    names file, row and column."""
    ranges = plausible_ranges(sensor)
    for column, (low, high, unit) in ranges.items():
        x = data[column].to_numpy(dtype=np.float64)
        bad = (x < low) | (x > high)
        if bad.any():
            i = int(np.argmax(bad))
            hint = " (kelvin?)" if column == "temperature_c" and 173.0 <= x[i] <= 473.0 else ""
            raise RecordingError(f"{x[i]:g} {unit} is not plausible for a {sensor or 'sensor'} recording "
                                 f"(expected {low:g}..{high:g} {unit}){hint}", file=table, row=i + 1, column=column)


def _check_consistency(data: pd.DataFrame, meta: RecordingMeta, table: str | None, side: str | None) -> None:
    """Sidecar against table: plausible values for the units, sample rate vs the median time
    step, positions only for kinds that have them."""
    _check_plausible(data, meta.sensor, table)
    if meta.sensor is not None and not kinds.get(meta.sensor).positions and "position" in data:
        given = data["position"].notna().to_numpy()
        if given.any():
            raise RecordingError(f"{meta.sensor} recordings have no positions", file=table,
                                 row=int(np.argmax(given)) + 1, column="position")
    t = data["time_s"].to_numpy()
    if meta.sample_rate_hz is None or t.size < 2:
        return
    step_s = float(np.median(np.diff(t), overwrite_input=True))
    if abs(1.0 / step_s - meta.sample_rate_hz) > RATE_TOLERANCE * meta.sample_rate_hz:
        raise RecordingError(
            f"sample_rate_hz {meta.sample_rate_hz:g} does not match the table: its median time step "
            f"{step_s:.6g} s means {1.0 / step_s:.6g} Hz (they must agree within 1 %)", file=side)
