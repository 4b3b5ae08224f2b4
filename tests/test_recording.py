"""Recording schema v1: the malformed-file corpus, exact round trips and atomic writes."""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tcbench.sensors import recording
from tcbench.sensors.recording import (
    Recording,
    RecordingError,
    RecordingMeta,
    make_recording,
    read_recording,
    sidecar_path,
    write_recording,
)

CORPUS = Path(__file__).parent / "data" / "malformed"

# File of the corpus -> (file named in the message, fragment only its own message contains).
EXPECTED = {
    "missing_column.csv": ("missing_column.csv", "missing column 'temperature_c'"),
    "nan_value.csv": ("nan_value.csv", "row 3, column 'output': 'NaN' is not finite"),
    "non_monotonic_time.csv": ("non_monotonic_time.csv", "row 4, column 'time_s': time_s goes back from 0.3 to 0.25"),
    "duplicate_time.csv": ("duplicate_time.csv", "row 3, column 'time_s': duplicate time_s 0.1 (same as row 2)"),
    "unknown_unit.csv": ("unknown_unit.json", "column 'input': unknown unit 'mg'; accepted: g, deg/s"),
    "unknown_unit_rad_s.csv": ("unknown_unit_rad_s.json", "column 'output': unknown unit 'rad/s'; accepted: Hz, deg/s"),
    "unit_inconsistent.csv": ("unit_inconsistent.json", "column 'output': unit 'deg/s' does not fit a msra recording"),
    "empty.csv": ("empty.csv", "empty file (no header)"),
    "header_only.csv": ("header_only.csv", "no data rows (header only)"),
    "text_in_numeric.csv": ("text_in_numeric.csv", "row 2, column 'temperature_c': 'abc' is not a number"),
    "truncated_last_line.csv": ("truncated_last_line.csv", "row 4: truncated last line (3 of 5 fields)"),
    "truncated_number.csv": ("truncated_number.csv", "row 3, column 'output': truncated last line ('1.5107e' is cut"),
    "bad_json.csv": ("bad_json.json", "invalid JSON: Expecting ',' delimiter (line 5"),
    "unknown_sensor.csv": ("unknown_sensor.json", "unknown sensor 'imu'"),
    "unknown_schema_version.csv": ("unknown_schema_version.json", "unknown schema_version 2"),
    "bad_position.csv": ("bad_position.csv", "row 2, column 'position': '+2g' is not a position"),
    "extra_column.csv": ("extra_column.csv", "unknown column 'humidity'"),
    "sample_rate_mismatch.csv": ("sample_rate_mismatch.json", "sample_rate_hz 100 does not match the table"),
    "blank_line.csv": ("blank_line.csv", "row 2: blank line"),
    "missing_field.csv": ("missing_field.csv", "row 2: 4 fields, the header has 5"),
    "empty_cell.csv": ("empty_cell.csv", "row 2, column 'input': empty cell"),
    "not_parquet.parquet": ("not_parquet.parquet", "not a readable Parquet file"),
    "kelvin_temperature.csv": ("kelvin_temperature.csv", "row 1, column 'temperature_c': 298.15 degC is not "
                               "plausible for a sensor recording (expected -100..200 degC) (kelvin?)"),
    "absurd_rate.csv": ("absurd_rate.csv", "row 3, column 'output': 35000 deg/s is not plausible for a gyro"),
}


def test_corpus_is_covered_and_fragments_distinct():
    tables = {p.name for p in CORPUS.iterdir() if p.suffix in (".csv", ".parquet")}
    assert tables == set(EXPECTED) | {"valid.csv"}
    fragments = [frag for _, frag in EXPECTED.values()]
    assert len(set(fragments)) == len(fragments)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_malformed_file_raises_one_line_error(name):
    where, fragment = EXPECTED[name]
    with pytest.raises(RecordingError) as info:
        read_recording(CORPUS / name)
    message = str(info.value)
    assert "\n" not in message and "\r" not in message
    assert message.startswith(str(CORPUS / where) + ": ")
    assert fragment in message
    others = [frag for other, (_, frag) in EXPECTED.items() if other != name]
    assert not any(frag in message for frag in others)


