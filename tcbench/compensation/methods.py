"""Compensation methods on a static-input task (MSRA, accelerometer chamber): a learner, no
compensation (raw), the memoriser (no physics: the training runs' mean output at the same time
since the start, the sanity row of docs/concepts/split-tiers.md), the lag-aware polynomial (lagpoly), and the
two oracles (the diagnosed model, ``learner=model`` and the board row ``diagnosed``, is fitted by
the diagnosis: :mod:`tcbench.tasks.diagnosed`).

Each method is a *compensator*: a function of a test recording and an output array (the
recorded one, or a probe of it) returning the compensated output (g for fulltemp, Hz for
roomtemp, g for chamber), so the scorer can also ask how a method answers at accelerations it never saw.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tcbench.compensation.data import MSRAData, TaskDataError, TaskRecording
from tcbench.compensation.lagpoly import LagPoly, fit_lag_poly
from tcbench.compensation.oracle import oracle_bias, oracle_inverse
from tcbench.learners.base import Learner

BASELINES = ("raw", "memoriser", "oracle", "oracle_thermometer", "lagpoly", "model")
BASELINE_LABELS = {"model": "diagnosed"}  # a board row named apart from its learner: the diagnosed model
Compensator = Callable[[TaskRecording, np.ndarray], np.ndarray]


def training_rmse_ug(data: MSRAData, learner: Learner, x: np.ndarray, y: np.ndarray) -> float:
    """RMSE of the trained learner on its training set ``x``, ``y``, in micro-g."""
    rmse = float(np.sqrt(np.mean((learner.predict(x) - y) ** 2)))
    per_g = 1.0 if data.form == "inverse" else data.scale_factor_hz_per_g
    return rmse / per_g * 1e6


def learner_compensator(data: MSRAData, learner: Learner,
                        input_range: tuple[np.ndarray, np.ndarray] | None = None) -> Compensator:
    """A trained learner's compensation of a test recording; ``input_range`` (lower, upper bounds
    per input column) holds its inputs to that box first, as ``tcbench calibrate`` holds a
    network's temperature and rate to their training range (beyond it a network's output is
    whatever its activations extrapolate to)."""
    def compensate(tr: TaskRecording, output: np.ndarray) -> np.ndarray:
        x, _ = data.features(tr.recording, output)
        if input_range is not None:
            x = np.clip(x, *input_range)
        return data.compensate(output, learner.predict(x))

    return compensate


def raw_compensator(data: MSRAData) -> Compensator:
    """No compensation: the output itself (its unit)."""
    return lambda tr, output: np.asarray(output, dtype=np.float64)


def memorised(recordings: list[TaskRecording], column: str = "output") -> Callable[[np.ndarray], np.ndarray]:
    """The recordings' mean ``column`` at the same time since their start, as a function of a
    record's times (past a shorter run's end, the mean of the runs still going; past the longest,
    its last value)."""
    recs = [tr.recording for tr in recordings]
    dt_s = min(float(np.median(np.diff(r.time_s))) for r in recs)
    durations = [float(r.time_s[-1] - r.time_s[0]) for r in recs]
    grid = np.arange(0.0, max(durations) + dt_s / 2, dt_s)
    grid = grid[grid <= max(durations)]  # the longest run covers every point
    rows = [np.interp(grid, r.time_s - r.time_s[0], getattr(r, column), right=np.nan) for r in recs]
    mean = np.nanmean(np.stack(rows), axis=0)
    return lambda t_s: np.interp(np.asarray(t_s) - t_s[0], grid, mean)


def memoriser_compensator(data: MSRAData) -> Compensator:
    """No physics: the training runs' mean output (and applied input) at the same time since their
    start, taken from a test run's output (``inverse``: the memorised input plus the output's
    departure from the memorised output, over the scale factor). On a test run that replays the
    training signal it is near the limit; on a new power-on it loses to a cubic in temperature where
    the drift follows temperature, and wins where it follows the time since power-on (a warm-up;
    docs/concepts/split-tiers.md)."""
    output, applied = memorised(data.train, "output"), memorised(data.train, "input")

    def compensate(tr: TaskRecording, out: np.ndarray) -> np.ndarray:
        t = tr.recording.time_s
        y = np.asarray(out, dtype=np.float64)
        if data.form == "inverse":
            return applied(t) + (y - output(t)) / data.scale_factor_hz_per_g
        return y - output(t)

    return compensate


def lagpoly_compensator(data: MSRAData, model: LagPoly | None = None) -> Compensator:
    """The lag-aware polynomial (:mod:`tcbench.compensation.lagpoly`) fitted on the training
    recordings (``model``: already fitted): the input solved from the output (``inverse``) or the
    modelled bias removed."""
    model = model if model is not None else fit_lag_poly([tr.recording for tr in data.train])
    if data.form == "inverse":
        return lambda tr, output: model.inverse(tr.recording, output)
    return lambda tr, output: np.asarray(output, dtype=np.float64) - model.bias_of(tr.recording)


def oracle_compensator(data: MSRAData, thermometer: bool = False) -> Compensator:
    """The physical limit: the simulator's deterministic model inverted at the true die
    temperature, so what is left is noise alone (simulated recordings only); with
    ``thermometer``, the same model fed the thermometer reading instead (the limit of a
    compensator that knows the physics and reads what a real one reads)."""
    if any(tr.truth is None for tr in data.test):
        raise TaskDataError("the oracle needs the simulator's truth; recordings read from files have none")
    fn = oracle_inverse if data.form == "inverse" else oracle_bias
    return lambda tr, output: fn(output, tr.truth, thermometer)  # type: ignore[arg-type]
