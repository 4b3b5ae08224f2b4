"""Time one diagnosis of a 24 h recording at 1 Hz with every detector (target: under 60 s on
2 cores) and of each gyro axis of the real 70-min tofupilot chamber cycle (target: under 10 s).

Two simulated recordings, with every default effect of the device (so the diagnosis has work to
do): an MSRA full-temperature test with 3.6 h soaks, and a gyro oven run, both cut to 24 h
(86 400 samples); every library effect and every open-world and non-mean detector runs. Times ``diagnose`` (fit, locate, attribute over every effect and grid, refit,
flicker test) and the report (JSON, markdown, model.yaml, three plots) separately, best of
``--repeats``, with the BLAS threads left at their default.

    python benchmarks/diagnose_speed.py --repeats 3
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from common import (
    add_json,
    blas_threads,
    command_line,
    environment,
    environment_line,
    parser_for,
    wall_times_s,
    write_json,
)

DEFAULT_JSON = Path(__file__).with_name("diagnose_speed.json")
HOURS = 24.0


def recording(sensor: str):  # type: ignore[no-untyped-def]
    from tcbench.sensors.recording import make_recording
    from tcbench.sensors.simulate import simulate_recording

    if sensor == "msra":
        rec = simulate_recording("msra", "fulltemp", 0, 0, soak_s=13000.0)
    else:
        rec = simulate_recording("gyro", "oven", 0, 0, sample_rate_hz=1.0, hold_s=8000.0)
    keep = rec.time_s < HOURS * 3600.0
    if keep.all():
        raise SystemExit(f"{sensor} recording is only {rec.time_s[-1] / 3600:.1f} h")
    d = rec.data[keep]
    return make_recording(d.time_s, d.temperature_c, d["input"], d.output, sensor=sensor,
                          sample_rate_hz=1.0, device_id=rec.meta.device_id or sensor)


def main() -> None:
    p = parser_for(__doc__)
    p.add_argument("--repeats", type=int, default=3)
    add_json(p, DEFAULT_JSON)
    args = p.parse_args()
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.report.write import write_report

    blas = blas_threads()
    env = environment("scipy")
    print(f"Command: `{command_line()}`\n\n{environment_line(env, 'scipy ' + str(env['scipy']))} BLAS: {blas}.\n")
    print("| recording | samples | diagnose (s) | report (s) | found |\n|---|---:|---:|---:|---|")
    results = {}
    for sensor in ("msra", "gyro"):
        rec = recording(sensor)
        times, d = wall_times_s(lambda rec=rec, sensor=sensor: diagnose(rec, name=f"{sensor} {HOURS:g} h"), args.repeats)
        with tempfile.TemporaryDirectory() as tmp:
            report_times, _ = wall_times_s(lambda d=d, tmp=tmp: write_report(d, Path(tmp) / "out"), args.repeats)
        results[sensor] = {"samples": int(rec.time_s.size), "diagnose_s": min(times), "report_s": min(report_times),
                           "all_diagnose_s": times, "found": d.effect_ids}
        print(f"| {sensor} | {rec.time_s.size} | {min(times):.1f} | {min(report_times):.1f} | {', '.join(d.effect_ids) or 'nothing'} |")
    worst = max(r["diagnose_s"] + r["report_s"] for r in results.values())
    print(f"\nSlowest {HOURS:g} h diagnosis with its report: **{worst:.1f} s** (target < 60 s): "
          f"**{'met' if worst < 60 else 'not met'}**.\n")
    from tcbench.datasets.real import tofupilot_gyro

    print("| tofupilot gyro axis | samples | diagnose (s) | found |\n|---|---:|---:|---|")
    for axis in ("x", "y", "z"):
        rec = tofupilot_gyro(axis)
        times, d = wall_times_s(lambda rec=rec: diagnose(rec, name=f"tofupilot {axis}"), args.repeats)
        results[f"tofupilot_{axis}"] = {"samples": int(rec.time_s.size), "diagnose_s": min(times),
                                        "all_diagnose_s": times, "found": d.effect_ids}
        print(f"| {axis} | {rec.time_s.size} | {min(times):.1f} | {', '.join(d.effect_ids) or 'nothing'} |")
    slowest = max(results[f"tofupilot_{a}"]["diagnose_s"] for a in "xyz")
    print(f"\nSlowest tofupilot axis: **{slowest:.1f} s** (target < 10 s): **{'met' if slowest < 10 else 'not met'}**.")
    write_json(args.json, {"command": command_line(), "environment": env, "blas": blas, "results": results,
                           "hours": HOURS, "median_samples": float(np.median([results[k]["samples"] for k in ("msra", "gyro")]))})


if __name__ == "__main__":
    main()
