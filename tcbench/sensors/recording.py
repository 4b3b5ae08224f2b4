"""Sensor recordings, schema v1: a CSV or Parquet table plus a JSON sidecar, validated on I/O.

Table columns: ``time_s`` (strictly increasing), ``temperature_c`` (the sensor's thermometer),
``input`` (applied acceleration in g, or applied rate in deg/s), ``output`` (MSRA frequency
difference in Hz, or gyro rate in deg/s) and, for MSRA only, an optional ``position`` (``+0g``,
``+1g``, ``-0g``, ``-1g``, or empty outside the four-position test). Other columns are rejected.
The sidecar ``<stem>.json`` holds the sensor kind, units, sample rate, device id and a free-form
``extra`` object; it is optional when reading and always written.

Every problem raises :class:`RecordingError` with one line naming the file and, where it applies,
the row and column. Rows are numbered like a user counts data rows: the first row below the
header is row 1, so CSV row ``n`` is line ``n + 1`` of the file.
"""

from __future__ import annotations

import contextlib
import csv
import json
import math
import os
import secrets
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pcsv
import pyarrow.parquet as pq

SCHEMA_VERSION = 1
SENSORS = ("msra", "gyro")
POSITIONS = ("+0g", "+1g", "-0g", "-1g")
NUMERIC_COLUMNS = ("time_s", "temperature_c", "input", "output")
COLUMNS = (*NUMERIC_COLUMNS, "position")
STANDARD_UNITS = {
    "msra": {"time_s": "s", "temperature_c": "degC", "input": "g", "output": "Hz"},
    "gyro": {"time_s": "s", "temperature_c": "degC", "input": "deg/s", "output": "deg/s"},
}
KNOWN_UNITS = {c: tuple(dict.fromkeys(u[c] for u in STANDARD_UNITS.values())) for c in NUMERIC_COLUMNS}
FORMATS = (".csv", ".parquet")
RATE_TOLERANCE = 0.01
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


@dataclass
class Recording:
    """A recording table (columns of :data:`COLUMNS`, row order = time order) and its metadata."""

    data: pd.DataFrame
    meta: RecordingMeta = field(default_factory=RecordingMeta)

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
        """Applied stimulus: acceleration in g (MSRA) or rate in deg/s (gyro)."""
        return self.data["input"].to_numpy(dtype=np.float64)

    @property
    def output(self) -> np.ndarray:
        """Sensor output: frequency difference in Hz (MSRA) or rate in deg/s (gyro)."""
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
    """Build and validate a recording from arrays, with the standard units of ``sensor``."""
    if sensor not in SENSORS:
        raise RecordingError(f"unknown sensor {sensor!r} (expected 'msra' or 'gyro')")
    columns: dict[str, Any] = {"time_s": time_s, "temperature_c": temperature_c, "input": input, "output": output}
    columns = {k: np.asarray(v, dtype=np.float64).reshape(-1) for k, v in columns.items()}
    if position is not None:
        columns["position"] = pd.Series(np.asarray(position, dtype=object).reshape(-1), dtype=object)
    meta = RecordingMeta(sensor, dict(STANDARD_UNITS[sensor]), float(sample_rate_hz), device_id,
                         extra=dict(extra or {}))
    rec = Recording(pd.DataFrame(columns), meta)
    rec.data = _checked(rec, None, None)[0]
    return rec


def sidecar_path(path: str | Path) -> Path:
    """The sidecar of a table: ``rec.csv`` and ``rec.parquet`` both map to ``rec.json``."""
    return Path(path).with_suffix(".json")


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
        fmt = _format(path)
        if not path.is_file():
            raise RecordingError("no such file")
        data = _read_csv(path) if fmt == ".csv" else _read_parquet(path)
        _check_table(data)
    side = sidecar_path(path)
    meta = RecordingMeta()
    if side.is_file():
        with _in_file(str(side)):
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
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise RecordingError(f"duplicate column {dup[0]!r}")
    unknown = [c for c in names if c not in COLUMNS]
    missing = [c for c in NUMERIC_COLUMNS if c not in names]
    if missing:
        also = f" (found unknown {', '.join(map(repr, unknown))})" if unknown else ""
        raise RecordingError(f"missing column {missing[0]!r}{also}")
    if unknown:
        allowed = ", ".join(COLUMNS)
        raise RecordingError(f"unknown column {', '.join(map(repr, unknown))} (schema v1 allows only {allowed})")


