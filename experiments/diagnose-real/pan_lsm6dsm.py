"""Diagnose the real PAN LSM6DSM cooling run (``data/real/pan_lsm6dsm_tvac_cooling``).

Conversion to schema v1, one recording per gyro axis (documented in README.md):
``time_s`` and ``temp_c`` as in the provenance file (temperature from the datasheet transfer
function, 25 degC + raw / 256); ``input`` 0 deg/s (the unit sat still; Earth rate, 0.004 deg/s,
is far below the noise); ``output`` the axis rate in deg/s after the provenance's x0.5
correction; the 3 samples flagged as spikes are dropped. The data are 25 bursts of 5 s at
about 50 Hz, 305 s apart: the recording keeps the bursts with their gaps, and the diagnosis
treats each burst as a segment.

    python experiments/diagnose-real/pan_lsm6dsm.py [--data DIR] [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.data_paths import REAL_DATA
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.report.write import write_report
from tcbench.sensors.recording import Recording, make_recording, write_recording

DATA = REAL_DATA / "pan_lsm6dsm_tvac_cooling"


def convert(csv: Path, axis: str) -> Recording:
    """One axis of the PAN cooling run as a schema-v1 gyro recording."""
    raw = pd.read_csv(csv)
    raw = raw[raw.spike_flag == 0]
    t = raw.time_s.to_numpy(float)
    fs = 1.0 / float(np.median(np.diff(t)))
    return make_recording(
        t, raw.temp_c.to_numpy(float), np.zeros(t.size), raw[f"gyro_{axis}_dps"].to_numpy(float),
        sensor="gyro", sample_rate_hz=fs, device_id="pan-etu-lsm6dsm",
        extra={"source": "PAN ETU cold TVC test 2020-03-07, psim@91d70ad TVCtest3_7_20.csv",
               "axis": axis, "bursts": int(raw.burst_id.nunique()), "spikes_dropped": 3},
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--out", type=Path, default=Path("leaderboards/diagnose-real/pan_lsm6dsm"))
    ap.add_argument("--recordings", type=Path, default=Path("recordings/pan_lsm6dsm"),
                    help="where the converted schema-v1 recordings go (generated data, not committed)")
    args = ap.parse_args()
    csv = args.data / "pan_lsm6dsm_tvac_cooling.csv"
    if not csv.exists():
        raise SystemExit(f"pan_lsm6dsm.py: {csv} not found; give --data DIR")
    for axis in ("x", "y", "z"):
        rec = convert(csv, axis)
        args.recordings.mkdir(parents=True, exist_ok=True)
        write_recording(rec, args.recordings / f"pan_lsm6dsm_{axis}.csv")
        d = diagnose(rec, name=f"PAN LSM6DSM gyro {axis} (cooling, 25 bursts)")
        write_report(d, args.out / axis)
        print(f"{axis}: {d.verdict}")
        print(f"   baseline RMSE held-out {d.baseline.rmse_heldout:.4g}, final {d.final.rmse_heldout:.4g}, "
              f"white {d.noise.white_sigma:.4g} deg/s")
        for c in d.candidates:
            print(f"   {c.effect:20s} {c.status:16s} gain {c.gain:9.1f}  wald {c.wald:8.1f}  {c.reason}")


if __name__ == "__main__":
    main()
