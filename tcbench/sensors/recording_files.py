"""Recording file formats: CSV (read with pyarrow, diagnosed row by row on failure), Parquet, JSON sidecars.

Reading returns normalised tables (see :mod:`tcbench.sensors.recording_schema`); writing goes
through :func:`_atomic_write`, which renames complete temporary files into place.

Before a CSV file is parsed its first line is read with a size cap and the rest is scanned in
pieces for NUL bytes and over-long lines, and a table pyarrow cannot parse is diagnosed piece by
piece: a binary, sparse or corrupted file of any size is judged with bounded memory.
"""

from __future__ import annotations

import csv
import json
import re
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

from tcbench.outputs import temp_name
from tcbench.sensors.recording_schema import FORMATS, NUMERIC_COLUMNS, RecordingError, _check_columns, _normalise

MAX_HEADER_BYTES = 64 * 1024  # a longer first line is no header
MAX_LINE_BYTES = 1024 * 1024  # a longer line is no recording's (and would straddle pyarrow's blocks)
MAX_SIDECAR_BYTES = 16 * 1024 * 1024
CHUNK_BYTES = 4 * 1024 * 1024  # files are scanned and diagnosed in pieces of this size


def _format(path: Path) -> str:
    """The table format from the suffix."""
    fmt = path.suffix.lower()
    if fmt not in FORMATS:
        raise RecordingError(f"unsupported format {path.suffix or '(no suffix)'!r}; expected .csv or .parquet")
    return fmt


def table_rows(path: str | Path) -> int | None:
    """The data rows of a recording's table, known without parsing it: a CSV file's lines after
    the header (counted in pieces of :data:`CHUNK_BYTES`), a Parquet file's row count from its
    footer. None when the file cannot tell (no table of a known format, unreadable, binary): its
    reader then says why."""
    path = Path(path)
    try:
        if _format(path) == ".parquet":
            return int(pq.ParquetFile(path).metadata.num_rows) if path.is_file() else None
        if not path.is_file():  # never opened: a named pipe would block
            return None
        lines, last = 0, b"\n"
        with path.open("rb") as f:
            while piece := f.read(CHUNK_BYTES):
                if b"\0" in piece:
                    return None
                lines, last = lines + piece.count(b"\n"), piece[-1:]
    except (RecordingError, OSError, pa.ArrowException):
        return None
    return max(lines + (last != b"\n") - 1, 0)


