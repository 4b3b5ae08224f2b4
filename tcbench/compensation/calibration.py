"""Calibration on a user's own record: fit an offset model on some temperature branches of a
static record (the sensor at rest, its true input known: 0 for a gyro, or the ``input`` column)
and score it on the others.

Methods, each a function of what a flight controller can read (the thermometer and time):

- ``raw``: no correction (the output minus the true input).
- ``poly3``: the cubic offset in the temperature as PX4 ships it (:mod:`tcbench.compensation.px4`:
  held at the edges of the fitted range).
- ``poly3_rate``: the cubic plus a term in the temperature rate (``dT/dt`` over a trailing
  window, :func:`tcbench.compensation.features.temperature_rate_c_per_s`): the first-order
  expansion of an offset seen through a thermal lag, which the heating and cooling branches
  of a cycle tell apart.
- ``bp``, ``elman``: the seed papers' networks (:mod:`tcbench.learners`) on ``[T, dT/dt]``,
  ``bp`` trained by Levenberg-Marquardt when the rows allow it, ``bp_gd`` the same network by
  the paper's gradient descent (1000 epochs), ``elman`` by Adam (:mod:`tcbench.compensation.training`),
  from the run's seed on the means of :data:`TRAIN_BIN_S` time bins of
  the training parts (see :func:`fit`). Their inputs are held to the box they were trained on
  (as PX4 holds its cubic to its temperature range): beyond it a network gives its value at the
  edge, never an extrapolation of its activations. A fit on one direction of a cycle has seen one
  sign of the rate only, so it cannot tell the other direction anything.
- ``model``: the diagnosed physics. ``tcbench diagnose`` on the training parts fits a model
  (polynomial core, thermal lag, hysteresis, warm-up, steps ...; :mod:`tcbench.diagnose`), and
  the deterministic output of what a compensator can run of it is the offset: its temperature
  terms, driven by the thermometer's history, without the terms keyed to the calibration run's
  clock (steps, transients, warm-up, ageing) or its rig's lines — what the diagnosis explains is
  not all that a compensator may use (:mod:`tcbench.compensation.fitted_model`); the command
  (:mod:`tcbench.commands.calibration`) runs the diagnosis and hands the model in with
  :func:`from_model`.
- ``memoriser``: no physics, a control. The training parts' mean offset as a function of the time
  elapsed since the start of the part each sample lies in (:func:`fit_memoriser`), subtracted from
  a held-out part at the same elapsed time since its own start. Not among the command's default
  methods: it needs the parts' starts, which a flight controller does not have.

The training parts are screened first (:mod:`tcbench.compensation.screening`: handling bursts,
spikes and thermometer glitches dropped, the parts cut at their gaps; the command does it and
hands the pieces in), so every method is fitted on the same samples.

The scores of a branch: the RMS of the residual (output minus true input minus the model's
offset), and the RMS of its running mean over ``drift_window_s`` (the drift, with the white
noise mostly averaged out), in the recording's unit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.errors import unknown_name
from tcbench.compensation.features import running_mean, temperature_rate_c_per_s
from tcbench.compensation.px4 import OffsetPolynomial, fit_offset
from tcbench.compensation.record import Record
from tcbench.compensation.training import fit_network

LEARNERS = ("bp", "bp_gd", "elman")
RATE_WINDOW_S = 120.0
TRAIN_BIN_S = 5.0  # the networks' training bins: see fit()
MEMORY_BIN_S = 5.0  # the memoriser's bins of elapsed time since a part's start


def record(t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray, truth: np.ndarray) -> Record:
    """A :class:`Record` of a whole recording, its temperature rate computed once."""
    return Record(t_s, temp_c, output, truth, temperature_rate_c_per_s(t_s, temp_c, RATE_WINDOW_S))


@dataclass(frozen=True)
class OffsetModel:
    """A fitted offset: the cubic in the temperature and, for ``poly3_rate``, a rate coefficient
    (unit per °C/s) on the rate the trailing window reads."""

    method: str
    cubic: OffsetPolynomial | None = None
    rate_coef: float = 0.0
    learner: Any = None  # a fitted tcbench learner on [T, dT/dt]
    sensor_model: Any = None  # a diagnosed PolynomialModel
    bin_s: float | None = None  # the learner's training bins (s); a sequential one also runs on them
    temp_range_c: tuple[float, float] | None = None  # a learner's training temperatures: its input is held to them
    rate_range: tuple[float, float] | None = None  # and its training rates (degC/s)
    training: dict[str, Any] | None = None  # how a network was trained (tcbench.compensation.training)
    memory: tuple[np.ndarray, np.ndarray] | None = None  # the memoriser's elapsed times (s) and mean offsets

    def offset(self, rec: Record, part_starts_s: np.ndarray | None = None) -> np.ndarray:
        """The offset at each sample of ``rec``. A sequential learner (``elman``) trained on bins
        steps once per bin: it runs on the record's bin means and its output is interpolated
        linearly between the bins' mean times (held beyond the first and last), so a sample reads
        the bin after its own, up to ``1.5 bin_s`` ahead. The memoriser reads the time elapsed
        since the start of each sample's part (``part_starts_s``, the parts' first times, s;
        ``None``: ``rec`` is one part); every other method ignores ``part_starts_s``."""
        if self.memory is not None:
            elapsed_s = elapsed_in_part_s(rec.t_s, part_starts_s)
            return np.interp(elapsed_s, *self.memory)
        if self.sensor_model is not None:
            from tcbench.compensation.fitted_model import deterministic_output

            return deterministic_output(self.sensor_model, rec.t_s, rec.temp_c, rec.truth,
                                        clock_terms=False) - rec.truth
        if self.learner is not None:
            if self.bin_s and self.learner.sequential:
                coarse = rec.binned(self.bin_s)
                return np.interp(rec.t_s, coarse.t_s, _predicted(self.learner, coarse, self.temp_range_c,
                                                                 self.rate_range))
            return _predicted(self.learner, rec, self.temp_range_c, self.rate_range)
        if self.cubic is None:
            return np.zeros_like(rec.output)
        return self.cubic.offset(rec.temp_c) + self.rate_coef * rec.rate_c_per_s


def _predicted(learner: Any, rec: Record, temp_range_c: tuple[float, float] | None = None,
               rate_range: tuple[float, float] | None = None) -> np.ndarray:
    """A fitted learner's output on ``[T, dT/dt]`` of ``rec``, ``T`` held to ``temp_range_c`` and
    ``dT/dt`` to ``rate_range`` (as PX4 holds its cubic to ``TMIN..TMAX``: beyond its training
    inputs a network's output is whatever its activations extrapolate to, so it gives its value
    at the edge of the box it was trained on)."""
    temp = rec.temp_c if temp_range_c is None else np.clip(rec.temp_c, *temp_range_c)
    rate = rec.rate_c_per_s if rate_range is None else np.clip(rec.rate_c_per_s, *rate_range)
    inputs = np.column_stack([temp, rate])
    return np.asarray(learner.predict(inputs), dtype=np.float64).reshape(-1)


def elapsed_in_part_s(t_s: np.ndarray, part_starts_s: np.ndarray | None = None) -> np.ndarray:
    """The time (s) elapsed at each of ``t_s`` since the start of the part it lies in: the latest
    of ``part_starts_s`` at or before it (``None``: since ``t_s[0]``, one part). A time before the
    first start counts from the first start (negative elapsed times, held to the memoriser's
    first bin)."""
    t = np.asarray(t_s, dtype=np.float64)
    if part_starts_s is None:
        return t - t[0] if t.size else t.copy()
    starts = np.sort(np.asarray(part_starts_s, dtype=np.float64).reshape(-1))
    if starts.size == 0:
        raise ValueError("part_starts_s is empty: give the parts' first times, or None for one part")
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, None)
    return t - starts[k]


def fit_memoriser(train: Sequence[Record], part_starts_s: np.ndarray | None = None,
                  bin_s: float = MEMORY_BIN_S) -> OffsetModel:
    """The ``memoriser``: the mean offset (output minus true input) of the training samples in
    each ``bin_s`` bin of the time elapsed since the start of their part (``part_starts_s``: the
    first times of the parts the records ``train`` were cut from, e.g. the fitted temperature
    branches or time blocks before screening cut them at gaps; ``None``: each record is a part),
    at the bin's mean elapsed time; at a held-out part it is interpolated linearly in the time
    elapsed since that part's start, and held beyond the first and last bins.

    What it can know: whatever the training parts share at the same time since their start — a
    constant bias, a warm-up or a drift keyed to the part's clock, and for the time blocks of one
    slow cooling the level and the trend within a block that its neighbours share. What it cannot
    know: the temperature. A held-out part whose temperature runs differently at the same elapsed
    time (the other direction of a cycle, another range, another rate) gets the training parts'
    offset at that time whatever its thermometer reads; beyond the longest training part it holds
    the last bin's offset. A compensator cannot run it (a flight has no parts; the split is known
    after the recording ends): it is a control. A method that does not beat it has not shown that
    it learned anything from the thermometer that the split's own clock does not already give."""
    if not bin_s > 0:
        raise ValueError(f"bin_s must be > 0, got {bin_s}")
    if not train:
        raise ValueError("the memoriser needs at least one training record")
    if part_starts_s is None:
        elapsed = np.concatenate([elapsed_in_part_s(r.t_s) for r in train])
    else:
        elapsed = elapsed_in_part_s(np.concatenate([r.t_s for r in train]), part_starts_s)
    target = np.concatenate([r.output - r.truth for r in train])
    index = np.floor(np.clip(elapsed, 0.0, None) / bin_s).astype(np.int64)
    counts = np.bincount(index)
    kept = counts > 0
    centres_s = np.bincount(index, weights=elapsed)[kept] / counts[kept]
    means = np.bincount(index, weights=target)[kept] / counts[kept]
    return OffsetModel("memoriser", memory=(centres_s, means))


