"""The recordings of a gyro drift/noise task: oven runs of one device, to train and to test.

Seed 001 §4.1 records two oven runs of one gyroscope (1 h at room temperature, 60 degC, then
10 degC steps held 1 h down to -40 degC) and trains on one, tests on the other. tcbench
simulates them (one device, run seeds ``100 * recordings_seed + i``, test runs on a split tier of
:mod:`tcbench.compensation.data`, the simulator's truth kept for the oracle) or reads schema-v1 gyro recordings (for example real ones; no oracle). The
pipeline needs a continuous record at one sample rate: a recording with gaps (a logger's
bursts) or an uneven clock is refused with one line naming the file.
"""

from __future__ import annotations

import functools
import json
import numbers
from dataclasses import dataclass, field

import numpy as np

from tcbench.compensation.data import DEFAULT_TIER, RunSpec, TaskDataError, TaskRecording, split_runs
from tcbench.sensors.recording import RecordingError, read_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.sensors.truth import simulate_truth

MIN_DURATION_S = 600.0  # shortest record the pipeline accepts (VMD, entropy windows, Allan)
CLOCK_TOLERANCE = 0.01  # relative spread of the sample interval a "uniform" clock may have


@dataclass
class GyroData:
    """Training and test recordings of one gyro task (output in deg/s)."""

    train: list[TaskRecording]
    test: list[TaskRecording]
    source: str = "simulated"
    info: dict[str, object] = field(default_factory=dict)

    @property
    def sample_rate_hz(self) -> float:
        """Sample rate of the training record (every record has one uniform rate)."""
        return sample_rate_hz(self.train[0].recording.time_s)

    @property
    def has_truth(self) -> bool:
        """True when every test recording carries the simulator's truth (the oracle exists)."""
        return all(tr.truth is not None for tr in self.test)


def sample_rate_hz(t_s: np.ndarray) -> float:
    """Sample rate (Hz) of uniformly spaced times ``t_s`` (s)."""
    return float((t_s.size - 1) / (t_s[-1] - t_s[0]))


def recording_key(tr: TaskRecording) -> str:
    """A name that identifies the record's content, for caching learner-independent stages."""
    extra = tr.recording.meta.extra or {}
    return f"{tr.name}|{tr.recording.meta.device_id}|{extra.get('seed')}|{extra.get('protocol_params')}" \
        f"|{len(tr.recording.data)}|{float(tr.recording.output[:64].sum())!r}"


@functools.lru_cache(maxsize=4)
def _simulated(run: RunSpec, sample_rate: float, hold_s: float, effects_json: str) -> TaskRecording:
    params = {"sample_rate_hz": sample_rate, "hold_s": hold_s, "room_s": hold_s, **dict(run.changes)}
    effects = json.loads(effects_json)
    rec = simulate_recording("gyro", "oven", run.device_seed, run.seed, effects, power_on=run.power_on, **params)
    truth = simulate_truth("gyro", "oven", run.device_seed, run.seed, effects, power_on=run.power_on, **params)
    return TaskRecording(run.name, rec, truth)


def check_effects(effects: dict[str, dict[str, float]] | None) -> dict[str, dict[str, float]]:
    """Effect changes ``{id: {param: value}}`` of the device (docs/concepts/physics.md, the effect library, output units deg/s);
    :class:`TaskDataError` naming an unknown effect or parameter."""
    from tcbench.sensors.kinds import unit

    if not effects:
        return {}
    if not isinstance(effects, dict) or not all(isinstance(v, dict) for v in effects.values()):
        raise TaskDataError(f"effects must map effect ids to {{parameter: value}}, got {effects!r}")
    try:
        unit("gyro", 0).model.with_effects(effects)
    except (KeyError, TypeError, ValueError) as exc:
        raise TaskDataError(f"effects: {str(exc).strip(chr(39))}") from None
    return {str(k): {str(p): float(v) for p, v in d.items()} for k, d in effects.items()}


def _is_real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and bool(np.isfinite(value))


