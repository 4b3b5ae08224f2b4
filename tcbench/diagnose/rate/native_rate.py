"""A record of any rate and length: the thermal terms fitted on bin means, the noise terms
measured on every sample.

The cost of a diagnosis grows with its rows (:mod:`tcbench.diagnose.rate.cost`: 25-50 s of one core
and 550 MB at 10^5 rows, 10-20 min and 8 GB at 2.7 M), while the physics it searches is slow: the
shortest thermal lag tried is 20 s, the open-world detectors bin the residual in 10 s or more and
the lag filter and play operator run on a 1 s clock. A record of more rows than
``settings.rate.max_rows`` is therefore diagnosed on **bin means**, and its **noise terms** are
measured on the full-rate stream, which averaging would hide.

**The bin** (:func:`plan_bins`): the longest that is still far shorter than every time scale the
thermal terms search, ``max_bin_s`` (1 s: the clock the lag filter and the play operator run on
anyway, a twentieth of the shortest lag searched, a tenth of the detectors' narrowest bin), as
``k = floor(max_bin_s * rate)`` samples. A longer bin would blur what the terms search; a shorter
one keeps nothing they use (the means of a slow term over 1 s carry its whole signal, and the
gains and Wald statistics, in units of the bins' own noise, are the same) and costs time and
memory by the row: 45 min at 1 kHz in 0.1 s bins would be 27 000 rows where 2 700 tell the
same. A record whose 1 s bins are still more than ``max_rows`` (over 27 h) is diagnosed on
them all (``max_rows`` of ``tcbench diagnose`` still refuses it where it says so). Bins never
straddle a gap or a change of input (they restart with every run of constant input inside a
continuous segment), and a bin enters the diagnosis when at least half of its ``k`` samples carry
weight, so that every row averages about the same noise.

**The noise, on every sample** (:func:`full_rate_noise`), in pieces of :data:`CHUNK_ROWS` where a
filter runs: the white sigma from first differences inside runs (as
:func:`~tcbench.diagnose.signals.prepare` does), the output's lattice and clipping (the screens'
own tests, :mod:`tcbench.diagnose.screens.quantisation` and :mod:`tcbench.diagnose.screens.saturation`, on the
full-rate output) and isolated outliers (:func:`~tcbench.diagnose.screens.outliers.find_outliers` on
the output against its running median, the Bonferroni bound taken over every sample of the
record). Clipped samples and outliers get zero weight: they never enter a bin mean, where a
50-sigma spike would become a step of 50/k sigma the thermal terms would have to explain.
Thermometer glitches (:mod:`tcbench.diagnose.screens.glitches`) are found on every sample too, before
binning (a 0.0 degC reading is a 200th of its size in a 200-sample mean, below any bound there):
held at the previous reading, their samples entering no bin, reported as the
``thermometer_glitches`` finding.
Bias instability (flicker) is judged as before on the bin means' residual: the Allan deviation of
``k``-sample means at ``tau >= k / rate`` is the full-rate stream's own, and the flicker floor
lies at taus of minutes, far above one bin.

The diagnosis of the bin means is returned as an :class:`AveragedDiagnosis`: its findings of the
noise (quantisation, saturation, outliers) and its ``model.yaml`` white noise are the full-rate
ones, ``report.json``'s ``noise`` is the full-rate stream's and its ``native_rate`` (report.md: a
section before the fit) says what was averaged, to what rate and why. A record within the budget
goes through :func:`~tcbench.diagnose.diagnosis.diagnose` as it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.findings import Finding
from tcbench.diagnose.result import Diagnosis
from tcbench.diagnose.screens import FINDINGS_ORDER
from tcbench.diagnose.screens.glitches import ID as GLITCHES
from tcbench.diagnose.screens.glitches import Glitches, repaired
from tcbench.diagnose.screens.outliers import Outliers, find_outliers, z_bound
from tcbench.diagnose.screens.quantisation import OutputQuantisation, find_output_quantisation
from tcbench.diagnose.screens.saturation import Saturation, find_saturation
from tcbench.diagnose.screens.thermometer_glitches import glitches
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, RateSettings
from tcbench.diagnose.signals import INPUT_CHANGE_TOL, MAD_TO_SIGMA, MIN_NOISE_DIFFS, DiagnosisDataError
from tcbench.sensors.recording import Recording
from tcbench.sensors.segments import segments, within_rate_hz

CHUNK_ROWS = 1_000_000  # the outlier filter runs on pieces of this many rows (memory, not a statistic)
FULL_RATE_IDS = ("outliers", "saturation", "quantisation")  # the findings measured on every sample


@dataclass(frozen=True)
class BinPlan:
    """How a record of ``rows`` samples at ``sample_rate_hz`` is diagnosed: on means of
    ``bin_samples`` samples (1: as it is), under the budget ``max_rows`` and the longest bin ``max_bin_s``."""

    rows: int
    sample_rate_hz: float
    bin_samples: int
    max_rows: int
    max_bin_s: float

    @property
    def averaged(self) -> bool:
        return self.bin_samples > 1

    @property
    def bin_s(self) -> float:
        """The bin's length (s)."""
        return self.bin_samples / self.sample_rate_hz

    @property
    def diagnosed_rows(self) -> int:
        """The rows the diagnosis is estimated to run on (one per bin, gaps aside)."""
        return math.ceil(self.rows / self.bin_samples)

    @property
    def capped(self) -> bool:
        """Whether the bins are still more than ``max_rows``."""
        return self.diagnosed_rows > self.max_rows

    def why(self) -> str:
        """One sentence: what was averaged, to what rate and why."""
        if not self.averaged:
            return (f"{self.rows} rows at {self.sample_rate_hz:.4g} Hz, within settings.rate.max_rows="
                    f"{self.max_rows}: diagnosed as recorded")
        over = (f"; its {self.diagnosed_rows} bins are more than the budget, and longer ones than settings.rate."
                f"max_bin_s={self.max_bin_s:g} s would blur the thermal terms" if self.capped else "")
        return (f"{self.rows} rows at {self.sample_rate_hz:.4g} Hz are more than settings.rate.max_rows="
                f"{self.max_rows} a diagnosis takes in time and memory: the thermal terms are fitted on means of "
                f"{self.bin_samples} samples ({self.bin_s:.4g} s, {self.sample_rate_hz / self.bin_samples:.4g} Hz), "
                "the longest bin still far shorter than any time scale they search (thermal lags from 20 s, the "
                f"detectors' bins from 10 s, the 1 s filter clock){over}; the noise terms are measured on every sample")

    def to_json(self) -> dict[str, Any]:
        return {"rows": self.rows, "sample_rate_hz": self.sample_rate_hz, "bin_samples": self.bin_samples,
                "bin_s": self.bin_s, "bin_rate_hz": self.sample_rate_hz / self.bin_samples,
                "max_rows": self.max_rows, "max_bin_s": self.max_bin_s}


