"""Bring your own data: a CSV table with columns of any name and common units, as a schema-v1 recording.

A column map names the file's column for each schema column, with the unit after a colon
(``sensor_time_ms:ms``, ``gyro_x_rads:rad/s``, ``gyro_x:mrad/s``). A unit is never assumed: a
column without one takes it from a ``units`` map (by schema column) or from a tcbench sidecar
beside the file that states its columns' units, and is refused otherwise; where two of them state
a column's unit they must agree. Values are converted to the schema units through pint
(:mod:`tcbench.sensors.units`: any unit of the right dimension), rows can be dropped where
a flag column is nonzero, and the result goes through every check of the schema
(:func:`~tcbench.sensors.recording.make_recording`: finite values, strictly increasing time,
plausible values for the unit, sample rate). Every problem raises :class:`RecordingError` in one
line naming the CSV file and, where it applies, its row (data rows counted from 1 below the
header, as in the file, dropped rows included) and its column (the file's name for it).
The sensor axis an output measures, when given (never guessed from a column's name), is written
to the sidecar's ``extra.axis``.

Gaps in the clock are kept: a recording of bursts is split into segments
(:mod:`tcbench.sensors.segments`), listed in the sidecar's ``extra.segments`` (first row in the
recording, samples, start and stop time of each), and the sample rate is the rate inside the
segments (to six significant digits).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv

from tcbench.errors import file_problem, meant
from tcbench.sensors.recording import (
    NUMERIC_COLUMNS,
    AXES,
    Recording,
    RecordingError,
    RecordingMeta,
    check_axis,
    check_sensor,
    make_recording,
    sidecar_path,
    sidecar_present,
    standard_units,
    write_recording,
)
from tcbench.sensors.recording_files import (
    CHUNK_BYTES,
    _check_fields,
    _diagnose_csv,
    _header_names,
    _load_json,
    _scan_text,
    sniff_delimiter,
)
from tcbench.sensors.recording_schema import _meta_from_dict
from tcbench.sensors.segments import GAP_FACTOR, gap_bounds, gaps, within_rate_hz
from tcbench.sensors.units import Conversion, UnitError, conversion
from tcbench.staging import staged_dir


REQUIRED = ("time_s", "temperature_c", "output")


@dataclass(frozen=True)
class Column:
    """One schema column taken from a file's column ``name`` in ``unit``."""

    target: str
    name: str
    unit: str
    convert: Conversion = Conversion()

    def describe(self) -> str:
        """``name [unit]`` as the sidecar records it."""
        return f"{self.name} [{self.unit}]"


KEYS = {"time_s": "time", "temperature_c": "temperature", "output": "output", "input": "input"}
"""Schema column -> the key that names its file column on the command line (``time=COL:unit``)."""
EXAMPLE_UNIT = {"s": "us", "degC": "degC", "deg/s": "rad/s", "Hz": "kHz", "g": "m/s^2"}  # a log's, for messages


@dataclass(frozen=True)
class StatedUnits:
    """Units stated apart from the column specs: ``given`` by schema column (a ``units`` map),
    ``sidecar`` by the file's column name (the tcbench sidecar ``sidecar_name`` beside the file,
    which may also state the ``sidecar_axis`` of its ``output``); ``no_sidecar`` says why a
    sidecar beside the file states none."""

    given: Mapping[str, str] = field(default_factory=dict)
    sidecar: Mapping[str, str] = field(default_factory=dict)
    sidecar_name: str = ""
    no_sidecar: str = ""
    sidecar_axis: str | None = None


def sidecar_units(path: Path, given: Mapping[str, str] | None = None) -> StatedUnits:
    """The units stated for the table at ``path``: ``given`` and those of a tcbench sidecar
    beside it (``<stem>.json`` holding a schema-v1 sidecar), by column name."""
    side = sidecar_path(path)
    stated = StatedUnits(dict(given or {}))
    try:
        if side == path or not sidecar_present(side):
            return stated
        meta = _meta_from_dict(_load_json(side))
    except (RecordingError, OSError) as exc:
        problem = exc.problem if isinstance(exc, RecordingError) else (exc.strerror or str(exc))
        return StatedUnits(stated.given, no_sidecar=f"{side.name} beside it states none: {problem}")
    axis = meta.extra.get("axis")
    return StatedUnits(stated.given, dict(meta.units), side.name, sidecar_axis=axis if axis in AXES else None)


