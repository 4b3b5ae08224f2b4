"""The recordings of a static-input compensation task and the learner's view of them.

Two tasks of seed 000 §3 on the MSRA, and one on an ordinary accelerometer:

- ``fulltemp`` (Table 2): four-position runs over -40..60 degC. A learner maps
  ``[U (Hz), temperature (degC)]`` to the applied acceleration (g) — form ``inverse``; the
  compensated output is its prediction, in g.
- ``roomtemp`` (Table 1): zero-bias runs at 0 g. The paper's literal mapping ``(U, T) -> 0 g``
  is degenerate (a constant 0 fits every training sample), so tcbench models the bias instead:
  ``[temperature (degC), temperature rate (degC/s)] -> U (Hz)`` — form ``bias``; the
  compensated output is ``U - prediction`` (Hz), a 2-input network as in the paper.
- ``chamber``: a static capacitive accelerometer (``accel``, output in g) through a chamber cycle
  (60 -> -20 -> 60 -> 25 degC), the most common real calibration record. Form ``bias`` as
  ``roomtemp``: ``[temperature, temperature rate] -> output (g)``; the compensated output is
  ``output - prediction`` (g). The rate input lets a learner tell heating from cooling (the
  lag and the package's hysteresis open a loop between them).

Recordings are simulated from the sensors package (one device, several runs that differ by
their run seed) or read from schema-v1 files (for example real ones); simulated ones keep the
simulator's truth for the oracle.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.metrics.accelerometer import four_position
from tcbench.metrics.report import DEFAULT_MSRA_SCALE_FACTOR_HZ_PER_G
from tcbench.sensors.recording import Recording, RecordingError, read_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.sensors.truth import Truth, simulate_truth

PROTOCOLS = {"fulltemp": "inverse", "roomtemp": "bias", "chamber": "bias"}
SENSORS = {"fulltemp": "msra", "roomtemp": "msra", "chamber": "accel"}  # the kind each protocol records
# (train, test) recordings: seed 000 §3.2's for the MSRA; three and two chamber cycles otherwise
DEFAULT_SPLIT = {"fulltemp": (3, 2), "roomtemp": (4, 2), "chamber": (3, 2)}
TRAIN_ON = ("positions", "all")


class TaskDataError(ValueError):
    """Recordings that cannot serve the task (wrong kind, missing positions, too few)."""


@dataclass
class TaskRecording:
    """One recording of the task, its name and (for simulated ones) the simulator's truth."""

    name: str
    recording: Recording
    truth: Truth | None = None


