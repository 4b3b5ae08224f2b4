"""Where a residual departs from white noise (tcbench.diagnose.select.locate)."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.diagnose.select.locate import locate

N = 20000


def _profile() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(N, dtype=float)
    temp = np.interp(t, [0, 1800, 7800, 9600, 15600, N], [20, 20, 60, 60, 20, 20])
    return t, temp


def test_white_noise_rarely_flagged() -> None:
    t, temp = _profile()
    hits = sum(bool(locate(t, temp, np.random.default_rng(s).standard_normal(N), None)) for s in range(10))
    assert hits <= 1


def test_step_span_found() -> None:
    t, temp = _profile()
    r = np.random.default_rng(1).standard_normal(N)
    r[5400:7200] += 3.0 / np.sqrt(180)
    spans = [m for m in locate(t, temp, r, 1.0) if m.what.startswith("time span")]
    assert spans and abs(spans[0].t_start_s - 5400) <= 180 and abs(spans[0].t_end_s - 7200) <= 180


def test_rate_residual_flagged_and_random_walk() -> None:
    t, temp = _profile()
    rng = np.random.default_rng(2)
    r = rng.standard_normal(N) + 30 * np.gradient(temp)
    assert any(m.what == "heating vs cooling" for m in locate(t, temp, r, None))
    r2 = rng.standard_normal(N) + np.cumsum(0.02 * rng.standard_normal(N))
    assert any(m.what.startswith("low-frequency") for m in locate(t, temp, r2, None))


def test_deterministic_and_bad_input() -> None:
    t, temp = _profile()
    r = np.random.default_rng(3).standard_normal(N)
    assert [m.to_dict() for m in locate(t, temp, r, None)] == [m.to_dict() for m in locate(t, temp, r, None)]
    for args, word in [((t, temp, np.r_[np.nan, r[1:]]), "finite"), ((t, temp[:-1], r), "length"),
                       ((t[:50], temp[:50], r[:50]), "100")]:
        with pytest.raises(ValueError, match=word):
            locate(*args, None)


def test_known_coloured_noise_is_not_a_mismatch() -> None:
    t, temp = _profile()
    rng = np.random.default_rng(3)
    kernel = np.ones(120) / np.sqrt(120)  # slow noise, like a smoothed thermometer seen through a slope
    slow = np.convolve(rng.standard_normal(N + 119), kernel, mode="valid") * 0.6
    r = rng.standard_normal(N) + slow
    assert locate(t, temp, r, 1.0)  # a white-noise test takes it for a mismatch
    model = np.convolve(np.random.default_rng(4).standard_normal(N + 119), kernel, mode="valid") * 0.6
    assert not locate(t, temp, r, 1.0, coloured=model)


def test_bursts_get_no_allan_finding() -> None:
    t = np.concatenate([k * 300.0 + np.arange(0, 60.0, 0.5) for k in range(60)])
    temp = 25.0 - t / 3600.0
    rng = np.random.default_rng(5)
    r = rng.standard_normal(t.size) + np.repeat(rng.standard_normal(60) * 0.05, 120)
    assert not any(m.what.startswith("low-frequency") for m in locate(t, temp, r, 1.0))
