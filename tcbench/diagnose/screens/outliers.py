"""Isolated outliers and spikes: samples one cannot let dominate a least-squares diagnosis.

A spike (a bus or logging glitch, a shock, an ESD event, a counter wrap) is one sample, or a
run of a few, far off the rest of the record. Least squares squares it: a single 50-sigma
sample in a day of data adds 2500 sigma^2 to the held-out error, more than any effect of the
library, and its Allan deviation looks like slow noise. :func:`find_outliers` finds such
samples so that the diagnosis gives them zero weight (fitting, cross-validated scoring and the
significance tests never see them) and reports them as a finding of their own.

Detection, on the residual ``r`` of the current model (output unit):

1. **Local level**: ``r`` minus the median of its ``window_samples`` - 1 neighbours (the sample
   itself left out, so the difference has Gaussian tails under white noise; mirrored at the
   ends, so the last sample is judged against its predecessors). The median ignores runs
   shorter than half the window and follows steps and slow structure the model misses, so only
   isolated departures remain.
2. **Robust scale**: ``s = 1.4826 * MAD`` of that high-passed residual (the white sigma when
   the MAD is below ``min_scale_sigma`` of it: on an output quantised to about two sigma or more
   most samples equal their neighbours' median, and the MAD reads 0.002 sigma).
3. **Bound on the record's length**: with ``n`` samples and a family-wise false-alarm level
   ``alpha`` (1 %), a sample is an outlier when ``|z| = |r - median| / s``
   exceeds ``z_n = tail * Phi^-1(1 - alpha / (2 n))`` (Bonferroni over the ``n`` two-sided
   tests): a record of pure Gaussian noise has probability at most ``alpha`` of showing any
   outlier. ``tail`` = 1.1 because a sample minus the median of its neighbours has heavier
   tails than its MAD implies (its standard deviation is 3 % above 1.4826 MAD, and the median
   is itself noisy); without it 4 % of clean 24 h records at 1 Hz showed an outlier, with it
   none of 300 (measured, see tests/test_diagnose_outliers.py). For a 24 h record at 1 Hz
   (``n = 86400``) ``z_n = 5.83``; for 4200 samples 5.19. ``min_z`` keeps the bound at
   4.5 or more for short records, where the MAD itself is uncertain.
4. **Isolated**: flagged samples are grouped into runs of consecutive indices; a run longer
   than ``max_run_samples`` samples is structure (a step, a saturation), not a spike, and is left
   to the other detectors.

The numbers are :class:`~tcbench.diagnose.settings.OutlierSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.ndimage import median_filter
from scipy.stats import norm

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.settings import DEFAULTS, OutlierSettings
from tcbench.diagnose.signals import MAD_TO_SIGMA, DiagnosisData

MAX_LISTED = 20  # outliers listed by time and size in the report; the count covers all

EXPLANATION = ("isolated samples far beyond the noise: candidate causes are a bus or logging glitch (a corrupted "
               "or duplicated frame), a mechanical shock or a vibration burst, an electrostatic discharge, or a "
               "counter or register wrap in the readout; they are given zero weight in every fit and test")
CONFIRM_WITH = ("the logger's error and dropped-frame counters for those times, a second logger on the same sensor, "
                "or an accelerometer channel logged alongside (a shock shows on it at the same instant)")


def z_bound(n: int, settings: OutlierSettings = DEFAULTS.screens.outliers) -> float:
    """Two-sided Bonferroni bound on ``|z|`` for ``n`` Gaussian samples at family-wise level
    ``settings.alpha``, times ``settings.tail`` (at least ``settings.min_z``)."""
    return float(max(settings.tail * norm.isf(settings.alpha / (2.0 * max(n, 1))), settings.min_z))


@dataclass(frozen=True)
class Outliers:
    """Outliers of one record: sample indices, times (s), sizes (output unit: residual minus
    the local median), robust z of each, the robust scale (output unit), the bound on ``|z|`` and
    the settings of the test."""

    index: np.ndarray
    time_s: np.ndarray
    size: np.ndarray
    z: np.ndarray
    scale: float
    bound: float
    settings: OutlierSettings = field(default=DEFAULTS.screens.outliers, repr=False)

    @property
    def count(self) -> int:
        return int(self.index.size)

    def finding(self, unit: str) -> Finding:
        """The report.json ``effects`` entry (``id`` and ``shape`` ``outliers``, not a library
        effect); times and sizes listed for the :data:`MAX_LISTED` largest, in time order."""
        keep = np.sort(np.argsort(-np.abs(self.z), kind="stable")[:MAX_LISTED])
        times = [round(float(t), 6) for t in self.time_s[keep]]
        return Finding(
            id="outliers", shape="outliers", library=False,
            params={"count": self.count, "time_s": times, "size": [float(s) for s in self.size[keep]], "unit": unit},
            where={"time_s": times},
            evidence={"robust_z": [round(float(z), 2) for z in self.z[keep]], "bound_z": round(self.bound, 3),
                      "robust_sigma": self.scale, "false_alarm": self.settings.alpha,
                      "test": f"|residual - running median of {self.settings.window_samples}| / (1.4826 MAD) above "
                              f"the Bonferroni bound for the record's samples"},
            explanation=(f"{self.count} sample(s) up to {float(np.max(np.abs(self.size))):.4g} {unit} "
                         f"({float(np.max(np.abs(self.z))):.3g} robust sigma) off the local level: " + EXPLANATION),
            confirm_with=CONFIRM_WITH,
        )


def find_outliers(t_s: np.ndarray, residual: np.ndarray, white_sigma: float, *,
                  settings: OutlierSettings = DEFAULTS.screens.outliers,
                  relative_sigma: np.ndarray | None = None) -> Outliers:
    """Isolated outliers of ``residual`` (output unit, samples at ``t_s`` in s); see the module
    doc. ``white_sigma`` (output unit) is the scale when the MAD is zero. ``relative_sigma``
    (per sample, RMS 1) is the noise level where it changes with temperature or time: each
    sample is then judged against its own level, not the record's."""
    r = np.asarray(residual, dtype=float)
    n = r.size
    bound = z_bound(n, settings)
    empty = np.zeros(0, dtype=np.int64)
    window = settings.window_samples
    if n < window:
        return Outliers(empty, np.zeros(0), np.zeros(0), np.zeros(0), float(white_sigma), bound, settings)
    footprint = np.ones(window, dtype=bool)
    footprint[window // 2] = False  # the level a sample is judged against does not contain it
    high = r - median_filter(r, footprint=footprint, mode="mirror")
    level = np.ones(n) if relative_sigma is None else np.asarray(relative_sigma, dtype=float)
    scale = float(MAD_TO_SIGMA * np.median(np.abs(high / level - np.median(high / level))))
    if not scale > settings.min_scale_sigma * white_sigma:  # a grid coarser than the noise: the MAD reads near 0
        scale = float(white_sigma)
    z = high / (scale * level)
    flagged = np.abs(z) > bound
    edges = np.diff(np.concatenate(([0], flagged.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    short = (ends - starts) <= settings.max_run_samples
    index = (np.concatenate([np.arange(a, b) for a, b in zip(starts[short], ends[short], strict=True)])
             if short.any() else empty)
    return Outliers(index, t_s[index], high[index], z[index], scale, bound, settings)


def without(data: DiagnosisData, index: np.ndarray) -> DiagnosisData:
    """``data`` with the samples at ``index`` removed (zero weight in every fit and test); the
    thermometer smoothing done on the whole record is kept."""
    if index.size == 0:
        return data
    keep = np.ones(data.n, dtype=bool)
    keep[index] = False
    return replace(data, t_s=data.t_s[keep], temp_raw_c=data.temp_raw_c[keep], temp_c=data.temp_c[keep],
                   rate_c_per_s=data.rate_c_per_s[keep], input=data.input[keep], output=data.output[keep],
                   run_id=data.run_id[keep])