def _normalise(data: pd.DataFrame) -> pd.DataFrame:
    """Canonical table: columns in schema order, float64 numbers, object positions (str or None)."""
    _check_columns([str(c) for c in data.columns])
    out = {}
    for c in NUMERIC_COLUMNS:
        if data[c].dtype.kind not in "iuf":
            raise RecordingError(f"holds {data[c].dtype} values, expected numbers", column=c)
        out[c] = data[c].to_numpy(dtype=np.float64, na_value=np.nan)
    if "position" in data:
        out["position"] = pd.Series(_positions(data["position"]), dtype=object)
    return pd.DataFrame(out)


def _positions(col: pd.Series) -> np.ndarray:
    """Position labels as an object array, with ``None`` for missing or empty cells."""
    labels = col.to_numpy(dtype=object, na_value=None, copy=True)
    labels[labels == ""] = None
    return labels


def _check_table(data: pd.DataFrame) -> None:
    """Row-level checks of a normalised table: rows present, finite numbers, positions, time."""
    if len(data) == 0:
        raise RecordingError("no data rows")
    values = data[list(NUMERIC_COLUMNS)].to_numpy(dtype=np.float64)
    bad = ~np.isfinite(values)
    if bad.any():
        i, j = divmod(int(np.argmax(bad)), values.shape[1])
        raise RecordingError(f"{values[i, j]} is not finite", row=i + 1, column=NUMERIC_COLUMNS[j])
    if "position" in data:
        labels = pd.Series(data["position"].to_numpy(dtype=object), dtype=object)
        wrong = ~(labels.isna() | labels.isin(POSITIONS)).to_numpy()
        if wrong.any():
            i = int(np.argmax(wrong))
            raise RecordingError(f"{labels[i]!r} is not a position (expected one of {', '.join(POSITIONS)} or empty)",
                                 row=i + 1, column="position")
    t = values[:, 0]
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0])
        prev, cur = float(t[i]), float(t[i + 1])
        problem = (f"duplicate time_s {cur!r} (same as row {i + 1})" if cur == prev
                   else f"time_s goes back from {prev!r} to {cur!r}")
        raise RecordingError(problem, row=i + 2, column="time_s")


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
    if sensor not in SENSORS:
        raise RecordingError(f"unknown sensor {sensor!r} (expected 'msra' or 'gyro')")
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
        unit, expected = units[c], STANDARD_UNITS[sensor][c]
        if unit not in KNOWN_UNITS[c]:
            raise RecordingError(f"unknown unit {unit!r}; accepted: {', '.join(KNOWN_UNITS[c])}", column=c)
        if unit != expected:
            raise RecordingError(f"unit {unit!r} does not fit a {sensor} recording (expected {expected!r})", column=c)
    return {c: units[c] for c in NUMERIC_COLUMNS}


def _check_consistency(data: pd.DataFrame, meta: RecordingMeta, table: str | None, side: str | None) -> None:
    """Sidecar against table: sample rate vs the median time step, positions only for MSRA."""
    if meta.sensor == "gyro" and "position" in data:
        given = data["position"].notna().to_numpy()
        if given.any():
            raise RecordingError("gyro recordings have no positions", file=table, row=int(np.argmax(given)) + 1,
                                 column="position")
    t = data["time_s"].to_numpy()
    if meta.sample_rate_hz is None or t.size < 2:
        return
    step_s = float(np.median(np.diff(t)))
    if abs(1.0 / step_s - meta.sample_rate_hz) > RATE_TOLERANCE * meta.sample_rate_hz:
        raise RecordingError(
            f"sample_rate_hz {meta.sample_rate_hz:g} does not match the table: its median time step "
            f"{step_s:.6g} s means {1.0 / step_s:.6g} Hz (they must agree within 1 %)", file=side)


# -- file formats --------------------------------------------------------------------------------
def _format(path: Path) -> str:
    """The table format from the suffix."""
    fmt = path.suffix.lower()
    if fmt not in FORMATS:
        raise RecordingError(f"unsupported format {path.suffix or '(no suffix)'!r}; expected .csv or .parquet")
    return fmt


