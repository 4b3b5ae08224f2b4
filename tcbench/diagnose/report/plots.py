"""Figures of a :class:`~tcbench.diagnose.diagnosis.Diagnosis`, as PNG (matplotlib Agg).

Each ``plot_*`` function writes one PNG to ``path`` and returns ``path``:
:func:`plot_residuals` (held-out residual of the starting and the final model against time and
temperature, with the located mismatch shaded), :func:`plot_allan` (Allan deviation of both
residuals against the white-noise line and the flagging bound) and :func:`plot_evidence` (each
candidate effect's penalised held-out gain against the detection threshold) and
:func:`plot_spectrum` (spectrum of both residuals: ``scipy.signal.periodogram``
for a continuous record or one with a few gaps, Lomb-Scargle for one made of bursts). :func:`plot_output` (the output
and the thermometer against time) is written when the diagnosis's series carries the output.

Every finding of ``report.json`` ``effects`` is marked from its ``where``, whatever its id:
vertical lines at its ``time_s`` on the time panels, its ``temperature_c`` band as a strip (and,
when narrower than the recording's range, a shading) on the temperature panels, its
``frequency_hz`` or ``period_s`` as vertical lines on the spectrum, its ``level`` as a
horizontal line on the output panel (on the thermometer's axis when the finding's ``params``
give ``unit`` degC). :func:`write_plots` writes them all into a directory.
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy.signal import periodogram

from tcbench.diagnose.report.lomb import lombscargle_chunked
from tcbench.diagnose.result import Diagnosis
from tcbench.diagnose.select.attribute import Evidence
from tcbench.diagnose.select.locate import AllanExcess
from tcbench.diagnose.terms import Term, terms
from tcbench.sensors.segments import segments, within_rate_hz

BEFORE_COLOUR, AFTER_COLOUR = "tab:red", "tab:blue"
STATUS_COLOUR = {"kept": "tab:green", "rejected": "0.6", "in the model": "tab:blue", "not identifiable": "0.3"}
SPAN_COLOUR = "gold"
MAX_POINTS = 20_000
MEAN_WINDOW_S = 300.0
DPI = 110
_BAND = re.compile(r"temperature band\s+(-?[\d.eE+]+)\.\.(-?[\d.eE+]+)")
PLOT_FILES = {"residuals": "residuals.png", "allan": "allan.png", "evidence": "evidence.png",
              "spectrum": "spectrum.png"}
OUTPUT_FILE = "output.png"
FINDING_COLOURS = ("tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:pink", "tab:olive", "tab:cyan",
                   "0.35")
SPECTRUM_POINTS = 4000  # faint points per spectrum (every k-th frequency)
SPECTRUM_BINS = 160  # log-spaced frequency bins of the averaged periodogram
LS_FREQUENCIES = 3000  # frequencies of the Lomb-Scargle periodogram of a burst record
GAP_FILL_MAX = 2.0  # a gapped record whose clock holds at most this many slots per sample is zero-filled
NARROW_BAND = 0.8  # a temperature band narrower than this share of the range is also shaded


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def _window_means(t_s: np.ndarray, temp_c: np.ndarray, r: np.ndarray, window_s: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Means of time, temperature and residual over consecutive ``window_s`` windows; NaN rows
    between windows that are not adjacent so that lines break across gaps."""
    idx = np.floor((t_s - t_s[0]) / window_s).astype(np.int64)
    counts = np.bincount(idx).astype(np.float64)
    occupied = np.flatnonzero(counts)
    n = counts[occupied]
    tm, cm, rm = (np.bincount(idx, weights=a)[occupied] / n for a in (t_s, temp_c, r))
    gap = np.flatnonzero(np.diff(occupied) > 1) + 1
    return tuple(np.insert(a, gap, np.nan) for a in (tm, cm, rm))  # type: ignore[return-value]


def _spans(d: Diagnosis) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """Located time spans (h from the start) and temperature bands (°C) of ``d.mismatch``."""
    t0 = float(d.series.t_s[0])
    times = [((m.t_start_s - t0) / 3600.0, (m.t_end_s - t0) / 3600.0)
             for m in d.mismatch if m.what.startswith("time span")]
    bands = [(float(g[1]), float(g[2])) for m in d.mismatch if (g := _BAND.match(m.what))]
    return times, bands