def _load_json(path: Path) -> Any:
    """Parsed JSON of a sidecar."""
    size = path.stat().st_size
    if size > MAX_SIDECAR_BYTES:
        raise RecordingError(f"{size / 2**20:.0f} MiB is too big for a sidecar (at most {MAX_SIDECAR_BYTES >> 20} MiB)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise RecordingError(f"invalid JSON: {exc.msg} (line {exc.lineno}, char {exc.colno})") from None
    except UnicodeDecodeError:
        raise RecordingError("invalid JSON: not UTF-8 text") from None


DELIMITERS = (",", "\t", ";")  # what a table's fields may be separated by (the header decides)


def _header_line(path: Path) -> str:
    """The first line of a CSV file as text (at most :data:`MAX_HEADER_BYTES` of it are read)."""
    with path.open("rb") as f:
        line = f.readline(MAX_HEADER_BYTES + 1)
    if b"\0" in line:
        raise RecordingError("the header holds a NUL byte: a binary file, not CSV text")
    if b"\r" in line.rstrip(b"\r\n"):
        raise RecordingError("lines end in a carriage return (CR) alone, old Mac style: a CSV table's lines end "
                             "in LF or CR LF (convert the line ends, e.g. tr '\\r' '\\n')")
    if len(line) > MAX_HEADER_BYTES:
        raise RecordingError(f"the first line is longer than {MAX_HEADER_BYTES >> 10} KiB: not a CSV header")
    try:
        text = line.decode("utf-8-sig").strip()
    except UnicodeDecodeError:
        raise RecordingError("the header is not UTF-8 text") from None
    if not text:
        raise RecordingError("empty file (no header)")
    return text


def sniff_delimiter(path: Path) -> str:
    """The field delimiter of a table (one of :data:`DELIMITERS`): the one its header line holds
    most often outside quotes (a comma when it holds none)."""
    text = re.sub(r'"[^"]*"', "", _header_line(path))
    counts = [text.count(d) for d in DELIMITERS]
    return DELIMITERS[int(np.argmax(counts))] if max(counts) else ","


def _header_names(path: Path, delimiter: str = ",") -> list[str]:
    """Column names from the first line of a table, whatever they are (at most
    :data:`MAX_HEADER_BYTES` of it are read)."""
    text = _header_line(path)
    try:
        return [c.strip() for c in next(csv.reader([text], delimiter=delimiter))]
    except csv.Error as exc:
        raise RecordingError(f"the header cannot be read as CSV ({exc})") from None


def _scan_text(path: Path, names: list[str], delimiter: str = ",") -> None:
    """Raise at the first NUL byte or line longer than :data:`MAX_LINE_BYTES` of a CSV file,
    reading it in pieces of :data:`CHUNK_BYTES` (a binary or sparse file of any size costs one
    piece of memory), before any parser sees it."""
    line, line_start, offset = 0, 0, 0  # line number (0: the header), where it starts, where the piece starts
    with path.open("rb") as f:
        while piece := f.read(CHUNK_BYTES):
            nul = piece.find(b"\0")
            text = piece if nul < 0 else piece[:nul]
            ends = np.flatnonzero(np.frombuffer(text, dtype=np.uint8) == ord("\n")) + offset
            starts = np.concatenate(([line_start], ends[:-1] + 1))
            long = np.flatnonzero(ends - starts > MAX_LINE_BYTES)
            if long.size:
                _long_line(f, int(starts[long[0]]), line + int(long[0]), names, delimiter)
            if ends.size:
                line, line_start = line + ends.size, int(ends[-1]) + 1
            if offset + len(text) - line_start > MAX_LINE_BYTES:
                _long_line(f, line_start, line, names, delimiter)
            if nul >= 0:
                f.seek(line_start)
                j = f.read(offset + nul - line_start).count(delimiter.encode())
                raise RecordingError("a NUL byte: a binary file, not CSV text", row=line or None,
                                     column=names[j] if j < len(names) else f"field {j + 1}")
            offset += len(piece)


def _long_line(f: BinaryIO, start: int, line: int, names: list[str], delimiter: str = ",") -> None:
    """Raise for the over-long line ``line`` starting at byte ``start``, naming its longest cell."""
    f.seek(start)
    cells = f.read(MAX_LINE_BYTES + 1).split(delimiter.encode())
    j = int(np.argmax([len(c) for c in cells]))
    column = names[j] if j < len(names) else f"field {j + 1}"
    raise RecordingError(f"a line longer than {MAX_LINE_BYTES >> 20} MiB ({len(cells[j])} bytes or more in this "
                         "cell)", row=line or None, column=column)


def _read_header(path: Path) -> list[str]:
    """Column names from the first line of a CSV file, checked against the schema."""
    names = _header_names(path)
    _check_columns(names)
    return names


def _read_csv(path: Path) -> pd.DataFrame:
    """Parse a CSV table fast with pyarrow; on any doubt re-read it as text to locate the problem."""
    names = _read_header(path)
    _scan_text(path, names)
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
        read_options=pcsv.ReadOptions(column_names=names, skip_rows=1, block_size=CHUNK_BYTES),
        parse_options=pcsv.ParseOptions(ignore_empty_lines=False),
        convert_options=pcsv.ConvertOptions(column_types=types, null_values=[""], strings_can_be_null=True,
                                            quoted_strings_can_be_null=False),
    )


def _diagnose_csv(path: Path, names: list[str], numeric: Sequence[str] = NUMERIC_COLUMNS,
                  delimiter: str = ",") -> None:
    """Raise the first structural or cell problem (in the ``numeric`` columns) of a CSV table;
    return if none is found. The file is read in pieces, never whole."""
    _check_fields(path, names, delimiter)
    try:
        _first_bad_row(path, names, numeric, delimiter)
    except pa.ArrowInvalid:  # a problem the field count does not show: the caller's message stands
        return


