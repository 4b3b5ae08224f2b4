"""The diagnosed model as a compensator of a bias-form task (``learner=model``).

``tcbench diagnose`` runs on the first training recording and fits a sensor model (polynomial
core, thermal lag, hysteresis, warm-up, steps ...); that model, run noise-free on a test
recording's thermometer, clock and input without its spectral lines
(:func:`tcbench.compensation.fitted_model.deterministic_output`), is the bias removed. One
recording is diagnosed, not all of them: the diagnosis fits one record's time line (its warm-up,
its steps), and the training recordings are separate runs.
"""

from __future__ import annotations

import numpy as np

from tcbench.compensation.data import MSRAData, TaskDataError, TaskRecording
from tcbench.compensation.fitted_model import deterministic_output
from tcbench.compensation.methods import Compensator
from tcbench.diagnose.diagnosis import Diagnosis, diagnose
from tcbench.diagnose.model_file import to_sensor_model
from tcbench.diagnose.report import model_spec
from tcbench.diagnose.signals import DiagnosisDataError


def diagnosed_compensator(data: MSRAData) -> tuple[Compensator, Diagnosis]:
    """The model diagnosed on ``data.train[0]`` as a compensator (see the module docstring), and
    the diagnosis; :class:`TaskDataError` when the recording cannot be diagnosed."""
    if data.form != "bias":
        raise TaskDataError(f"the diagnosed model compensates bias-form tasks; {data.protocol} solves for the input")
    first = data.train[0]
    try:
        diag = diagnose(first.recording, name=first.name)
    except DiagnosisDataError as exc:
        raise TaskDataError(f"learner model: training recording {first.name} cannot be diagnosed ({exc})") from None
    model = to_sensor_model(model_spec(diag))

    def compensate(tr: TaskRecording, output: np.ndarray) -> np.ndarray:
        r = tr.recording
        return np.asarray(output, dtype=np.float64) - deterministic_output(model, r.time_s, r.temperature_c, r.input)

    return compensate, diag
