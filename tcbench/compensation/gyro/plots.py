"""Figures of the gyro drift/noise pipeline (seed 001 Figs. 11-14, 17-19), as PNG (matplotlib Agg).

Every function writes one PNG to ``path`` and returns ``path``. Times are given in seconds and
drawn in hours from the first sample; rates are in ``unit`` (deg/s by default). Long records are
drawn as a min/max envelope of at most ``MAX_COLUMNS`` bins, which looks like the full trace at
the figure's resolution and keeps the PNG small and fast to write.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch

from tcbench.compensation.gyro.pipeline import ModeClasses
from tcbench.signal.allan import AllanDeviation

DPI = 110
MAX_COLUMNS = 1500  # envelope bins of a long trace (about the figure's width in pixels)
ZOOM_S = 600.0  # the zoomed window of the TFPF figure: 10 min in the middle of the record
MAX_PARETO_LABELS = 5
CLASS_COLOUR = {"noise": "tab:red", "mixed": "tab:orange", "drift": "tab:blue"}
UNKNOWN_COLOUR = "0.25"
RAW_COLOUR, FINAL_COLOUR, PREDICTED_COLOUR, TEMP_COLOUR = "tab:red", "tab:blue", "tab:blue", "tab:green"
ALLAN_SCALE = {"deg/h": 3600.0, "deg/s": 1.0}
MARKERS = "osD^v<>phX*"


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def _hours(t_s: np.ndarray) -> np.ndarray:
    """Time from the first sample in hours."""
    t = np.asarray(t_s, dtype=np.float64)
    return (t - t[0]) / 3600.0


def _envelope(x: np.ndarray, y: np.ndarray, max_columns: int = MAX_COLUMNS) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` unchanged when short, else the min and max of ``y`` in each of at most
    ``max_columns`` equal-count bins, interleaved as a zig-zag line at each bin's mean ``x``."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if y.size <= 2 * max_columns:
        return x, y
    per_bin = -(-y.size // max_columns)
    n_bins = -(-y.size // per_bin)
    pad = n_bins * per_bin - y.size
    xb = np.pad(x, (0, pad), constant_values=np.nan).reshape(n_bins, per_bin)
    yb = np.pad(y, (0, pad), constant_values=np.nan).reshape(n_bins, per_bin)
    xm = np.nanmean(xb, axis=1)
    return np.repeat(xm, 2), np.column_stack((np.nanmin(yb, axis=1), np.nanmax(yb, axis=1))).ravel()


def _trace(ax: plt.Axes, t_h: np.ndarray, y: np.ndarray, **kwargs: object) -> None:
    """Plot ``y`` against ``t_h`` (h), as an envelope when long."""
    ax.plot(*_envelope(t_h, y), **kwargs)


def _top_legend(ax: plt.Axes, twins: Sequence[plt.Axes] = (), headroom: float = 0.3) -> None:
    """One-row legend of ``ax`` and ``twins`` in a band of ``headroom`` (fraction of the data
    range) added above the data, so that it covers no trace."""
    lines = [h for a in (ax, *twins) for h in a.get_legend_handles_labels()[0]]
    for a in (ax, *twins):
        lo, hi = a.get_ylim()
        a.set_ylim(lo, hi + headroom * (hi - lo))
    ax.legend(lines, [h.get_label() for h in lines], fontsize=7, loc="upper right", ncol=len(lines))


def _std(y: np.ndarray) -> float:
    return float(np.std(np.asarray(y, dtype=np.float64)))


def _freq_text(f_hz: float) -> str:
    """A centre frequency in Hz or mHz, three significant digits."""
    return f"{f_hz * 1e3:.3g} mHz" if abs(f_hz) < 1.0 else f"{f_hz:.3g} Hz"


def modes_figure(
    path: Path, t_s: np.ndarray, modes: np.ndarray, centre_freqs_hz: np.ndarray | None,
    labels: tuple[str, ...] | None, title: str, *, unit: str = "deg/s",
) -> Path:
    """Seed 001 Fig. 12: the VMD modes (k, n) as k stacked panels against time (h), each named
    "IMF i" with, when given, its class (colour-coded) and its centre frequency."""
    u = np.atleast_2d(np.asarray(modes, dtype=np.float64))
    k = u.shape[0]
    t_h = _hours(t_s)
    fig, axes = plt.subplots(k, 1, figsize=(9, 0.95 * k + 1.4), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        label = labels[i] if labels is not None else None
        colour = CLASS_COLOUR.get(label, UNKNOWN_COLOUR) if label else UNKNOWN_COLOUR
        _trace(ax, t_h, u[i], color=colour, lw=0.6)
        freq = _freq_text(float(centre_freqs_hz[i])) if centre_freqs_hz is not None else None
        name = "\n".join(s for s in (f"IMF {i + 1}", label, freq) if s)
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize=8, color=colour)
        ax.tick_params(labelsize=7)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time (h)")
    if labels is not None:
        present = [c for c in CLASS_COLOUR if c in labels]
        axes[0, 0].legend(handles=[Patch(color=CLASS_COLOUR[c], label=c) for c in present], fontsize=7,
                          ncol=len(present), loc="lower right", bbox_to_anchor=(1.0, 1.0), frameon=False)
    axes[0, 0].set_title(f"{title} (amplitudes in {unit})", loc="left", fontsize=10)
    return _save(fig, path)


def _entropy_top(entropy: np.ndarray, classes: ModeClasses) -> float:
    """The y limit of the entropy bars: above every finite entropy and both thresholds."""
    finite = entropy[np.isfinite(entropy)]
    return 1.2 * max(float(finite.max()) if finite.size else 0.0, classes.noise_above)


def entropy_classes_figure(path: Path, classes: ModeClasses, title: str) -> Path:
    """Seed 001 Fig. 13: (a) the sample entropy of each IMF against the two class thresholds,
    an infinite (undefined) entropy clipped at the top with a marker; (b) the class of each IMF."""
    e = np.asarray(classes.entropy, dtype=np.float64)
    x = np.arange(1, e.size + 1)
    colours = [CLASS_COLOUR.get(lab, UNKNOWN_COLOUR) for lab in classes.label]
    top = _entropy_top(e, classes)
    shown = np.where(np.isinf(e), top, e)
    fig, (ax, ax_c) = plt.subplots(2, 1, figsize=(max(5.5, 0.6 * e.size + 2.5), 5.2), sharex=True,
                                   gridspec_kw={"height_ratios": [4, 1]})
    ax.bar(x, np.nan_to_num(shown, nan=0.0), color=colours, width=0.7)
    for xi, ei, si in zip(x, e, shown, strict=True):
        if np.isinf(ei):
            ax.text(xi, 0.95 * top, "∞", ha="center", va="top", fontsize=12, color="white", weight="bold")
        else:
            ax.text(xi, si, "n/a" if np.isnan(ei) else f"{ei:.2g}", ha="center", va="bottom", fontsize=7)
    if np.isinf(e).any():
        ax.plot(x[np.isinf(e)], np.full(int(np.isinf(e).sum()), top), "^", ms=9, color="k", zorder=3,
                label="∞ (undefined), clipped")
    ax.axhline(classes.noise_above, color=CLASS_COLOUR["noise"], ls="--", lw=1,
               label=f"noise above {classes.noise_above:g}")
    ax.axhline(classes.drift_below, color=CLASS_COLOUR["drift"], ls="--", lw=1,
               label=f"drift below {classes.drift_below:g}")
    ax.set_ylim(0.0, 1.06 * top)
    ax.set(ylabel="sample entropy (nats)", title=f"(a) {title}")
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, axis="y", alpha=0.3)
    ax_c.bar(x, np.ones(e.size), color=colours, width=0.95)
    for xi, lab in zip(x, classes.label, strict=True):
        ax_c.text(xi, 0.5, lab, ha="center", va="center", fontsize=7, color="white", weight="bold")
    ax_c.set_yticks([])
    ax_c.set_ylim(0.0, 1.0)
    ax_c.set_xticks(x, [f"IMF {i}" for i in x], fontsize=8)
    ax_c.set_title("(b) class of each IMF", fontsize=9)
    return _save(fig, path)


def _zoom_window(t_s: np.ndarray, window_s: float = ZOOM_S) -> np.ndarray:
    """Mask of ``window_s`` (at most a fifth of the record) in the middle of the record."""
    t = np.asarray(t_s, dtype=np.float64)
    half = 0.5 * min(window_s, 0.2 * (t[-1] - t[0]))
    mid = 0.5 * (t[0] + t[-1])
    return (t >= mid - half) & (t <= mid + half)


def mixed_tfpf_figure(
    path: Path, t_s: np.ndarray, mixed: np.ndarray, denoised: np.ndarray, title: str, *, unit: str = "deg/s",
) -> Path:
    """Seed 001 Fig. 14: the mixed part before and after TFPF against time (h), whole record (a)
    and a 10-min window in the middle (b, shaded in a)."""
    t_h = _hours(t_s)
    mixed, denoised = np.asarray(mixed, dtype=np.float64), np.asarray(denoised, dtype=np.float64)
    inside = _zoom_window(t_s)
    fig, (ax, ax_z) = plt.subplots(2, 1, figsize=(9, 6))
    for a, mask in ((ax, slice(None)), (ax_z, inside)):
        _trace(a, t_h[mask], mixed[mask], color=RAW_COLOUR, lw=0.6, alpha=0.6,
               label=f"mixed part (std {_std(mixed):.3g} {unit})")
        _trace(a, t_h[mask], denoised[mask], color=FINAL_COLOUR, lw=0.9,
               label=f"after TFPF (std {_std(denoised):.3g} {unit})")
        a.set(xlabel="time (h)", ylabel=f"rate ({unit})")
        a.grid(True, alpha=0.3)
    zoom_h = t_h[inside]
    ax.axvspan(zoom_h[0], zoom_h[-1], color="gold", alpha=0.3, lw=0, label="zoomed window")
    _top_legend(ax)
    ax.set_title(f"(a) {title}", fontsize=10)
    ax_z.set_title(f"(b) zoom: {60 * (zoom_h[-1] - zoom_h[0]):.3g} min in the middle", fontsize=10)
    return _save(fig, path)


def drift_prediction_figure(
    path: Path, t_s: np.ndarray, temperature_c: np.ndarray, drift_part: np.ndarray,
    predicted_drift: np.ndarray, title: str, *, unit: str = "deg/s",
) -> Path:
    """Seed 001 Fig. 17: (a) the drift part and the learner's prediction against time (h), with
    temperature on a twin axis; (b) the compensated drift (drift part - prediction)."""
    t_h = _hours(t_s)
    drift = np.asarray(drift_part, dtype=np.float64)
    residual = drift - np.asarray(predicted_drift, dtype=np.float64)
    fig, (ax, ax_r) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    _trace(ax, t_h, drift, color=RAW_COLOUR, lw=1.2, label="drift part")
    _trace(ax, t_h, predicted_drift, color=PREDICTED_COLOUR, lw=1.0, ls="--", label="prediction")
    twin = ax.twinx()
    _trace(twin, t_h, temperature_c, color=TEMP_COLOUR, lw=0.9, alpha=0.8, label="temperature")
    twin.set_ylabel("temperature (°C)", color=TEMP_COLOUR)
    twin.tick_params(axis="y", colors=TEMP_COLOUR)
    ax.set_ylabel(f"drift ({unit})")
    ax.set_title(f"(a) {title}", fontsize=10)
    ax.grid(True, alpha=0.3)
    _top_legend(ax, (twin,))
    rms = float(np.sqrt(np.mean(residual**2)))
    _trace(ax_r, t_h, residual, color=FINAL_COLOUR, lw=0.8,
           label=f"drift − prediction (RMS {rms:.3g} {unit}; drift std {_std(drift):.3g})")
    ax_r.axhline(0.0, color="k", lw=0.5)
    ax_r.set(xlabel="time (h)", ylabel=f"compensated drift ({unit})")
    ax_r.set_title("(b) compensated drift", fontsize=10)
    _top_legend(ax_r)
    ax_r.grid(True, alpha=0.3)
    return _save(fig, path)


def final_output_figure(
    path: Path, t_s: np.ndarray, raw_output: np.ndarray, final_output: np.ndarray, title: str,
    true_rate: np.ndarray | None = None, *, unit: str = "deg/s",
) -> Path:
    """Seed 001 Fig. 18: the raw gyro output and the pipeline's final output against time (h),
    with the true rate when given (the legend then gives each trace's RMS error against it)."""
    t_h = _hours(t_s)
    fig, ax = plt.subplots(figsize=(9, 4.5))
    truth = None if true_rate is None else np.asarray(true_rate, dtype=np.float64)
    for y, name, colour, lw, alpha in ((raw_output, "raw output", RAW_COLOUR, 0.6, 0.6),
                                       (final_output, "final output", FINAL_COLOUR, 0.8, 0.9)):
        y = np.asarray(y, dtype=np.float64)
        stat = (f"RMS error {np.sqrt(np.mean((y - truth) ** 2)):.3g}" if truth is not None
                else f"std {_std(y):.3g}")
        _trace(ax, t_h, y, color=colour, lw=lw, alpha=alpha, label=f"{name} ({stat} {unit})")
    if truth is not None:
        _trace(ax, t_h, truth, color="k", lw=1.0, ls="--", label="true rate")
    ax.set(xlabel="time (h)", ylabel=f"rate ({unit})", title=title)
    _top_legend(ax)
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def _slope_guide(ax: plt.Axes, curves: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
    """A dashed slope −1/2 line over the whole tau range, a factor 2 above the highest first point."""
    taus = np.concatenate([t for t, _ in curves])
    tau_lo, tau_hi = float(taus.min()), float(taus.max())
    start = 2.0 * max(float(np.nanmax(a[:1])) for _, a in curves)
    x = np.array([tau_lo, tau_hi])
    ax.loglog(x, start * np.sqrt(tau_lo / x), "--", color="0.5", lw=1, label="slope −1/2 (white noise)")


def allan_methods_figure(
    path: Path, curves: dict[str, AllanDeviation], title: str, units: str = "deg/h",
    annotations: dict[str, str] | None = None,
) -> Path:
    """Seed 001 Fig. 19: the Allan deviation of every method on one log-log axis (deviations
    given in deg/s, drawn in ``units``: "deg/h" (x 3600) or "deg/s"), with a slope −1/2 guide;
    ``annotations[name]`` is appended to that method's legend label."""
    if units not in ALLAN_SCALE:
        raise ValueError(f"units must be one of {', '.join(ALLAN_SCALE)}, got {units!r}")
    if not curves:
        raise ValueError("curves must name at least one method")
    scale = ALLAN_SCALE[units]
    notes = annotations or {}
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    drawn = []
    for i, (name, ad) in enumerate(curves.items()):
        adev = np.asarray(ad.adev, dtype=np.float64) * scale
        adev = np.where(adev > 0, adev, np.nan)
        label = f"{name} ({notes[name]})" if name in notes else name
        ax.loglog(ad.tau_s, adev, f"{MARKERS[i % len(MARKERS)]}-", ms=3.5, lw=1.2, label=label)
        drawn.append((np.asarray(ad.tau_s, dtype=np.float64), adev))
    _slope_guide(ax, drawn)
    ax.set(xlabel="τ (s)", ylabel=f"Allan deviation ({units})", title=title)
    ax.legend(fontsize=7, loc="best")
    ax.grid(True, which="both", alpha=0.3)
    return _save(fig, path)


def _label_indices(order: np.ndarray, n_max: int = MAX_PARETO_LABELS) -> np.ndarray:
    """At most ``n_max`` indices spread evenly along ``order``, both ends included."""
    if order.size <= n_max:
        return order
    return order[np.unique(np.round(np.linspace(0, order.size - 1, n_max)).astype(np.int64))]


def pareto_figure(
    path: Path, front_f: np.ndarray, all_f: np.ndarray | None, chosen_f: np.ndarray | None, *,
    objective_names: tuple[str, str] = ("fuzzy entropy", "permutation entropy"), title: str,
    front_x: np.ndarray | None = None,
) -> Path:
    """Seed 001 Fig. 11: the two objectives of every evaluated point (grey), the Pareto front
    (red) and the chosen compromise (star); with ``front_x`` (rows k, alpha) a few front points
    are labelled "k=8, α=9755", up and to the right (the dominated side of a convex front).
    ``objective_names`` are the axis labels (with units, if any)."""
    front = np.atleast_2d(np.asarray(front_f, dtype=np.float64))
    order = np.argsort(front[:, 0], kind="stable")
    fig, ax = plt.subplots(figsize=(7, 5.2))
    if all_f is not None:
        pts = np.atleast_2d(np.asarray(all_f, dtype=np.float64))
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=3, color="0.65", alpha=0.6, label=f"evaluated ({len(pts)})")
    ax.plot(front[order, 0], front[order, 1], "o-", ms=4, lw=1, color="tab:red",
            label=f"Pareto front ({len(front)})")
    if chosen_f is not None:
        c = np.asarray(chosen_f, dtype=np.float64).ravel()
        ax.plot(c[0], c[1], "*", ms=16, color="gold", mec="k", zorder=4, label="chosen compromise")
    if front_x is not None:
        xs = np.atleast_2d(np.asarray(front_x, dtype=np.float64))
        for i in _label_indices(order):
            ax.annotate(f"k={int(round(xs[i, 0]))}, α={xs[i, 1]:.0f}", front[i], fontsize=7,
                        xytext=(8, 8), textcoords="offset points",
                        bbox={"fc": "white", "ec": "0.7", "alpha": 0.85, "pad": 1.5},
                        arrowprops={"arrowstyle": "-", "color": "0.5", "lw": 0.6})
    ax.set(xlabel=objective_names[0], ylabel=objective_names[1], title=title)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def run_figures(score: Any, tuning: Any, where: Path, title: str) -> list[Path]:
    """Seed 001's figures of one gyro run: Figs. 12-14 and 17-19 per test record (those its
    method has parts for) and Fig. 11 when VMD was tuned (``tuning``: a runner ``VMDTuning``)."""
    paths = []
    for i, r in enumerate(score.recordings, start=1):
        head = f"{title}: test {i} ({r.name})"
        parts = r.parts
        if parts is not None and parts.modes is not None:
            freqs = _centre_frequencies_hz(parts.modes, 1.0 / float(np.median(np.diff(r.t_s))))
            paths.append(modes_figure(where / f"fig12_modes_test{i}.png", r.t_s, parts.modes, freqs,
                                      parts.classes.label, head))
            paths.append(entropy_classes_figure(where / f"fig13_entropy_test{i}.png", parts.classes, head))
            if np.any(parts.mixed_part):
                paths.append(mixed_tfpf_figure(where / f"fig14_mixed_test{i}.png", r.t_s, parts.mixed_part,
                                               parts.denoised_mixed, head))
        if parts is not None and np.any(parts.predicted_drift):
            paths.append(drift_prediction_figure(where / f"fig17_drift_test{i}.png", r.t_s, r.temp_c,
                                                 parts.drift_part, parts.predicted_drift, head))
        paths.append(final_output_figure(where / f"fig18_output_test{i}.png", r.t_s, r.raw_dps, r.after_dps,
                                         head, true_rate=r.true_rate_dps))
        bw = r.after.get("bandwidth_hz")
        paths.append(allan_methods_figure(where / f"fig19_allan_test{i}.png",
                                          {"raw": r.allan_before, "this method": r.allan_after}, head,
                                          annotations={"this method": f"bandwidth {bw:.3g} Hz"} if bw else None))
    if tuning is not None:
        paths.append(pareto_figure(where / "fig11_pareto.png", tuning.front_f, tuning.evaluated_f, tuning.chosen_f,
                                   title=f"{title}: VMD tuning", front_x=tuning.front_x))
    return paths


def _centre_frequencies_hz(modes: np.ndarray, fs_hz: float) -> np.ndarray:
    """Power-weighted mean frequency of each mode (Hz), as VMD's eq. 5 defines a centre."""
    power = np.abs(np.fft.rfft(modes, axis=1)) ** 2
    freqs = np.fft.rfftfreq(modes.shape[1], 1.0 / fs_hz)
    total = power.sum(axis=1)
    return np.where(total > 0, power @ freqs / np.where(total > 0, total, 1.0), 0.0)
