"""Calibrate the diagnosis thresholds on recordings with nothing missing.

Diagnoses ``--controls`` concealed controls per sensor (seeds from ``--first-seed``, a range
kept for tuning and never used by ``run.py``) and reports, over the library's deterministic
effects, the largest penalised held-out gain and robust Wald statistic each control offers, and
how many controls would name an effect at the thresholds in ``tcbench.diagnose.attribute``.

    python experiments/diagnose-concealed/calibrate.py --controls 100 --workers 2
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from joblib import Parallel, delayed

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.settings import DEFAULTS

DETECTION_THRESHOLD = DEFAULTS.selection.detection_threshold_sigma2
WALD_THRESHOLD = DEFAULTS.selection.wald_threshold


def _one(sensor: str, seed: int) -> tuple[str, float, float, list[str]]:
    rec, _ = concealed_recording(sensor, None, seed)
    d = diagnose(rec)
    det = [e for e in d.candidates if e.effect != "bias_instability" and np.isfinite(e.gain)]
    gains = np.array([e.gain for e in det])
    walds = np.array([e.wald for e in det])
    joint = max((min(g / DETECTION_THRESHOLD, w / WALD_THRESHOLD) for g, w in zip(gains, walds, strict=True)), default=0.0)
    return sensor, float(gains.max()), float(joint), d.effect_ids


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controls", type=int, default=100, help="controls per sensor")
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    seeds = range(args.first_seed, args.first_seed + args.controls)
    t0 = time.perf_counter()
    rows = Parallel(n_jobs=args.workers)(delayed(_one)(s, seed) for seed in seeds for s in ("msra", "gyro"))
    print(f"{len(rows)} controls in {time.perf_counter() - t0:.0f} s; thresholds: gain > {DETECTION_THRESHOLD:g} sigma^2 "
          f"and robust Wald > {WALD_THRESHOLD:g}")
    for sensor in ("msra", "gyro", "all"):
        sub = [r for r in rows if sensor in ("all", r[0])]
        gains = np.array([r[1] for r in sub])
        joint = np.array([r[2] for r in sub])
        named = sum(bool(r[3]) for r in sub)
        flick = sum("bias_instability" in r[3] for r in sub)
        q = np.quantile(gains, [0.5, 0.9, 0.99])
        print(f"  {sensor:4s}: n={len(sub)}  max gain median/90%/99% = {q[0]:.1f}/{q[1]:.1f}/{q[2]:.1f};  "
              f"deterministic effect would pass both thresholds: {int((joint > 1).sum())}; "
              f"named anything: {named} ({100 * named / len(sub):.1f} %), bias_instability: {flick}")


if __name__ == "__main__":
    main()
