"""Temperature branches: the real chamber cycles split where their temperature turns, and
nowhere else (soak noise, quantisation, a small overshoot)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import PAN_CSV

from tcbench.datasets.real import tofupilot_gyro
from tcbench.signal.branches import temperature_branches


def test_the_tofupilot_cycle_is_cool_heat_cool() -> None:
    """PROVENANCE.md: 52 degC cooled to -17.6 (about 22 min), heated to 74 (about 52 min), cooled to ~35."""
    rec = tofupilot_gyro("y")
    branches = temperature_branches(rec.time_s, rec.temperature_c)
    assert [b.direction for b in branches] == ["cooling", "heating", "cooling"]
    assert branches[0].start == 0 and branches[-1].stop == len(rec.data)
    assert all(a.stop == b.start for a, b in zip(branches, branches[1:]))
    turns_min = [rec.time_s[b.start] / 60 for b in branches[1:]]
    assert turns_min == pytest.approx([22.6, 52.1], abs=1.0)
    assert branches[0].to_c == pytest.approx(rec.temperature_c.min(), abs=0.5)
    assert branches[1].to_c == pytest.approx(rec.temperature_c.max(), abs=0.5)


def test_the_pan_cooling_is_one_branch() -> None:
    table = pd.read_csv(PAN_CSV)
    (branch,) = temperature_branches(table["time_s"].to_numpy(), table["temp_c"].to_numpy())
    assert branch.direction == "cooling" and branch.span_c > 5 and (branch.start, branch.stop) == (0, len(table))


def test_soaks_noise_and_overshoot_do_not_split_a_branch() -> None:
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 6 * 3600.0, 1.0)
    # -20 -> 60 -> -20 -> 60 degC ramps of 80 min with 40-min soaks, a 2 degC overshoot, noise, 1/16 degC steps
    knots_t = np.array([0, 40, 120, 160, 240, 280, 360]) * 60.0
    knots_c = np.array([-20, -20, 60, 60, -20, -20, 60], dtype=float)
    temp = np.interp(t, knots_t, knots_c) + 2.0 * np.exp(-np.clip(t - 120 * 60, 0, None) / 300) * (t > 120 * 60)
    temp = np.round((temp + rng.normal(0, 0.1, t.size)) * 16) / 16
    branches = temperature_branches(t, temp)
    assert [b.direction for b in branches] == ["heating", "cooling", "heating"]
    assert [round(t[b.start] / 60) for b in branches[1:]] == pytest.approx([122, 240], abs=6)


@pytest.mark.parametrize(("t", "temp", "words"), [
    ([0.0, 1.0], [20.0], "matching"),
    ([0.0, 0.0, 1.0], [20.0, 21.0, 22.0], "strictly"),
    ([0.0, 1.0, 2.0], [20.0, np.nan, 22.0], "finite"),
])
def test_bad_input_is_one_line(t: list[float], temp: list[float], words: str) -> None:
    with pytest.raises(ValueError, match=words):
        temperature_branches(np.array(t), np.array(temp))