def _numbers(x: object) -> list[float]:
    """A number or a list of numbers as a list of floats."""
    return [float(v) for v in x] if isinstance(x, (list, tuple, np.ndarray)) else [float(x)]  # type: ignore[arg-type]


def located(d: Diagnosis, key: str) -> list[tuple[str, str, object]]:
    """``(id, colour, value)`` of every finding of ``d`` whose ``where`` has ``key``; colours
    follow the findings' order so that one finding has one colour in every plot."""
    out = []
    for i, f in enumerate(d.effects):
        where = f.where or {}
        if key in where and where[key] is not None:
            out.append((str(f.id), FINDING_COLOURS[i % len(FINDING_COLOURS)], where[key]))
    return out


def _frequencies(d: Diagnosis) -> list[tuple[str, str, list[float]]]:
    """Located lines (Hz) of every finding: its ``frequency_hz`` or, failing that, 1 / ``period_s``."""
    out = [(i, c, _numbers(v)) for i, c, v in located(d, "frequency_hz")]
    named = {i for i, _, _ in out}
    out += [(i, c, [1.0 / p for p in _numbers(v) if p > 0]) for i, c, v in located(d, "period_s") if i not in named]
    return out


def mark_times(ax: plt.Axes, d: Diagnosis, t0: float, t1: float) -> int:
    """Vertical lines (hours from ``t0``) at each finding's ``time_s`` inside the record's span
    ``[t0, t1]`` (5 % margin); the number of lines drawn."""
    margin = 0.05 * (t1 - t0)
    drawn = 0
    for name, colour, value in located(d, "time_s"):
        times = [t for t in _numbers(value) if t0 - margin <= t <= t1 + margin]
        for k, t in enumerate(times):
            ax.axvline((t - t0) / 3600.0, color=colour, lw=1.0, ls="--", alpha=0.8, zorder=3,
                       label=f"{name}: time" if k == 0 else None)
        drawn += len(times)
    return drawn


def mark_bands(ax: plt.Axes, d: Diagnosis, temp_range: tuple[float, float]) -> int:
    """Each finding's ``temperature_c`` band as a strip at the bottom of ``ax`` (one row per
    finding), also shaded over the panel's height when narrower than :data:`NARROW_BAND` of the
    recording's ``temp_range``; the number of bands drawn."""
    width = max(temp_range[1] - temp_range[0], 1e-9)
    bands = located(d, "temperature_c")
    for row, (name, colour, band) in enumerate(bands):
        low, high = (float(v) for v in band)  # type: ignore[union-attr]
        y0 = 0.02 + 0.04 * row
        ax.axvspan(low, high, ymin=y0, ymax=y0 + 0.03, color=colour, alpha=0.8, lw=0, zorder=3,
                   label=f"{name}: temperature band")
        if high - low < NARROW_BAND * width:
            ax.axvspan(low, high, color=colour, alpha=0.12, lw=0, zorder=0)
    return len(bands)


def mark_levels(ax: plt.Axes, d: Diagnosis, unit: str) -> int:
    """Horizontal lines at the ``level`` of each finding whose ``params`` ``unit`` (the output
    unit when it gives none) is ``unit``; the number of lines drawn."""
    drawn = 0
    for i, f in enumerate(d.effects):
        where = f.where or {}
        if where.get("level") is None or str((f.params or {}).get("unit", d.unit)) != unit:
            continue
        colour = FINDING_COLOURS[i % len(FINDING_COLOURS)]
        for k, level in enumerate(_numbers(where["level"])):
            ax.axhline(level, color=colour, lw=1.2, ls="-.", zorder=3, label=f"{f.id}: level" if k == 0 else None)
            drawn += 1
    return drawn