def _sidecar_axis(spec: Mapping[str, Column], axis: str | None, stated: StatedUnits) -> str | None:
    """The axis of an output: ``axis`` as given, else the one the sidecar beside the file states
    for its ``output`` column when that is the column read; the two must agree."""
    if stated.sidecar_axis is None or spec["output"].name != "output":
        return axis
    if axis is not None and axis != stated.sidecar_axis:
        raise RecordingError(f"axis {axis} given, but the sidecar {stated.sidecar_name} says the output is the "
                             f"{stated.sidecar_axis} axis")
    return stated.sidecar_axis


def parse_column(target: str, spec: str, sensor: str, available: Sequence[str],
                 stated: StatedUnits | None = None) -> Column:
    """The file column and unit of ``spec`` (``name:unit``, or ``name`` with the unit ``stated``)
    for schema column ``target``; a name that exists in the file as written wins over splitting
    at its last colon. A unit stated nowhere, or stated twice differently, is an error."""
    schema_unit = standard_units(sensor)[target]
    name, unit = spec, ""
    if spec not in available and ":" in spec:
        name, unit = spec.rsplit(":", 1)
    if name not in available:
        raise RecordingError(f"no column {name!r} (for {target}); the file has: "
                             f"{', '.join(map(str, available))}" + meant(name, map(str, available)))
    unit = _stated_unit(target, spec, name, unit, sensor, stated or StatedUnits())
    try:
        convert = conversion(unit, schema_unit)
    except UnitError as exc:
        raise RecordingError(f"{exc}, for {target} of a {sensor} recording (in {schema_unit})", column=name) from None
    return Column(target, name, unit, convert)


def _stated_unit(target: str, spec: str, name: str, unit: str, sensor: str, stated: StatedUnits) -> str:
    """The one unit said for column ``name``: after its colon in ``spec``, in the ``units`` map or
    in the sidecar beside the file."""
    key, schema_unit = KEYS[target], standard_units(sensor)[target]
    said = [(u, how) for u, how in ((unit, f"{key}={spec}"), (stated.given.get(target, ""), f"units={{{key}:...}}"),
                                    (stated.sidecar.get(name, ""), f"the sidecar {stated.sidecar_name}")) if u]
    if not said:
        what = f"{sensor} {key}" if key in ("output", "input") else key
        example = EXAMPLE_UNIT.get(schema_unit, schema_unit)
        also = f"; {stated.no_sidecar}" if stated.no_sidecar else ""
        raise RecordingError(f"{key}={spec}: no unit; say it after a colon, e.g. {key}={name}:{example}, "
                             f"or units={{{key}:UNIT}} ({what} is stored in {schema_unit}){also}")
    first, how = said[0]
    for other, other_how in said[1:]:
        if not _same_unit(first, other, schema_unit):
            raise RecordingError(f"{how} says {first!r} but {other_how} says {other!r}; say one unit")
    return first


def _same_unit(a: str, b: str, schema_unit: str) -> bool:
    """True when ``a`` and ``b`` convert to ``schema_unit`` alike (a unit that does not convert is
    left to the conversion's own message)."""
    if a == b:
        return True
    try:
        ca, cb = conversion(a, schema_unit), conversion(b, schema_unit)
    except UnitError:
        return False
    return math.isclose(ca.mul, cb.mul, rel_tol=1e-12) and math.isclose(ca.offset, cb.offset, abs_tol=1e-9)


