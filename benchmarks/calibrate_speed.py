"""Time ``tcbench calibrate`` on a 24 h, 1 Hz static gyro record against ``numpy.polyfit`` (targets:
the poly3 command under 5 s, the default methods under 60 s on 2 cores), and show the held-out drift
of the networks trained on every sample and on time bins on the real tofupilot gyro axes.

The record: the gyro oven run of device 0 at 1 Hz (3.6 h holds widened to 8000 s), cut to 24 h
(86 400 samples): a heating branch (0, 6 904 samples) and a cooling branch (1, 79 496). Each case
fits on one of them (``--train-branches``; 0 is the command's default, 1 the worst case) and
scores on both. Timed, best of ``--repeats`` (wall and CPU seconds, ratio to the polyfit):

- ``numpy.polyfit(T, y, 3)`` on the whole record: the bound;
- each method's fit + residual + scores in process (``model``: the diagnosis of the training
  part, its model file, the residual), and the networks also on every sample (``bin_s=None``,
  the code before the bins) for the before/after;
- the whole command in a subprocess (``methods=[raw,poly3]`` and the default methods, MLflow
  tracking on as a user runs it, in a scratch folder): wall time, and the child's CPU time.

Then the drift: on each tofupilot gyro axis (``data/real``), bp and elman fitted on branch 0 with
seeds 0..``--drift-seeds``-1, on samples and on bins (``--drift-bins``); the median and range over seeds of the RMS
of the 60-s running mean of the residual on the held-out branches 1 and 2.

    python benchmarks/calibrate_speed.py --repeats 3 --drift-seeds 10
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from common import add_json, blas_threads, command_line, environment, environment_line, parser_for, write_json

from tcbench.data_paths import REAL_DATA

DEFAULT_JSON = Path(__file__).with_name("calibrate_speed.json")
TOFUPILOT = REAL_DATA / "tofupilot_imu_chamber" / "imu_raw_data.csv"
HOURS = 24.0
DEFAULT_METHODS = ("raw", "poly3", "poly3_rate", "bp", "elman", "model")
LONG_S = 20.0  # a step taking longer is timed once


def day_record() -> Any:
    """The 24 h, 1 Hz gyro oven record (see the module docstring)."""
    from tcbench.sensors.recording import make_recording
    from tcbench.sensors.simulate import simulate_recording

    rec = simulate_recording("gyro", "oven", 0, 0, sample_rate_hz=1.0, hold_s=8000.0)
    d = rec.data[rec.time_s < HOURS * 3600.0]
    return make_recording(d.time_s, d.temperature_c, d["input"], d.output, sensor="gyro", sample_rate_hz=1.0,
                          device_id=rec.meta.device_id)


def timed(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Best wall and best CPU seconds of ``repeats`` calls of ``fn()`` (one call once a call has
    taken over :data:`LONG_S`)."""
    walls: list[float] = []
    cpus: list[float] = []
    while len(walls) < repeats and not (walls and walls[-1] > LONG_S):
        w, c = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
    return min(walls), min(cpus)


def command_s(path: Path, methods: tuple[str, ...], train: int, folder: Path) -> tuple[float, float]:
    """Wall and CPU seconds of ``tcbench calibrate`` on ``path`` in a subprocess run in ``folder``."""
    args = [sys.executable, "-m", "tcbench", "calibrate", f"recording={path}", f"methods=[{','.join(methods)}]",
            f"train_branches=[{train}]", f"out={folder / 'out'}"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, cwd=folder, capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"{' '.join(args)} failed:\n{done.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def method_step(method: str, rec: Any, branches: list[Any], train: int,
                bin_s: float | None) -> Callable[[], object]:
    """fit + residual + scores of one method, as the command runs them."""
    from tcbench.compensation.calibration import fit, from_model, record, residual, scores

    whole = record(rec.time_s, rec.temperature_c, rec.output, rec.input)

    def step() -> object:
        b = branches[train]
        model = from_model(_diagnosed(rec, b)) if method == "model" else \
            fit(method, [whole.part(b.start, b.stop)], 0, bin_s=bin_s)
        res = residual(model, whole)
        return [scores(res[p.start:p.stop], rec.time_s[p.start:p.stop]) for p in branches]

    return step


def _diagnosed(rec: Any, b: Any) -> Any:
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.model_file import to_sensor_model
    from tcbench.diagnose.report.write import model_spec
    from tcbench.diagnose.select.plan import min_full_duration_s
    from tcbench.sensors.recording import make_recording

    part = make_recording(rec.time_s[b.start:b.stop], rec.temperature_c[b.start:b.stop], rec.input[b.start:b.stop],
                          rec.output[b.start:b.stop], sensor="gyro", sample_rate_hz=1.0, device_id="day")
    diagnosis = diagnose(part, name="training part", min_duration_s=min_full_duration_s())
    return to_sensor_model(model_spec(diagnosis))