def residual_spectrum(t_s: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, str]:
    """One-sided spectrum of a residual: ``(frequency Hz, power, method)``. A continuous record
    takes ``scipy.signal.periodogram`` (density, unit^2/Hz, at its median sample interval). A
    record whose gaps hold a small part of its span (a logging gap, samples given zero weight)
    takes the same periodogram on its within-segment clock with zeros in the gaps, scaled by the
    share of the clock it fills: memory and time of the span, not of samples x frequencies. A
    record of bursts (gaps over :data:`GAP_FILL_MAX` of the samples) takes the Lomb-Scargle
    periodogram on log-spaced frequencies from one over its span to half its within-burst rate,
    scaled to the same density for white noise, evaluated in chunks of bounded memory."""
    t = np.asarray(t_s, dtype=np.float64)
    x = np.asarray(r, dtype=np.float64) - float(np.mean(r))
    if segments(t)[-1] == 0:
        fs = 1.0 / float(np.median(np.diff(t)))
        f, p = periodogram(x, fs=fs, detrend="constant")
        return f[1:], p[1:], "periodogram"
    fs = within_rate_hz(t)
    slot = np.rint((t - t[0]) * fs).astype(np.int64)
    if slot[-1] + 1 <= GAP_FILL_MAX * t.size:
        filled = np.bincount(slot, weights=x, minlength=int(slot[-1]) + 1)
        f, p = periodogram(filled, fs=fs, detrend=False)
        return f[1:], p[1:] * (filled.size / t.size), "periodogram, gaps zero-filled"
    f = np.geomspace(1.0 / float(t[-1] - t[0]), 0.5 * fs, LS_FREQUENCIES)
    power = lombscargle_chunked(t, x, 2.0 * np.pi * f)  # about the variance at every frequency for white noise
    return f, power * (2.0 / fs), "Lomb-Scargle"


def _log_binned(f: np.ndarray, p: np.ndarray, bins: int = SPECTRUM_BINS) -> tuple[np.ndarray, np.ndarray]:
    """Mean power in log-spaced frequency bins (empty bins dropped)."""
    edges = np.geomspace(f[0], f[-1] * (1 + 1e-9), bins + 1)
    idx = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, bins - 1)
    n = np.bincount(idx, minlength=bins)
    ok = n > 0
    fm = np.bincount(idx, weights=np.log(f), minlength=bins)[ok] / n[ok]
    pm = np.bincount(idx, weights=p, minlength=bins)[ok] / n[ok]
    return np.exp(fm), pm


