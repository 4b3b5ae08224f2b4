"""Thermometer glitches: single readings far off the thermometer's local level.

A bus or logging glitch can hand the thermometer a reading of 0.0 degC, or the converter's
floor (-40 degC), for a sample or a few. The smoothed temperature every term of the model is
driven by would carry it over a whole smoothing window, and the thermometer's noise estimate
would grow with its square. :func:`find_glitches` finds them the way
:mod:`tcbench.diagnose.screens.outliers` finds output spikes, on the raw reading: the reading minus the
median of its ``window_samples`` - 1 neighbours (past the ends, the readings reflected through a
robust line, so a ramp's last readings are judged against the ramp), over a robust scale
(1.4826 MAD of that difference; on a lattice, where the MAD reads 0, the RMS of the departures
without their largest 1 %, and at least half the typical non-zero step), above the Bonferroni
bound of the record's length (:func:`~tcbench.diagnose.screens.outliers.z_bound`), in runs of at most
``max_run_samples``. A thermometer with little noise bends at a ramp's corner by many times its
noise, so a glitch must also lie outside the band its neighbours span (their
``max_run_samples`` most extreme readings on either side left out, so a run's own readings do
not widen it) by more than the band is wide: a reading the sensor could have gone through is
never called a glitch. The numbers are the outliers'
(:class:`~tcbench.diagnose.settings.OutlierSettings`).

A glitch gets zero weight: before the thermometer is smoothed its reading is replaced by the
previous good one (:func:`repaired`, so it moves neither the smoothing nor the lattice), and
its sample is left out of every fit and test (:func:`~tcbench.diagnose.screens.outliers.without`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import median_filter, rank_filter

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.outliers import MAX_LISTED, z_bound
from tcbench.diagnose.settings import DEFAULTS, OutlierSettings
from tcbench.diagnose.signals import MAD_TO_SIGMA
from tcbench.sensors.recording import Recording

ID = "thermometer_glitches"
TRIM_QUANTILE = 0.99  # the robust scale's RMS leaves out the largest 1 % of the departures
EXPLANATION = ("thermometer readings far off their neighbours: a bus or logging glitch (a read that returned zero, "
               "the converter's floor or full scale, a corrupted frame), not a temperature the sensor went through; "
               "they are given zero weight (the smoothed temperature never sees them, their samples are left out "
               "of every fit and test)")
CONFIRM_WITH = ("the logger's error counters at those times, the thermometer's raw register (0x0000 or a full-scale "
                "code), or a second thermometer on the same board")


@dataclass(frozen=True)
class Glitches:
    """Thermometer glitches of one record: sample indices, times (s), readings and the local
    level they departed from (degC), robust z of each, the robust scale (degC) and the bound."""

    index: np.ndarray
    time_s: np.ndarray
    reading_c: np.ndarray
    level_c: np.ndarray
    z: np.ndarray
    scale_c: float
    bound: float
    settings: OutlierSettings = field(default=DEFAULTS.screens.outliers, repr=False)

    @property
    def count(self) -> int:
        return int(self.index.size)

    def finding(self) -> Finding:
        """The report.json ``effects`` entry (``id`` ``thermometer_glitches``, shape ``outliers``):
        how many, and the :data:`~tcbench.diagnose.screens.outliers.MAX_LISTED` largest by time, reading
        and the level they departed from."""
        keep = np.sort(np.argsort(-np.abs(self.z), kind="stable")[:MAX_LISTED])
        times = [round(float(t), 6) for t in self.time_s[keep]]
        readings = [float(v) for v in self.reading_c[keep]]
        said = ", ".join(f"{v:.4g} degC at {t:.6g} s" for t, v in zip(times, readings, strict=True))
        return Finding(
            id=ID, shape="outliers", library=False,
            params={"count": self.count, "time_s": times, "reading_c": readings,
                    "level_c": [round(float(v), 4) for v in self.level_c[keep]], "unit": "degC"},
            where={"time_s": times},
            evidence={"robust_z": [round(float(z), 2) for z in self.z[keep]], "bound_z": round(self.bound, 3),
                      "robust_sigma": self.scale_c, "false_alarm": self.settings.alpha,
                      "test": f"|reading - running median of {self.settings.window_samples}| / robust sigma (degC) "
                              "above the Bonferroni bound for the record's samples, and off its neighbours' band by "
                              "more than the band is wide, on the raw thermometer"},
            explanation=f"{self.count} thermometer reading(s) off the local level ({said}): " + EXPLANATION,
            confirm_with=CONFIRM_WITH,
        )


def _step_floor_c(temp_c: np.ndarray) -> float:
    """Half the typical non-zero step of the reading (degC): the scale of a staircase."""
    d = np.abs(np.diff(temp_c))
    d = d[d > 0]
    return 0.5 * float(np.median(d)) if d.size else 0.0


def _none(bound: float, settings: OutlierSettings) -> Glitches:
    """No glitch found."""
    empty = np.zeros(0)
    return Glitches(np.zeros(0, dtype=np.int64), empty, empty, empty, empty, 0.0, bound, settings)


def _trimmed_rms(departure: np.ndarray) -> float:
    """RMS of ``departure`` without its largest 1 % (the glitches among them): the noise of a
    reading on a lattice, where most readings equal their neighbours' median and the MAD reads 0."""
    a = np.abs(departure)
    return float(np.sqrt(np.mean(np.square(a[a <= np.quantile(a, TRIM_QUANTILE)]))))