def speed(rec: Any, path: Path, train: int, repeats: int) -> list[dict[str, Any]]:
    """The timed rows of one case (see the module docstring)."""
    from tcbench.compensation.calibration import LEARNERS, TRAIN_BIN_S
    from tcbench.signal.branches import temperature_branches

    branches = temperature_branches(rec.time_s, rec.temperature_c, 5.0)
    temp, out = rec.temperature_c, rec.output
    rows = [{"step": "numpy.polyfit(T, y, 3), whole record (bound)",
             **dict(zip(("wall_s", "cpu_s"), timed(lambda: np.polyfit(temp, out, 3), max(repeats, 5))))}]
    for m in DEFAULT_METHODS:
        bins = [TRAIN_BIN_S, None] if m in LEARNERS else [TRAIN_BIN_S]
        for bin_s in bins:
            label = f"{m}: fit + residual + scores" + (
                "" if m not in LEARNERS else f" ({'every sample, before' if bin_s is None else f'{bin_s:g}-s bins'})")
            wall, cpu = timed(method_step(m, rec, branches, train, bin_s), repeats)
            rows.append({"step": label, "wall_s": wall, "cpu_s": cpu})
            print(f"  {label}: {wall:.3f} s", file=sys.stderr, flush=True)
    for methods in (("raw", "poly3"), DEFAULT_METHODS):
        runs: list[tuple[float, float]] = []
        while len(runs) < repeats and not (runs and runs[-1][0] > LONG_S):
            with tempfile.TemporaryDirectory() as tmp:
                runs.append(command_s(path, methods, train, Path(tmp)))
        wall, cpu = min(r[0] for r in runs), min(r[1] for r in runs)
        rows.append({"step": f"tcbench calibrate methods=[{','.join(methods)}] (subprocess)",
                     "wall_s": wall, "cpu_s": cpu})
        print(f"  command {methods}: {wall:.1f} s", file=sys.stderr, flush=True)
    bound = rows[0]["wall_s"]
    for r in rows:
        r["ratio_to_polyfit"] = r["wall_s"] / bound
    return rows


def drift(seeds: int, bins: list[float]) -> list[dict[str, Any]]:
    """Held-out drift of bp and elman on the tofupilot gyro axes, on samples and on bins of each
    width in ``bins``."""
    from tcbench.compensation.calibration import LEARNERS, fit, record, residual, scores
    from tcbench.datasets.real import tofupilot_gyro
    from tcbench.signal.branches import temperature_branches

    rows = []
    for axis in "xyz":
        r = tofupilot_gyro(axis, TOFUPILOT)
        parts = temperature_branches(r.time_s, r.temperature_c, 5.0)
        whole = record(r.time_s, r.temperature_c, r.output, r.input)
        train = [whole.part(parts[0].start, parts[0].stop)]
        for m in LEARNERS:
            for bin_s in (None, *bins):
                runs = (residual(fit(m, train, s, bin_s=bin_s), whole) for s in range(seeds))
                d = np.array([[scores(res[p.start:p.stop], r.time_s[p.start:p.stop])["drift_rms"] for p in parts[1:]]
                              for res in runs])
                rows.append({"axis": axis, "method": m, "bin_s": bin_s, "median": np.median(d, axis=0).tolist(),
                             "min": d.min(axis=0).tolist(), "max": d.max(axis=0).tolist()})
    return rows


def main() -> None:
    p = parser_for(__doc__)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--train-branches", type=int, nargs="*", default=[0, 1], help="none: skip the timing")
    p.add_argument("--drift-seeds", type=int, default=10, help="seeds of the drift check (0: skip it)")
    p.add_argument("--drift-bins", type=float, nargs="+", default=None,
                   help="training bin widths (s) of the drift check; default: the command's")
    add_json(p, DEFAULT_JSON)
    args = p.parse_args()
    from tcbench.sensors.recording import write_recording

    env = environment("scipy")
    load_before = os.getloadavg()
    print(f"Command: `{command_line()}`\n\n{environment_line(env, 'scipy ' + str(env['scipy']))} "
          f"BLAS: {blas_threads()}. Load average before (1, 5, 15 min): "
          f"{', '.join(f'{x:.2f}' for x in load_before)}.\n")
    rec = day_record()
    results: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = write_recording(rec, Path(tmp) / "day.parquet")
        for train in args.train_branches:
            print(f"case: trained on branch {train}", file=sys.stderr, flush=True)
            results[f"train_branch_{train}"] = speed(rec, path, train, args.repeats)
    for case, rows in results.items():
        print(f"\n### 24 h at 1 Hz ({rec.time_s.size} samples), {case.replace('_', ' ')}\n")
        print("| step | wall (s) | CPU (s) | wall / polyfit |\n|---|---:|---:|---:|")
        for r in rows:
            print(f"| {r['step']} | {r['wall_s']:.4g} | {r['cpu_s']:.4g} | {r['ratio_to_polyfit']:.3g} |")
    load_after = os.getloadavg()
    print(f"\nLoad average after: {', '.join(f'{x:.2f}' for x in load_after)} ({os.cpu_count()} cores).")
    from tcbench.compensation.calibration import TRAIN_BIN_S

    drifts = drift(args.drift_seeds, args.drift_bins or [TRAIN_BIN_S]) if args.drift_seeds else []
    if drifts:
        print(f"\n### Held-out drift (deg/s) on the tofupilot gyro, fitted on branch 0, "
              f"seeds 0..{args.drift_seeds - 1}\n")
        print("| axis | method | training rows | branch 1: median [min..max] | branch 2: median [min..max] |\n"
              "|---|---|---|---:|---:|")
        for r in drifts:
            cells = [f"{r['median'][k]:.3f} [{r['min'][k]:.3f}..{r['max'][k]:.3f}]" for k in (0, 1)]
            rows_text = "every sample" if r["bin_s"] is None else f"{r['bin_s']:g}-s bins"
            print(f"| {r['axis']} | {r['method']} | {rows_text} | {cells[0]} | {cells[1]} |")
    write_json(args.json, {"command": command_line(), "environment": env, "blas": blas_threads(),
                           "load_before": load_before, "load_after": load_after, "samples": int(rec.time_s.size),
                           "results": results, "drift": drifts})


if __name__ == "__main__":
    main()
