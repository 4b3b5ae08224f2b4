"""Accelerometer metrics of seed 000: zero-bias stability (Table 1) and the four-position scale
factor and bias over temperature (Table 2, eq. 12).

Conventions, stated once here and in every report that uses them:

- zero-bias stability: 1 sigma (sample std, ddof=1) of non-overlapping ``window_s`` averages
  (default 10 s: the "(1 sigma, 10 s)" convention) of ``output / scale factor``, in micro-g,
  over the data from ``start_s`` on. Table 1's three rows start 30 min and 20 min after
  power-on and at power-on ("zero start").
- scale factor at a node: ``K1 = (U(+1g) - U(-1g)) / 2`` in Hz/g; bias:
  ``B0 = (U(+0g) + U(-0g)) / (U(+1g) - U(-1g)) * g``. Seed 000 prints eq. 12 with a minus
  between the 0 g outputs, which cancels the bias and measures misalignment instead; the plus
  form is the default and ``bias_form="printed"`` gives the printed one.
- variation over temperature: scale factor ``std(K1)/mean(K1)`` in ppm, bias ``std(B0)`` in
  micro-g, both with the sample std (ddof=1) over the nodes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from tcbench.sensors.segments import bounds, segments, within_rate_hz

POSITION_ORDER = ("+0g", "+1g", "-0g", "-1g")


def zero_bias_stability_ug(
    t_s: np.ndarray,
    output: np.ndarray,
    scale_factor_per_g: float,
    start_s: float = 0.0,
    window_s: float = 10.0,
) -> float:
    """1 sigma of non-overlapping ``window_s`` means of ``output / scale factor`` from
    ``start_s`` on, in micro-g (``window_s`` <= one sample gives the raw-sample 1 sigma).

    A clock with gaps (a logger's bursts, :func:`tcbench.sensors.segments.segments`) has its
    windows taken inside each segment, so none spans a gap; a segment's last partial window is
    left out, as is a continuous record's."""
    keep = t_s >= t_s[0] + start_s
    t, y = t_s[keep], output[keep] / scale_factor_per_g
    if t.size < 2:
        raise ValueError(f"no data after {start_s} s to compute zero-bias stability")
    per = max(1, int(round(window_s * within_rate_hz(t))))
    starts, stops = bounds(segments(t))
    lengths = stops - starts
    position = np.arange(y.size) - np.repeat(starts, lengths)  # index inside its segment
    y = y[position < np.repeat(lengths // per * per, lengths)]  # complete windows only
    m = y.size // per
    if m < 2:
        raise ValueError(f"fewer than two {window_s} s windows after {start_s} s")
    means = y.reshape(m, per).mean(axis=1)
    return float(np.std(means, ddof=1) * 1e6)


ZERO_BIAS_STARTS_S = {"after_30min_ug": 1800.0, "after_20min_ug": 1200.0, "zero_start_ug": 0.0}


def zero_bias_table(
    t_s: np.ndarray, output: np.ndarray, scale_factor_per_g: float, window_s: float = 10.0
) -> dict[str, float]:
    """Seed 000 Table 1 rows: stability after 30 min, after 20 min, and from zero start (micro-g)."""
    return {row: zero_bias_stability_ug(t_s, output, scale_factor_per_g, start_s, window_s)
            for row, start_s in ZERO_BIAS_STARTS_S.items()}


def position_blocks(position: np.ndarray) -> pd.DataFrame:
    """Runs of identical non-empty position labels: ``label, start, stop`` (row indices)."""
    labels = np.asarray(position, dtype=str)
    change = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
    stops = np.r_[change[1:], labels.size]
    runs = pd.DataFrame({"label": labels[change], "start": change, "stop": stops})
    return runs[runs["label"] != ""].reset_index(drop=True)


def four_position(
    temperature_c: np.ndarray,
    output: np.ndarray,
    position: np.ndarray,
    bias_form: str = "plus",
) -> pd.DataFrame:
    """Scale factor (Hz/g) and bias (g) at each temperature node of a four-position test.

    A node is one complete sequence ``+0g, +1g, -0g, -1g`` of labelled blocks; each block's
    output is its mean. Incomplete sequences raise ``ValueError`` naming where they are.
    """
    if bias_form not in {"plus", "printed"}:
        raise ValueError(f"bias_form must be 'plus' or 'printed', got {bias_form!r}")
    blocks = position_blocks(position)
    if len(blocks) == 0 or len(blocks) % 4:
        raise ValueError(f"{len(blocks)} labelled position blocks; expected groups of four")
    labels = blocks["label"].to_numpy().reshape(-1, 4)
    bad = np.flatnonzero((labels != np.array(POSITION_ORDER)).any(axis=1))
    if bad.size:
        raise ValueError(f"node {bad[0] + 1}: positions {list(labels[bad[0]])}, expected {list(POSITION_ORDER)}")
    csum = np.r_[0.0, np.cumsum(output)]
    tsum = np.r_[0.0, np.cumsum(temperature_c)]
    start, stop = blocks["start"].to_numpy(), blocks["stop"].to_numpy()
    u = ((csum[stop] - csum[start]) / (stop - start)).reshape(-1, 4)
    temp = ((tsum[stop] - tsum[start]) / (stop - start)).reshape(-1, 4).mean(axis=1)
    span = u[:, 1] - u[:, 3]
    zero = u[:, 0] + u[:, 2] if bias_form == "plus" else u[:, 0] - u[:, 2]
    return pd.DataFrame({
        "temperature_c": temp,
        "u_p0": u[:, 0], "u_p1": u[:, 1], "u_m0": u[:, 2], "u_m1": u[:, 3],
        "scale_factor_hz_per_g": span / 2.0,
        "bias_g": zero / span,
    })


@dataclass(frozen=True)
class TemperatureVariation:
    """Variation of scale factor (ppm) and bias (micro-g) over the temperature nodes."""

    scale_factor_ppm: float
    bias_ug: float
    nodes: int


def temperature_variation(nodes: pd.DataFrame) -> TemperatureVariation:
    """Seed 000 Table 2: ``std/mean`` of the scale factor in ppm and ``std`` of the bias in
    micro-g over the nodes (sample std, ddof=1)."""
    if len(nodes) < 2:
        raise ValueError("need at least two temperature nodes")
    k = nodes["scale_factor_hz_per_g"].to_numpy()
    b = nodes["bias_g"].to_numpy()
    return TemperatureVariation(
        scale_factor_ppm=float(np.std(k, ddof=1) / abs(np.mean(k)) * 1e6),
        bias_ug=float(np.std(b, ddof=1) * 1e6),
        nodes=len(nodes),
    )
