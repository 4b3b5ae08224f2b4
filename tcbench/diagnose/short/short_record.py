"""What a record too short for a full diagnosis can tell (shorter than
:func:`tcbench.diagnose.select.plan.min_full_duration_s`).

A full diagnosis scores every effect held out by five-fold blocked cross-validation, and needs a
block of two thermometer-smoothing windows per fold. A 200 s record cannot give that, but it
still answers three questions (:mod:`tcbench.diagnose.short.short_tests`): does the output move with
temperature (the slope), does its level step (at the start of a temperature ramp or anywhere),
and how large and how white is its noise. :func:`short_record` runs the tests the record's
samples and temperature allow and lists, with the duration each needs, the ones it cannot run.

The thermometer is smoothed as in a diagnosis (:func:`~tcbench.diagnose.signals.fitted_window_s`
over at most the default window); the input, when it varies, is a column of every fit; the
step found, when significant, is a column of the slope's fit and both are removed from the
residual the noise test reads. The numbers are the settings' ``short`` section
(:class:`~tcbench.diagnose.settings.ShortSettings`), with the plan's and the smoothing's for what a
full diagnosis needs.

A record of more rows than ``settings.rate.max_rows`` (15 min at 1 kHz is 900 000) is tested as a
diagnosis takes it (:mod:`tcbench.diagnose.rate.native_rate`): the slope, the step and the Allan
deviation on bin means of the same plan, the noise terms on every sample (white sigma and
density, the output's lattice, clipping and isolated outliers, reported as findings; clipped
samples and outliers enter no bin), and report.json's ``native_rate`` (report.md's section
"Native rate") says what was averaged, to what rate and why.

Thermometer glitches (a bus sample of 0.0 or -40 degC) are found on the raw reading of every
sample as a diagnosis finds them (:mod:`tcbench.diagnose.screens.glitches`), reported as its
``thermometer_glitches`` finding and given zero weight: held at the previous reading before the
thermometer is smoothed, their samples left out of every test (and of every bin).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.rate.native_rate import NativeRate, bin_means, full_rate_noise, plan_for
from tcbench.diagnose.screens import FINDINGS_ORDER
from tcbench.diagnose.screens.glitches import ID as GLITCHES
from tcbench.diagnose.screens.glitches import repaired
from tcbench.diagnose.screens.thermometer_glitches import glitches
from tcbench.diagnose.select.plan import min_full_duration_s
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, report_mapping
from tcbench.diagnose.short.short_tests import (
    NOT_RUN,
    SIGNIFICANT,
    ShortTest,
    basis,
    level_step,
    temperature_slope,
    white_noise,
)
from tcbench.diagnose.signals import INPUT_CHANGE_TOL, MAD_TO_SIGMA, fitted_window_s, smooth_temperature
from tcbench.diagnose.terms.temperature_shapes import NODE_SPANS, NODE_TAU_S
from tcbench.sensors import kinds
from tcbench.sensors.recording import Recording
from tcbench.sensors.segments import segments

DRIFT = ("a drift in time (ageing, warm-up, a random walk): the temperature moves one way on this record; "
         "one that heats and cools tells them apart")
_WORDS = {1: "one", 2: "two", 3: "three", 4: "four"}  # a small count in words
# what a short record's report reads from the bin means (:class:`~tcbench.diagnose.rate.native_rate.NativeRate`'s ``of_bins``)
OF_BINS = ("the temperature slope, the level step and the Allan deviation of this report",
           "The temperature slope, the level step and the Allan deviation below")


@dataclass
class ShortRecordReport:
    """The report of a short record: the tests run (:class:`~tcbench.diagnose.short.short_tests.ShortTest`)
    and those it needs more time for (``{id, needs_s, what}``), and the settings they ran with."""

    sensor: str
    unit: str
    recording: str
    duration_s: float
    samples: int
    sample_rate_hz: float
    temperature_span_c: float
    smooth_s: float
    ramp_starts_s: list[float]
    tests: list[ShortTest]
    needs_more_time: list[dict[str, Any]]
    settings: DiagnoseSettings = field(default=DEFAULTS, repr=False)
    findings: list[Finding] = field(default_factory=list)
    native_rate: NativeRate | None = None

    @property
    def full_duration_s(self) -> float:
        return min_full_duration_s(self.settings)

    @property
    def ran(self) -> list[str]:
        return [t.id for t in self.tests if t.ran]

    @property
    def verdict(self) -> str:
        """One line: the record is short, each test's outcome."""
        parts = []
        for t in self.tests:
            if not t.ran:
                parts.append(f"{t.id} not run")
            elif t.id == "level_step" and t.status == SIGNIFICANT:
                where = " at a ramp start" if t.values.get("at_ramp_start") else ""
                parts.append(f"level_step {t.status} ({t.values['size']:.4g} {self.unit} at "
                             f"{t.values['time_s']:.4g} s{where})")
            elif t.id == "temperature_slope" and t.status == SIGNIFICANT:
                parts.append(f"temperature_slope {t.status} ({t.values['slope_per_c']:.4g} {self.unit}/degC)")
            else:
                parts.append(f"{t.id} {t.status}")
        if self.findings:
            parts.append(f"found: {', '.join(f.id for f in self.findings)}")
        return (f"short record ({self.duration_s:.4g} s of the {self.full_duration_s:.4g} s a full diagnosis "
                f"needs): {'; '.join(parts)}")

    def to_json(self) -> dict[str, Any]:
        """``report.json`` of a short record (``findings`` and ``native_rate`` only when there are any)."""
        return {
            "report": "short_record", "sensor": self.sensor, "unit": self.unit, "recording": self.recording,
            "verdict": self.verdict, "duration_s": self.duration_s, "samples": self.samples,
            "sample_rate_hz": self.sample_rate_hz, "temperature_span_c": self.temperature_span_c,
            "thermometer_smooth_s": self.smooth_s, "ramp_starts_s": self.ramp_starts_s,
            "full_diagnosis_needs_s": self.full_duration_s, "level": self.settings.short.alpha,
            "tests": [t.to_json() for t in self.tests], "needs_more_time": self.needs_more_time,
            **({"findings": [f.to_json() for f in self.findings]} if self.findings else {}),
            **({"native_rate": self.native_rate.to_json()} if self.native_rate is not None else {}),
            "settings": report_mapping(self.settings),
        }

    def tags(self) -> dict[str, str]:
        """MLflow tags: the report kind and each test's status."""
        return {"tcbench.report": "short_record", **{f"tcbench.short.{t.id}": t.status for t in self.tests}}

    def metrics(self) -> dict[str, float]:
        """MLflow metrics: duration, each test's numbers (scalars only) and 1/0 for significant."""
        out = {"duration_s": self.duration_s, "full_diagnosis_needs_s": self.full_duration_s}
        for t in self.tests:
            out |= {f"{t.id}.{k}": float(v) for k, v in t.values.items()
                    if isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)}
            if t.ran:
                out[f"{t.id}.significant"] = float(t.status == SIGNIFICANT)
        return out