def check_settings(sample_rate: float, hold_s: float, n_train: int, n_test: int) -> None:
    """Raise :class:`TaskDataError` for settings no oven run can have."""
    if not (_is_real(sample_rate) and 0.1 <= sample_rate <= 1000.0):
        raise TaskDataError(f"sample_rate_hz must be in [0.1, 1000] Hz, got {sample_rate}")
    if not (_is_real(hold_s) and 60.0 <= hold_s <= 86400.0):
        raise TaskDataError(f"hold_s must be in [60, 86400] s, got {hold_s}")
    for name, value in (("n_train", n_train), ("n_test", n_test)):
        if not (_is_real(value) and int(value) == value and 1 <= value <= 10):
            raise TaskDataError(f"{name} must be an integer in 1..10, got {value!r}")


def simulated_gyro_data(device_seed: int, recordings_seed: int, n_train: int = 1, n_test: int = 1,
                        sample_rate: float = 10.0, hold_s: float = 3600.0,
                        effects: dict[str, dict[str, float]] | None = None, split: str = DEFAULT_TIER) -> GyroData:
    """``n_train`` training and ``n_test`` test oven runs of gyro ``device_seed`` (its effects
    changed by ``effects``, see :func:`check_effects`) on tier ``split``
    (:func:`tcbench.compensation.data.split_runs`)."""
    check_settings(sample_rate, hold_s, n_train, n_test)
    changes = json.dumps(check_effects(effects), sort_keys=True)
    train, test = split_runs("oven", split, device_seed, recordings_seed, n_train, n_test)
    recs = [_simulated(run, float(sample_rate), float(hold_s), changes) for run in train + test]
    return GyroData(recs[:n_train], recs[n_train:], "simulated",
                    {"device_seed": int(device_seed), "recordings_seed": int(recordings_seed), "split": split,
                     "sample_rate_hz": float(sample_rate), "hold_s": float(hold_s), "effects": json.loads(changes)})


def load_gyro_file(path: str, role: str) -> TaskRecording:
    """A schema-v1 gyro recording fit for the pipeline; :class:`TaskDataError` naming the file."""
    try:
        rec = read_recording(path)
    except RecordingError as exc:
        raise TaskDataError(str(exc)) from None
    if rec.meta.sensor != "gyro":
        kind = rec.meta.sensor or "unknown (no sidecar)"
        raise TaskDataError(f"{path}: {role} recording is from a {kind} sensor; gyro tasks need gyro recordings")
    t = rec.time_s
    dt = np.diff(t)
    if t.size < 3 or t[-1] - t[0] < MIN_DURATION_S:
        raise TaskDataError(f"{path}: {role} recording lasts {t[-1] - t[0]:.0f} s; the pipeline needs "
                            f"at least {MIN_DURATION_S:.0f} s")
    step = float(np.median(dt))
    worst = int(np.argmax(np.abs(dt - step)))
    if abs(dt[worst] - step) > CLOCK_TOLERANCE * step:
        raise TaskDataError(f"{path}: {role} recording is not uniformly sampled (rows {worst + 1}-{worst + 2}: "
                            f"{dt[worst]:g} s against a median of {step:g} s); the pipeline needs one "
                            "continuous record (no bursts or gaps)")
    if np.ptp(rec.temperature_c) < 1.0:
        raise TaskDataError(f"{path}: {role} recording spans {np.ptp(rec.temperature_c):.2f} degC; a drift "
                            "model needs a temperature range")
    return TaskRecording(path.rsplit("/", 1)[-1].rsplit(".", 1)[0], rec, None)


def file_gyro_data(train_files: list[str], test_files: list[str]) -> GyroData:
    """Task data from schema-v1 gyro recordings (no simulator truth: no oracle)."""
    if not train_files or not test_files:
        raise TaskDataError("give at least one training and one test recording")
    train = [load_gyro_file(p, "training") for p in train_files]
    test = [load_gyro_file(p, "test") for p in test_files]
    return GyroData(train, test, "files", {"train_files": list(train_files), "test_files": list(test_files)})
