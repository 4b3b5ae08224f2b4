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
