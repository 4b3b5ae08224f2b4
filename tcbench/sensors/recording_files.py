"""Recording file formats: CSV (read with pyarrow, diagnosed row by row on failure), Parquet, JSON sidecars.

Reading returns normalised tables (see :mod:`tcbench.sensors.recording_schema`); writing goes
through :func:`_atomic_write`, which renames complete temporary files into place.
"""

from __future__ import annotations

import csv
import json
import os
import secrets
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pcsv
import pyarrow.parquet as pq

from tcbench.sensors.recording_schema import FORMATS, NUMERIC_COLUMNS, RecordingError, _check_columns, _normalise


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


def _header_names(path: Path) -> list[str]:
    """Column names from the first line of a CSV file, whatever they are."""
    with path.open("rb") as f:
        line = f.readline()
    try:
        text = line.decode("utf-8-sig").strip()
    except UnicodeDecodeError:
        raise RecordingError("the header is not UTF-8 text") from None
    if not text:
        raise RecordingError("empty file (no header)")
    return [c.strip() for c in next(csv.reader([text]))]


def _read_header(path: Path) -> list[str]:
    """Column names from the first line of a CSV file, checked against the schema."""
    names = _header_names(path)
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


def _diagnose_csv(path: Path, names: list[str], numeric: Sequence[str] = NUMERIC_COLUMNS) -> None:
    """Raise the first structural or cell problem (in the ``numeric`` columns) of a CSV table;
    return if none is found."""
    raw = path.read_bytes()
    complete = raw.endswith(b"\n")
    _check_fields(raw, names)
    text = _arrow_csv(path, names, dict.fromkeys(names, pa.string()))
    first: tuple[int, int, str] | None = None
    for j, c in enumerate(numeric):
        cells = text[c].combine_chunks().fill_null("")
        i, problem = _first_bad_cell(cells, last_is_cut=not complete)
        if problem and (first is None or i < first[0]):
            first = (i, j, problem)
    if first is not None:
        raise RecordingError(first[2], row=first[0] + 1, column=numeric[first[1]])


def _check_fields(raw: bytes, names: list[str]) -> None:
    """Raise at the first line of the CSV text ``raw`` below the header that is blank, cut short
    or has a number of fields other than the header's."""
    fields = _fields_per_line(raw)[1:]
    wrong = np.flatnonzero(fields != len(names))
    if wrong.size:
        i = int(wrong[0])
        n = int(fields[i])
        if n == 0:
            raise RecordingError("blank line", row=i + 1)
        if i == fields.size - 1 and n < len(names) and not raw.endswith(b"\n"):
            raise RecordingError(f"truncated last line ({n} of {len(names)} fields)", row=i + 1)
        raise RecordingError(f"{n} fields, the header has {len(names)}", row=i + 1)


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