def plot_spectrum(d: Diagnosis, path: Path) -> Path:
    """Log-log spectrum of the held-out residual of the starting and the final model (faint:
    every frequency; line: log-binned means) against the white-noise level ``2 sigma^2 / fs``,
    with each finding's located lines (``frequency_hz`` or ``period_s``) marked."""
    s = d.series
    sigma = float(d.noise.white_sigma)
    fig, ax = plt.subplots(figsize=(7, 4))
    method, floor = "periodogram", float("inf")
    fs = within_rate_hz(np.asarray(s.t_s, dtype=np.float64))
    for res, colour, label in ((s.residual_before, BEFORE_COLOUR, "starting model"),
                               (s.residual_after, AFTER_COLOUR, "final model")):
        f, p, method = residual_spectrum(s.t_s, res)
        step = max(1, int(np.ceil(f.size / SPECTRUM_POINTS)))
        ax.loglog(f[::step], p[::step], ".", ms=1, color=colour, alpha=0.15, rasterized=True)
        fb, pb = _log_binned(f, p)
        ax.loglog(fb, pb, "-", color=colour, lw=1.3, label=f"{label} (log-binned)")
        floor = min(floor, float(np.min(pb[pb > 0])) if (pb > 0).any() else floor)
    white = 2.0 * sigma**2 / fs
    ax.axhline(white, color="k", ls="--", lw=1, label="white-noise level")
    ax.set_ylim(bottom=min(floor, white) / 10.0)
    for name, colour, freqs in _frequencies(d):
        for k, fr in enumerate(freqs):
            ax.axvline(fr, color=colour, lw=1.2, ls="--", zorder=3,
                       label=f"{name}: {fr:.3g} Hz ({1.0 / fr / 60.0:.3g} min)" if k == 0 else None)
    ax.set(xlabel="frequency (Hz)", ylabel=f"power ({d.unit})²/Hz")
    ax.set_title(f"{d.recording or 'recording'}: {method} of the held-out residual", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(True, which="both", alpha=0.3)
    return _save(fig, path)


def plot_output(d: Diagnosis, path: Path) -> Path:
    """The output (left axis) and the smoothed thermometer (right axis) against time, with
    each finding's instants and levels marked. Needs ``d.series.output``."""
    s = d.series
    t = np.asarray(s.t_s, dtype=np.float64)
    y = np.asarray(s.output, dtype=np.float64)  # type: ignore[attr-defined]
    step = max(1, int(np.ceil(t.size / MAX_POINTS)))
    t_h = (t - t[0]) / 3600.0
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(t_h[::step], y[::step], ".", ms=1, color="0.3", alpha=0.4, rasterized=True)
    ax_t = ax.twinx()
    ax_t.plot(t_h, s.temp_c, "-", color="tab:red", lw=1.0, alpha=0.7, label="thermometer (smoothed)")
    mark_times(ax, d, float(t[0]), float(t[-1]))
    mark_levels(ax, d, d.unit)
    mark_levels(ax_t, d, "degC")
    ax.set(xlabel="time (h)", ylabel=f"output ({d.unit})",
           title=f"{d.recording or 'recording'}: output and thermometer, located findings marked")
    ax_t.set_ylabel("thermometer (°C)")
    lines = ax.get_legend_handles_labels()
    lines_t = ax_t.get_legend_handles_labels()
    if lines[0] or lines_t[0]:
        ax.legend(lines[0] + lines_t[0], lines[1] + lines_t[1], fontsize=7, loc="upper right")
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_residuals(d: Diagnosis, path: Path) -> Path:
    """2x2 panels: held-out residual of the starting (left) and final (right) model against time
    (top) and temperature (bottom), raw (faint) and as 5-min means; located time spans and
    temperature bands shaded; the grey band is +-1 white sigma."""
    s = d.series
    t, temp = np.asarray(s.t_s, dtype=np.float64), np.asarray(s.temp_c, dtype=np.float64)
    sigma = float(d.noise.white_sigma)
    step = max(1, int(np.ceil(t.size / MAX_POINTS)))
    t_h = (t - t[0]) / 3600.0
    times, bands = _spans(d)
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharey=True)
    columns = (
        (s.residual_before, BEFORE_COLOUR, "starting model", d.baseline),
        (s.residual_after, AFTER_COLOUR, "final model", d.final),
    )
    ranges: list[tuple[float, float]] = []
    for col, (res, colour, label, fit) in enumerate(columns):
        r = np.asarray(res, dtype=np.float64)
        tm, cm, rm = _window_means(t, temp, r, MEAN_WINDOW_S)
        p_lo, p_hi = np.nanpercentile(r, [0.2, 99.8])
        ranges.append((float(p_lo), float(p_hi)))
        ranges.append((float(np.nanmin(rm)), float(np.nanmax(rm))))
        ax_t, ax_c = axes[0, col], axes[1, col]
        for ax, x_raw, x_mean in ((ax_t, t_h, (tm - t[0]) / 3600.0), (ax_c, temp, cm)):
            ax.axhspan(-sigma, sigma, color="0.85", zorder=0, label="±1 white σ")
            ax.plot(x_raw[::step], r[::step], ".", ms=1, color=colour, alpha=0.15, rasterized=True)
            ax.plot(x_mean, rm, "-" if ax is ax_t else "-o", color=colour, lw=1.4, ms=2,
                    label=f"{MEAN_WINDOW_S / 60:g}-min means")
            ax.axhline(0.0, color="k", lw=0.6)
            ax.grid(True, alpha=0.3)
        for i, (a, b) in enumerate(times):
            ax_t.axvspan(a, b, color=SPAN_COLOUR, alpha=0.25, lw=0, zorder=0,
                         label="located time span" if i == 0 else None)
        for i, (a, b) in enumerate(bands):
            ax_c.axvspan(a, b, color=SPAN_COLOUR, alpha=0.25, lw=0, zorder=0,
                         label="located temperature band" if i == 0 else None)
        mark_times(ax_t, d, float(t[0]), float(t[-1]))
        mark_bands(ax_c, d, (float(np.min(temp)), float(np.max(temp))))
        rmse = fit.rmse_heldout
        terms = ", ".join(fit.model) or "minimal"
        sep = "\n" if len(terms) > 40 else " "  # a long list of terms on a line of its own
        ax_t.set_title(f"{label} ({terms}):{sep}RMSE held-out {rmse:.4g} {d.unit} = {rmse / sigma:.3g} σ", fontsize=9)
        ax_t.set_xlabel("time (h)")
        ax_c.set_xlabel("thermometer (°C)")
        ax_t.legend(fontsize=7, loc="upper right")
        ax_c.legend(fontsize=7, loc="upper right")
    lo = min(v[0] for v in ranges)
    hi = max(v[1] for v in ranges)
    pad = 0.05 * (hi - lo) if hi > lo else sigma
    axes[0, 0].set_ylim(min(lo, -sigma) - pad, max(hi, sigma) + pad)
    axes[0, 0].set_ylabel(f"held-out residual ({d.unit})")
    axes[1, 0].set_ylabel(f"held-out residual ({d.unit})")
    fig.suptitle(f"{d.recording or 'recording'} ({d.sensor}): baseline RMSE held-out "
                 f"{d.baseline.rmse_heldout:.4g} {d.unit}, final {d.final.rmse_heldout:.4g} {d.unit}; "
                 "shaded: mismatch located on the starting model", fontsize=10)
    return _save(fig, path)