def needs_more_time(duration_s: float, settings: DiagnoseSettings = DEFAULTS) -> list[dict[str, Any]]:
    """What a full diagnosis would test and the record length each needs, for a record of ``duration_s``."""
    full = min_full_duration_s(settings)
    folds, window_s = settings.plan.folds, settings.smoothing.default_window_s
    node = max(full, NODE_SPANS * float(NODE_TAU_S[0]))
    rows = [
        {"id": "effect_attribution", "needs_s": full,
         "what": (f"the full diagnosis (thermal lag, hysteresis, warm-up, ageing, temperature rate, cubic, "
                  f"nonlinearity, bias instability, the open-world terms, saturation, quantisation, outliers), "
                  f"each scored held out by {folds}-fold blocked cross-validation: {folds} folds of one block of "
                  f"{_WORDS.get(settings.plan.block_windows, f'{settings.plan.block_windows:g}')} {window_s:g}-s "
                  "thermometer-smoothing windows")},
        {"id": "second_node", "needs_s": node,
         "what": f"a second thermal node: more than {NODE_SPANS:g} times its shortest time constant "
                 f"({NODE_TAU_S[0]:g} s)"},
    ]
    return [r for r in rows if duration_s < r["needs_s"]]


def ramp_starts(t_s: np.ndarray, rate_c_per_s: np.ndarray, ramp_share: float = DEFAULTS.short.ramp_share
                ) -> np.ndarray:
    """Times where |dT/dt| rises through ``ramp_share`` of its largest value."""
    a = np.abs(rate_c_per_s)
    if a.size < 2 or not a.max() > 0:
        return np.empty(0)
    above = a >= ramp_share * a.max()
    return t_s[np.flatnonzero(above[1:] & ~above[:-1]) + 1]


def _white_sigma(y: np.ndarray, same: np.ndarray) -> float:
    """Per-sample white sigma from first differences at constant input in one segment (MAD, or
    RMS on an output on a coarse grid)."""
    d = np.diff(y)[same]
    if d.size < 2:
        return 0.0
    sigma = float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    return sigma if sigma > 0 else float(np.sqrt(np.mean(d * d) / 2.0))


