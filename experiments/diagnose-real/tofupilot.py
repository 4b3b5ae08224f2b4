"""Diagnose every gyro axis of the real tofupilot chamber cycle and compare with the reference.

``data/real/tofupilot_imu_chamber/imu_raw_data.csv`` (PROVENANCE.md there): a static
IMU cooled to -17.6 degC, heated to 74 degC and cooled to 35 degC in 70.7 min at about 2 Hz.
Each axis is converted by :func:`tcbench.datasets.real.tofupilot_gyro` (tab-separated,
us to s, rad/s to deg/s, first sample dropped), diagnosed, and its report written to
``--out/tofupilot/{x,y,z}/``; the per-axis rows of ``run.py``'s summary are printed. ``run.py``
runs this record and PAN LSM6DSM in one command.

    python experiments/diagnose-real/tofupilot.py [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from run import HEADER, diagnose_record


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("leaderboards/diagnose-real"))
    args = ap.parse_args()
    print("\n".join(HEADER + diagnose_record("tofupilot", args.out)))


if __name__ == "__main__":
    main()
