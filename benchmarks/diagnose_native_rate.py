"""Logs at their native rate (issue 46): ``tcbench diagnose`` on a record of millions of rows,
its thermal terms fitted on bin means and its noise measured on every sample
(:mod:`tcbench.diagnose.rate.native_rate`), against the targets and against the same record averaged
by hand.

Each case is a simulated gyro oven run (device 0, run 0) sampled at the case's rate and cut to
its length (``log45m1k``: 45 min at 1 kHz from 1.5 h into a run of 10-min holds, 2.7 M rows;
``day100``: 24 h at 100 Hz of a run of 2-h holds, 8.64 M rows), written as Parquet; then, each
once in a fresh process under ``/usr/bin/time -v`` with the two thermometer windows one after the
other (``JOBLIB_MULTIPROCESSING=0``) and one BLAS thread:

1. ``tcbench diagnose`` of the full-rate record at the default settings (the command's wall and
   CPU time and its peak resident memory, reading the file included);
2. ``tcbench diagnose`` of the same record averaged by hand into means of the same number of
   samples the command chose (``settings.rate.max_rows`` lifted, so it is diagnosed as given).

The two reports are compared: the effects named (in any order: the forward selection may take
two of similar gain in either order), and each amplitude with its interval (three standard
errors from the cluster-robust Wald statistic, ``se = |a| / sqrt(Wald)``) inside the other's; a
nonlinear parameter (a time constant, a period, a phase) is listed with its relative difference.
A switched load's square is compared with a positive size (on and off swapped where needed).

    python benchmarks/diagnose_native_rate.py --case log45m1k day100
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from common import add_json, command_line, environment, environment_line, parser_for, write_json

DEFAULT_JSON = Path(__file__).with_name("diagnose_native_rate.json")
CASES = {  # name: (rate Hz, hours, from hour, hold s, target wall s, target peak GB)
    "log45m1k": (1000.0, 0.75, 1.5, 600.0, 60.0, 1.5),  # a ramp up, the 61 degC hold and a ramp down
    "day100": (100.0, 24.0, 0.0, 7200.0, 180.0, 2.0),  # 2 h holds: the run lasts 25.5 h
}
ENV = {"JOBLIB_MULTIPROCESSING": "0", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def write_records(case: str, folder: Path) -> tuple[Path, Path, dict[str, Any]]:
    """The full-rate record of ``case`` and its hand-averaged copy (means of the bin the front
    stage plans for it), as Parquet in ``folder``, and the plan."""
    from tcbench.diagnose.rate.native_rate import plan_for
    from tcbench.sensors.recording import make_recording, write_recording
    from tcbench.sensors.simulate import simulate_recording

    rate, hours, start_h, hold_s, _, _ = CASES[case]
    r = simulate_recording("gyro", "oven", 0, 0, sample_rate_hz=rate, hold_s=hold_s)
    d = r.data[(r.time_s >= start_h * 3600.0) & (r.time_s < (start_h + hours) * 3600.0)]
    rec = make_recording(d.time_s, d.temperature_c, d["input"], d.output, sensor="gyro", sample_rate_hz=rate,
                         device_id="g")
    del r, d
    full = folder / f"{case}.parquet"
    write_recording(rec, full)
    plan = plan_for(rec)
    k = plan.bin_samples
    n = rec.time_s.size // k * k

    def mean(x: np.ndarray) -> np.ndarray:
        return x[:n].reshape(-1, k).mean(axis=1)

    hand = folder / f"{case}-by-hand.parquet"
    write_recording(make_recording(mean(rec.time_s), mean(rec.temperature_c), mean(rec.input), mean(rec.output),
                                   sensor="gyro", sample_rate_hz=rate / k, device_id="g"), hand)
    return full, hand, plan.to_json() | {"diagnosed_rows": plan.diagnosed_rows}


def timed_diagnose(recording: Path, out: Path, *extra: str) -> dict[str, Any]:
    """``tcbench diagnose`` of ``recording`` under ``/usr/bin/time -v``: wall, CPU, peak RSS and the report."""
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "tcbench", "diagnose", f"recording={recording}", f"out={out}",
           "tracking.enabled=false", *extra]
    done = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **ENV}, check=False)
    if done.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")
    err = done.stderr

    def field(name: str) -> str:
        return re.search(rf"{re.escape(name)}: (.+)", err).group(1).strip()  # type: ignore[union-attr]

    wall = [float(x) for x in field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":")]
    return {"wall_s": sum(v * 60 ** i for i, v in enumerate(reversed(wall))),
            "cpu_s": float(field("User time (seconds)")) + float(field("System time (seconds)")),
            "peak_mb": float(field("Maximum resident set size (kbytes)")) / 1024.0, "load": os.getloadavg()[0],
            "report": json.loads((out / "report.json").read_text())}


NONLINEAR = {"tau_s", "time_s", "width_c", "period_s", "phase_rad", "on_s", "duty", "start_s", "end_s"}


def canonical(params: dict[str, Any]) -> dict[str, Any]:
    """A switched load's square with a positive size: ``offset + size * on`` is ``(offset + size) -
    size * off``, the same square read with on and off swapped (duty ``1 - duty``)."""
    if {"duty", "size", "offset"} <= params.keys() and params["size"] < 0:
        return {**params, "offset": params["offset"] + params["size"], "size": -params["size"],
                "duty": 1.0 - params["duty"]}
    return params


def compare(a: dict[str, Any], b: dict[str, Any], z: float = 3.0) -> dict[str, Any]:
    """The effects of two reports side by side: the same ids (in any order), and each parameter with
    whether it lies inside the other's interval (amplitudes) or its relative difference (the
    nonlinear ones: times, periods, phases, shares)."""
    ids_a, ids_b = [e["id"] for e in a["effects"]], [e["id"] for e in b["effects"]]
    rows = []
    for ea in a["effects"]:
        eb = next((e for e in b["effects"] if e["id"] == ea["id"]), None)
        if eb is None:
            continue
        pa, pb = canonical(ea["params"]), canonical(eb["params"])
        for key, va in pa.items():
            vb = pb.get(key)
            if not isinstance(va, float) or not isinstance(vb, float):
                continue
            row = {"effect": ea["id"], "param": key, "native": va, "by_hand": vb,
                   "relative": abs(va - vb) / max(abs(vb), 1e-300)}
            wald = [e["evidence"].get("robust_wald") for e in (ea, eb)]
            if all(wald) and key not in NONLINEAR:
                se = [abs(v) / np.sqrt(w) for v, w in zip((va, vb), wald, strict=True)]
                row |= {"se": se, "inside": bool(all(abs(va - vb) <= z * s for s in se))}
            rows.append(row)
    return {"same_effects": sorted(ids_a) == sorted(ids_b), "native": ids_a, "by_hand": ids_b, "params": rows}


def main() -> None:
    parser = parser_for(__doc__)
    parser.add_argument("--case", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--keep", type=Path, default=None, help="write the records here and keep them")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    env = environment("scipy", "pyarrow")
    print(f"Command: `{command_line()}`\n\n{environment_line(env, 'scipy ' + str(env['scipy']))}\n")
    results = {}
    for case in args.case:
        rate, hours, _, _, wall_target, gb_target = CASES[case]
        with tempfile.TemporaryDirectory() as tmp:
            folder = args.keep or Path(tmp)
            folder.mkdir(parents=True, exist_ok=True)
            full, hand, plan = write_records(case, folder)
            native = timed_diagnose(full, folder / f"{case}-native")
            by_hand = timed_diagnose(hand, folder / f"{case}-hand", f"settings.rate.max_rows={plan['diagnosed_rows']}")
        same = compare(native["report"], by_hand["report"])
        results[case] = {"plan": plan, "native": {k: v for k, v in native.items() if k != "report"},
                         "by_hand": {k: v for k, v in by_hand.items() if k != "report"}, "compare": same,
                         "noise": native["report"]["noise"], "native_rate": native["report"]["native_rate"]}
        ok = native["wall_s"] <= wall_target and native["peak_mb"] <= gb_target * 1024
        print(f"## {case}: {plan['rows']} rows at {rate:g} Hz over {hours:g} h, means of {plan['bin_samples']} "
              f"({plan['bin_s']:.3g} s)\n")
        print("| run | wall (s) | CPU (s) | peak RSS (MB) | load | effects |\n|---|---:|---:|---:|---:|---|")
        for label, run, ids in (("native rate", native, same["native"]), ("by hand", by_hand, same["by_hand"])):
            print(f"| {label} | {run['wall_s']:.1f} | {run['cpu_s']:.1f} | {run['peak_mb']:.0f} | {run['load']:.1f} | "
                  f"{', '.join(ids) or 'nothing'} |")
        print(f"\ntarget {wall_target:g} s and {gb_target:g} GB: {'met' if ok else 'NOT met'}; same effects: "
              f"{same['same_effects']}")
        for row in same["params"]:
            inside = f", inside each other's 3-se interval: {row['inside']}" if "inside" in row else ""
            print(f"- {row['effect']}.{row['param']}: {row['native']:.6g} vs {row['by_hand']:.6g} "
                  f"(relative {row['relative']:.2g}{inside})")
        print(f"- white sigma per sample {native['report']['noise']['white_sigma']:.4g} at {rate:g} Hz; bins "
              f"{native['report']['native_rate']['white_sigma_bins']:.4g}\n", flush=True)
    write_json(args.json, {"command": command_line(), "environment": env, "cases": results})


if __name__ == "__main__":
    main()
