"""Screening a static record before an offset model is fitted to it: the samples no temperature
model should see (a handling burst, a spike train, a thermometer glitch) dropped, the record cut
at its gaps, and what was dropped and why reported.

A least-squares fit squares its errors: a handling burst (the board picked up and turned, the
gyro reading -4.4 rad/s for 30 s) in a record whose offset moves by 0.05 rad/s pulls a network
or a cubic far off wherever the burst's temperature lies, and a calibration fitted through it is
worse than none there. Screening finds such departures on the output (minus the true input) and
on the thermometer of each training part:

1. **Local level**: the running median over :data:`WINDOW_S` (in samples at the part's rate,
   mirrored at the ends). A median follows ramps and steps (it is edge-preserving) and ignores a
   departure shorter than a quarter of its window, so a burst of up to 60 s at the very end of a
   part still stands out against it.
2. **Robust scale**: ``1.4826 MAD`` of the part minus that level (the white noise and whatever
   the level misses).
3. **Bound**: ``|z| > max(TAIL * Phi^-1(1 - ALPHA / (2 n)), MIN_Z)`` (Bonferroni over the
   part's ``n`` samples at family-wise false-alarm :data:`ALPHA`, as the diagnosis's outlier test:
   :mod:`tcbench.diagnose.screens.outliers`), at least :data:`MIN_Z` robust sigmas since a real record's
   structure (a chamber's lines, a lag's loop) is not white.
4. **Guard**: each flagged run widened by :data:`GUARD_S` on both sides (a handling event's
   start and end lie below the bound but not within the noise).

A run of at most :data:`MAX_SPIKE` samples is a ``spike``; a longer one a ``burst``. A gap (a
step of more than :data:`~tcbench.sensors.segments.GAP_FACTOR` median intervals) drops nothing,
but the part is cut there: the pieces are fitted as separate parts (a network's time bins never
straddle a gap). The rate feature keeps the value the whole record gave it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.ndimage import median_filter
from scipy.stats import norm

from tcbench.sensors.segments import GAP_FACTOR, within_rate_hz

if TYPE_CHECKING:
    from tcbench.compensation.calibration import Record

WINDOW_S = 240.0  # the running median's window: ignores departures up to WINDOW_S / 4
ALPHA = 0.01
TAIL = 1.1
MIN_Z = 8.0
GUARD_S = 5.0
MAX_SPIKE = 5  # samples: a longer run is a burst (and widened by GUARD_S)
TREND_PASSES = 3
THERMO_WINDOW = 31  # samples
THERMO_MIN_C = 1.0
MAD_TO_SIGMA = 1.4826


@dataclass
class Screening:
    """What screening kept and dropped: the kept ``pieces`` (records), and per reason
    (``burst``, ``spike``, ``thermometer``) the runs, samples and seconds dropped; the gaps cut."""

    pieces: list[Any]
    keep: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))  # per screened sample
    dropped: dict[str, dict[str, float]] = field(default_factory=dict)
    gaps: int = 0
    gap_s: float = 0.0
    kept: int = 0
    total: int = 0

    def merge(self, other: Screening) -> Screening:
        """Both screenings' pieces and counts (several training parts)."""
        dropped = {k: dict(v) for k, v in self.dropped.items()}
        for reason, d in other.dropped.items():
            mine = dropped.setdefault(reason, {"runs": 0, "samples": 0, "seconds": 0.0})
            for key, value in d.items():
                mine[key] += value
        return Screening(self.pieces + other.pieces, np.concatenate([self.keep, other.keep]), dropped, self.gaps + other.gaps, self.gap_s + other.gap_s,
                         self.kept + other.kept, self.total + other.total)

    @property
    def dropped_samples(self) -> int:
        return int(sum(d["samples"] for d in self.dropped.values()))

    def describe(self) -> str:
        """One line: ``screened: 64 of 4200 samples dropped (32 s): 1 burst (62 samples, 31 s), ...``."""
        what = [f"{int(d['runs'])} {reason}{'s' * (d['runs'] != 1)} ({int(d['samples'])} samples, {d['seconds']:.3g} s)"
                for reason, d in self.dropped.items() if d["runs"]]
        seconds = sum(d["seconds"] for d in self.dropped.values())
        line = (f"screened: {self.dropped_samples} of {self.total} training samples dropped ({seconds:.3g} s)"
                + (": " + ", ".join(what) if what else ""))
        if self.gaps:
            line += f"; cut at {self.gaps} gap{'s' * (self.gaps != 1)} ({self.gap_s:.4g} s without samples)"
        return line

    def as_dict(self) -> dict[str, Any]:
        return {"total": self.total, "kept": self.kept, "dropped": self.dropped, "gaps": self.gaps,
                "gap_s": self.gap_s, "window_s": WINDOW_S, "min_z": MIN_Z, "guard_s": GUARD_S}


def _robust_scale(x: np.ndarray) -> float:
    """``1.4826 MAD`` of ``x``, or of its first differences over root 2 when the MAD is 0 (a
    quantised output: most samples equal their level)."""
    scale = MAD_TO_SIGMA * float(np.median(np.abs(x - np.median(x))))
    if scale > 0:
        return scale
    d = np.diff(x)
    return max(MAD_TO_SIGMA * float(np.median(np.abs(d - np.median(d)))), float(np.std(d))) / np.sqrt(2.0) or 1e-300