def test_valid_corpus_file():
    rec = read_recording(CORPUS / "valid.csv")
    assert rec.meta.sensor == "msra" and rec.meta.sample_rate_hz == 10.0 and rec.meta.device_id == "msra-007"
    assert rec.meta.extra == {"protocol": "four_position", "device_seed": 7}
    assert rec.time_s.dtype == np.float64 and rec.time_s.tolist() == [0.0, 0.1, 0.2, 0.3, 0.4]
    assert rec.input.tolist() == [0.0, 1.0, 0.0, -1.0, 0.0]
    assert rec.position.tolist() == ["+0g", "+1g", "-0g", "-1g", None]


def _awkward_recording(n: int = 200, seed: int = 1, sensor: str = "msra") -> Recording:
    """Floats that stress the text round trip: random mantissa bits at every exponent from the
    subnormals up to the plausible range's end (the schema refuses larger), -0.0, 1/3, 0.1."""
    rng = np.random.default_rng(seed)
    mantissa, _ = np.frexp(rng.integers(1, 2**63, size=n, dtype=np.int64).view(np.float64))
    bits = np.ldexp(np.where(np.isfinite(mantissa), mantissa, 0.75), rng.integers(-1074, 10, size=n))
    bits[:6] = [-0.0, 5e-324, 999.9999999999999, 1 / 3, 0.1, -2.2250738585072014e-308]
    time_s = np.arange(n) / 50.0 + rng.uniform(0, 1e-4, n)
    position = rng.choice(np.array(["+0g", "+1g", "-0g", "-1g", None], dtype=object), n) if sensor == "msra" else None
    return make_recording(time_s, rng.normal(25, 10, n), bits, rng.normal(0, 1e3, n), sensor=sensor,
                          sample_rate_hz=50.0, device_id="dev-1", position=position,
                          extra={"protocol": "ramp", "device_seed": np.int64(3), "sim": {"k": [1.0, 2.5]}})


def _assert_same(a: Recording, b: Recording) -> None:
    for col in ("time_s", "temperature_c", "input", "output"):
        x, y = getattr(a, col), getattr(b, col)
        assert x.dtype == y.dtype == np.float64
        assert np.array_equal(x.view(np.int64), y.view(np.int64)), col  # bitwise, -0.0 included
    assert (a.position is None) == (b.position is None)
    if a.position is not None:
        assert a.position.tolist() == b.position.tolist()
    assert a.meta == b.meta


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.parametrize("sensor", ["msra", "gyro"])
def test_round_trip_is_exact(tmp_path, suffix, sensor):
    rec = _awkward_recording(sensor=sensor)
    path = write_recording(rec, tmp_path / f"rec{suffix}")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([f"rec{suffix}", "rec.json"])
    back = read_recording(path)
    _assert_same(rec, back)
    assert back.meta.extra == {"protocol": "ramp", "device_seed": 3, "sim": {"k": [1.0, 2.5]}}
    assert back.meta.units == recording.standard_units(sensor)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(min_value=-100.0, max_value=200.0, allow_nan=False), min_size=1, max_size=20))
def test_csv_round_trip_any_finite_float(values):
    n = len(values)
    rec = make_recording(np.arange(n) / 10.0, values, values[::-1], values, sensor="gyro", sample_rate_hz=10.0,
                         device_id="g")
    with tempfile.TemporaryDirectory() as tmp:
        _assert_same(rec, read_recording(write_recording(rec, Path(tmp) / "r.csv")))


def test_csv_is_plain_text(tmp_path):
    rec = make_recording([0.0, 0.5], [25.0, 25.5], [0.0, 1.0], [10.25, 11.0], sensor="msra", sample_rate_hz=2.0,
                         device_id="m", position=["+0g", None])
    write_recording(rec, tmp_path / "r.csv")
    assert (tmp_path / "r.csv").read_text() == (
        "time_s,temperature_c,input,output,position\n0,25,0,10.25,+0g\n0.5,25.5,1,11,\n")


def _invalid() -> Recording:
    good = _awkward_recording(n=10)
    data = good.data.copy()
    data.loc[5, "time_s"] = data.loc[4, "time_s"]
    return Recording(data, good.meta)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_invalid_recording_is_not_written(tmp_path, suffix):
    with pytest.raises(RecordingError, match=r"rec\.\w+: row 6, column 'time_s': duplicate time_s"):
        write_recording(_invalid(), tmp_path / f"rec{suffix}")
    assert list(tmp_path.iterdir()) == []


