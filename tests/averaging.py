"""A recording averaged by hand, the reference the native-rate diagnosis is compared with."""

from __future__ import annotations

import numpy as np

from tcbench.sensors.recording import Recording, make_recording


def by_hand(rec: Recording, k: int) -> Recording:
    """``rec`` as means of ``k`` consecutive samples (a partial last bin dropped), its sensor and
    device kept, its rate divided by ``k``."""
    n = rec.time_s.size // k * k

    def mean(x: np.ndarray) -> np.ndarray:
        return x[:n].reshape(-1, k).mean(axis=1)

    return make_recording(mean(rec.time_s), mean(rec.temperature_c), mean(rec.input), mean(rec.output),
                          sensor=rec.meta.sensor, sample_rate_hz=rec.meta.sample_rate_hz / k,
                          device_id=rec.meta.device_id)