def fit(method: str, train: Sequence[Record], seed: int = 0, bin_s: float | None = TRAIN_BIN_S,
        bp_training: str = "lm", part_starts_s: np.ndarray | None = None) -> OffsetModel:
    """The offset model ``method`` (one of :data:`METHODS`) fitted on the records ``train``; a
    network's initial weights drawn from ``seed``; ``bp`` trained by Levenberg-Marquardt when
    the rows allow it (``bp_training=gd``: gradient descent; :mod:`tcbench.compensation.training`).

    A network (``bp``, ``elman``) is trained on the means of ``bin_s`` time bins of each training
    record (:meth:`Record.binned`; ``None``: on every sample), its normalisation fitted to the
    samples. Approximation: the inputs ``[T, dT/dt]`` carry nothing faster than the thermometer's
    changes (the rate is a 120-s trailing slope), so a network whose output is nearly constant
    within a bin sees, in the mean squared error of the samples (bins of nearly equal counts),
    the error of the bin means plus the within-bin variance of the target (noise, which no
    parameter changes): the same minimum and gradient to first order in the within-bin change of
    the inputs, on fewer rows (5 s at 1 Hz: 5x fewer). ``bp`` then predicts each sample; ``elman``,
    a recurrence, steps once per bin (its context one bin back, its training window ``window``
    bins) and predicts on bins too (:meth:`OffsetModel.offset`). Fitted on the first branch of
    the tofupilot cycle (2 Hz, up to 3 degC/min) with ten seeds, the held-out drift on samples and
    on 5-s bins differ by less than the seeds' spread on every gyro axis, either way (coarser
    bins began to cost both networks on y: ``benchmarks/calibrate_speed.py``, ``RESULTS.md``).

    ``memoriser`` reads ``part_starts_s`` (:func:`fit_memoriser`); the other methods ignore it."""
    if method not in METHODS:
        raise ValueError(unknown_name("calibration method", method, METHODS))
    return FITTERS[method](_FitInputs(method, train, seed, bin_s, bp_training, part_starts_s))


