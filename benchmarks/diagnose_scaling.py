"""How the time of one diagnosis grows with the rows of the record: the measurement behind
``tcbench diagnose``'s estimate and its ``max_rows`` limit (:mod:`tcbench.diagnose.rate.cost`).

Each size is a simulated gyro oven run (device 0, run 0, 50-min holds) cut to ``--hours`` and
sampled so that it holds the given number of rows, diagnosed once in a fresh process, its two
thermometer windows one after the other (``JOBLIB_MULTIPROCESSING=0``) with one BLAS thread: the
CPU seconds are one core's work, what a busy machine gives a diagnosis; the peak resident memory
includes the simulation's. The fit is the least
squares line of ``log(seconds)`` on ``log(rows)`` and the upper envelope: the same slope through
the slowest point, the estimate ``tcbench diagnose`` states.

    python benchmarks/diagnose_scaling.py --rows 1e4 3e4 1e5 2e5 3e5 1e6 --hours 6
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from common import add_json, command_line, environment, environment_line, parser_for, write_json

DEFAULT_JSON = Path(__file__).with_name("diagnose_scaling.json")
CHILD = """
import json, os, resource, sys, time
from tcbench.diagnose.diagnosis import diagnose
from tcbench.sensors.recording import make_recording
from tcbench.sensors.simulate import simulate_recording

rows, hours = int(float(sys.argv[1])), float(sys.argv[2])
rate = rows / (hours * 3600.0)
r = simulate_recording("gyro", "oven", 0, 0, sample_rate_hz=rate, hold_s=3000.0)
d = r.data[r.time_s < hours * 3600.0]
rec = make_recording(d.time_s, d.temperature_c, d["input"], d.output, sensor="gyro", sample_rate_hz=rate,
                     device_id="g")
cpu, wall = time.process_time(), time.perf_counter()
found = diagnose(rec, name="scaling")
print(json.dumps({"rows": int(rec.time_s.size), "hours": hours, "cpu_s": time.process_time() - cpu,
                  "wall_s": time.perf_counter() - wall, "load": os.getloadavg()[0], "found": found.effect_ids,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def measure(rows: float, hours: float) -> dict[str, object]:
    """One diagnosis of ``rows`` rows over ``hours`` in a fresh process."""
    env = {**os.environ, "JOBLIB_MULTIPROCESSING": "0", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", CHILD, str(rows), str(hours)], capture_output=True, text=True,
                          check=True, env=env)
    return json.loads(done.stdout.strip().splitlines()[-1])


def fit(rows: np.ndarray, seconds: np.ndarray) -> dict[str, float]:
    """``seconds = a * (rows / 1e5) ** p`` by least squares in logs, and the ``a`` of the same
    slope through the slowest point above the line (the envelope)."""
    x, y = np.log(rows / 1e5), np.log(seconds)
    p, log_a = np.polyfit(x, y, 1)
    envelope = float(np.exp(np.max(y - p * x)))
    return {"p": float(p), "a_s": float(np.exp(log_a)), "envelope_a_s": envelope}


def main() -> None:
    parser = parser_for(__doc__)
    parser.add_argument("--rows", type=float, nargs="+", default=[1e4, 3e4, 1e5, 2e5, 3e5, 1e6])
    parser.add_argument("--hours", type=float, default=6.0)
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    env = environment("scipy")
    print(f"Command: `{command_line()}`\n\n{environment_line(env, 'scipy ' + str(env['scipy']))}\n")
    print("| rows | rate (Hz) | CPU (s) | wall (s) | load | peak RSS (MB) | found |\n|---:|---:|---:|---:|---:|---:|---|")
    runs = []
    for rows in args.rows:
        started = time.perf_counter()
        run = measure(rows, args.hours)
        runs.append(run)
        print(f"| {run['rows']} | {run['rows'] / (args.hours * 3600):.3g} | {run['cpu_s']:.1f} | {run['wall_s']:.1f} | "
              f"{run['load']:.1f} | {run['peak_mb']:.0f} | {', '.join(run['found']) or 'nothing'} |", flush=True)
        print(f"  ({time.perf_counter() - started:.0f} s with the simulation)", file=sys.stderr)
    figure = fit(np.array([r["rows"] for r in runs], float), np.array([r["cpu_s"] for r in runs], float))
    print(f"\nFit: CPU s = {figure['a_s']:.3g} x (rows / 1e5)^{figure['p']:.2f}; envelope "
          f"{figure['envelope_a_s']:.3g} x (rows / 1e5)^{figure['p']:.2f}.")
    write_json(args.json, {"command": command_line(), "environment": env, "hours": args.hours, "runs": runs,
                           "fit": figure})


if __name__ == "__main__":
    main()
