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

Recordings are simulated from the sensors package or read from schema-v1 files (for example
real ones); simulated ones keep the simulator's truth for the oracle. A simulated task draws its
test runs on one of four tiers (:data:`SPLITS`, docs/concepts/split-tiers.md), from easiest to hardest:

- ``replay``: the training runs' power-on again, with new noise (the signal replayed: a
  diagnostic, not a benchmark — a memoriser of the training runs can win here);
- ``next_run`` (the default): new power-ons of the same device under the same programme (turn-on
  bias and scale factor, hysteresis state, chamber timing and the thermometer differ,
  :mod:`tcbench.sensors.runs`);
- ``new_profile``: new power-ons under a programme the training never saw (:data:`NEW_PROFILE`:
  the holds in reverse order and ramps twice as fast; for the room-temperature test, a room 5 °C
  warmer);
- ``new_device``: the training runs on some units of the population, the test runs on others.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.errors import unknown_name
from tcbench.metrics.accelerometer import four_position
from tcbench.sensors import kinds
from tcbench.sensors.data_hash import shared_recordings
from tcbench.sensors.recording import Recording, RecordingError, read_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.sensors.truth import Truth, simulate_truth

PROTOCOLS = {"fulltemp": "inverse", "roomtemp": "bias", "chamber": "bias"}
SENSORS = {"fulltemp": "msra", "roomtemp": "msra", "chamber": "accel"}  # the kind each protocol records
# (train, test) recordings: seed 000 §3.2's for the MSRA; three and two chamber cycles otherwise
DEFAULT_SPLIT = {"fulltemp": (3, 2), "roomtemp": (4, 2), "chamber": (3, 2)}
TRAIN_ON = ("positions", "all")
SPLITS = ("replay", "next_run", "new_profile", "new_device")
DEFAULT_TIER = "next_run"
# what the new_profile tier changes in its test runs' programme (simulate_recording's arguments)
NEW_PROFILE: dict[str, dict[str, object]] = {
    "fulltemp": {"reverse": True, "ramp_scale": 2.0},
    "chamber": {"reverse": True, "ramp_scale": 2.0},
    "roomtemp": {"ambient_c": 28.0},
    "oven": {"reverse": True, "ramp_scale": 2.0},  # the gyro's (tcbench.compensation.gyro.data)
}


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

    def input_range(self, x_train: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (each ``(2,)``) a learner's inputs are held to with
        ``clamp_inputs``: the thermal columns' (temperature, and for ``bias`` its rate) minimum
        and maximum over the training inputs ``x_train``; the output ``U`` of ``inverse`` is the
        measurand and stays free (``-inf``, ``inf``)."""
        low, high = np.min(x_train, axis=0), np.max(x_train, axis=0)
        if self.form == "inverse":
            low[0], high[0] = -np.inf, np.inf
        return low, high

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

    def training_runs(self, sequential: bool = False) -> np.ndarray:
        """The training recording (its index in :attr:`train`) of each row of :meth:`training_set`."""
        sizes = [self.training_rows(tr.recording, sequential).size for tr in self.train]
        return np.repeat(np.arange(len(sizes)), sizes)

    def compensate(self, output: np.ndarray, prediction: np.ndarray) -> np.ndarray:
        """Compensated output from a learner's prediction over every row: the prediction in g
        (fulltemp), or ``output - prediction`` in the output unit (roomtemp: Hz, chamber: g)."""
        return prediction if self.form == "inverse" else output - prediction


def recording_seed(recordings_seed: int, index: int) -> int:
    """Run seed of the ``index``-th recording of a task instance."""
    return 100 * int(recordings_seed) + int(index)


def check_tier(split: object) -> None:
    """A :class:`TaskDataError` unless ``split`` is one of :data:`SPLITS`."""
    if split not in SPLITS:
        raise TaskDataError(unknown_name("split", split, SPLITS) + f" (default {DEFAULT_TIER})")


@dataclass(frozen=True)
class RunSpec:
    """One simulated run of a task: the device, the run seed, whose power-on it runs (None: its
    own) and the programme's changes (``simulate_recording`` keyword arguments, as sorted pairs)."""

    device_seed: int
    seed: int
    power_on: int | None = None
    changes: tuple[tuple[str, object], ...] = ()

    @property
    def name(self) -> str:
        replay = "" if self.power_on is None else f"-replay{self.power_on}"
        profile = "-newprofile" if self.changes else ""
        return f"dev{self.device_seed}-seed{self.seed}{replay}{profile}"


def _replay(protocol: str, d: int, train_seeds: list[int],
            test_seeds: list[int]) -> tuple[list[RunSpec], list[RunSpec]]:
    return [RunSpec(d, s, train_seeds[0]) for s in train_seeds], [RunSpec(d, s, train_seeds[0]) for s in test_seeds]


def _next_run(protocol: str, d: int, train_seeds: list[int],
              test_seeds: list[int]) -> tuple[list[RunSpec], list[RunSpec]]:
    return [RunSpec(d, s) for s in train_seeds], [RunSpec(d, s) for s in test_seeds]


def _new_profile(protocol: str, d: int, train_seeds: list[int],
                 test_seeds: list[int]) -> tuple[list[RunSpec], list[RunSpec]]:
    changes = tuple(sorted(NEW_PROFILE[protocol].items()))
    return [RunSpec(d, s) for s in train_seeds], [RunSpec(d, s, None, changes) for s in test_seeds]


def _new_device(protocol: str, d: int, train_seeds: list[int],
                test_seeds: list[int]) -> tuple[list[RunSpec], list[RunSpec]]:
    n_train = len(train_seeds)
    return ([RunSpec(d + i, s) for i, s in enumerate(train_seeds)],
            [RunSpec(d + n_train + j, s) for j, s in enumerate(test_seeds)])


# The training and test runs of each tier: ``(protocol, device_seed, train seeds, test seeds) ->
# (train, test)``; its keys are :data:`SPLITS`.
TIER_RUNS: dict[str, Callable[[str, int, list[int], list[int]], tuple[list[RunSpec], list[RunSpec]]]] = {
    "replay": _replay,
    "next_run": _next_run,
    "new_profile": _new_profile,
    "new_device": _new_device,
}


def split_runs(protocol: str, split: str, device_seed: int, recordings_seed: int, n_train: int,
               n_test: int) -> tuple[list[RunSpec], list[RunSpec]]:
    """The training and test runs of a simulated task on tier ``split`` (:data:`SPLITS`); a
    :class:`TaskDataError` for an unknown tier, or for one whose test runs would be training runs."""
    check_tier(split)
    seeds = [recording_seed(recordings_seed, i) for i in range(n_train + n_test)]
    d = int(device_seed)
    train, test = TIER_RUNS[split](protocol, int(device_seed), seeds[:n_train], seeds[n_train:])
    if reused := set(train) & set(test):
        raise TaskDataError(f"split {split!r} would test on its own training run {sorted(reused, key=str)[0].name}")
    return train, test


@functools.lru_cache(maxsize=16)
def _simulated(protocol: str, run: RunSpec) -> TaskRecording:
    args = dict(run.changes)
    rec = simulate_recording(SENSORS[protocol], protocol, run.device_seed, run.seed, power_on=run.power_on, **args)
    truth = simulate_truth(SENSORS[protocol], protocol, run.device_seed, run.seed, power_on=run.power_on, **args)
    return TaskRecording(run.name, rec, truth)


def simulated_data(protocol: str, device_seed: int, recordings_seed: int, n_train: int, n_test: int,
                   train_on: str = "positions", rate_window_s: float = 120.0,
                   split: str = DEFAULT_TIER) -> MSRAData:
    """``n_train`` training and ``n_test`` test runs of device ``device_seed`` on tier ``split``
    (see the module docstring)."""
    check_split(protocol, n_train, n_test, train_on, rate_window_s)
    train_runs, test_runs = split_runs(protocol, split, device_seed, recordings_seed, n_train, n_test)
    recs = [_simulated(protocol, run) for run in train_runs + test_runs]
    sf = float(recs[0].recording.meta.extra.get("scale_factor_hz_per_g") or 1.0)
    return MSRAData(protocol, recs[:n_train], recs[n_train:], sf, train_on, rate_window_s, "simulated",
                    {"device_seed": int(device_seed), "recordings_seed": int(recordings_seed), "split": split})


def check_split(protocol: str, n_train: int, n_test: int, train_on: str, rate_window_s: float) -> None:
    """Raise :class:`TaskDataError` for an impossible split or setting."""
    if protocol not in PROTOCOLS:
        raise TaskDataError(unknown_name("compensation protocol", protocol, PROTOCOLS))
    if int(n_train) != n_train or n_train < 1 or int(n_test) != n_test or n_test < 1:
        raise TaskDataError(f"n_train and n_test must be integers >= 1, got {n_train} and {n_test}")
    if n_train + n_test > 100:
        raise TaskDataError(f"at most 100 recordings per task, got {n_train + n_test}")
    if train_on not in TRAIN_ON:
        raise TaskDataError(f"train_on must be one of {', '.join(TRAIN_ON)}, got {train_on!r}")
    if not np.isfinite(rate_window_s) or rate_window_s <= 0:
        raise TaskDataError(f"rate_window_s must be a positive number of seconds, got {rate_window_s}")


def _check_chamber_file(rec: Recording, path: str, role: str) -> None:
    if np.ptp(rec.input) > 1e-9:
        raise TaskDataError(f"{path}: {role} recording's applied input varies "
                            f"({rec.input.min():g}..{rec.input.max():g} g); the chamber task needs a static unit")


def _check_fulltemp_file(rec: Recording, path: str, role: str) -> None:
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


# What a recording file must show for a protocol beyond its sensor kind: ``(recording, path, role)``
# raising :class:`TaskDataError`; a protocol without an entry takes any recording of its kind.
FILE_CHECKS: dict[str, Callable[[Recording, str, str], None]] = {
    "chamber": _check_chamber_file,
    "fulltemp": _check_fulltemp_file,
}


def _load(path: str, protocol: str, role: str) -> TaskRecording:
    try:
        rec = read_recording(path)
    except RecordingError as exc:
        raise TaskDataError(str(exc)) from None
    sensor = SENSORS[protocol]
    if rec.meta.sensor != sensor:
        kind = rec.meta.sensor or "unknown (no sidecar)"
        raise TaskDataError(f"{path}: {role} recording is from a {kind} sensor; this task needs {sensor} recordings")
    check = FILE_CHECKS.get(protocol)
    if check is not None:
        check(rec, path, role)
    return TaskRecording(Path(path).stem, rec, None)


def file_data(protocol: str, train_files: list[str], test_files: list[str], train_on: str = "positions",
              rate_window_s: float = 120.0) -> MSRAData:
    """Task data from schema-v1 recordings (no simulator truth: no oracle)."""
    check_split(protocol, len(train_files), len(test_files), train_on, rate_window_s)
    train = [_load(p, protocol, "training") for p in train_files]
    test = [_load(p, protocol, "test") for p in test_files]
    if shared := shared_recordings(train_files, test_files):
        raise TaskDataError(f"{shared[0]} is both a training and a test recording (the same data); a task never "
                            "tests on its own training runs")
    sfs = [r.recording.meta.extra.get("scale_factor_hz_per_g") for r in train + test if r.recording.meta.extra]
    sf = float(next((s for s in sfs if s), kinds.get(SENSORS[protocol]).nominal_scale_factor))
    return MSRAData(protocol, train, test, sf, train_on, rate_window_s, "files",
                    {"train_files": list(train_files), "test_files": list(test_files)})