def plan_bins(rows: int, sample_rate_hz: float, settings: RateSettings = DEFAULTS.rate) -> BinPlan:
    """The bin of a record of ``rows`` samples at ``sample_rate_hz`` (see the module doc)."""
    k = 1
    if rows > settings.max_rows:
        k = max(1, math.floor(settings.max_bin_s * sample_rate_hz * (1.0 + 1e-6)))  # 999.9999 Hz is 1 kHz
    return BinPlan(int(rows), float(sample_rate_hz), int(k), settings.max_rows, settings.max_bin_s)


def plan_for(rec: Recording, settings: RateSettings = DEFAULTS.rate) -> BinPlan:
    """:func:`plan_bins` of ``rec`` at the rate its sidecar states (the reader checked it against
    the clock), else at its clock's inside its segments (gaps excluded). The stated rate keeps the
    bins' own exact (1000 Hz in 1000-sample bins is 1 Hz, not 0.99999999 Hz): the diagnosis sizes
    windows in samples from it, and a hair's difference moves a window by a sample."""
    t = rec.time_s
    rate_hz = rec.meta.sample_rate_hz or (within_rate_hz(t) if t.size > 1 else 1.0)
    return plan_bins(t.size, float(rate_hz), settings)


@dataclass(frozen=True)
class FullRate:
    """The noise terms of the full-rate stream: its white sigma per sample (output unit), the
    output's lattice (None when it is on none), clipping and isolated outliers, and the samples
    they give zero weight."""

    samples: int
    sample_rate_hz: float
    white_sigma: float
    quantisation: OutputQuantisation | None
    saturation: Saturation
    outliers: Outliers
    zero_weight: np.ndarray = field(repr=False)

    def findings(self, unit: str) -> dict[str, Finding]:
        """``{id: finding}`` of what was found, for :data:`FULL_RATE_IDS`."""
        out: dict[str, Finding] = {}
        if self.outliers.count:
            out["outliers"] = self.outliers.finding(unit)
        if self.saturation.found:
            out["saturation"] = self.saturation.finding(unit)
        if self.quantisation is not None:
            out["quantisation"] = self.quantisation.finding(unit)
        return out

    def white_density(self) -> float:
        """model.yaml's white-noise density (unit / sqrt(Hz)): the per-sample sigma at the full rate,
        less the lattice's own ``q^2 / 12`` (simulate quantises again)."""
        q = self.quantisation.step if self.quantisation is not None else 0.0
        return float(np.sqrt(max(self.white_sigma**2 - q**2 / 12.0, 0.0) / self.sample_rate_hz))


