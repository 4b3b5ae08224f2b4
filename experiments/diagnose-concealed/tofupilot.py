"""Diagnose every gyro axis of the real tofupilot chamber cycle and compare with the reference.

``../shared/data/real/tofupilot_imu_chamber/imu_raw_data.csv`` (PROVENANCE.md there): a static
IMU cooled to -17.6 degC, heated to 74 degC and cooled to 35 degC in 70.7 min at about 2 Hz.
Each axis is converted by :func:`tcbench.diagnose.real_records.tofupilot_gyro` (tab-separated,
us to s, rad/s to deg/s, first sample dropped), diagnosed, and its report written to
``--out/{x,y,z}/``; ``--out/summary.md`` holds the per-axis table: the starting model's, the final
model's and the physics-agnostic reference's held-out RMSE (in white sigma), final / reference,
and the effects named.

    python experiments/diagnose-concealed/tofupilot.py [--out DIR]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from tcbench.diagnose.diagnosis import REFERENCE_RATIO, diagnose
from tcbench.diagnose.real_records import TOFUPILOT_CSV, tofupilot_gyro
from tcbench.diagnose.report import write_report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", type=Path, default=TOFUPILOT_CSV)
    ap.add_argument("--out", type=Path, default=Path("leaderboards/diagnose-real/tofupilot"))
    args = ap.parse_args()
    if not args.csv.exists():
        raise SystemExit(f"tofupilot.py: {args.csv} not found; give --csv FILE")
    rows = ["| axis | baseline held-out | final held-out | reference held-out | final / reference | test | effects named | s |",
            "|---|---|---|---|---|---|---|---|"]
    for axis in ("x", "y", "z"):
        t0 = time.perf_counter()
        d = diagnose(tofupilot_gyro(axis, args.csv), name=f"tofupilot chamber cycle gyro {axis}")
        seconds = time.perf_counter() - t0
        write_report(d, args.out / axis)
        s = d.noise["white_sigma"]
        ratio = d.reference["final_over_reference"]
        rows.append(f"| {axis} | {d.baseline['rmse_heldout'] / s:.2f} sigma | {d.final['rmse_heldout'] / s:.2f} sigma | "
                    f"{d.reference['rmse_heldout'] / s:.2f} sigma | {ratio:.2f} | {d.statistics['significance_test']} | "
                    f"{', '.join(d.effect_ids) or '-'} | {seconds:.1f} |")
        print(f"{axis}: {d.verdict}", flush=True)
    head = [f"# tofupilot chamber cycle, gyro x/y/z: final model against the reference (target <= {REFERENCE_RATIO:g})",
            "", "White sigma per axis from first differences; blocks and test as in each report.json `statistics`.", ""]
    text = "\n".join(head + rows) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