def short_record(rec: Recording, sensor: str | None = None, name: str = "",
                 settings: DiagnoseSettings = DEFAULTS) -> ShortRecordReport:
    """The tests ``rec`` supports (see module doc), whatever its length, with ``settings``: on its
    samples within ``settings.rate.max_rows``, else on bin means with the noise terms of every sample."""
    glitch = glitches(rec, settings.screens).found  # thermometer glitches: held at the previous reading, zero weight
    rec = repaired(rec, glitch.index)
    plan = plan_for(rec, settings.rate)
    if not plan.averaged:
        report = _tested(rec, sensor, name, settings, glitch.index)
        report.findings = [glitch.finding()] if glitch.count else []
        return report
    full = full_rate_noise(rec, settings, plan.sample_rate_hz)
    binned, dropped = bin_means(rec, plan, np.union1d(full.zero_weight, glitch.index))
    report = _tested(binned, sensor, name, settings)
    noise = next(t for t in report.tests if t.id == "white_noise")
    bin_sigma = float(noise.values["white_sigma"])
    noise.values |= {"white_sigma": full.white_sigma,
                     "density_per_sqrt_hz": full.white_sigma / float(np.sqrt(plan.sample_rate_hz)),
                     "white_sigma_bins": bin_sigma}
    found = full.findings(report.unit) | ({GLITCHES: glitch.finding()} if glitch.count else {})
    report.findings = [found[key] for key in FINDINGS_ORDER if key in found]
    report.native_rate = NativeRate(plan, full, int(binned.data.shape[0]), dropped, bin_sigma, OF_BINS,
                                    glitch.count)
    report.samples, report.sample_rate_hz = plan.rows, plan.sample_rate_hz
    report.duration_s = float(rec.time_s[-1] - rec.time_s[0])
    report.needs_more_time = needs_more_time(report.duration_s, settings)
    return report


def _tested(rec: Recording, sensor: str | None, name: str, settings: DiagnoseSettings,
            zero_weight: np.ndarray | None = None) -> ShortRecordReport:
    """The tests ``rec`` supports, on its samples as they are, those at ``zero_weight`` left out
    after the thermometer is smoothed."""
    short, default_s = settings.short, settings.smoothing.default_window_s
    kind = str(sensor or rec.meta.sensor)
    unit = str((rec.meta.units or {}).get("output", kinds.get(kind).output_unit))
    t, temp, u, y = rec.time_s, rec.temperature_c, rec.input, rec.output
    n = t.size
    duration_s = float(t[-1] - t[0]) if n else 0.0
    rate_hz = float(rec.meta.sample_rate_hz or (1.0 / np.median(np.diff(t)) if n > 1 else 1.0))
    window_s = fitted_window_s(t, temp, default_s, settings.smoothing.bias_to_noise) if n > 1 else default_s
    temp_s, rate = smooth_temperature(t, temp, window_s) if n > 1 else (temp, np.zeros(n))
    if zero_weight is not None and zero_weight.size:
        keep = np.ones(n, dtype=bool)
        keep[zero_weight] = False
        t, temp_s, rate, u, y = t[keep], temp_s[keep], rate[keep], u[keep], y[keep]
        n = t.size
    span_c = float(np.ptp(temp_s)) if n else 0.0
    moves = n > 1 and np.ptp(u) > INPUT_CHANGE_TOL * max(1.0, float(np.max(np.abs(u))))
    same = (np.diff(segments(t)) == 0) & (np.abs(np.diff(u)) <= INPUT_CHANGE_TOL * max(1.0, float(np.max(np.abs(u)))))
    sigma = _white_sigma(y, same) if n > 1 else 0.0
    columns = [np.ones(n), *([u] if moves else [])]
    starts = ramp_starts(t, rate, short.ramp_share) if span_c >= short.min_slope_span_c else np.empty(0)
    slope_ok = span_c >= short.min_slope_span_c
    base = np.column_stack([*columns, *([temp_s - temp_s.mean()] if slope_ok else [])])
    step, step_column = level_step(t, y, base, np.random.default_rng(short.seed), sigma, short,
                                   settings.surrogate.draws)
    if step.ran and starts.size:
        gap = float(np.min(np.abs(starts - step.values["time_s"])))
        step.values |= {"nearest_ramp_start_s": float(starts[np.argmin(np.abs(starts - step.values["time_s"]))]),
                        "at_ramp_start": gap <= window_s / 2.0}
    others = np.column_stack([*columns, *([step_column] if step_column is not None else [])])
    if slope_ok or n < short.min_fit_samples:
        slope = temperature_slope(temp_s, y, others, short)
        if slope.ran and abs(float(np.corrcoef(t, temp_s)[0, 1])) > short.one_way_corr:
            slope.values["confusable_with"] = DRIFT
    else:
        slope = ShortTest("temperature_slope", "slope of the output against temperature", NOT_RUN,
                          reason=f"needs the temperature to change by {short.min_slope_span_c:g} degC; "
                                 f"this record's changes by {span_c:.3g} degC")
    fit = np.column_stack([others, *([temp_s] if slope_ok else [])])
    q = basis(fit) if n else fit
    residual = y - q @ (q.T @ y)
    noise = white_noise(t, residual, sigma, rate_hz, short.alpha, settings.locate.min_allan_samples)
    return ShortRecordReport(
        sensor=kind, unit=unit, recording=name, duration_s=duration_s, samples=int(rec.time_s.size), sample_rate_hz=rate_hz,
        temperature_span_c=span_c, smooth_s=float(window_s), ramp_starts_s=[float(s) for s in starts],
        tests=[slope, step, noise], needs_more_time=needs_more_time(duration_s, settings), settings=settings)