@dataclass(frozen=True)
class _FitInputs:
    """What :func:`fit` was given, for the fitter of its method (:data:`FITTERS`)."""

    method: str
    train: Sequence[Record]
    seed: int
    bin_s: float | None
    bp_training: str
    part_starts_s: np.ndarray | None

    def temp_c(self) -> np.ndarray:
        return np.concatenate([r.temp_c for r in self.train])

    def target(self) -> np.ndarray:
        return np.concatenate([r.output - r.truth for r in self.train])

    def rate_c_per_s(self) -> np.ndarray:
        return np.concatenate([r.rate_c_per_s for r in self.train])


def _fit_raw(a: _FitInputs) -> OffsetModel:
    return OffsetModel("raw")


def _fit_model(a: _FitInputs) -> OffsetModel:
    raise ValueError("the diagnosed model is fitted by tcbench diagnose: pass it to from_model()")


def _fit_memoriser(a: _FitInputs) -> OffsetModel:
    return fit_memoriser(a.train, a.part_starts_s)


def _fit_poly3(a: _FitInputs) -> OffsetModel:
    return OffsetModel("poly3", fit_offset(a.temp_c(), a.target()))


def _fit_poly3_rate(a: _FitInputs) -> OffsetModel:
    temp, target = a.temp_c(), a.target()
    cubic = fit_offset(temp, target)
    dt = np.clip(temp, cubic.tmin_c, cubic.tmax_c) - cubic.tref_c
    design = np.column_stack([dt ** n for n in range(4)] + [a.rate_c_per_s()])
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    both = OffsetPolynomial(tuple(float(c) for c in coef[:4]), cubic.tref_c, cubic.tmin_c, cubic.tmax_c)  # type: ignore[arg-type]
    return OffsetModel("poly3_rate", both, float(coef[4]))


