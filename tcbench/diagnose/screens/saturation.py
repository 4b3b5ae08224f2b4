"""Saturation: an output clipped at a ceiling or a floor.

A range limit, a converter at full scale or a digital filter's overflow holds the output at one
value while the physics would take it beyond. In a noisy record that is a point mass at the
extreme: many samples at (or within a tiny tolerance of) the maximum, where an unclipped noisy
output has one maximum and its density falls towards it. :func:`find_saturation` tests each side:

- **top cell**: the samples within ``tol`` of the extreme value, ``tol`` half the output's
  lattice step when it is quantised, else ``tol_sigma`` white sigmas (so a clip followed by
  a little rounding is still one level);
- **next cell**: the samples in the adjacent ``h`` below it (above it for a floor), ``h`` one
  lattice step or ``next_sigma`` white sigmas, whichever is larger;
- **test**: without clipping, the density of the output near its extreme is at most
  ``density_ratio`` times its density in the next cell (a noisy output's density falls towards its
  extreme; even a noise-free sine on a lattice, whose density rises towards its peak, puts at most
  about 2.4 times the next level's count on its top level). So of the samples in the two cells
  the top one holds a fraction ``p0 = ratio w_top / (ratio w_top + h)`` at most (``w_top`` =
  ``tol`` for a continuous output, one step on a lattice: 0.012 and 0.75). Clipping is called when
  the top cell holds at least ``min_count`` samples and a binomial test rejects ``p0`` at
  ``alpha`` / 2 per side (1 % family-wise).

The clipped samples, and the unclipped ones between clipped samples less than
``episode_gap_samples`` samples apart (they are the truncated lower part of the same distribution,
biased away from the clip), get zero weight in every fit (:func:`~tcbench.diagnose.screens.outliers.without`),
unless that would remove more than ``max_episode_share`` of the record, in which case only
the clipped samples are. ``model.yaml`` gets ``saturation: {upper, lower}`` so that
``tcbench simulate model=`` clips its output the same way. The numbers are
:class:`~tcbench.diagnose.settings.SaturationSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.stats import binom

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.settings import DEFAULTS, SaturationSettings
from tcbench.diagnose.signals import DiagnosisData

EXPLANATION = ("the output is held at a flat ceiling or floor: the sensor's measurement range, the converter "
               "at full scale (ADC clipping), or a digital filter's accumulator overflowing; the clipped "
               "samples carry no information about the physics beyond the clip and are given zero weight in "
               "every fit")
CONFIRM_WITH = ("the datasheet's measurement range and the configured full-scale setting; a repeat run with a "
                "wider range (or a smaller input) that keeps the output clear of the clip level")


@dataclass(frozen=True)
class Side:
    """One clipped side: the clip ``level`` (output unit), samples at it, samples in the next
    cell and the binomial p-value."""

    level: float
    count: int
    next_count: int
    p_value: float


@dataclass(frozen=True)
class Saturation:
    """Saturation of one record: the sides found (``upper``/``lower``, None if not clipped),
    the indices given zero weight, the clipped ones' temperature band (degC) and time span (s),
    and the settings of the test."""

    upper: Side | None
    lower: Side | None
    index: np.ndarray
    clipped: int
    temperature_c: tuple[float, float] | None
    time_s: tuple[float, float] | None
    settings: SaturationSettings = field(default=DEFAULTS.screens.saturation, repr=False)

    @property
    def found(self) -> bool:
        return self.upper is not None or self.lower is not None

    def model_params(self) -> dict[str, float]:
        """``model.yaml``'s ``saturation`` parameters (only the sides found)."""
        return {k: s.level for k, s in (("upper", self.upper), ("lower", self.lower)) if s is not None}

    def finding(self, unit: str) -> Finding:
        """The report.json ``effects`` entry (``saturation``)."""
        sides = {k: s for k, s in (("upper", self.upper), ("lower", self.lower)) if s is not None}
        levels = [s.level for s in sides.values()]
        where: dict[str, Any] = {"level": levels[0] if len(levels) == 1 else levels}
        if self.temperature_c is not None:
            where["temperature_c"] = [round(self.temperature_c[0], 3), round(self.temperature_c[1], 3)]
        said = " and ".join(f"{k} {s.level:.6g} {unit} ({s.count} samples)" for k, s in sides.items())
        return Finding(
            id="saturation", shape="saturation", library=False,
            params={**self.model_params(), "clipped": self.clipped, "zero_weight": int(self.index.size)},
            where=where,
            evidence={"sides": {k: {"count": s.count, "next_count": s.next_count, "p_value": float(s.p_value)}
                                for k, s in sides.items()},
                      "density_ratio_bound": self.settings.density_ratio, "false_alarm": self.settings.alpha,
                      "time_s": [round(self.time_s[0], 3), round(self.time_s[1], 3)] if self.time_s else None,
                      "test": "samples at the extreme value against the adjacent cell: binomial test against "
                              f"a density at most {self.settings.density_ratio:g} times the adjacent one's"},
            explanation=f"the output is clipped at {said}"
                        + (f", between {self.temperature_c[0]:.3g} and {self.temperature_c[1]:.3g} degC"
                           if self.temperature_c else "") + ": " + EXPLANATION,
            confirm_with=CONFIRM_WITH,
        )