def _trend_in_temperature(temp_c: np.ndarray, y: np.ndarray, bound: float) -> np.ndarray:
    """A cubic in the temperature fitted to ``y`` with the samples beyond ``bound`` robust sigmas
    left out, refitted :data:`TREND_PASSES` times (what the thermometer explains, so that the
    running median sees a flat remainder even where the output moves fast at a record's ends)."""
    u = (temp_c - temp_c.mean()) / (np.ptp(temp_c) or 1.0)
    design = np.vander(u, 4)
    keep = np.ones(y.size, dtype=bool)
    for _ in range(TREND_PASSES):
        coef, *_ = np.linalg.lstsq(design[keep], y[keep], rcond=None)
        r = y - design @ coef
        keep = np.abs(r - np.median(r[keep])) <= bound * _robust_scale(r[keep])
    return design @ coef


def _widened(bad: np.ndarray, samples: int) -> np.ndarray:
    """``bad`` with every run of more than :data:`MAX_SPIKE` samples widened by ``samples`` on each side."""
    if not samples or not bad.any():
        return bad
    starts, stops = _runs(bad)
    long = (stops - starts) > MAX_SPIKE
    out = bad.copy()
    for a, b in zip(starts[long], stops[long], strict=True):
        out[max(0, a - samples):b + samples] = True
    return out


def _rate_hz(t_s: np.ndarray) -> float:
    """Samples per second over the whole span (gaps included): a window of seconds in samples."""
    return (t_s.size - 1) / float(t_s[-1] - t_s[0]) if t_s[-1] > t_s[0] else 1.0


def flagged(t_s: np.ndarray, temp_c: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Samples of the output ``y`` (at times ``t_s``, thermometer ``temp_c``) beyond the bound
    against their level, each flagged run longer than a spike widened by :data:`GUARD_S` (a
    boolean mask; see the module doc)."""
    n = y.size
    if n < 8:
        return np.zeros(n, dtype=bool)
    bound = max(TAIL * float(norm.isf(ALPHA / (2.0 * n))), MIN_Z)
    width = min(n, max(3, int(round(WINDOW_S * _rate_hz(t_s)))))
    bad = np.ones(n, dtype=bool)
    for rest in (y, y - _trend_in_temperature(temp_c, y, bound)):
        high = rest - median_filter(rest, size=width + 1 - width % 2, mode="mirror")
        bad &= np.abs(high - np.median(high)) > bound * _robust_scale(high)
    return _widened(bad, int(round(GUARD_S * _rate_hz(t_s))))


def thermometer_flagged(temp_c: np.ndarray) -> np.ndarray:
    """Thermometer glitches: samples more than ``max(bound robust sigmas, THERMO_MIN_C)`` off the
    median of their :data:`THERMO_WINDOW` neighbours (no chamber moves the package that much in
    a few samples)."""
    n = temp_c.size
    if n < THERMO_WINDOW:
        return np.zeros(n, dtype=bool)
    high = temp_c - median_filter(temp_c, size=THERMO_WINDOW, mode="mirror")
    bound = max(TAIL * float(norm.isf(ALPHA / (2.0 * n))), MIN_Z)
    return np.abs(high) > max(bound * _robust_scale(high), THERMO_MIN_C)


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and stops (exclusive) of the runs of True in ``mask``."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def screen(rec: Record, enabled: bool = True) -> Screening:
    """The record's pieces once bursts, spikes and thermometer glitches are dropped and it is
    cut at its gaps; ``enabled=False``: only cut at the gaps (nothing dropped)."""
    n = rec.t_s.size
    dt = np.diff(rec.t_s)
    gap = dt > GAP_FACTOR * float(np.median(dt)) if n > 1 else np.zeros(0, dtype=bool)
    drop = np.zeros(n, dtype=bool)
    dropped: dict[str, dict[str, float]] = {}
    dt_s = 1.0 / within_rate_hz(rec.t_s) if n > 1 else 0.0
    if enabled:
        thermo = thermometer_flagged(rec.temp_c)
        output = np.zeros(n, dtype=bool)
        ok = ~thermo
        output[ok] = flagged(rec.t_s[ok], rec.temp_c[ok], (rec.output - rec.truth)[ok])
        for reason, mask in (("burst", output), ("thermometer", thermo)):
            starts, stops = _runs(mask)
            if reason == "burst":
                spike = (stops - starts) <= MAX_SPIKE
                groups = {"burst": ~spike, "spike": spike}
            else:
                groups = {"thermometer": np.ones(starts.size, dtype=bool)}
            for name, pick in groups.items():
                count = int((stops[pick] - starts[pick]).sum())
                dropped[name] = {"runs": int(pick.sum()), "samples": count, "seconds": count * dt_s}
        drop = output | thermo
    cut = np.concatenate(([0], np.flatnonzero(gap) + 1, [n]))
    keep = np.zeros(n, dtype=bool)
    for a, b in zip(cut[:-1], cut[1:], strict=True):
        starts, stops = _runs(~drop[a:b])
        for s, e in zip(a + starts, a + stops, strict=True):
            keep[s:e] = e - s >= 2  # a lone sample between dropped runs is no piece
    starts, stops = _runs(keep)
    cuts = np.flatnonzero(gap) + 1
    pieces = [rec.part(int(a), int(b)) for s, e in zip(starts, stops, strict=True)
              for a, b in _pairs(s, e, cuts)]
    gap_s = float(dt[gap].sum()) if gap.any() else 0.0
    return Screening(pieces, keep, dropped, int(gap.sum()), gap_s, int(keep.sum()), n)


def _pairs(start: int, stop: int, cuts: np.ndarray) -> list[tuple[int, int]]:
    """``start:stop`` cut at the indices ``cuts`` inside it."""
    inner = cuts[(cuts > start) & (cuts < stop)]
    edges = np.concatenate(([start], inner, [stop]))
    return list(zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True))


def screened_all(parts: list[Record], enabled: bool = True) -> Screening:
    """:func:`screen` of every training part, merged."""
    out = Screening([])
    for part in parts:
        out = out.merge(screen(part, enabled))
    return out