@dataclass(frozen=True)
class _Stream:
    """The full-rate arrays :func:`~tcbench.diagnose.screens.saturation.find_saturation` reads."""

    t_s: np.ndarray
    temp_c: np.ndarray
    output: np.ndarray
    white_sigma: float


def run_starts(t_s: np.ndarray, input_: np.ndarray) -> np.ndarray:
    """Per sample, whether it starts a run: the first sample, one after a gap
    (:func:`~tcbench.sensors.segments.segments`) or one whose input differs from the one before."""
    gap = np.diff(segments(t_s)) > 0
    changed = np.abs(np.diff(input_)) > INPUT_CHANGE_TOL * max(1.0, float(np.max(np.abs(input_))) if input_.size else 1.0)
    return np.concatenate(([True], gap | changed))


def _sigma(y: np.ndarray, same: np.ndarray, step: float, clip_sigma: float, fallback: float) -> float:
    """The white sigma from the first differences of ``y`` where ``same`` (consecutive samples of one
    run, both kept): the MAD's, or on a lattice of ``step`` the RMS of differences clipped at
    ``clip_sigma`` times the larger of it and the step (as the quantisation screen measures it)."""
    d = np.diff(y)[same]
    if d.size < MIN_NOISE_DIFFS:
        return fallback
    sigma = float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    if not sigma > 0:
        sigma = float(np.sqrt(np.mean(d * d) / 2.0))
    if step > 0:
        bound = clip_sigma * max(sigma, step)
        sigma = float(np.sqrt(np.mean(np.minimum(np.abs(d), bound) ** 2) / 2.0))
    return sigma


