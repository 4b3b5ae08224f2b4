"""Calibrate the diagnosis thresholds on recordings with nothing missing.

Diagnoses ``--controls`` concealed controls per sensor (seeds from ``--first-seed``, a range
kept for tuning and never used by ``run.py``) and reports, over the library's deterministic
effects, the largest penalised held-out gain and robust Wald statistic each control offers, and
how many controls would name an effect at the thresholds of ``DiagnoseSettings().selection``. The
open-world terms (:mod:`tcbench.diagnose.select.discover`) are judged by their own thresholds, not
these: they are left out of the statistics and counted apart where a control names one.

With ``--write-settings PATH`` it also writes the thresholds these controls calibrate, as a
fragment of ``conf/diagnose.yaml``'s ``settings:`` block (commented, with the equivalent
``tcbench diagnose settings.selection.<key>=`` overrides): each threshold is the smallest (rounded
up to 0.1, at least 0.1) that at most a share ``--false-alarm`` of the controls exceeds with any
deterministic candidate, the largest gain for ``detection_threshold_sigma2`` and the largest robust
Wald statistic for ``wald_threshold``; an effect is named only above both.

    python experiments/diagnose-concealed/calibrate.py --controls 100 --workers 2
    python experiments/diagnose-concealed/calibrate.py --controls 100 --write-settings calibrated.yaml
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, from_mapping, yaml_lines
from tcbench.diagnose.terms import is_open

SENSORS = ("msra", "gyro")
CALIBRATED = ("selection.detection_threshold_sigma2", "selection.wald_threshold")


def _one(sensor: str, seed: int) -> tuple[str, float, float, list[str], float]:
    """``(sensor, largest gain, largest joint ratio to the thresholds, effects named, largest
    robust Wald)`` of one control, over its library's deterministic candidates (no open-world term)."""
    selection = DEFAULTS.selection
    rec, _ = concealed_recording(sensor, None, seed)
    d = diagnose(rec)
    det = [e for e in d.candidates
           if e.effect != "bias_instability" and not is_open(e.effect) and np.isfinite(e.gain)]
    gains = np.array([e.gain for e in det])
    walds = np.array([e.wald for e in det])
    joint = max((min(g / selection.detection_threshold_sigma2, w / selection.wald_threshold)
                 for g, w in zip(gains, walds, strict=True)), default=0.0)
    finite = walds[np.isfinite(walds)]
    return (sensor, float(gains.max()) if gains.size else -math.inf, float(joint), d.effect_ids,
            float(finite.max()) if finite.size else -math.inf)


def calibrated(largest: np.ndarray, false_alarm: float) -> float:
    """The smallest threshold (rounded up to 0.1, at least 0.1) that at most ``false_alarm`` of
    the controls' ``largest`` statistics exceed."""
    ranked = np.sort(largest[np.isfinite(largest)])
    if ranked.size == 0:
        raise ValueError("no control offered a finite statistic to calibrate on")
    allowed = int(np.floor(false_alarm * ranked.size))  # controls that may lie above the threshold
    at = float(ranked[ranked.size - 1 - allowed])
    return max(math.ceil(10.0 * at) / 10.0, 0.1)


def settings_fragment(rows: list[tuple[str, float, float, list[str], float]], false_alarm: float,
                      seeds: range) -> tuple[str, DiagnoseSettings]:
    """The YAML fragment of ``conf/diagnose.yaml``'s ``settings:`` with the thresholds the
    controls ``rows`` calibrate at ``false_alarm``, and the settings it makes (checked)."""
    gains = np.array([r[1] for r in rows])
    walds = np.array([r[4] for r in rows])
    selection = replace(DEFAULTS.selection, detection_threshold_sigma2=calibrated(gains, false_alarm),
                        wald_threshold=calibrated(walds, false_alarm))
    settings = DiagnoseSettings(selection=selection)
    overrides = " ".join(f"settings.{key}={getattr(selection, key.split('.')[1])}" for key in CALIBRATED)
    head = [f"# calibrated by experiments/diagnose-concealed/calibrate.py on {len(rows)} concealed controls "
            f"({', '.join(SENSORS)}, seeds {seeds.start}-{seeds.stop - 1})",
            f"# false-alarm target {false_alarm:g}: at most that share of the controls has a deterministic "
            "candidate above each threshold",
            f"# largest gain per control: median {np.median(gains):.2f}, max {np.max(gains):.2f} sigma^2; "
            f"largest robust Wald: median {np.median(walds[np.isfinite(walds)]):.2f}",
            "# merge into conf/diagnose.yaml's settings:, or give: tcbench diagnose ... " + overrides]
    text = "\n".join([*head, *yaml_lines(settings, keys=CALIBRATED)]) + "\n"
    import yaml  # the fragment reads back as the settings it says

    assert from_mapping(yaml.safe_load(text)["settings"]) == settings
    return text, settings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controls", type=int, default=100, help="controls per sensor")
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--false-alarm", type=float, default=0.01,
                    help="share of the controls each calibrated threshold may leave above it")
    ap.add_argument("--write-settings", type=Path, default=None, metavar="PATH",
                    help="write the calibrated thresholds as a settings YAML fragment to PATH")
    args = ap.parse_args()
    if not 0.0 < args.false_alarm < 1.0:
        ap.error(f"--false-alarm must be in (0, 1), got {args.false_alarm}")
    seeds = range(args.first_seed, args.first_seed + args.controls)
    t0 = time.perf_counter()
    rows = Parallel(n_jobs=args.workers)(delayed(_one)(s, seed) for seed in seeds for s in SENSORS)
    selection = DEFAULTS.selection
    print(f"{len(rows)} controls in {time.perf_counter() - t0:.0f} s; thresholds: gain > "
          f"{selection.detection_threshold_sigma2:g} sigma^2 and robust Wald > {selection.wald_threshold:g}")
    for sensor in (*SENSORS, "all"):
        sub = [r for r in rows if sensor in ("all", r[0])]
        gains = np.array([r[1] for r in sub])
        joint = np.array([r[2] for r in sub])
        named = sum(any(not is_open(e) for e in r[3]) for r in sub)
        flick = sum("bias_instability" in r[3] for r in sub)
        open_named = sum(any(is_open(e) for e in r[3]) for r in sub)
        q = np.quantile(gains, [0.5, 0.9, 0.99])
        print(f"  {sensor:4s}: n={len(sub)}  max gain median/90%/99% = {q[0]:.1f}/{q[1]:.1f}/{q[2]:.1f};  "
              f"deterministic effect would pass both thresholds: {int((joint > 1).sum())}; "
              f"named a library effect: {named} ({100 * named / len(sub):.1f} %), bias_instability: {flick}; "
              f"an open-world term (its own thresholds): {open_named}")
    if args.write_settings is not None:
        text, settings = settings_fragment(rows, args.false_alarm, seeds)
        args.write_settings.write_text(text, encoding="utf-8")
        print(f"wrote {args.write_settings}: detection_threshold_sigma2 {settings.selection.detection_threshold_sigma2:g}, "
              f"wald_threshold {settings.selection.wald_threshold:g} at false-alarm {args.false_alarm:g}")


if __name__ == "__main__":
    main()