def _end_value(x: np.ndarray) -> float:
    """The reading at ``x[0]`` on a robust line through ``x``: the median slope of its steps, the
    median level about it (a glitch among them moves neither)."""
    slope = float(np.median(np.diff(x)))
    return float(np.median(x - slope * np.arange(x.size)))


def _extended(x: np.ndarray, half: int) -> np.ndarray:
    """``x`` with ``half`` samples more at each end, reflected through the robust line's value at
    that end: a ramp carries on through the ends, so the first and last readings are judged
    against the ramp's level, not against readings mirrored back from the past."""
    k = min(2 * half + 1, x.size)
    first, last = _end_value(x[:k]), _end_value(x[::-1][:k])
    return np.concatenate((2.0 * first - x[half:0:-1], x, 2.0 * last - x[-2:-half - 2:-1]))


def find_glitches(t_s: np.ndarray, temp_c: np.ndarray,
                  settings: OutlierSettings = DEFAULTS.screens.outliers) -> Glitches:
    """Glitches of the raw thermometer reading ``temp_c`` (degC) at ``t_s`` (s); see the module doc."""
    x = np.asarray(temp_c, dtype=float)
    n, window = x.size, settings.window_samples
    bound = z_bound(n, settings)
    if n < window:
        return _none(bound, settings)
    footprint = np.ones(window, dtype=bool)
    half = window // 2
    footprint[half] = False  # the level a reading is judged against does not contain it
    extended = _extended(x, half)
    level = median_filter(extended, footprint=footprint, mode="nearest")[half:half + n]
    skip = min(settings.max_run_samples, half - 1)  # the other samples of a glitch run are left out of the band
    band_low = rank_filter(extended, skip, footprint=footprint, mode="nearest")[half:half + n]
    band_high = rank_filter(extended, -skip - 1, footprint=footprint, mode="nearest")[half:half + n]
    outside = np.maximum(band_low - x, x - band_high) > band_high - band_low  # off by more than the band is wide
    departure = x - level
    mad = float(MAD_TO_SIGMA * np.median(np.abs(departure - np.median(departure))))
    scale = max(mad, _trimmed_rms(departure), _step_floor_c(x))
    if not scale > 0:  # a constant reading has nothing to be off from
        return _none(bound, settings)
    z = departure / scale
    edges = np.diff(np.concatenate(([0], ((np.abs(z) > bound) & outside).astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    short = (ends - starts) <= settings.max_run_samples
    flagged = np.zeros(n + 1, dtype=np.int64)
    np.add.at(flagged, starts[short], 1)
    np.add.at(flagged, ends[short], -1)
    index = np.flatnonzero(np.cumsum(flagged[:-1]) > 0)
    return Glitches(index, np.asarray(t_s, dtype=float)[index], x[index], level[index], z[index], scale, bound,
                    settings)


def repaired(rec: Recording, index: np.ndarray) -> Recording:
    """``rec`` with the thermometer reading at ``index`` replaced by the previous good one (the
    first good one for a glitch at the start); the table is copied, ``rec`` is left as it was."""
    if index.size == 0:
        return rec
    temp = rec.temperature_c.copy()
    good = np.ones(temp.size, dtype=bool)
    good[index] = False
    last = np.maximum.accumulate(np.where(good, np.arange(temp.size), -1))
    last = np.where(last < 0, int(np.flatnonzero(good)[0]), last)
    temp = temp[last]
    data = rec.data.copy()
    data["temperature_c"] = temp
    return Recording(data, rec.meta)