def _first_bad_row(path: Path, names: list[str], numeric: Sequence[str], delimiter: str = ",") -> None:
    """Raise at the first cell of the ``numeric`` columns that is empty, not a number or not
    finite, reading the table in batches."""
    complete = _ends_with_newline(path)
    reader = pcsv.open_csv(
        path,
        read_options=pcsv.ReadOptions(column_names=names, skip_rows=1, block_size=CHUNK_BYTES),
        parse_options=pcsv.ParseOptions(ignore_empty_lines=False, delimiter=delimiter),
        convert_options=pcsv.ConvertOptions(column_types=dict.fromkeys(names, pa.string()), null_values=[""],
                                            strings_can_be_null=True, quoted_strings_can_be_null=False),
    )
    row0, batch = 0, _next_batch(reader)
    while batch is not None:
        after = _next_batch(reader)
        first: tuple[int, int, str] | None = None
        for j, c in enumerate(numeric):
            cells = batch.column(batch.schema.get_field_index(c)).fill_null("")
            i, problem = _first_bad_cell(cells, last_is_cut=after is None and not complete)
            if problem and (first is None or i < first[0]):
                first = (i, j, problem)
        if first is not None:
            raise RecordingError(first[2], row=row0 + first[0] + 1, column=numeric[first[1]])
        row0, batch = row0 + batch.num_rows, after


def _ends_with_newline(path: Path) -> bool:
    """True when the file's last byte is a newline (or the file is empty)."""
    with path.open("rb") as f:
        if f.seek(0, os.SEEK_END) == 0:
            return True
        f.seek(-1, os.SEEK_END)
        return f.read(1) == b"\n"


def _next_batch(reader: pcsv.CSVStreamingReader) -> pa.RecordBatch | None:
    """The next non-empty record batch of a streaming CSV reader, or None at the end."""
    for batch in reader:
        if batch.num_rows:
            return batch
    return None


def _check_fields(path: Path, names: list[str], delimiter: str = ",") -> None:
    """Raise at the first line of the CSV file below the header that is blank, cut short or has
    a number of fields other than the header's (read in pieces of whole lines)."""
    row0, rest = 0, b""
    with path.open("rb") as f:
        f.readline(MAX_HEADER_BYTES + 1)
        while True:
            piece = f.read(CHUNK_BYTES)
            text = rest + piece
            cut = len(text) if not piece else text.rfind(b"\n") + 1
            block, rest = text[:cut], text[cut:]
            if block:
                _check_block(block, names, row0, last=not piece, delimiter=delimiter)
                row0 += block.count(b"\n") + (not block.endswith(b"\n"))
            if not piece:
                return


def _check_block(block: bytes, names: list[str], row0: int, *, last: bool, delimiter: str = ",") -> None:
    """:func:`_check_fields` on whole lines ``block`` whose first line is data row ``row0 + 1``;
    ``last`` when the block ends the file."""
    fields = _fields_per_line(block, delimiter)
    wrong = np.flatnonzero(fields != len(names))
    if wrong.size:
        i = int(wrong[0])
        n = int(fields[i])
        if n == 0:
            raise RecordingError("blank line", row=row0 + i + 1)
        if last and i == fields.size - 1 and n < len(names) and not block.endswith(b"\n"):
            raise RecordingError(f"truncated last line ({n} of {len(names)} fields)", row=row0 + i + 1)
        raise RecordingError(f"{n} fields, the header has {len(names)}", row=row0 + i + 1)


def _fields_per_line(raw: bytes, delimiter: str = ",") -> np.ndarray:
    """Number of ``delimiter``-separated fields on each line of ``raw`` (0 for a blank line)."""
    buf = np.frombuffer(raw, dtype=np.uint8)
    ends = np.flatnonzero(buf == ord("\n"))
    if not raw.endswith(b"\n"):
        ends = np.append(ends, buf.size)
    starts = np.concatenate(([0], ends[:-1] + 1))
    commas = np.flatnonzero(buf == ord(delimiter))
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
            temp = target.with_name(temp_name(target.name, secrets.token_hex(6)))
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
