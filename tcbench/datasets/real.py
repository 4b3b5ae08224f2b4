"""Real recordings used to prove the diagnosis, read into schema-v1 :class:`Recording` objects.

``tcbench import`` reads comma-separated tables only; the tofupilot chamber cycle is
tab-separated, so it is converted here (see its ``PROVENANCE.md``): ``timestamp`` in µs to s,
``imu.gyro.*`` in rad/s to deg/s, ``imu.temperature`` in degC; the first sample (a start-up
glitch) is dropped; the IMU sat still, so the input is 0 deg/s. The recordings are the
repository's ``data/real/`` (:mod:`tcbench.data_paths`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.data_paths import REAL_DATA, real_file
from tcbench.sensors.recording import Recording, make_recording

TOFUPILOT_CSV = REAL_DATA / "tofupilot_imu_chamber" / "imu_raw_data.csv"


def tofupilot_gyro(axis: str, csv: str | Path | None = None) -> Recording:
    """One gyro ``axis`` (``x``, ``y`` or ``z``) of the tofupilot chamber cycle (``csv``, by
    default the repository's :data:`TOFUPILOT_CSV`) as a gyro recording: time in s from the first
    kept sample, temperature in degC, rate in deg/s."""
    if axis not in ("x", "y", "z"):
        raise ValueError(f"axis must be x, y or z, got {axis!r}")
    raw = pd.read_csv(real_file(TOFUPILOT_CSV) if csv is None else csv, sep="\t")
    raw = raw.iloc[1:]  # the first sample is a start-up glitch
    t = raw["timestamp"].to_numpy(np.float64) * 1e-6
    t = t - t[0]
    rate = np.degrees(raw[f"imu.gyro.{axis}"].to_numpy(np.float64))
    return make_recording(
        t, raw["imu.temperature"].to_numpy(np.float64), np.zeros(t.size), rate,
        sensor="gyro", sample_rate_hz=float(1.0 / np.median(np.diff(t))), device_id="tofupilot-imu",
        extra={"source": "tofupilot/examples templates/imu_thermal_calibration/data/imu_raw_data.csv",
               "axis": axis, "first_sample_dropped": True},
    )