def _side(y: np.ndarray, tol: float, width: float, h: float, alpha: float, settings: SaturationSettings
          ) -> tuple[Side, np.ndarray] | None:
    """The clipped side at the maximum of ``y`` (samples within ``tol``, a cell ``width`` wide
    against the next ``h``) at level ``alpha``, or None."""
    level = float(np.max(y))
    at = y >= level - tol
    count = int(at.sum())
    next_count = int(np.count_nonzero((y < level - tol) & (y >= level - tol - h)))
    ratio = settings.density_ratio
    p0 = ratio * width / (ratio * width + h)
    p_value = float(binom.sf(count - 1, count + next_count, p0))
    if count < settings.min_count or p_value >= alpha:
        return None
    return Side(level, count, next_count, p_value), at


def find_saturation(data: DiagnosisData, step: float = 0.0, *,
                    settings: SaturationSettings = DEFAULTS.screens.saturation) -> Saturation:
    """Clipping of ``data.output`` at its maximum and/or minimum (see the module doc); ``step``
    is the output's lattice step (output unit, 0 when it is not quantised)."""
    y = np.asarray(data.output, dtype=float)
    sigma = float(data.white_sigma)
    tol = max(0.5 * step, settings.tol_sigma * sigma, 1e-12 * float(np.max(np.abs(y))))
    h = max(step, settings.next_sigma * sigma)
    width = 2.0 * tol if step > 0 else tol
    upper = _side(y, tol, width, h, 0.5 * settings.alpha, settings)
    lower = _side(-y, tol, width, h, 0.5 * settings.alpha, settings)
    clipped = np.zeros(y.size, dtype=bool)
    for side in (upper, lower):
        if side is not None:
            clipped |= side[1]
    if not clipped.any():
        return Saturation(None, None, np.zeros(0, dtype=np.int64), 0, None, None, settings)
    hits = np.flatnonzero(clipped)
    episode = clipped.copy()
    close = np.diff(hits) < settings.episode_gap_samples
    starts, ends = hits[:-1][close], hits[1:][close]
    if starts.size:  # fill each short gap between clipped samples (vectorised by a difference array)
        mark = np.zeros(y.size + 1, dtype=np.int64)
        np.add.at(mark, starts, 1)
        np.add.at(mark, ends, -1)
        episode |= np.cumsum(mark[:-1]) > 0
    index = np.flatnonzero(episode if episode.mean() <= settings.max_episode_share else clipped)
    lower_side = Side(-lower[0].level, lower[0].count, lower[0].next_count, lower[0].p_value) if lower else None
    return Saturation(
        upper[0] if upper else None, lower_side, index, int(hits.size),
        (float(data.temp_c[hits].min()), float(data.temp_c[hits].max())),
        (float(data.t_s[hits].min()), float(data.t_s[hits].max())), settings,
    )
