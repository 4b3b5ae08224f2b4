"""A PX4 thermal-calibration log at 1 kHz imported (issue 46): the peak memory of ``tcbench import``
against the size of the log's gyro topic and of the recordings it writes.

The log is made here: the formats and header of the repository's sample log
(``data/real/px4_ulog_samples/sample_log_small.ulg``) with one ``sensor_gyro`` instance of
``--minutes`` (45) at 1 kHz in PX4's own field types (``uint64`` clocks, ``float32`` axes and
temperature), written with pyulog's writer. ``tcbench import csv=LOG sensor=gyro`` then runs once in
a fresh process under ``/usr/bin/time -v`` (wall, CPU, peak resident memory), after the import of a
``--base-rows`` log of the same kind (the process's own peak without the data: modules, pint's
registry); with ``--tcbench PATH`` the tcbench found at ``PATH`` is the one run (a checkout to
compare with). The peak above the small log's is set against the topic (pyulog's arrays, the
one full copy of the data) and one axis's recording (four float64 columns).

    python benchmarks/import_ulog_1khz.py --minutes 45
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from common import add_json, command_line, environment, environment_line, parser_for, write_json
from tcbench.data_paths import REAL_DATA

DEFAULT_JSON = Path(__file__).with_name("import_ulog_1khz.json")
SAMPLE = REAL_DATA / "px4_ulog_samples" / "sample_log_small.ulg"


def make_log(path: Path, rows: int) -> int:
    """A ULog at ``path`` holding ``rows`` samples of one ``sensor_gyro`` instance at 1 kHz (a 30 degC
    warm-up, each axis 1e-3 rad/s per degC plus noise); the topic's bytes in its logged types."""
    from pyulog import ULog

    log = ULog(str(SAMPLE), ["sensor_gyro"])
    topic = next(d for d in log.data_list if d.name == "sensor_gyro" and d.multi_id == 0)
    log._data_list = [topic]  # the one instance; pyulog's writer writes what the list holds
    rng = np.random.default_rng(0)
    t_us = np.arange(rows, dtype=np.uint64) * np.uint64(1000) + np.uint64(1_000_000)
    temp = (20.0 + 30.0 * np.arange(rows) / rows).astype(np.float32)
    axes = {a: (s * 1e-3 * temp + 3e-3 * rng.standard_normal(rows)).astype(np.float32)
            for a, s in (("x", 1.0), ("y", 2.0), ("z", -1.0))}
    topic.data = {"timestamp": t_us + np.uint64(200), "timestamp_sample": t_us,
                  "device_id": np.full(rows, topic.data["device_id"][0], np.uint32), **axes, "temperature": temp,
                  "error_count": np.zeros(rows, np.uint32)}
    log.write_ulog(str(path))
    return int(sum(v.nbytes for v in topic.data.values()))


def timed_import(log: Path, out: Path, tcbench_path: Path | None) -> dict[str, float]:
    """``tcbench import`` of ``log`` under ``/usr/bin/time -v``: wall and CPU seconds, peak RSS (MB)."""
    env = dict(os.environ)
    if tcbench_path is not None:
        env["PYTHONPATH"] = str(tcbench_path)
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "tcbench", "import", f"csv={log}", "sensor=gyro",
           f"out={out}", "tracking.enabled=false"]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    if done.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")

    def field(name: str) -> str:
        return re.search(rf"{re.escape(name)}: (.+)", done.stderr).group(1).strip()  # type: ignore[union-attr]

    wall = [float(x) for x in field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":")]
    return {"wall_s": sum(v * 60 ** i for i, v in enumerate(reversed(wall))),
            "cpu_s": float(field("User time (seconds)")) + float(field("System time (seconds)")),
            "peak_mb": float(field("Maximum resident set size (kbytes)")) / 1024.0, "load": os.getloadavg()[0]}


def main() -> None:
    parser = parser_for(__doc__)
    parser.add_argument("--minutes", type=float, default=45.0)
    parser.add_argument("--base-rows", type=int, default=12_000,
                        help="rows of a second, small log: its import's peak is the process without the data")
    parser.add_argument("--tcbench", type=Path, default=None, help="run the tcbench found at this path")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    env = environment("pyulog")
    rows = int(args.minutes * 60 * 1000)
    with tempfile.TemporaryDirectory() as tmp:
        small = Path(tmp) / "small-1khz.ulg"
        make_log(small, args.base_rows)
        base = timed_import(small, Path(tmp) / "out-small", args.tcbench)
        log = Path(tmp) / "thermal-1khz.ulg"
        topic_bytes = make_log(log, rows)
        run = timed_import(log, Path(tmp) / "out", args.tcbench)
        written = sum(p.stat().st_size for p in (Path(tmp) / "out").iterdir())
        log_mb = log.stat().st_size / 1e6
    axis_mib = rows * 4 * 8 / 2**20  # one axis's recording: four float64 columns
    recordings_mb = 3 * axis_mib
    above = run["peak_mb"] - base["peak_mb"]
    print(f"Command: `{command_line()}`\n\n{environment_line(env, 'pyulog ' + str(env['pyulog']))}\n")
    print("| rows | log (MB) | topic in memory (MiB) | one axis (MiB) | recordings in memory (MiB) | wall (s) "
          "| CPU (s) | peak RSS (MiB) | small log's peak (MiB) | above it (MiB) | (above - topic) / one axis |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    print(f"| {rows} | {log_mb:.0f} | {topic_bytes / 2**20:.0f} | {axis_mib:.0f} | {recordings_mb:.0f} | "
          f"{run['wall_s']:.1f} | {run['cpu_s']:.1f} | {run['peak_mb']:.0f} | {base['peak_mb']:.0f} | {above:.0f} | "
          f"{(above - topic_bytes / 2**20) / axis_mib:.2f} |")
    write_json(args.json, {"command": command_line(), "environment": env, "rows": rows, "log_mb": log_mb,
                           "topic_mib": topic_bytes / 2**20, "axis_mib": axis_mib, "recordings_mib": recordings_mb,
                           "written_mb": written / 1e6, **run, "base_rows": args.base_rows,
                           "base_peak_mb": base["peak_mb"]})


if __name__ == "__main__":
    main()