def _load_json(path: Path) -> Any:
    """Parsed JSON of a sidecar."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise RecordingError(f"invalid JSON: {exc.msg} (line {exc.lineno}, char {exc.colno})") from None
    except UnicodeDecodeError:
        raise RecordingError("invalid JSON: not UTF-8 text") from None


def _read_header(path: Path) -> list[str]:
    """Column names from the first line of a CSV file."""
    with path.open("rb") as f:
        line = f.readline()
    try:
        text = line.decode("utf-8-sig").strip()
    except UnicodeDecodeError:
        raise RecordingError("the header is not UTF-8 text") from None
    if not text:
        raise RecordingError("empty file (no header)")
    names = [c.strip() for c in next(csv.reader([text]))]
    _check_columns(names)
    return names


def _read_csv(path: Path) -> pd.DataFrame:
    """Parse a CSV table fast with pyarrow; on any doubt re-read it as text to locate the problem."""
    names = _read_header(path)
    types = {c: pa.float64() if c in NUMERIC_COLUMNS else pa.string() for c in names}
    try:
        table = _arrow_csv(path, names, types)
    except pa.ArrowInvalid as exc:
        _diagnose_csv(path, names)
        raise RecordingError(f"cannot parse the table ({str(exc).splitlines()[0]})") from None
    if table.num_rows == 0:
        raise RecordingError("no data rows (header only)")
    columns = {c: table[c].to_numpy() for c in NUMERIC_COLUMNS}
    if not all(np.isfinite(v).all() for v in columns.values()):
        _diagnose_csv(path, names)
    if "position" in names:
        columns["position"] = pd.Series(table["position"].to_numpy(), dtype=object)
    return _normalise(pd.DataFrame(columns))


def _arrow_csv(path: Path, names: list[str], types: dict[str, pa.DataType]) -> pa.Table:
    """Read the rows below the header with the given column types; empty cells become null."""
    return pcsv.read_csv(
        path,
        read_options=pcsv.ReadOptions(column_names=names, skip_rows=1),
        parse_options=pcsv.ParseOptions(ignore_empty_lines=False),
        convert_options=pcsv.ConvertOptions(column_types=types, null_values=[""], strings_can_be_null=True,
                                            quoted_strings_can_be_null=False),
    )


def _diagnose_csv(path: Path, names: list[str]) -> None:
    """Raise the first structural or cell problem of a CSV table; return if none is found."""
    raw = path.read_bytes()
    complete = raw.endswith(b"\n")
    fields = _fields_per_line(raw)[1:]
    wrong = np.flatnonzero(fields != len(names))
    if wrong.size:
        i = int(wrong[0])
        n = int(fields[i])
        if n == 0:
            raise RecordingError("blank line", row=i + 1)
        if i == fields.size - 1 and n < len(names) and not complete:
            raise RecordingError(f"truncated last line ({n} of {len(names)} fields)", row=i + 1)
        raise RecordingError(f"{n} fields, the header has {len(names)}", row=i + 1)
    text = _arrow_csv(path, names, dict.fromkeys(names, pa.string()))
    first: tuple[int, int, str] | None = None
    for j, c in enumerate(NUMERIC_COLUMNS):
        cells = text[c].combine_chunks().fill_null("")
        i, problem = _first_bad_cell(cells, last_is_cut=not complete)
        if problem and (first is None or i < first[0]):
            first = (i, j, problem)
    if first is not None:
        raise RecordingError(first[2], row=first[0] + 1, column=NUMERIC_COLUMNS[first[1]])


def _fields_per_line(raw: bytes) -> np.ndarray:
    """Number of comma-separated fields on each line of ``raw`` (0 for a blank line)."""
    buf = np.frombuffer(raw, dtype=np.uint8)
    ends = np.flatnonzero(buf == ord("\n"))
    if not raw.endswith(b"\n"):
        ends = np.append(ends, buf.size)
    starts = np.concatenate(([0], ends[:-1] + 1))
    commas = np.flatnonzero(buf == ord(","))
    count = np.searchsorted(commas, ends) - np.searchsorted(commas, starts)
    length = ends - starts
    length = length - ((length > 0) & (buf[np.maximum(ends - 1, 0)] == ord("\r")))
    return np.where(length == 0, 0, count + 1)


def _first_bad_cell(cells: pa.Array, *, last_is_cut: bool) -> tuple[int, str]:
    """Index and description of the first unparsable or non-finite cell (``(-1, "")`` if none)."""
    cells = pc.utf8_trim_whitespace(cells)
    n_ok = _parsable_prefix(cells)
    if n_ok < len(cells):
        cell = cells[n_ok].as_py()
        if not cell:
            problem = "empty cell"
        elif last_is_cut and n_ok == len(cells) - 1:
            problem = f"truncated last line ({cell!r} is cut short)"
        else:
            problem = f"{cell!r} is not a number"
        bad = n_ok
    else:
        problem, bad = "", -1
    values = cells.slice(0, n_ok).cast(pa.float64()).to_numpy()
    nonfinite = np.flatnonzero(~np.isfinite(values))
    if nonfinite.size:
        return int(nonfinite[0]), f"{cells[int(nonfinite[0])].as_py()!r} is not finite"
    return bad, problem


def _parsable_prefix(cells: pa.Array) -> int:
    """Length of the longest prefix of ``cells`` that parses as float64 (bisection)."""
    def parses(n: int) -> bool:
        try:
            cells.slice(0, n).cast(pa.float64())
        except pa.ArrowInvalid:
            return False
        return True

    if parses(len(cells)):
        return len(cells)
    lo, hi = 0, len(cells)  # the prefix of length lo parses, the one of length hi does not
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if parses(mid) else (lo, mid)
    return lo


def _read_parquet(path: Path) -> pd.DataFrame:
    """Read a Parquet table; numeric columns must be numbers and position strings."""
    try:
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        raise RecordingError(f"not a readable Parquet file ({str(exc).splitlines()[0]})") from None
    _check_columns(table.column_names)
    for c in table.column_names:
        kind = table.schema.field(c).type
        if c == "position":
            ok, want = pa.types.is_string(kind) or pa.types.is_large_string(kind) or pa.types.is_null(kind), "string"
        else:
            ok, want = pa.types.is_floating(kind) or pa.types.is_integer(kind), "double"
        if not ok:
            raise RecordingError(f"has Parquet type {kind}, expected {want}", column=c)
    columns = {c: table[c].to_numpy().astype(np.float64) for c in NUMERIC_COLUMNS}
    if "position" in table.column_names:
        columns["position"] = pd.Series(table["position"].to_numpy(zero_copy_only=False), dtype=object)
    return _normalise(pd.DataFrame(columns))


def _write_table(data: pd.DataFrame, f: BinaryIO, fmt: str) -> None:
    """Write a normalised table as CSV (shortest round-trip floats, unquoted) or Parquet."""
    arrays = [pa.array(data[c].to_numpy(), pa.float64()) for c in NUMERIC_COLUMNS]
    if "position" in data:
        arrays.append(pa.array(data["position"].to_numpy(dtype=object), pa.string()))
    table = pa.Table.from_arrays(arrays, names=list(data.columns))
    if fmt == ".parquet":
        pq.write_table(table, f)
        return
    f.write((",".join(table.column_names) + "\n").encode())
    pcsv.write_csv(table, f, write_options=pcsv.WriteOptions(include_header=False, quoting_style="none"))


def _write_json(text: str, f: BinaryIO) -> None:
    f.write(text.encode("utf-8"))


def _json_default(value: Any) -> Any:
    """JSON form of numpy scalars and arrays found in ``extra``."""
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON-serialisable")


def _atomic_write(writers: dict[Path, Callable[[BinaryIO], None]]) -> None:
    """Write every target to a temporary sibling, then rename all into place; clean up on failure."""
    temps: dict[Path, Path] = {}
    try:
        for target, write in writers.items():
            temp = target.with_name(f".{target.name}.{secrets.token_hex(6)}.tmp")
            temps[target] = temp
            with open(os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "wb") as f:
                write(f)
                f.flush()
                os.fsync(f.fileno())
        for target, temp in temps.items():
            os.replace(temp, target)
    finally:
        for temp in temps.values():
            temp.unlink(missing_ok=True)
