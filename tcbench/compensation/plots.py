"""Figures of MSRA compensation (seed 000 Figs. 7-10) and of training, as PNG (matplotlib Agg).

Every function writes one PNG to ``path`` and returns ``path``. Node tables are the DataFrames of
:func:`tcbench.metrics.accelerometer.four_position` (columns ``temperature_c``, ``u_p0``,
``u_p1``, ``u_m0``, ``u_m1``, ``scale_factor_hz_per_g``, ...): before compensation in Hz, after
it in g.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

POSITION_COLUMNS = {"+0g": "u_p0", "+1g": "u_p1", "-0g": "u_m0", "-1g": "u_m1"}
BEFORE_COLOUR, AFTER_COLOUR = "tab:red", "tab:blue"


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def zero_bias_before_after(
    path: Path, t_s: np.ndarray, before_ug: np.ndarray, after_ug: np.ndarray, title: str
) -> Path:
    """Seed 000 Fig. 7: zero-bias output before and after compensation against time (min), each
    with its mean removed, in micro-g, on two stacked axes; the legends give each trace's 1 sigma
    (sample std of the samples shown)."""
    t_min = np.asarray(t_s, dtype=np.float64) / 60.0
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 5.5), sharex=True)
    for ax, values, label, colour in (
        (axes[0], before_ug, "before", BEFORE_COLOUR), (axes[1], after_ug, "after", AFTER_COLOUR)
    ):
        y = np.asarray(values, dtype=np.float64)
        y = y - y.mean()
        sigma_ug = float(np.std(y, ddof=1))
        ax.plot(t_min, y, color=colour, lw=0.6, label=f"{label} compensation, 1σ of samples = {sigma_ug:.3g} µg")
        ax.set_ylabel("zero bias − mean (µg)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_title(title)
    axes[1].set_xlabel("time (min)")
    return _save(fig, path)


def four_position_before_after(
    path: Path, nodes_before: pd.DataFrame, nodes_after: pd.DataFrame, title: str
) -> Path:
    """Seed 000 Fig. 8: the outputs of the four positions at each temperature node, before (Hz)
    and after (g) compensation, in two panels."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for ax, nodes, unit, when in ((axes[0], nodes_before, "Hz", "before"), (axes[1], nodes_after, "g", "after")):
        for label, column in POSITION_COLUMNS.items():
            ax.plot(nodes["temperature_c"], nodes[column], "o-", ms=4, label=label)
        ax.set(xlabel="temperature (°C)", ylabel=f"output ({unit})", title=f"{when} compensation")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, title="position", title_fontsize=8)
    fig.suptitle(title)
    return _save(fig, path)


def positions_vs_temperature(
    path: Path, nodes_before: pd.DataFrame, nodes_after: pd.DataFrame, title: str
) -> Path:
    """Seed 000 Figs. 9-10: per position (2 x 2 panels), the output's deviation from its mean
    over the nodes against temperature. Before: Hz divided by the mean scale factor of
    ``nodes_before``, in micro-g equivalent (left axis); after: g in micro-g (right axis,
    its own scale, so the residual stays visible). Legends give each trace's peak-to-peak."""
    sf_hz_per_g = float(np.mean(nodes_before["scale_factor_hz_per_g"]))
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    for ax, (label, column) in zip(axes.ravel(), POSITION_COLUMNS.items(), strict=True):
        before = np.asarray(nodes_before[column], dtype=np.float64)
        after = np.asarray(nodes_after[column], dtype=np.float64)
        before_ug = (before - before.mean()) / sf_hz_per_g * 1e6
        after_ug = (after - after.mean()) * 1e6
        twin = ax.twinx()
        lines = ax.plot(nodes_before["temperature_c"], before_ug, "o-", ms=4, color=BEFORE_COLOUR,
                        label=f"before (p-p {np.ptp(before_ug):.3g} µg)")
        lines += twin.plot(nodes_after["temperature_c"], after_ug, "s-", ms=4, color=AFTER_COLOUR,
                           label=f"after (p-p {np.ptp(after_ug):.3g} µg)")
        ax.set(xlabel="temperature (°C)", title=f"position {label}")
        ax.set_ylabel("before − mean (µg equiv.)", color=BEFORE_COLOUR)
        twin.set_ylabel("after − mean (µg)", color=AFTER_COLOUR)
        ax.tick_params(axis="y", colors=BEFORE_COLOUR)
        twin.tick_params(axis="y", colors=AFTER_COLOUR)
        ax.grid(True, alpha=0.3)
        ax.legend(lines, [line.get_label() for line in lines], fontsize=8)
    fig.suptitle(f"{title} (scale factor {sf_hz_per_g:.4g} Hz/g)")
    return _save(fig, path)


def training_curve(path: Path, history_loss: Sequence[float], title: str) -> Path:
    """Training error (eq. 3, normalised units) against epoch, log y axis."""
    loss = np.asarray(history_loss, dtype=np.float64)
    epochs = np.arange(1, loss.size + 1)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(epochs, np.maximum(loss, 1e-300), "o-" if loss.size < 20 else "-", ms=3)
    ax.set_yscale("log")
    ax.set(xlabel="epoch", ylabel="training error (eq. 3, normalised)", title=title)
    ax.grid(True, which="both", alpha=0.3)
    return _save(fig, path)