def _fit_learner(network: str, algorithm: str | None = None) -> Callable[[_FitInputs], OffsetModel]:
    """The fitter of a network method: the learner ``network`` trained with ``algorithm``
    (``None``: the ``bp_training`` asked for)."""

    def fit_one(a: _FitInputs) -> OffsetModel:
        if a.bin_s is not None and not a.bin_s > 0:
            raise ValueError(f"bin_s must be > 0 or None, got {a.bin_s}")
        learner, training = fit_network(network, a.train, a.seed, a.bin_s, algorithm or a.bp_training)
        temp, rate = a.temp_c(), a.rate_c_per_s()
        return OffsetModel(a.method, learner=learner, bin_s=a.bin_s,
                           temp_range_c=(float(temp.min()), float(temp.max())),
                           rate_range=(float(rate.min()), float(rate.max())), training=training)

    return fit_one


# The fitter of each calibration method; their names are :data:`METHODS`.
FITTERS: dict[str, Callable[[_FitInputs], OffsetModel]] = {
    "raw": _fit_raw,
    "poly3": _fit_poly3,
    "poly3_rate": _fit_poly3_rate,
    "bp": _fit_learner("bp"),
    "bp_gd": _fit_learner("bp", "gd"),
    "elman": _fit_learner("elman"),
    "model": _fit_model,
    "memoriser": _fit_memoriser,
}
METHODS = tuple(FITTERS)


def from_model(sensor_model: Any) -> OffsetModel:
    """The ``model`` method: a diagnosed :class:`~tcbench.sensors.fitted.PolynomialModel` as the
    offset, as a compensator runs it: without the terms keyed to the calibration run's clock
    (steps, transients, warm-up, ageing) or its rig's lines
    (:func:`tcbench.compensation.fitted_model.compensator`; the diagnosis still reports them)."""
    return OffsetModel("model", sensor_model=sensor_model)


def residual(model: OffsetModel, rec: Record, part_starts_s: np.ndarray | None = None) -> np.ndarray:
    """Output minus true input minus the model's offset (``part_starts_s``: see :meth:`OffsetModel.offset`)."""
    return rec.output - rec.truth - model.offset(rec, part_starts_s)


def scores(res: np.ndarray, t_s: np.ndarray, drift_window_s: float = 60.0) -> dict[str, float]:
    """RMS of a residual, and of its centred running mean over ``drift_window_s``."""
    dt = float(np.median(np.diff(t_s))) if t_s.size > 1 else 1.0
    width = max(1, int(round(drift_window_s / dt)))
    smooth = running_mean(res, width) if res.size >= width else np.array([res.mean()])
    return {"rms": float(np.sqrt(np.mean(res ** 2))), "drift_rms": float(np.sqrt(np.mean(smooth ** 2)))}