def test_invalid_meta_is_not_written(tmp_path):
    good = _awkward_recording(n=10)
    bad = Recording(good.data, RecordingMeta("msra", {**good.meta.units, "output": "kHz"}, 50.0, "d"))
    with pytest.raises(RecordingError, match=r"rec\.json: column 'output': unknown unit 'kHz'; accepted: Hz, deg/s"):
        write_recording(bad, tmp_path / "rec.csv")
    with pytest.raises(RecordingError, match=r"sensor None"):
        write_recording(Recording(good.data), tmp_path / "rec.csv")  # no sidecar data: cannot write
    assert list(tmp_path.iterdir()) == []


def test_overwrite_is_atomic(tmp_path, monkeypatch):
    path = write_recording(_awkward_recording(n=10), tmp_path / "rec.csv")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    with pytest.raises(RecordingError):
        write_recording(_invalid(), path)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before

    def broken(text, f):  # the table temp file is complete, the sidecar fails half-way
        f.write(text[:10].encode())
        raise OSError("disk full")

    monkeypatch.setattr(recording, "_write_json", broken)
    with pytest.raises(OSError, match="disk full"):
        write_recording(_awkward_recording(n=20, seed=2), path)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_directory_is_named_as_such(tmp_path):
    folder = tmp_path / "run.csv"
    folder.mkdir()
    with pytest.raises(RecordingError, match="is a directory, not a recording") as info:
        read_recording(folder)
    assert str(info.value).startswith(str(folder))


def test_plausible_ranges_are_checked_when_made_too():
    t = np.arange(4) * 0.1
    with pytest.raises(RecordingError, match="row 3, column 'output': 2e.06 Hz is not plausible for a msra"):
        make_recording(t, np.full(4, 25.0), np.zeros(4), np.array([0.0, 0.0, 2e6, 0.0]), sensor="msra",
                       sample_rate_hz=10.0, device_id="m")
    ok = make_recording(t, np.full(4, 200.0), np.full(4, 1000.0), np.full(4, -1e6), sensor="msra",
                        sample_rate_hz=10.0, device_id="m")  # the bounds themselves are plausible
    assert ok.temperature_c.max() == 200.0


def test_unsupported_suffix(tmp_path):
    with pytest.raises(ValueError, match=r"rec\.txt: unsupported format '\.txt'; expected \.csv or \.parquet"):
        write_recording(_awkward_recording(n=10), tmp_path / "rec.txt")
    with pytest.raises(RecordingError, match="no such file"):
        read_recording(tmp_path / "missing.csv")
    assert list(tmp_path.iterdir()) == []


def test_read_without_sidecar(tmp_path):
    rec = _awkward_recording(n=10)
    path = write_recording(rec, tmp_path / "rec.parquet")
    sidecar_path(path).unlink()
    back = read_recording(path)
    assert back.meta == RecordingMeta() and back.meta.sensor is None and not back.meta.known
    assert np.array_equal(back.output, rec.output)


def test_make_recording_units_and_checks():
    rec = make_recording([0.0, 0.01], [20.0, 20.0], [100.0, 100.0], [100.2, 100.1], sensor="gyro",
                         sample_rate_hz=100.0, device_id="g-1")
    assert rec.meta.units == {"time_s": "s", "temperature_c": "degC", "input": "deg/s", "output": "deg/s"}
    assert rec.position is None and rec.meta.extra == {}
    with pytest.raises(RecordingError, match="row 1, column 'position': gyro recordings have no positions"):
        make_recording([0.0], [20.0], [0.0], [0.0], sensor="gyro", sample_rate_hz=1.0, device_id="g",
                       position=["+1g"])
    with pytest.raises(RecordingError, match="unknown sensor 'imu'"):
        make_recording([0.0], [20.0], [0.0], [0.0], sensor="imu", sample_rate_hz=1.0, device_id="x")
    with pytest.raises(RecordingError, match=r"row 2, column 'temperature_c': inf is not finite"):
        make_recording([0.0, 1.0], [20.0, math.inf], [0.0, 0.0], [0.0, 0.0], sensor="msra", sample_rate_hz=1.0,
                       device_id="m")


