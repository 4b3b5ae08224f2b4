"""Real recordings used to prove the diagnosis, read into schema-v1 :class:`Recording` objects.

``tcbench import`` reads comma-separated tables only; the tofupilot chamber cycle is
tab-separated, so it is converted here (see its ``PROVENANCE.md``): ``timestamp`` in µs to s,
``imu.gyro.*`` in rad/s to deg/s, ``imu.temperature`` in degC; the first sample (a start-up
glitch) is dropped; the IMU sat still, so the input is 0 deg/s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.sensors.recording import Recording, make_recording

SHARED_REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
TOFUPILOT_CSV = SHARED_REAL / "tofupilot_imu_chamber" / "imu_raw_data.csv"


def tofupilot_gyro(axis: str, csv: str | Path = TOFUPILOT_CSV) -> Recording:
    """One gyro ``axis`` (``x``, ``y`` or ``z``) of the tofupilot chamber cycle as a gyro
    recording: time in s from the first kept sample, temperature in degC, rate in deg/s."""
    if axis not in ("x", "y", "z"):
        raise ValueError(f"axis must be x, y or z, got {axis!r}")
    raw = pd.read_csv(csv, sep="\t").iloc[1:]  # the first sample is a start-up glitch
    t = raw["timestamp"].to_numpy(np.float64) * 1e-6
    t = t - t[0]
    rate = np.degrees(raw[f"imu.gyro.{axis}"].to_numpy(np.float64))
    return make_recording(
        t, raw["imu.temperature"].to_numpy(np.float64), np.zeros(t.size), rate,
        sensor="gyro", sample_rate_hz=float(1.0 / np.median(np.diff(t))), device_id="tofupilot-imu",
        extra={"source": "tofupilot/examples templates/imu_thermal_calibration/data/imu_raw_data.csv",
               "axis": axis, "first_sample_dropped": True},
    )
