"""The part of a static record a calibration reads (:class:`Record`), apart from the methods that
fit it, so that :mod:`tcbench.compensation.calibration` and :mod:`tcbench.compensation.training`
both read it without importing each other."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.compensation.features import bin_means


@dataclass(frozen=True)
class Record:
    """The part of a static record a calibration reads: time (s), thermometer (°C), the
    output and the true input (same unit), and the temperature rate (°C/s) the trailing window
    reads there (:func:`record` computes it once, on the whole record, so a part keeps the rate
    its past gives it)."""

    t_s: np.ndarray
    temp_c: np.ndarray
    output: np.ndarray
    truth: np.ndarray
    rate_c_per_s: np.ndarray

    def part(self, start: int, stop: int) -> Record:
        return Record(*(getattr(self, f)[start:stop] for f in ("t_s", "temp_c", "output", "truth", "rate_c_per_s")))

    def binned(self, bin_s: float) -> Record:
        """The record averaged over time bins of ``bin_s`` from its first sample
        (:func:`~tcbench.compensation.features.bin_means`): one row per bin, every column its mean."""
        t_s, cols = bin_means(self.t_s, np.column_stack([self.temp_c, self.output, self.truth, self.rate_c_per_s]),
                              bin_s)
        return Record(t_s, *(np.ascontiguousarray(c) for c in cols.T))
