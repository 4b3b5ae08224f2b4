"""Matplotlib (Agg) figures saved as PNG: a run's convergence and a leaderboard's."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def _offset(values: np.ndarray, f_opt: float) -> np.ndarray:
    """Distance to the optimum value, floored so a log axis can show it."""
    return np.maximum(values - f_opt, 1e-16)


def run_convergence(
    path: Path,
    evaluations: Sequence[int],
    best_f: Sequence[float],
    mean_f: Sequence[float],
    f_opt: float,
    title: str,
    labels: tuple[str, str] | None = None,
) -> Path:
    """Best-so-far and population-mean fitness against evaluations for one run (or two other
    curves named by ``labels``, e.g. hypervolume gap and IGD)."""
    first, second = labels or ("best so far", "population mean")
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(evaluations, best_f, label=first)
    ax.plot(evaluations, mean_f, label=second, alpha=0.8)
    if labels:
        ax.set_yscale("log")
    else:
        ax.axhline(f_opt, color="k", lw=0.8, ls=":", label=f"optimum ({f_opt:g})")
    ax.set(xlabel="evaluations", ylabel="objective", title=title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def band_convergence(
    path: Path,
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]],
    f_opt: float,
    title: str,
    ylabel: str = "best so far - optimum",
    log: bool = True,
) -> Path:
    """Median with inter-quartile band over seeds, one line per method.

    ``curves[method] = (x, Y)`` with ``Y`` of shape (seeds, len(x)) on the common grid ``x``.
    """
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for method, (x, y) in curves.items():
        seen = ~np.all(np.isnan(y), axis=0)  # grid points before any run's first record
        x, y = x[seen], y[:, seen]
        yy = _offset(y, f_opt) if log else y
        q25, q50, q75 = np.nanpercentile(yy, [25, 50, 75], axis=0)
        (line,) = ax.plot(x, q50, label=f"{method} (median, n={len(y)})")
        ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.2, lw=0)
    if log:
        ax.set_yscale("log")
    else:
        ax.axhline(f_opt, color="k", lw=0.8, ls=":", label=f"optimum ({f_opt:g})")
    ax.set(xlabel="evaluations", ylabel=ylabel, title=title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _block_means(t_s: np.ndarray, y: np.ndarray, block_s: float,
                 segment: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    per = max(1, int(round(block_s / float(np.median(np.diff(t_s)))))) if t_s.size > 1 else 1
    if segment is not None and segment[-1] > 0:  # blocks stay inside segments (a burst shorter: one block)
        starts = np.flatnonzero(np.diff(segment, prepend=-1))
        within = np.arange(y.size) - starts[segment - segment[0]]
        block = np.cumsum(np.diff(segment * (y.size + 1) + within // per, prepend=-1) != 0) - 1
        n = np.bincount(block)
        return np.bincount(block, t_s) / n, np.bincount(block, y) / n
    m = y.size // per
    if m == 0:
        return t_s, y
    return t_s[: m * per].reshape(m, per).mean(axis=1), y[: m * per].reshape(m, per).mean(axis=1)


def _broken_at_gaps(t_s: np.ndarray, y: np.ndarray, segment: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """``t_s`` and ``y`` with a NaN between segments, so a line plot does not bridge the gaps."""
    if segment is None or t_s.size < 2:
        return t_s, y
    gaps = np.flatnonzero(np.diff(segment)) + 1
    return np.insert(t_s.astype(float), gaps, np.nan), np.insert(y.astype(float), gaps, np.nan)


def recording_overview(
    path: Path,
    t_s: np.ndarray,
    temperature_c: np.ndarray,
    output: np.ndarray,
    output_label: str,
    title: str,
    max_points: int = 20000,
    segment: np.ndarray | None = None,
) -> Path:
    """Temperature and output against time, and output against temperature with heating,
    cooling and steady spans in different colours, so that loops between them show. The output
    is drawn raw (light) and as means over ``duration / 1000`` (at least 10 s, dark). With
    ``segment`` (segment number per sample, bursts with gaps between them) no mean and no raw
    output line reaches across a gap (the slow thermometer and the means are joined)."""
    duration_s = float(t_s[-1] - t_s[0]) if t_s.size > 1 else 1.0
    tm, ym = _block_means(t_s, output, max(10.0, duration_s / 1000.0), segment)
    _, temp_m = _block_means(t_s, temperature_c, max(10.0, duration_s / 1000.0), segment)
    # rate of the thermometer over +-30 s, robust to its noise and resolution
    rate_c_per_min = np.interp(tm + 30.0, t_s, temperature_c) - np.interp(tm - 30.0, t_s, temperature_c)
    heating, cooling = rate_c_per_min > 0.05, rate_c_per_min < -0.05
    still = ~(heating | cooling)
    step = max(1, t_s.size // max_points)
    fig = plt.figure(figsize=(11, 6.5))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.6, 1])
    ax_t = fig.add_subplot(grid[0, 0])
    ax_y = fig.add_subplot(grid[1, 0], sharex=ax_t)
    ax_xy = fig.add_subplot(grid[:, 1])
    seg = None if segment is None or segment[-1] == 0 else segment[::step]
    t_raw, y_raw = _broken_at_gaps(t_s[::step], output[::step], seg)
    ax_t.plot(t_s[::step] / 3600.0, temperature_c[::step], color="tab:red", lw=0.8)
    ax_t.set(ylabel="thermometer (°C)", title=title)
    ax_y.plot(t_raw / 3600.0, y_raw, color="tab:blue", lw=0.4, alpha=0.35, label="raw")
    ax_y.plot(tm / 3600.0, ym, color="navy", lw=0.9, label="block means")
    ax_y.set(xlabel="time (h)", ylabel=output_label)
    ax_y.legend(fontsize=8, loc="best")
    ax_xy.scatter(temp_m[still], ym[still], s=2, color="0.6", label="steady (< 0.05 °C/min)")
    ax_xy.scatter(temp_m[heating], ym[heating], s=2, color="tab:red", label="heating")
    ax_xy.scatter(temp_m[cooling], ym[cooling], s=2, color="tab:blue", label="cooling")
    ax_xy.set(xlabel="thermometer (°C)", ylabel=f"{output_label}, block means",
              title="output against temperature")
    ax_xy.legend(markerscale=4, fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def allan_plot(
    path: Path,
    tau_s: np.ndarray,
    adev: np.ndarray,
    lines: Mapping[str, tuple[float, float, float]],
    unit: str,
    title: str,
) -> Path:
    """Log-log Allan deviation with fitted noise lines ``label: (value at tau_ref, slope, tau_ref)``."""
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.loglog(tau_s, adev, "o-", ms=3, label="Allan deviation")
    for label, (value, slope, tau_ref) in lines.items():
        if np.isfinite(value):
            ax.loglog(tau_s, value * (tau_s / tau_ref) ** slope, "--", lw=1, label=label)
    ax.set_ylim(adev.min() / 3, adev.max() * 3)
    ax.set(xlabel="τ (s)", ylabel=f"σ(τ) ({unit})", title=title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def rate_temperature_plot(
    path: Path,
    temperature_c: np.ndarray,
    output: np.ndarray,
    points: tuple[np.ndarray, np.ndarray],
    fit: tuple[float, float],
    point_label: str,
    output_label: str,
    title: str,
    max_points: int = 20000,
) -> Path:
    """Output against temperature: every sample as a faint cloud, the ``points`` (temperature,
    mean output) as markers and the line ``fit = (slope, intercept)`` through them. The output
    axis shows the central 99 % of the samples and every point (a few spikes would flatten it)."""
    step = max(1, temperature_c.size // max_points)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.scatter(temperature_c[::step], output[::step], s=1, color="tab:blue", alpha=0.12, lw=0, label="samples")
    ax.plot(points[0], points[1], "o", ms=4, color="navy", label=point_label)
    t_line = np.array([temperature_c.min(), temperature_c.max()])
    ax.plot(t_line, fit[0] * t_line + fit[1], "-", color="tab:red", lw=1.2, label="least-squares line")
    low, high = np.percentile(output, [0.5, 99.5])
    pad = 0.15 * max(high - low, float(np.ptp(points[1])), 1e-12)
    ax.set_ylim(min(low, points[1].min()) - pad, max(high, points[1].max()) + pad)
    ax.set(xlabel="thermometer (°C)", ylabel=output_label, title=title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, markerscale=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path

def front_plot(
    path: Path, fronts: Mapping[str, np.ndarray], true_front: np.ndarray, title: str
) -> Path:
    """Obtained fronts against the true Pareto front (2 objectives: plane; 3: 3-D scatter)."""
    m = true_front.shape[1]
    fig = plt.figure(figsize=(6.5, 5))
    ax = fig.add_subplot(projection="3d" if m == 3 else None)
    if m == 3:
        ax.scatter(*true_front.T, s=2, color="0.7", label="true front")
        for method, f in fronts.items():
            ax.scatter(*f.T, s=8, label=f"{method} ({len(f)} points)")
        ax.set(xlabel="f1", ylabel="f2", zlabel="f3")
    else:
        order = np.argsort(true_front[:, 0])
        ax.plot(*true_front[order].T, ".", ms=2, color="0.6", label="true front")
        for method, f in fronts.items():
            ax.plot(f[:, 0], f[:, 1], "o", ms=3, label=f"{method} ({len(f)} points)")
        ax.set(xlabel="f1", ylabel="f2")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def line_styles(n: int) -> list[dict[str, str]]:
    """``n`` distinct line styles: the ten default colours solid, then dashed, then dotted, then
    dash-dotted (40 before any repeats)."""
    dashes = ("-", "--", ":", "-.")
    return [{"color": f"C{k % 10}", "ls": dashes[k // 10 % len(dashes)]} for k in range(n)]


def ecdf_plot(path: Path, evaluations: np.ndarray, curves: Mapping[str, np.ndarray], title: str) -> Path:
    """COCO-style runtime ECDF: fraction of (function, target) pairs solved against evaluations."""
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ranked = sorted(curves.items(), key=lambda kv: -kv[1][-1])
    for (method, frac), style in zip(ranked, line_styles(len(ranked)), strict=True):
        ax.step(evaluations, frac, where="post", **style, label=f"{method} ({frac[-1]:.0%})")
    ax.set_xscale("log")
    ax.set_ylim(0, 1)
    ax.set(xlabel="evaluations", ylabel="fraction of (function, target) pairs", title=title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
