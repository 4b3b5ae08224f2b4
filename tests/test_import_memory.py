"""A long log imported without copies it does not need: a PX4 topic's fields stay as pyulog read
them (the import converts only the columns it uses), and a column nothing was dropped from is
not copied again on its way into the recording; the recordings of a log's axes are built, written
and let go one at a time."""

from __future__ import annotations

import contextlib
import io
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from conftest import PX4_LOG

from tcbench.commands.errors import CommandError
from tcbench.commands.recordings import RecordingOutcome, import_recording
from tcbench.commands.schemas import ImportConfig
from tcbench.sensors.importer import import_table
from tcbench.sensors.recording import Recording
from tcbench.sensors.ulog import default_columns, read_topic


def test_a_topics_fields_keep_their_logged_types() -> None:
    fields = read_topic(PX4_LOG, "gyro")[0].fields
    assert fields["x"].dtype == np.float32 and fields["timestamp"].dtype == np.uint64  # not float64 copies


def test_a_column_nothing_was_dropped_from_becomes_the_recordings_own() -> None:
    inst = read_topic(PX4_LOG, "gyro")[0]
    table = {**inst.fields, "x": np.asarray(inst.fields["x"], dtype=np.float64)}
    rec = import_table(table, "gyro", default_columns(list(table)) | {"output": "x:deg/s"}, source="log", axis="x")
    assert np.shares_memory(rec.data["output"].to_numpy(), table["x"])  # deg/s, the schema's unit: no copy
    dropped = import_table({**table, "error_count": np.arange(table["x"].size) % 2}, "gyro",
                           default_columns(list(table)) | {"output": "x:deg/s"}, source="log", axis="x",
                           drop=["error_count"])
    assert not np.shares_memory(dropped.data["output"].to_numpy(), table["x"])


# -- a log's recordings built, written and dropped one at a time ----------------------------------
def _thermal_log(path: Path, rows: int) -> int:
    """A ULog at ``path`` with one ``sensor_gyro`` instance of ``rows`` samples at 1 kHz (the
    sample log's formats, PX4's field types, a 20 -> 50 degC ramp); the topic's bytes as logged."""
    from pyulog import ULog

    log = ULog(str(PX4_LOG), ["sensor_gyro"])
    topic = next(d for d in log.data_list if d.multi_id == 0)
    log._data_list = [topic]  # pyulog writes the topics its list holds
    rng = np.random.default_rng(7)
    t_us = np.arange(rows, dtype=np.uint64) * np.uint64(1000) + np.uint64(1_000_000)
    temp_c = np.linspace(20.0, 50.0, rows, dtype=np.float32)
    axes = {a: (1e-3 * temp_c + 3e-3 * rng.standard_normal(rows)).astype(np.float32) for a in "xyz"}
    topic.data = {"timestamp": t_us + np.uint64(200), "timestamp_sample": t_us,
                  "device_id": np.full(rows, topic.data["device_id"][0], np.uint32), **axes,
                  "temperature": temp_c, "error_count": np.zeros(rows, np.uint32)}
    log.write_ulog(str(path))
    return int(sum(v.nbytes for v in topic.data.values()))


def _import(log: Path, out: Path, **given: object) -> RecordingOutcome:
    """``tcbench import csv=LOG sensor=gyro out=OUT`` with ``given``, untracked, its output not shown."""
    cfg = ImportConfig(csv=str(log), sensor="gyro", out=str(out), **given)
    cfg.tracking.enabled = False
    with contextlib.redirect_stdout(io.StringIO()):
        return import_recording(cfg)


def test_a_logs_import_holds_one_axis_beside_the_topic(tmp_path: Path) -> None:
    """The traced peak of importing a 1 kHz log's three gyro axes stays within pyulog's topic, one
    axis's recording (four float64 columns) and three columns of temporaries: the axes are built,
    written and let go in turn (all three held together, and their construction's copies, came to
    the topic plus 4.7 axes)."""
    rows = 100_000
    warm, log = tmp_path / "warm.ulg", tmp_path / "log.ulg"
    _thermal_log(warm, 50)
    topic_bytes = _thermal_log(log, rows)
    tracemalloc.start()
    try:
        _import(warm, tmp_path / "warm")  # pint's registry, pyulog and the rest loaded: not the log's
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        outcome = _import(log, tmp_path / "out")
        peak_bytes = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    axis_bytes = 4 * 8 * rows  # one axis's recording: four float64 columns
    axes = (peak_bytes - topic_bytes) / axis_bytes
    assert peak_bytes <= topic_bytes + axis_bytes + 3 * 8 * rows, f"peak: the topic and {axes:.2f} axes"
    assert [o.rec.samples for o in [outcome, *outcome.also]] == [rows] * 3
    assert not isinstance(outcome.rec, Recording)  # the outcome keeps no table


def test_an_axis_that_fails_leaves_the_written_ones_unmoved(tmp_path: Path) -> None:
    """The second axis of a log failing after the first was written: the output folder is left as
    it was, its earlier files unchanged and nothing of the first axis in it."""
    log = tmp_path / "log.ulg"
    _thermal_log(log, 200)
    out = tmp_path / "out"
    _import(log, out, output="x:rad/s")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(CommandError, match="no column 'w'"):
        _import(log, out, output="y:rad/s,w:rad/s", overwrite=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.ulg", "out"]  # no staging folder left