def _draw_allan(ax: plt.Axes, ex: AllanExcess, colour: str, label: str, marker: str, ms: float) -> None:
    ax.loglog(ex.tau_s, ex.adev, f"{marker}-", ms=ms, color=colour, label=f"{label}: residual")
    ax.loglog(ex.tau_s, ex.white, "--", lw=1, color=colour, label=f"{label}: white (+thermometer) line")
    ax.loglog(ex.tau_s, ex.white * ex.bound, ":", lw=1, color=colour, label=f"{label}: flagging bound")
    if ex.first_over is not None:
        k = ex.first_over
        ax.loglog(ex.tau_s[k], ex.adev[k], "*", ms=12, color=colour, mec="k",
                  label=f"{label}: above bound from τ = {ex.tau_s[k]:.4g} s")


def plot_allan(d: Diagnosis, path: Path) -> Path:
    """Log-log Allan deviation of the held-out residual before and after, each with its white
    (+ thermometer) noise line and flagging bound; says so when one is not available."""
    fig, ax = plt.subplots(figsize=(7, 5))
    missing = []
    same = d.final.model == d.baseline.model
    after = "final model (= starting model)" if same else "final model"
    for ex, colour, label, marker, ms in ((d.series.allan_before, BEFORE_COLOUR, "starting model", "o", 6),
                                          (d.series.allan_after, AFTER_COLOUR, after, "s", 3)):
        if ex is None:
            missing.append(label)
        else:
            _draw_allan(ax, ex, colour, label, marker, ms)
    if missing:
        why = "recording too short or made of bursts"
        ax.text(0.5, 0.5 if len(missing) == 2 else 0.06,
                "\n".join(f"{m}: Allan deviation not available ({why})" for m in missing),
                transform=ax.transAxes, ha="center", va="center", fontsize=9, color="0.3")
    if len(missing) < 2:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.legend(fontsize=7, loc="lower left")
        ax.grid(True, which="both", alpha=0.3)
    else:
        ax.set_xticks([])
        ax.set_yticks([])
    ax.set(xlabel="τ (s)", ylabel=f"Allan deviation ({d.unit})",
           title=f"{d.recording or 'recording'}: Allan deviation of the held-out residual")
    return _save(fig, path)


def _fmt(x: float) -> str:
    return f"{x:.3g}"