def _outliers(t_s: np.ndarray, y: np.ndarray, starts: np.ndarray, sigma: float, settings: DiagnoseSettings) -> Outliers:
    """Isolated outliers of ``y`` against its running median, in pieces of :data:`CHUNK_ROWS`
    (overlapping by a filter window), judged against the bound of the whole record's samples; a
    sample within half a window of a run's start is not judged (the median straddles the step)."""
    s = settings.screens.outliers
    n, pad = y.size, s.window_samples
    found: list[Outliers] = []
    for a in range(0, n, CHUNK_ROWS):
        lo, hi = max(0, a - pad), min(n, a + CHUNK_ROWS + pad)
        # alpha scaled to the piece: its Bonferroni bound is then the whole record's
        piece = find_outliers(t_s[lo:hi], y[lo:hi], sigma, settings=replace(s, alpha=s.alpha * (hi - lo) / n))
        own = (piece.index + lo >= a) & (piece.index + lo < a + CHUNK_ROWS)
        found.append(replace(piece, index=piece.index[own] + lo, time_s=piece.time_s[own], size=piece.size[own],
                             z=piece.z[own]))
    index = np.concatenate([f.index for f in found])
    near = np.zeros(n + 1, dtype=np.int64)  # within half a window of a run's start
    first = np.flatnonzero(starts)
    np.add.at(near, np.clip(first - pad // 2, 0, n), 1)
    np.add.at(near, np.clip(first + pad // 2 + 1, 0, n), -1)
    judged = np.cumsum(near[:-1])[index] == 0
    scale = float(np.median([f.scale for f in found])) if found else sigma
    return Outliers(index[judged], np.concatenate([f.time_s for f in found])[judged],
                    np.concatenate([f.size for f in found])[judged], np.concatenate([f.z for f in found])[judged],
                    scale, z_bound(n, s), s)


def full_rate_noise(rec: Recording, settings: DiagnoseSettings = DEFAULTS,
                    sample_rate_hz: float | None = None) -> FullRate:
    """The noise terms of ``rec``'s every sample (see the module doc); :class:`DiagnosisDataError`
    when its output has no sample-to-sample noise to measure."""
    t, y, u = rec.time_s, rec.output, rec.input
    starts = run_starts(t, u)
    same = ~starts[1:]
    sigma = _sigma(y, same, 0.0, 0.0, 0.0)
    if not sigma > 0:
        raise DiagnosisDataError("the output has no sample-to-sample noise: it is constant at constant input")
    screens = settings.screens
    grid = find_output_quantisation(y, sigma, screens.quantisation)
    step = grid.step if grid is not None else 0.0
    if grid is not None and step:
        sigma = _sigma(y, same, step, screens.quantisation.clip_sigma, sigma)
        grid = replace(grid, white_sigma=sigma)
    clipped = find_saturation(_Stream(t, rec.temperature_c, y, sigma), step,  # type: ignore[arg-type]
                              settings=screens.saturation)
    keep = np.ones(y.size, dtype=bool)
    if clipped.index.size:
        keep[clipped.index] = False
        sigma = _sigma(y, same & keep[1:] & keep[:-1], step, screens.quantisation.clip_sigma, sigma)
    spikes = _outliers(t, y, starts, sigma, settings)
    keep[spikes.index] = False
    rate_hz = sample_rate_hz or rec.meta.sample_rate_hz or (within_rate_hz(t) if t.size > 1 else 1.0)
    return FullRate(int(y.size), float(rate_hz), sigma, grid, clipped, spikes, np.flatnonzero(~keep))


def bin_means(rec: Recording, plan: BinPlan, zero_weight: np.ndarray) -> tuple[Recording, int]:
    """``rec`` as means of ``plan.bin_samples`` samples inside each run (the samples at
    ``zero_weight`` left out), at ``plan``'s bin rate, and the bins dropped for holding fewer than
    half a bin of kept samples."""
    t, u = rec.time_s, rec.input
    n, k = t.size, plan.bin_samples
    starts = run_starts(t, u)
    idx = np.arange(n)
    local = idx - np.maximum.accumulate(np.where(starts, idx, 0))
    bin_id = np.cumsum(local % k == 0) - 1
    weight = np.ones(n)
    weight[zero_weight] = 0.0
    count = np.bincount(bin_id, weights=weight)
    enough = count >= 0.5 * k
    safe = np.where(enough, count, 1.0)
    t0 = float(t[0])
    columns = {"time_s": t0 + np.bincount(bin_id, weights=(t - t0) * weight)[enough] / safe[enough]}
    for name, x in (("temperature_c", rec.temperature_c), ("input", u), ("output", rec.output)):
        columns[name] = np.bincount(bin_id, weights=x * weight)[enough] / safe[enough]
    if rec.position is not None:
        columns["position"] = rec.position[np.flatnonzero(local % k == 0)][enough]
    meta = replace(rec.meta, sample_rate_hz=plan.sample_rate_hz / k)
    return Recording(pd.DataFrame(columns), meta), int(np.count_nonzero(~enough))


# what a diagnosis reads from the bin means (report.json's ``native_rate.what``; report.md's sentence)
OF_BINS = ("the thermal terms, the mismatch, the reference fit, bias instability and every RMSE and gain of this "
           "report", "The fit, the mismatch, the reference and bias instability below")


@dataclass(frozen=True)
class NativeRate:
    """What the front stage did: the plan, the full-rate noise, the bins diagnosed and dropped,
    the white sigma of the bin means the diagnosis measured, what the report read from the bin
    means (``of_bins``: the phrase in report.json, the sentence's subject in report.md) and the
    thermometer glitches given zero weight with the clipped samples and outliers."""

    plan: BinPlan
    full: FullRate
    bins: int
    dropped_bins: int
    bin_white_sigma: float
    of_bins: tuple[str, str] = OF_BINS
    glitch_samples: int = 0

    def _zero_weight(self) -> str:
        """The samples given zero weight, in words."""
        if not self.glitch_samples:
            return f"{self.full.zero_weight.size} samples given zero weight as clipped or outliers"
        return (f"{self.full.zero_weight.size} samples given zero weight as clipped or outliers and "
                f"{self.glitch_samples} as thermometer glitches")

    def to_json(self) -> dict[str, Any]:
        """report.json's ``native_rate``."""
        expected = self.full.white_sigma / np.sqrt(self.plan.bin_samples)
        return {
            **self.plan.to_json(), "averaged": True, "bins_diagnosed": self.bins, "bins_dropped": self.dropped_bins,
            "zero_weight_samples": int(self.full.zero_weight.size),
            **({"glitch_samples": self.glitch_samples} if self.glitch_samples else {}),
            "why": self.plan.why(),
            "what": f"{self.of_bins[0]} are of the bin means; white noise, quantisation, saturation and outliers are "
                    "measured on every sample, and clipped samples and outliers"
                    + (" and thermometer glitches" if self.glitch_samples else "") + " enter no bin",
            "white_sigma_full_rate": self.full.white_sigma, "white_sigma_bins": self.bin_white_sigma,
            "white_sigma_bins_expected": float(expected),
            "bins_over_expected": float(self.bin_white_sigma / expected) if expected > 0 else None,
        }

    def markdown(self, unit: str) -> list[str]:
        """report.md's section on the averaging."""
        expected = self.full.white_sigma / np.sqrt(self.plan.bin_samples)
        return ["## Native rate", "",
                f"{self.plan.why()}.", "",
                (f"{self.bins} bins diagnosed ({self.dropped_bins} dropped for holding fewer than half a bin of "
                 f"kept samples; {self._zero_weight()}). "
                 f"{self.of_bins[1]} are of the bin means; white "
                 "noise, quantisation, saturation and outliers are measured on every sample."), "",
                (f"White noise: {self.full.white_sigma:.4g} {unit} per sample at {self.full.sample_rate_hz:.4g} Hz; "
                 f"the bin means' {self.bin_white_sigma:.4g} {unit} (white noise alone would give "
                 f"{expected:.4g}: a ratio above 1 is noise slower than a bin)."), ""]


@dataclass
class AveragedDiagnosis(Diagnosis):
    """A diagnosis of bin means with the noise terms of the full-rate stream (see the module doc)."""

    native_rate: NativeRate | None = None

    def preface(self) -> list[str]:
        return self.native_rate.markdown(self.unit) if self.native_rate is not None else []

    def to_json(self) -> dict[str, Any]:
        out = super().to_json()
        if self.native_rate is not None:
            full = self.native_rate.full
            out["noise"] = {**out["noise"], "white_sigma": full.white_sigma, "samples": full.samples,
                            "sample_rate_hz": full.sample_rate_hz, "bins": self.noise.samples}
            out["native_rate"] = self.native_rate.to_json()
        return out


def white_sigma(diag: Diagnosis) -> float:
    """The white sigma per sample of the recording a diagnosis read: the full-rate stream's when it was averaged."""
    native = getattr(diag, "native_rate", None)
    return native.full.white_sigma if native is not None else diag.noise.white_sigma


def merged(diag: Diagnosis, native: NativeRate, glitch: Glitches | None = None) -> AveragedDiagnosis:
    """``diag`` (of the bin means) with the full-rate noise findings, model terms and ``native``,
    and the thermometer glitches found on every sample (``glitch``)."""
    full = native.full
    own = full.findings(diag.unit)
    if glitch is not None and glitch.count:
        own[GLITCHES] = glitch.finding()
    kept = {e.id: e for e in diag.effects if e.id in FINDINGS_ORDER and e.id not in (*FULL_RATE_IDS, GLITCHES)}
    effects = [e for e in diag.effects if e.id not in FINDINGS_ORDER]
    effects += [own.get(key) or kept[key] for key in FINDINGS_ORDER if key in own or key in kept]
    model = dict(diag.model)
    terms = dict(model["effects"])
    if "white_noise" in terms:
        terms["white_noise"] = {"density": full.white_density()}
    for key, value in (("quantisation", {"step": float(full.quantisation.step)} if full.quantisation else None),
                       ("saturation", full.saturation.model_params() if full.saturation.found else None)):
        terms.pop(key, None)
        if value:
            terms[key] = value
    model["effects"] = terms
    model.pop("outliers", None)
    if full.outliers.count:
        model["outliers"] = {"time_s": [float(t) for t in full.outliers.time_s],
                             "size": [float(v) for v in full.outliers.size]}
    fields = {f: getattr(diag, f) for f in Diagnosis.__dataclass_fields__}
    if glitch is not None and glitch.count:
        fields["statistics"] = replace(diag.statistics, screens={**diag.statistics.screens, GLITCHES: glitch.count})
    return AveragedDiagnosis(**(fields | {"effects": effects, "model": model, "outliers": full.outliers}),
                             native_rate=native)


def diagnose_any_rate(rec: Recording, *, sensor: str | None = None, declared: dict[str, dict[str, float]] | None = None,
                      name: str = "", min_duration_s: float | None = None,
                      settings: DiagnoseSettings | None = None) -> Diagnosis:
    """:func:`~tcbench.diagnose.diagnosis.diagnose` of ``rec`` when it is within
    ``settings.rate.max_rows``; otherwise of its bin means, with the noise terms of every sample
    (an :class:`AveragedDiagnosis`; see the module doc)."""
    settings = DEFAULTS if settings is None else settings
    plan = plan_for(rec, settings.rate)
    if not plan.averaged:
        return diagnose(rec, sensor=sensor, declared=declared, name=name, min_duration_s=min_duration_s,
                        settings=settings)
    glitch = glitches(rec, settings.screens).found  # on every sample: a bin mean would hide them
    rec = repaired(rec, glitch.index)
    full = full_rate_noise(rec, settings, plan.sample_rate_hz)
    binned, dropped = bin_means(rec, plan, np.union1d(full.zero_weight, glitch.index))
    diag = diagnose(binned, sensor=sensor, declared=declared, name=name, min_duration_s=min_duration_s,
                    settings=settings)
    native = NativeRate(plan, full, int(binned.data.shape[0]), dropped, float(diag.noise.white_sigma),
                        glitch_samples=glitch.count)
    return merged(diag, native, glitch)