def test_parquet_with_text_column(tmp_path):
    table = pa.table({"time_s": [0.0, 1.0], "temperature_c": ["20", "21"], "input": [0.0, 0.0], "output": [1.0, 1.0]})
    pq.write_table(table, tmp_path / "r.parquet")
    with pytest.raises(RecordingError, match=r"r\.parquet: column 'temperature_c': has Parquet type string"):
        read_recording(tmp_path / "r.parquet")


def test_bad_cell_deep_in_a_big_file(tmp_path):
    n = 100_000
    lines = [f"{i / 100!r},25.0,0.0,{i % 7}.5" for i in range(n)]
    lines[77_776] = "777.76,25.0,0.0,1.2.3"
    (tmp_path / "big.csv").write_text("time_s,temperature_c,input,output\n" + "\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"big\.csv: row 77777, column 'output': '1\.2\.3' is not a number$"):
        read_recording(tmp_path / "big.csv")


def test_million_rows_read_fast(tmp_path):
    n = 1_000_000
    rng = np.random.default_rng(0)
    rec = make_recording(np.arange(n) / 100.0, rng.normal(25, 5, n), rng.normal(size=n), rng.normal(size=n),
                         sensor="msra", sample_rate_hz=100.0, device_id="big",
                         position=np.resize(np.array(["+0g", "+1g", "-0g", "-1g"], dtype=object), n))
    path = write_recording(rec, tmp_path / "big.csv")
    start = time.perf_counter()
    back = read_recording(path)
    elapsed = time.perf_counter() - start
    assert len(back.data) == n and back.position[-1] == "-1g"
    assert elapsed < 5.0


def test_data_frame_is_canonical():
    data = pd.DataFrame({"position": ["+0g", ""], "output": [1, 2], "input": [0, 0], "temperature_c": [20, 21],
                         "time_s": [0, 1]})
    rec = Recording(data, RecordingMeta("msra", recording.standard_units("msra"), 1.0, "m"))
    rec.validate()
    assert rec.time_s.dtype == np.float64 and rec.position.tolist() == ["+0g", None]


def test_bom_crlf_and_quoted_csv(tmp_path):
    text = '\ufefftime_s,temperature_c,input,output,position\r\n0,25,0,1.5,"+0g"\r\n0.5, 25.5 ,1,2,\r\n'
    (tmp_path / "w.csv").write_bytes(text.encode("utf-8"))
    rec = read_recording(tmp_path / "w.csv")
    assert rec.temperature_c.tolist() == [25.0, 25.5] and rec.position.tolist() == ["+0g", None]
    (tmp_path / "d.csv").write_text("time_s,temperature_c,input,output,time_s\n0,25,0,1.5,0\n")
    with pytest.raises(RecordingError, match=r"d\.csv: duplicate column 'time_s'$"):
        read_recording(tmp_path / "d.csv")


# -- bounded reading: the same verdicts read in small pieces ---------------------------------------
@pytest.mark.parametrize(("row", "line", "end"), [
    (321, "320,25,0,abc", "\n"),  # not a number
    (321, "", "\n"),  # blank line
    (321, "320,25,0", "\n"),  # a field short
    (400, "399,25,0,1\0", "\n"),  # a NUL byte
    (500, "499,25,0,1.", "\n"),  # fine
    (500, "499,25,0,", "\n"),  # empty cell at the end
    (500, "499,25,0,1.", ""),  # fine without the last newline
    (500, "499,25,0,1e", ""),  # a number cut short
    (500, "499,25", ""),  # a line cut short
])
def test_pieces_give_the_whole_file_verdict(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, row: int, line: str,
                                            end: str) -> None:
    import tcbench.sensors.recording_files as files

    lines = [f"{i},25,0,1" for i in range(500)]
    lines[row - 1] = line
    path = tmp_path / "t.csv"
    path.write_text("time_s,temperature_c,input,output\n" + "\n".join(lines) + end)

    def verdict() -> str:
        try:
            read_recording(path)
        except RecordingError as err:
            return str(err)
        return "ok"

    whole = verdict()
    monkeypatch.setattr(files, "CHUNK_BYTES", 64)
    assert verdict() == whole
    assert whole == "ok" or f"row {row}," in whole or f"row {row}:" in whole, whole
