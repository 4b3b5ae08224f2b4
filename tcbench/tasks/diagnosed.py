"""The diagnosed model as a compensator (``learner=model``, the board row ``diagnosed``).

``tcbench diagnose`` (any rate: :func:`tcbench.diagnose.rate.native_rate.diagnose_any_rate`, as
``tcbench calibrate``'s ``model`` method runs it) fits a sensor model (polynomial core, thermal
lag, hysteresis, second node ...) to each training run, and the compensator is the mean of those
models run as a shipped compensator runs them
(:func:`tcbench.compensation.fitted_model.deterministic_output` with ``clock_terms=False``: the
thermometer and time as read, no term keyed to a training run's clock, no rig lines, no noise).
Each training run is diagnosed on its own and the models' outputs averaged: a diagnosis fits one
record's time line (its turn-on bias, its steps, its warm-up), and the training runs are separate
power-ons that share none. The mean uses every run and averages away each run's turn-on bias and
the terms only one run's noise or events called for, where refitting the first run's terms on the
others would keep that one run's choice of terms. The test recordings are never read by the fit:
:func:`diagnose_runs` takes the training runs only.

The room-temperature runs hold less than the diagnosis's least temperature span; they are
diagnosed with a smaller one (:data:`MIN_SPAN_C`).

Forms: ``bias`` (zero-g and chamber runs, the gyro at rest) subtracts the mean model's output at
zero input; ``inverse`` (four-position runs) solves the mean model's output
``U = b(T) + s(T) a + k(T) a^2`` (its core's bias and scale factor, its ``accel_nonlinearity``)
for the input ``a``, the three coefficients read from the models at ``a = -1, 0, 1 g``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from tcbench.compensation.data import MSRAData, TaskDataError, TaskRecording
from tcbench.compensation.fitted_model import deterministic_output
from tcbench.compensation.methods import Compensator
from tcbench.diagnose.diagnosis import Diagnosis
from tcbench.diagnose.model_file import to_sensor_model
from tcbench.diagnose.rate.native_rate import diagnose_any_rate
from tcbench.diagnose.report.write import model_spec
from tcbench.diagnose.settings import DEFAULTS
from tcbench.diagnose.signals import DiagnosisDataError
from tcbench.sensors.fitted import PolynomialModel

# The least temperature span a training run must have, where a task's runs hold less than the
# diagnosis's 2 degC: the room-temperature runs drift 0.8-1.2 degC, across which the MSRA's bias
# moves by about 0.15 Hz, tens of its white-noise sigmas (on device 0 the four runs' mean model
# took the test runs' bias std from 0.056 and 0.037 Hz to 0.022 and 0.0045 Hz).
MIN_SPAN_C = {"roomtemp": 0.5}


@dataclass(frozen=True)
class DiagnosedModels:
    """The model diagnosed on each training run (``names``), and the diagnoses."""

    names: tuple[str, ...]
    models: tuple[PolynomialModel, ...]
    diagnoses: tuple[Diagnosis, ...]

    def output(self, t_s: np.ndarray, temp_c: np.ndarray, applied: float) -> np.ndarray:
        """The models' mean noise-free output (their unit) at a constant input ``applied`` (the
        input unit: g, deg/s) over a record's clock ``t_s`` and thermometer ``temp_c``, as a
        compensator runs them (no clock-keyed terms)."""
        level = np.full(np.shape(t_s), float(applied))
        return np.mean([deterministic_output(m, t_s, temp_c, level, clock_terms=False) for m in self.models], axis=0)

    def bias(self, t_s: np.ndarray, temp_c: np.ndarray) -> np.ndarray:
        """The mean model's output at zero input: the bias a bias-form compensator removes."""
        return self.output(t_s, temp_c, 0.0)

    def response(self, t_s: np.ndarray, temp_c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The mean model's ``b, s, k`` of ``U = b + s a + k a^2`` at each sample, read from its
        output at ``a = -1, 0, 1`` (input unit)."""
        minus, zero, plus = (self.output(t_s, temp_c, a) for a in (-1.0, 0.0, 1.0))
        return zero, 0.5 * (plus - minus), 0.5 * (plus + minus) - zero


def solve_input(output: np.ndarray, b: np.ndarray, s: np.ndarray, k: np.ndarray) -> np.ndarray:
    """The input ``a`` with ``b + s a + k a^2 = output``: the root nearest the linear solution
    ``(output - b) / s`` (the stable form of the quadratic formula; the vertex where none is real)."""
    du = np.asarray(output, dtype=np.float64) - b
    root = np.sqrt(np.maximum(s ** 2 + 4.0 * k * du, 0.0))
    return 2.0 * du / (s + np.copysign(root, s))


def diagnose_runs(train: Sequence[TaskRecording], min_span_c: float | None = None) -> DiagnosedModels:
    """``tcbench diagnose`` on each training run and its model; ``min_span_c`` replaces the
    diagnosis's least temperature span (``data.min_span_c``, default 2 degC); :class:`TaskDataError`
    naming the first run that cannot be diagnosed."""
    settings = DEFAULTS if min_span_c is None else replace(DEFAULTS, data=replace(DEFAULTS.data, min_span_c=min_span_c))
    names, models, diagnoses = [], [], []
    for tr in train:
        try:
            diag = diagnose_any_rate(tr.recording, name=tr.name, settings=settings)
        except DiagnosisDataError as exc:
            raise TaskDataError(f"learner model: training recording {tr.name} cannot be diagnosed ({exc})") from None
        names.append(tr.name)
        models.append(to_sensor_model(model_spec(diag)))
        diagnoses.append(diag)
    return DiagnosedModels(tuple(names), tuple(models), tuple(diagnoses))


def diagnosed_compensator(data: MSRAData) -> tuple[Compensator, DiagnosedModels]:
    """The models diagnosed on ``data.train`` as a compensator of the task's form (see the module
    docstring), and the models; :class:`TaskDataError` when a training run cannot be diagnosed."""
    fitted = diagnose_runs(data.train, MIN_SPAN_C.get(data.protocol))
    inverse = data.form == "inverse"
    seen: dict[int, tuple[np.ndarray, ...]] = {}  # per test recording: the scorer probes it more than once

    def compensate(tr: TaskRecording, output: np.ndarray) -> np.ndarray:
        r, out = tr.recording, np.asarray(output, dtype=np.float64)
        if id(r) not in seen:
            seen[id(r)] = (fitted.response(r.time_s, r.temperature_c) if inverse
                           else (fitted.bias(r.time_s, r.temperature_c),))
        known = seen[id(r)]
        return solve_input(out, *known) if inverse else out - known[0]

    return compensate, fitted


def gyro_method(fitted: DiagnosedModels, t_s: np.ndarray, temp_c: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The gyro's compensation of a record with clock ``t_s`` and thermometer ``temp_c``: its
    output minus the mean model's bias (computed once, so the bandwidth probe reuses it)."""
    bias = fitted.bias(t_s, temp_c)
    return lambda y: np.asarray(y, dtype=np.float64) - bias
