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
) -> Path:
    """Best-so-far and population-mean fitness against evaluations for one run."""
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(evaluations, best_f, label="best so far")
    ax.plot(evaluations, mean_f, label="population mean", alpha=0.8)
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


def recording_overview(
    path: Path,
    t_s: np.ndarray,
    temperature_c: np.ndarray,
    output: np.ndarray,
    output_label: str,
    title: str,
    max_points: int = 20000,
) -> Path:
    """Temperature and output against time, and output against temperature with heating and
    cooling drawn in different colours so that loops between them show."""
    step = max(1, t_s.size // max_points)
    t_h, temp, out = t_s[::step] / 3600.0, temperature_c[::step], output[::step]
    rate_c_per_min = np.gradient(temp, t_h * 60.0) if temp.size > 1 else np.zeros_like(temp)
    heating, cooling = rate_c_per_min > 0.05, rate_c_per_min < -0.05
    fig = plt.figure(figsize=(11, 6.5))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.6, 1])
    ax_t = fig.add_subplot(grid[0, 0])
    ax_y = fig.add_subplot(grid[1, 0], sharex=ax_t)
    ax_xy = fig.add_subplot(grid[:, 1])
    ax_t.plot(t_h, temp, color="tab:red", lw=0.8)
    ax_t.set(ylabel="thermometer (°C)", title=title)
    ax_y.plot(t_h, out, color="tab:blue", lw=0.5)
    ax_y.set(xlabel="time (h)", ylabel=output_label)
    still = ~(heating | cooling)
    ax_xy.scatter(temp[still], out[still], s=1, color="0.6", label="steady (< 0.05 °C/min)")
    ax_xy.scatter(temp[heating], out[heating], s=1, color="tab:red", label="heating")
    ax_xy.scatter(temp[cooling], out[cooling], s=1, color="tab:blue", label="cooling")
    ax_xy.set(xlabel="thermometer (°C)", ylabel=output_label, title="output against temperature")
    ax_xy.legend(markerscale=6)
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