def _read(path: Path, used: Sequence[str], header: Sequence[str], delimiter: str = ","
          ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The ``used`` columns of a table (fields separated by ``delimiter``) as float64 (empty
    cells NaN) and a mask of the empty cells (rows x ``used``), read with pyarrow; a line with the
    wrong number of fields, a blank line or a cell that is not a number is located as the
    schema's reader does."""
    try:
        table = pcsv.read_csv(
            path,
            read_options=pcsv.ReadOptions(column_names=list(header), skip_rows=1, block_size=CHUNK_BYTES),
            parse_options=pcsv.ParseOptions(ignore_empty_lines=False, delimiter=delimiter),
            convert_options=pcsv.ConvertOptions(column_types=dict.fromkeys(used, pa.float64()),
                                                include_columns=list(used), null_values=[""],
                                                strings_can_be_null=True, quoted_strings_can_be_null=False),
        )
    except pa.ArrowInvalid as exc:
        _diagnose_csv(path, list(header), list(used), delimiter)
        raise RecordingError(f"cannot parse the table ({str(exc).splitlines()[0]})") from None
    empty = np.zeros((table.num_rows, len(used)), dtype=bool)
    if any(table[c].null_count for c in used):  # an empty cell, or a short or blank line
        _check_fields(path, list(header), delimiter)
        empty = np.column_stack([table[c].is_null().to_numpy(zero_copy_only=False) for c in used])
    return {c: table[c].to_numpy() for c in used}, empty


def _check_filled(empty: np.ndarray, used: Sequence[str], keep: np.ndarray) -> None:
    """Raise at the first empty cell (rows x ``used`` mask) of the kept rows."""
    if not empty.any():
        return
    kept = empty[keep]
    if kept.any():
        i, j = divmod(int(np.argmax(kept)), kept.shape[1])
        raise RecordingError("empty cell", row=int(np.flatnonzero(keep)[i]) + 1, column=used[j])


def _dropped(raw: Mapping[str, np.ndarray], drop: Sequence[str], n_rows: int) -> np.ndarray:
    """Rows to drop: where any ``drop`` column is nonzero (an empty or NaN flag is an error)."""
    out = np.zeros(n_rows, dtype=bool)
    for name in drop:
        flag = raw[name]
        unset = np.isnan(flag)
        if unset.any():
            raise RecordingError("a drop= column needs a number in every row (nonzero drops the row, 0 keeps it)",
                                 row=int(np.argmax(unset)) + 1, column=name)
        out |= flag != 0
    return out


def _in_csv(err: RecordingError, file: str, rows: np.ndarray, columns: Mapping[str, Column],
            table: Mapping[str, np.ndarray], sensor: str) -> RecordingError:
    """A schema error about the converted ``table``, told in the CSV's terms: its file, its row
    numbers (in the message too) and its column names, with the conversion behind a value."""
    def row(n: int) -> int:
        return int(rows[n - 1]) if 1 <= n <= rows.size else n

    col = columns.get(err.column or "")
    problem = re.sub(r"\brow (\d+)", lambda m: f"row {row(int(m.group(1)))}", err.problem)
    unit = standard_units(sensor)[col.target] if col is not None else None
    if col is not None and err.row and col.unit != unit and np.isfinite(table[col.target][err.row - 1]):
        problem += f" (after converting {col.unit} to {unit})"
    return RecordingError(problem, file=file, row=row(err.row) if err.row else None,
                          column=col.name if col is not None else err.column)


def import_csv(
    path: str | Path,
    sensor: str,
    columns: Mapping[str, str],
    *,
    units: Mapping[str, str] | None = None,
    axis: str | None = None,
    drop: Sequence[str] = (),
    device_id: str | None = None,
    sample_rate_hz: float | None = None,
) -> Recording:
    """A schema-v1 recording from the CSV table at ``path``.

    ``columns`` maps ``time_s``, ``temperature_c``, ``output`` and optionally ``input`` to a
    file column, ``name:unit`` (:mod:`tcbench.sensors.units`), or ``name`` when ``units`` (by
    schema column) or a tcbench sidecar beside the file states its unit; a missing ``input`` is 0.
    ``axis`` (x, y or z) is the sensor axis the output measures, written to ``extra.axis``. Rows
    where a ``drop`` column is nonzero are left out before any check. ``device_id`` defaults to
    the file's stem, ``sample_rate_hz`` to the rate inside the segments (one over the median
    interval). Raises :class:`RecordingError` naming the file, row and column.
    """
    shared = {k: v for k, v in columns.items() if k != "output"}
    return import_csv_axes(path, sensor, shared, [columns.get("output", "")], units=units, axes=[axis], drop=drop,
                           device_id=device_id, sample_rate_hz=sample_rate_hz)[0]


def import_csv_axes(path: str | Path, sensor: str, columns: Mapping[str, str], outputs: Sequence[str], *,
                    units: Mapping[str, str] | None = None, axes: Sequence[str | None] | None = None,
                    drop: Sequence[str] = (), device_id: str | None = None,
                    sample_rate_hz: float | None = None) -> list[Recording]:
    """One recording per ``outputs`` column of the table at ``path``, sharing the other
    ``columns`` (clock, temperature, input): the file is read once. ``axes`` gives each output's
    sensor axis (x, y, z or None: not recorded). As :func:`import_csv` otherwise."""
    path = Path(path)
    name = str(path)
    axes = list(axes) if axes is not None else [None] * len(outputs)
    _check_axes(axes, outputs)
    for output in outputs:
        _check_request(sensor, {**columns, "output": output})
    try:
        if path.is_dir():
            raise RecordingError("is a directory, not a CSV file")
        if problem := file_problem(path):
            raise RecordingError(problem)
        delimiter = sniff_delimiter(path)
        header = _header_names(path, delimiter)
        _scan_text(path, header, delimiter)
        stated = sidecar_units(path, units)
        specs = [_spec({**columns, "output": output}, drop, sensor, header, stated) for output in outputs]
        used = list(dict.fromkeys(c for _, spec_used in specs for c in spec_used))
        twice = [c for c in used if header.count(c) > 1]
        if twice:
            raise RecordingError(f"the header names column {twice[0]!r} more than once")
        axes = [_sidecar_axis(spec, axis, stated) for (spec, _), axis in zip(specs, axes, strict=True)]
        raw, empty = _read(path, used, header, delimiter)
    except RecordingError as err:
        raise err.located(name) from None
    return [_recording({c: raw[c] for c in spec_used}, empty[:, [used.index(c) for c in spec_used]], spec, drop,
                       sensor, name, {"file": path.name, "delimiter": delimiter}, device_id or path.stem,
                       sample_rate_hz, axis)
            for (spec, spec_used), axis in zip(specs, axes, strict=True)]


def import_table(table: Mapping[str, np.ndarray], sensor: str, columns: Mapping[str, str], *, source: str,
                 units: Mapping[str, str] | None = None, axis: str | None = None, drop: Sequence[str] = (),
                 device_id: str | None = None, sample_rate_hz: float | None = None,
                 about: Mapping[str, object] | None = None) -> Recording:
    """A schema-v1 recording from columns already read (a log's topic): as :func:`import_csv`,
    ``source`` naming them in errors and ``about`` describing them in the sidecar."""
    _check_axes([axis], [columns.get("output", "")])
    _check_request(sensor, columns)
    try:
        spec, used = _spec(columns, drop, sensor, list(table), StatedUnits(dict(units or {})))
        raw = {c: np.asarray(table[c], dtype=np.float64) for c in used}
        empty = np.broadcast_to(False, (len(next(iter(raw.values()))), len(used)))  # a log has no empty cells
    except RecordingError as err:
        raise err.located(source) from None
    return _recording(raw, empty, spec, drop, sensor, source, dict(about or {}), device_id or source,
                      sample_rate_hz, axis)


def _check_axes(axes: Sequence[str | None], outputs: Sequence[str]) -> None:
    """One axis (x, y, z or None) per output column."""
    if len(axes) != len(outputs):
        raise RecordingError(f"{len(axes)} {'axis' if len(axes) == 1 else 'axes'} given for {len(outputs)} output "
                             f"column{'s' * (len(outputs) != 1)}; give one per column")
    for axis in axes:
        if axis is not None:
            check_axis(axis)


def _check_request(sensor: str, columns: Mapping[str, str]) -> None:
    check_sensor(sensor)
    unknown = [k for k in columns if k not in NUMERIC_COLUMNS]
    if unknown:
        raise RecordingError(f"unknown schema column {unknown[0]!r} (expected {', '.join(NUMERIC_COLUMNS)})")
    missing = [k for k in REQUIRED if not columns.get(k)]
    if missing:
        raise RecordingError(f"say which column holds {missing[0]} ({', '.join(REQUIRED)} are required)")


def _spec(columns: Mapping[str, str], drop: Sequence[str], sensor: str, header: Sequence[str],
          stated: StatedUnits) -> tuple[dict[str, Column], list[str]]:
    """The parsed column map and the source columns it reads (drop flags included)."""
    spec = {k: parse_column(k, v, sensor, header, stated) for k, v in columns.items() if v}
    for flag in drop:
        if flag not in header:
            raise RecordingError(f"no column {flag!r} (for drop); the file has: {', '.join(header)}"
                                 + meant(flag, header))
    return spec, list(dict.fromkeys([c.name for c in spec.values()] + list(drop)))


def _recording(raw: dict[str, np.ndarray], empty: np.ndarray, spec: Mapping[str, Column], drop: Sequence[str],
               sensor: str, name: str, source: dict[str, object], device_id: str,
               sample_rate_hz: float | None, axis: str | None = None) -> Recording:
    """The recording of the columns ``raw`` read from ``name`` (rows to drop, units, segments,
    every check of the schema, the ``axis`` when known), its errors in the source's terms.
    ``raw`` is emptied as its columns are converted, so that a column the caller does not keep
    elsewhere is let go once the recording's own is made: the columns in memory are at most those
    read and those of the recording, never both in full."""
    used = list(raw)
    try:
        keep = ~_dropped(raw, drop, empty.shape[0])
        _check_filled(empty, used, keep)
        n_kept = int(np.count_nonzero(keep))
        kept = (lambda x: x) if n_kept == keep.size else (lambda x: x[keep])  # nothing dropped: no copy of a column
        uses = {c: sum(col.name == c for col in spec.values()) for c in used}
        table = {}
        for col in spec.values():
            table[col.target] = col.convert.to_schema(kept(raw[col.name]))
            uses[col.name] -= 1
            if not uses[col.name]:
                del raw[col.name]
        raw.clear()
    except RecordingError as err:
        raise err.located(name) from None
    table.setdefault("input", np.zeros(n_kept))
    if n_kept < 2:
        after = f" left after dropping {int((~keep).sum())}" if (~keep).any() else ""
        raise RecordingError(f"{n_kept} data row{'s' * (n_kept != 1)}{after}; a recording needs at least two",
                             file=name)
    t = table["time_s"]
    clock_ok = bool(np.isfinite(t).all() and (np.diff(t) > 0).all())  # else the schema's check names the row
    gap = gaps(t) if clock_ok else np.zeros(t.size - 1, dtype=bool)  # a flag per step, not a number per sample
    starts, stops = gap_bounds(gap)
    rate = float(sample_rate_hz) if sample_rate_hz is not None else (
        float(f"{within_rate_hz(t, gap=gap):.6g}") if clock_ok else math.nan)
    del gap
    extra = {
        "source": {**source, "columns": {k: c.describe() for k, c in spec.items()},
                   **({"input": "0 (no column given)"} if "input" not in spec else {}),
                   "drop": list(drop), "rows_read": int(keep.size), "rows_dropped": int((~keep).sum())},
        "segments": {"count": int(starts.size), "gap_factor": GAP_FACTOR, "first_rows": (starts + 1).tolist(),
                     "samples": (stops - starts).tolist(), "start_s": t[starts].tolist(),
                     "stop_s": t[stops - 1].tolist()},
        **({"axis": axis} if axis is not None else {}),
    }
    try:
        return make_recording(table["time_s"], table["temperature_c"], table["input"], table["output"],
                              sensor=sensor, sample_rate_hz=rate, device_id=device_id, extra=extra)
    except RecordingError as err:
        raise _in_csv(err, name, np.flatnonzero(keep) + 1, spec, table, sensor) from None


def save(rec: Recording, out: str | Path, stem: str, inputs: Sequence[str | Path] = (), overwrite: bool = True,
         replaced: list[Path] | None = None) -> Path:
    """Write ``rec`` as ``out/<stem>.csv`` and its sidecar, all or nothing (``out`` is not even
    created when writing fails); neither may replace one of ``inputs``
    (:class:`~tcbench.staging.InputOverwriteError`), nor an existing file without ``overwrite``
    (:func:`~tcbench.staging.staged_dir`)."""
    return save_all({stem: rec}, out, inputs, overwrite, replaced)[0]


def save_all(recs: Mapping[str, Recording], out: str | Path, inputs: Sequence[str | Path] = (), overwrite: bool = True,
             replaced: list[Path] | None = None) -> list[Path]:
    """Write each recording as ``out/<stem>.csv`` with its sidecar, all of them or none; files
    already there are replaced only with ``overwrite`` (their paths appended to ``replaced``)."""
    return [w.path for w in save_each(recs.items(), out, inputs, overwrite, replaced)]


@dataclass(frozen=True)
class Written:
    """A recording once written: its file, its metadata and its number of samples (the table is
    on disk, no longer in memory)."""

    path: Path
    meta: RecordingMeta
    samples: int


def save_each(recs: Iterable[tuple[str, Recording]], out: str | Path, inputs: Sequence[str | Path] = (),
              overwrite: bool = True, replaced: list[Path] | None = None) -> list[Written]:
    """Write each recording ``recs`` gives as ``out/<stem>.csv`` with its sidecar, and let it go
    before taking the next: given a generator that builds each recording when asked, one recording
    at a time is in memory. All of them are written or none (a build or write that raises leaves
    ``out`` as it was); files already there are replaced only with ``overwrite``. A stem given
    twice is written once, the later recording replacing the earlier."""
    written: dict[str, Written] = {}
    with staged_dir(out, inputs, overwrite, replaced) as tmp:
        for stem, rec in recs:
            write_recording(rec, tmp / f"{stem}.csv")
            written[stem] = Written(Path(out) / f"{stem}.csv", rec.meta, len(rec.data))
            del rec  # the table goes before the next one is built
    return list(written.values())
