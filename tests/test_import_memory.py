"""A long log imported without copies it does not need: a PX4 topic's fields stay as pyulog read
them (the import converts only the columns it uses), and a column nothing was dropped from is
not copied again on its way into the recording."""

from __future__ import annotations

import numpy as np
from conftest import PX4_LOG

from tcbench.sensors.importer import import_table
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
