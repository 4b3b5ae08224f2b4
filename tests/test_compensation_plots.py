"""Each compensation figure writes a non-empty PNG from small synthetic inputs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tcbench.compensation import plots

pytestmark = pytest.mark.figures  # rendered: these tests look at the figures (tests/conftest.py)

PNG_MAGIC = b"\x89PNG"


def _nodes(unit_scale: float, offset: float) -> pd.DataFrame:
    temp_c = np.linspace(-40.0, 60.0, 6)
    drift = 1e-3 * (temp_c - 25.0)
    return pd.DataFrame({
        "temperature_c": temp_c,
        "u_p0": offset + drift, "u_p1": offset + unit_scale + drift,
        "u_m0": offset + 0.5 * drift, "u_m1": offset - unit_scale + drift,
        "scale_factor_hz_per_g": np.full(6, unit_scale),
        "bias_g": drift,
    })


def _is_png(path: Path) -> bool:
    return path.exists() and path.stat().st_size > 1000 and path.read_bytes()[:4] == PNG_MAGIC


def test_zero_bias_before_after(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    t_s = np.arange(600.0)
    out = plots.zero_bias_before_after(tmp_path / "fig7.png", t_s, 100.0 * np.exp(-t_s / 300.0)
                                       + rng.normal(0, 10, 600), rng.normal(0, 10, 600), "zero bias")
    assert _is_png(out)


def test_four_position_figures(tmp_path: Path) -> None:
    before, after = _nodes(200.0, 150.0), _nodes(1.0, 0.0)
    assert _is_png(plots.four_position_before_after(tmp_path / "fig8.png", before, after, "four positions"))
    assert _is_png(plots.positions_vs_temperature(tmp_path / "fig9.png", before, after, "positions"))


def test_training_curve(tmp_path: Path) -> None:
    assert _is_png(plots.training_curve(tmp_path / "loss.png", list(0.5 * 0.95 ** np.arange(200)), "loss"))
    assert _is_png(plots.training_curve(tmp_path / "closed.png", [1e-6], "closed form"))
