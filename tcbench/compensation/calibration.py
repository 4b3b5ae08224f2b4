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

The training parts are screened first (:mod:`tcbench.compensation.screening`: handling bursts,
spikes and thermometer glitches dropped, the parts cut at their gaps; the command does it and
hands the pieces in), so every method is fitted on the same samples.

The scores of a branch: the RMS of the residual (output minus true input minus the model's
offset), and the RMS of its running mean over ``drift_window_s`` (the drift, with the white
noise mostly averaged out), in the recording's unit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.errors import unknown_name
from tcbench.compensation.features import running_mean, temperature_rate_c_per_s
from tcbench.compensation.px4 import OffsetPolynomial, fit_offset
from tcbench.compensation.record import Record
from tcbench.compensation.training import fit_network

METHODS = ("raw", "poly3", "poly3_rate", "bp", "bp_gd", "elman", "model")
LEARNERS = ("bp", "bp_gd", "elman")
RATE_WINDOW_S = 120.0
TRAIN_BIN_S = 5.0  # the networks' training bins: see fit()


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

    def offset(self, rec: Record) -> np.ndarray:
        """The offset at each sample of ``rec``. A sequential learner (``elman``) trained on bins
        steps once per bin: it runs on the record's bin means and its output is interpolated
        linearly between the bins' mean times (held beyond the first and last), so a sample reads
        the bin after its own, up to ``1.5 bin_s`` ahead."""
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


def fit(method: str, train: Sequence[Record], seed: int = 0, bin_s: float | None = TRAIN_BIN_S,
        bp_training: str = "lm") -> OffsetModel:
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
    bins began to cost both networks on y: ``benchmarks/calibrate_speed.py``, ``RESULTS.md``)."""
    if method not in METHODS:
        raise ValueError(unknown_name("calibration method", method, METHODS))
    if method == "raw":
        return OffsetModel("raw")
    if method == "model":
        raise ValueError("the diagnosed model is fitted by tcbench diagnose: pass it to from_model()")
    temp = np.concatenate([r.temp_c for r in train])
    target = np.concatenate([r.output - r.truth for r in train])
    rate = np.concatenate([r.rate_c_per_s for r in train])
    if method in LEARNERS:
        if bin_s is not None and not bin_s > 0:
            raise ValueError(f"bin_s must be > 0 or None, got {bin_s}")
        network, algorithm = ("bp", "gd") if method == "bp_gd" else (method, bp_training)
        learner, training = fit_network(network, train, seed, bin_s, algorithm)
        return OffsetModel(method, learner=learner, bin_s=bin_s, temp_range_c=(float(temp.min()), float(temp.max())),
                           rate_range=(float(rate.min()), float(rate.max())), training=training)
    cubic = fit_offset(temp, target)
    if method == "poly3":
        return OffsetModel("poly3", cubic)
    dt = np.clip(temp, cubic.tmin_c, cubic.tmax_c) - cubic.tref_c
    design = np.column_stack([dt ** n for n in range(4)] + [rate])
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    both = OffsetPolynomial(tuple(float(c) for c in coef[:4]), cubic.tref_c, cubic.tmin_c, cubic.tmax_c)  # type: ignore[arg-type]
    return OffsetModel("poly3_rate", both, float(coef[4]))


def from_model(sensor_model: Any) -> OffsetModel:
    """The ``model`` method: a diagnosed :class:`~tcbench.sensors.fitted.PolynomialModel` as the
    offset, as a compensator runs it: without the terms keyed to the calibration run's clock
    (steps, transients, warm-up, ageing) or its rig's lines
    (:func:`tcbench.compensation.fitted_model.compensator`; the diagnosis still reports them)."""
    return OffsetModel("model", sensor_model=sensor_model)


def residual(model: OffsetModel, rec: Record) -> np.ndarray:
    """Output minus true input minus the model's offset."""
    return rec.output - rec.truth - model.offset(rec)


def scores(res: np.ndarray, t_s: np.ndarray, drift_window_s: float = 60.0) -> dict[str, float]:
    """RMS of a residual, and of its centred running mean over ``drift_window_s``."""
    dt = float(np.median(np.diff(t_s))) if t_s.size > 1 else 1.0
    width = max(1, int(round(drift_window_s / dt)))
    smooth = running_mean(res, width) if res.size >= width else np.array([res.mean()])
    return {"rms": float(np.sqrt(np.mean(res ** 2))), "drift_rms": float(np.sqrt(np.mean(smooth ** 2)))}
