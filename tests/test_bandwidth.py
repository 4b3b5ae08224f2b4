"""Bandwidth kept by a pipeline (tcbench.metrics.bandwidth)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from tcbench.metrics.bandwidth import bandwidth_kept

FS = 10.0
T = np.arange(0.0, 3600.0, 1.0 / FS)
Y = np.random.default_rng(0).standard_normal(T.size) * 0.01


def test_identity_keeps_everything() -> None:
    bw = bandwidth_kept(lambda x: x, T, Y)
    assert np.isinf(bw.f3db_hz) and np.allclose(bw.gain, 1.0, atol=1e-9)


@pytest.mark.parametrize("multisine", [True, False])
def test_first_order_low_pass(multisine: bool) -> None:
    fc = 0.05  # Hz
    a = np.exp(-2 * np.pi * fc / FS)
    bw = bandwidth_kept(lambda x: lfilter([1 - a], [1, -a], x), T, Y, multisine=multisine)
    assert bw.f3db_hz == pytest.approx(fc, rel=0.1)


def test_moving_average_and_bad_input() -> None:
    n = 100  # 10 s moving average: -3 dB at 0.443 / 10 s
    bw = bandwidth_kept(lambda x: np.convolve(x, np.ones(n) / n, mode="same"), T, Y)
    assert bw.f3db_hz == pytest.approx(0.0443, rel=0.1)
    with pytest.raises(ValueError, match="shape"):
        bandwidth_kept(lambda x: x[:-1], T, Y)
    with pytest.raises(ValueError, match="amplitude"):
        bandwidth_kept(lambda x: x, T, Y, amplitude=0.0)