def plot_evidence(d: Diagnosis, path: Path) -> Path:
    """Penalised held-out gain (sigma^2 units, symlog) of every deterministic candidate against
    the detection threshold, coloured by status and annotated with the robust Wald statistic;
    the term judged otherwise (its :attr:`~tcbench.diagnose.terms.Term.gain_name`:
    ``bias_instability``'s Allan ratio against its bound) in its own panel below."""
    other = next(t for t in terms() if t.gain_name)
    det = [e for e in d.candidates if e.effect != other.id]
    flicker = next((e for e in d.candidates if e.effect == other.id), None)
    fig, (ax, ax_b) = plt.subplots(2, 1, figsize=(9, 1.2 + 0.45 * len(det) + 1.6),
                                   gridspec_kw={"height_ratios": [max(len(det), 1), 1.6]})
    y = np.arange(len(det))[::-1]
    gains = np.array([e.gain for e in det], dtype=np.float64)
    finite = np.isfinite(gains)
    selection = d.statistics.settings.selection
    threshold = selection.detection_threshold_sigma2
    span = float(np.nanmax(np.abs(gains[finite]))) if finite.any() else threshold
    span = max(span, threshold) * 30.0
    ax.barh(y[finite], gains[finite], color=[STATUS_COLOUR.get(e.status, "0.6") for e, f in zip(det, finite) if f],
            height=0.6)
    for yi, e in zip(y, det, strict=True):
        if not np.isfinite(e.gain):
            ax.text(0.0, yi, f"  {e.status}", va="center", ha="left", fontsize=8, style="italic",
                    color=STATUS_COLOUR.get(e.status, "0.3"))
            continue
        note = f"Wald {_fmt(e.wald)}" if np.isfinite(e.wald) else "Wald n/a"
        x_text, ha = (e.gain, "left") if e.gain >= 0 else (e.gain, "right")
        ax.text(x_text, yi, f"  {note}  " if ha == "left" else f"{note}  ", va="center", ha=ha, fontsize=7)
    ax.axvline(threshold, color="k", ls="--", lw=1, label=f"detection threshold {threshold:g} σ²")
    for yi, e in zip(y, det, strict=True):  # open-world terms need more: their detectors search
        if np.isfinite(e.gain) and float(e.threshold) != threshold:
            ax.plot([e.threshold, e.threshold], [yi - 0.4, yi + 0.4], color="k", ls=":", lw=1.5)
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_xscale("symlog", linthresh=max(threshold, 1.0))
    ax.set_xlim(-span, span)
    ax.set_yticks(y, [e.effect for e in det])
    ax.set_ylim(-0.7, len(det) - 0.3)
    for status, colour in STATUS_COLOUR.items():
        if status != "not identifiable" and any(e.status == status for e in det):
            ax.barh([np.nan], [np.nan], color=colour, label=status)
    ax.set(xlabel="penalised held-out gain (σ² units; symlog)",
           title=f"{d.recording or 'recording'}: candidate effects "
                 f"(kept needs gain > {threshold:g} and robust Wald > {selection.wald_threshold:g})")
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(True, axis="x", alpha=0.3)
    _flicker_panel(ax_b, other, flicker)
    return _save(fig, path)


def _flicker_panel(ax: plt.Axes, t: Term, e: Evidence | None) -> None:
    """Term ``t``'s evidence ``e`` against its bound (``bias_instability``: Allan deviation /
    white line at the first tau over the bound)."""
    ax.set_yticks([0], [t.id])
    ax.set_xlabel(t.gain_label)
    if e is None or not np.isfinite(e.gain):
        text = "not tested" if e is None else f"{e.status}: {e.reason}"
        ax.text(0.02, 0.5, text, transform=ax.transAxes, va="center", fontsize=8, style="italic",
                color=STATUS_COLOUR.get(e.status if e else "", "0.3"))
        ax.set_xticks([])
        return
    ax.barh([0], [e.gain], color=STATUS_COLOUR.get(e.status, "0.6"), height=0.5, label=e.status)
    ax.axvline(e.threshold, color="k", ls="--", lw=1, label=f"bound {e.threshold:.3g}")
    ax.axvline(1.0, color="k", lw=0.5)
    ax.set_xlim(min(0.9, e.threshold * 0.95), max(e.gain, e.threshold) * 1.1)
    ax.text(e.gain, 0, f"  ratio {e.gain:.3g}", va="center", fontsize=7)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(True, axis="x", alpha=0.3)


def write_plots(d: Diagnosis, out_dir: str | Path) -> dict[str, str]:
    """Write ``residuals.png``, ``allan.png``, ``evidence.png``, ``spectrum.png`` and, when the
    series carries the output, ``output.png`` into ``out_dir`` (created if needed); returns
    name -> file name (relative to ``out_dir``)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    plots = {"residuals": plot_residuals, "allan": plot_allan, "evidence": plot_evidence, "spectrum": plot_spectrum}
    for name, plot in plots.items():
        plot(d, out / PLOT_FILES[name])
    files = dict(PLOT_FILES)
    if getattr(d.series, "output", None) is not None:
        plot_output(d, out / OUTPUT_FILE)
        files["output"] = OUTPUT_FILE
    return files
