"""Figures of a :class:`~tcbench.diagnose.diagnosis.Diagnosis`, as PNG (matplotlib Agg).

Each ``plot_*`` function writes one PNG to ``path`` and returns ``path``:
:func:`plot_residuals` (held-out residual of the starting and the final model against time and
temperature, with the located mismatch shaded), :func:`plot_allan` (Allan deviation of both
residuals against the white-noise line and the flagging bound) and :func:`plot_evidence` (each
candidate effect's penalised held-out gain against the detection threshold).
:func:`write_plots` writes all three into a directory.
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tcbench.diagnose.attribute import WALD_THRESHOLD, Evidence
from tcbench.diagnose.diagnosis import Diagnosis
from tcbench.diagnose.locate import AllanExcess

BEFORE_COLOUR, AFTER_COLOUR = "tab:red", "tab:blue"
STATUS_COLOUR = {"kept": "tab:green", "rejected": "0.6", "in the model": "tab:blue", "not identifiable": "0.3"}
SPAN_COLOUR = "gold"
MAX_POINTS = 20_000
MEAN_WINDOW_S = 300.0
DPI = 110
_BAND = re.compile(r"temperature band\s+(-?[\d.eE+]+)\.\.(-?[\d.eE+]+)")
PLOT_FILES = {"residuals": "residuals.png", "allan": "allan.png", "evidence": "evidence.png"}


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


def plot_residuals(d: Diagnosis, path: Path) -> Path:
    """2x2 panels: held-out residual of the starting (left) and final (right) model against time
    (top) and temperature (bottom), raw (faint) and as 5-min means; located time spans and
    temperature bands shaded; the grey band is +-1 white sigma."""
    s = d.series
    t, temp = np.asarray(s.t_s, dtype=np.float64), np.asarray(s.temp_c, dtype=np.float64)
    sigma = float(d.noise["white_sigma"])
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
        rmse = fit["rmse_heldout"]
        terms = ", ".join(fit.get("model", [])) or "minimal"
        ax_t.set_title(f"{label} ({terms}): RMSE held-out {rmse:.4g} {d.unit} = {rmse / sigma:.3g} σ", fontsize=9)
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
                 f"{d.baseline['rmse_heldout']:.4g} {d.unit}, final {d.final['rmse_heldout']:.4g} {d.unit}; "
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
    same = d.final.get("model") == d.baseline.get("model")
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
    ``bias_instability`` (an Allan ratio against its bound) in its own panel below."""
    det = [e for e in d.candidates if e.effect != "bias_instability"]
    flicker = next((e for e in d.candidates if e.effect == "bias_instability"), None)
    fig, (ax, ax_b) = plt.subplots(2, 1, figsize=(9, 1.2 + 0.45 * len(det) + 1.6),
                                   gridspec_kw={"height_ratios": [max(len(det), 1), 1.6]})
    y = np.arange(len(det))[::-1]
    gains = np.array([e.gain for e in det], dtype=np.float64)
    finite = np.isfinite(gains)
    threshold = float(det[0].threshold) if det else 10.0
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
                 f"(kept needs gain > {threshold:g} and robust Wald > {WALD_THRESHOLD:g})")
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(True, axis="x", alpha=0.3)
    _flicker_panel(ax_b, flicker)
    return _save(fig, path)


def _flicker_panel(ax: plt.Axes, e: Evidence | None) -> None:
    """``bias_instability``: Allan deviation / white line at the first tau over the bound."""
    ax.set_yticks([0], ["bias_instability"])
    ax.set_xlabel("Allan deviation / white line at the first τ over the bound (not a σ² gain)")
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
    """Write ``residuals.png``, ``allan.png`` and ``evidence.png`` into ``out_dir`` (created if
    needed); returns name -> file name (relative to ``out_dir``)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name, plot in (("residuals", plot_residuals), ("allan", plot_allan), ("evidence", plot_evidence)):
        plot(d, out / PLOT_FILES[name])
    return dict(PLOT_FILES)
