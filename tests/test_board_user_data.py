"""Runs on the user's recordings: keyed by the data's content hash on the compensation boards, no
run merged or dropped, training and testing on the same data warned about and marked."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tcbench.sensors.data_hash import DataHashError, content_hash, shared_recordings
from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording


def _cycle(tmp: Path, name: str, run_seed: int, device_seed: int = 1) -> str:
    """A simulated chamber cycle written as a user's schema-v1 recording (table and sidecar)."""
    path = tmp / f"{name}.csv"
    write_recording(simulate_recording("accel", "chamber", device_seed, run_seed), path)
    return str(path)


def test_content_hash_follows_the_bytes_not_the_names(tmp_path: Path) -> None:
    a, b = _cycle(tmp_path, "a", 0), _cycle(tmp_path, "b", 1)
    copy = tmp_path / "copy.csv"
    shutil.copy(a, copy)
    shutil.copy(tmp_path / "a.json", tmp_path / "copy.json")
    h = content_hash([a])
    assert len(h) == 12 and int(h, 16) >= 0
    assert content_hash([copy]) == h  # another name, the same data
    assert content_hash([b]) != h
    assert content_hash([a, b]) != content_hash([b, a])  # in order
    assert content_hash([a], [b]) != content_hash([a, b], [])  # the groups apart
    (tmp_path / "copy.json").write_text((tmp_path / "copy.json").read_text().replace('"accel"', '"accel" '))
    assert content_hash([copy]) != h  # the sidecar is part of the recording
    (tmp_path / "copy.json").unlink()
    assert content_hash([copy]) != h
    assert shared_recordings([a], [b, str(copy), a]) == [str(copy), a]
    with pytest.raises(DataHashError, match=r"missing.csv: cannot be read"):
        content_hash([tmp_path / "missing.csv"])