@dataclass
class MSRAData:
    """Training and test recordings of one task and how a learner sees them;
    ``scale_factor_hz_per_g`` is the output per g (1 for an accelerometer reading in g)."""

    protocol: str
    train: list[TaskRecording]
    test: list[TaskRecording]
    scale_factor_hz_per_g: float
    train_on: str = "positions"
    rate_window_s: float = 120.0
    source: str = "simulated"
    info: dict[str, object] = field(default_factory=dict)

    @property
    def form(self) -> str:
        """``inverse`` (fulltemp) or ``bias`` (roomtemp, chamber)."""
        return PROTOCOLS[self.protocol]

    def features(self, rec: Recording, output: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Learner inputs (n, 2) and targets (n,) over every row of ``rec`` (``output``
        replaces the recorded output, e.g. to probe the learner at other accelerations)."""
        u = rec.output if output is None else output
        if self.form == "inverse":
            return np.column_stack([u, rec.temperature_c]), rec.input
        rate = temperature_rate_c_per_s(rec.time_s, rec.temperature_c, self.rate_window_s)
        return np.column_stack([rec.temperature_c, rate]), u

    def training_rows(self, rec: Recording, sequential: bool) -> np.ndarray:
        """Rows a learner trains on: labelled four-position samples (``train_on=positions``,
        fulltemp, feed-forward learners) or every row (recurrent learners need the sequence)."""
        if self.form == "inverse" and self.train_on == "positions" and not sequential:
            labels = rec.position
            if labels is not None:
                return np.flatnonzero(labels != None)  # noqa: E711 - object array of str/None
        return np.arange(len(rec.data))

    def training_set(self, sequential: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Inputs and targets of every training recording, stacked in time order."""
        xs, ys = [], []
        for tr in self.train:
            x, y = self.features(tr.recording)
            rows = self.training_rows(tr.recording, sequential)
            xs.append(x[rows])
            ys.append(y[rows])
        return np.concatenate(xs), np.concatenate(ys)

    def compensate(self, output: np.ndarray, prediction: np.ndarray) -> np.ndarray:
        """Compensated output from a learner's prediction over every row: the prediction in g
        (fulltemp), or ``output - prediction`` in the output unit (roomtemp: Hz, chamber: g)."""
        return prediction if self.form == "inverse" else output - prediction


def recording_seed(recordings_seed: int, index: int) -> int:
    """Run seed of the ``index``-th recording of a task instance."""
    return 100 * int(recordings_seed) + int(index)


@functools.lru_cache(maxsize=8)
def _simulated(protocol: str, device_seed: int, seed: int) -> TaskRecording:
    rec = simulate_recording(SENSORS[protocol], protocol, device_seed, seed)
    truth = simulate_truth(SENSORS[protocol], protocol, device_seed, seed)
    return TaskRecording(f"dev{device_seed}-seed{seed}", rec, truth)


def simulated_data(protocol: str, device_seed: int, recordings_seed: int, n_train: int, n_test: int,
                   train_on: str = "positions", rate_window_s: float = 120.0) -> MSRAData:
    """``n_train + n_test`` simulated runs of device ``device_seed``; the first ``n_train`` train."""
    check_split(protocol, n_train, n_test, train_on, rate_window_s)
    recs = [_simulated(protocol, int(device_seed), recording_seed(recordings_seed, i))
            for i in range(n_train + n_test)]
    sf = float(recs[0].recording.meta.extra.get("scale_factor_hz_per_g") or 1.0)
    return MSRAData(protocol, recs[:n_train], recs[n_train:], sf, train_on, rate_window_s,
                    "simulated", {"device_seed": int(device_seed), "recordings_seed": int(recordings_seed)})


def check_split(protocol: str, n_train: int, n_test: int, train_on: str, rate_window_s: float) -> None:
    """Raise :class:`TaskDataError` for an impossible split or setting."""
    if protocol not in PROTOCOLS:
        raise TaskDataError(f"unknown compensation protocol {protocol!r}; known: {', '.join(PROTOCOLS)}")
    if int(n_train) != n_train or n_train < 1 or int(n_test) != n_test or n_test < 1:
        raise TaskDataError(f"n_train and n_test must be integers >= 1, got {n_train} and {n_test}")
    if n_train + n_test > 100:
        raise TaskDataError(f"at most 100 recordings per task, got {n_train + n_test}")
    if train_on not in TRAIN_ON:
        raise TaskDataError(f"train_on must be one of {', '.join(TRAIN_ON)}, got {train_on!r}")
    if not np.isfinite(rate_window_s) or rate_window_s <= 0:
        raise TaskDataError(f"rate_window_s must be a positive number of seconds, got {rate_window_s}")


def _load(path: str, protocol: str, role: str) -> TaskRecording:
    try:
        rec = read_recording(path)
    except RecordingError as exc:
        raise TaskDataError(str(exc)) from None
    sensor = SENSORS[protocol]
    if rec.meta.sensor != sensor:
        kind = rec.meta.sensor or "unknown (no sidecar)"
        raise TaskDataError(f"{path}: {role} recording is from a {kind} sensor; this task needs {sensor} recordings")
    if protocol == "chamber" and np.ptp(rec.input) > 1e-9:
        raise TaskDataError(f"{path}: {role} recording's applied input varies "
                            f"({rec.input.min():g}..{rec.input.max():g} g); the chamber task needs a static unit")
    if protocol == "fulltemp":
        labels = rec.position
        if labels is None or not np.isin(labels.astype(str), ["+1g", "-1g"]).any():
            raise TaskDataError(f"{path}: {role} recording has no four-position test "
                                "(+0g, +1g, -0g, -1g); the full-temperature task needs one per node")
        pos = np.where(labels == None, "", labels).astype(str)  # noqa: E711
        try:
            nodes = four_position(rec.temperature_c, rec.output, pos)
        except ValueError as exc:
            raise TaskDataError(f"{path}: {role} recording: {exc}") from None
        if len(nodes) < 2:
            raise TaskDataError(f"{path}: {role} recording has {len(nodes)} temperature node; need at least 2")
    return TaskRecording(Path(path).stem, rec, None)


def file_data(protocol: str, train_files: list[str], test_files: list[str], train_on: str = "positions",
              rate_window_s: float = 120.0) -> MSRAData:
    """Task data from schema-v1 recordings (no simulator truth: no oracle)."""
    check_split(protocol, len(train_files), len(test_files), train_on, rate_window_s)
    train = [_load(p, protocol, "training") for p in train_files]
    test = [_load(p, protocol, "test") for p in test_files]
    sfs = [r.recording.meta.extra.get("scale_factor_hz_per_g") for r in train + test if r.recording.meta.extra]
    default = DEFAULT_MSRA_SCALE_FACTOR_HZ_PER_G if SENSORS[protocol] == "msra" else 1.0
    sf = float(next((s for s in sfs if s), default))
    return MSRAData(protocol, train, test, sf, train_on, rate_window_s, "files",
                    {"train_files": list(train_files), "test_files": list(test_files)})
