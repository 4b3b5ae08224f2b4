"""How long a user waits for ``tcbench <command> --help`` and for a one-line error, per command.

Each row is one command line run as a fresh process (the installed ``tcbench`` script next to
this Python, or ``--tcbench PATH``) in an empty temporary folder: the median (and range) of the
wall time from start to exit over ``--repeats`` runs, and beside it the median CPU time (user +
system), which grows much less than the wall time on a busy machine. Every ``--help`` must exit
0 with the command's usage; every error must exit 2 with one line on stderr and leave the
folder empty. The errors are the common ones: an unknown or misspelt key, a value of the wrong
type, a missing recording. Two floors for reference: an empty Python and ``import tcbench``
(which registers the tasks with gymnasium). The issue's target: every row under 1 s on a quiet
2-core machine.

Usage::

    python benchmarks/cli_latency.py --repeats 7
"""

from __future__ import annotations

import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import add_json, command_line, parser_for, table_head, table_row, versions, write_json

DEFAULT_JSON = Path(__file__).with_name("cli_latency.json")
TARGET_S = 1.0
MISSING = "nope.csv"  # never created: the missing-recording errors name it

# (what it is, the command's arguments); an empty first entry is a floor, run with python -c
CASES: list[tuple[str, list[str]]] = [
    ("floor: python", ["-c", "pass"]),
    ("floor: import tcbench", ["-c", "import tcbench"]),
    ("help", ["--help"]),
    ("help", ["run", "--help"]),
    ("unknown key", ["run", "bogus=1"]),
    ("American spelling", ["run", "optimizer=fa"]),
    ("bad value type", ["run", "seed=abc"]),
    ("help", ["simulate", "--help"]),
    ("misspelt key", ["simulate", "sede=1"]),
    ("help", ["metrics", "--help"]),
    ("missing recording", ["metrics", MISSING]),
    ("help", ["import", "--help"]),
    ("missing file", ["import", f"csv={MISSING}", "sensor=gyro", "time=t", "temperature=T", "output=o", "out=x"]),
    ("help", ["diagnose", "--help"]),
    ("missing recording", ["diagnose", f"recording={MISSING}"]),
    ("help", ["calibrate", "--help"]),
    ("missing recording", ["calibrate", MISSING]),
    ("help", ["leaderboard", "--help"]),
    ("misspelt key", ["leaderboard", "experiment=x"]),
    ("help", ["list", "--help"]),
    ("misspelt key", ["list", "wat=tasks"]),
    ("help", ["quickstart", "--help"]),
    ("bad value type", ["quickstart", "seeds=abc"]),
]


def children_cpu_s() -> float:
    """CPU seconds (user + system) of this process's finished children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def once(argv: list[str]) -> tuple[float, float, subprocess.CompletedProcess[str]]:
    """One run of ``argv`` in an empty temporary folder: its wall time, its CPU time and what it returned."""
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"}
    with tempfile.TemporaryDirectory() as tmp:
        cpu0, t0 = children_cpu_s(), time.perf_counter()
        done = subprocess.run(argv, cwd=tmp, env=env, capture_output=True, text=True, timeout=600)
        wall, cpu = time.perf_counter() - t0, children_cpu_s() - cpu0
        left = sorted(p.name for p in Path(tmp).iterdir())
    if left:
        raise RuntimeError(f"{' '.join(argv)} left {left} behind")
    return wall, cpu, done


def checked(what: str, args: list[str], done: subprocess.CompletedProcess[str]) -> str:
    """What the command answered: its usage line or its one error line; a RuntimeError when it
    did not answer as it should."""
    if what.startswith("floor"):
        ok, answer = done.returncode == 0, ""
    elif what == "help":
        ok, answer = done.returncode == 0 and done.stdout.startswith("usage: tcbench"), done.stdout.split("\n", 1)[0]
    else:
        lines = done.stderr.strip().splitlines()
        ok = done.returncode == 2 and len(lines) == 1 and lines[0].startswith("tcbench: error:")
        answer = lines[0] if lines else ""
    if not ok:
        raise RuntimeError(f"{args}: exit {done.returncode}\n{done.stdout[-1000:]}\n{done.stderr[-2000:]}")
    return answer


def main() -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--repeats", type=int, default=5, help="runs of each command line (the median is reported)")
    parser.add_argument("--tcbench", type=Path, default=Path(sys.executable).with_name("tcbench"),
                        help="the tcbench script to time (its Python times the floors)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    python = str(args.tcbench.with_name("python"))
    load_start = os.getloadavg()[0]
    rows = []
    for what, case in CASES:
        argv = [python, *case] if what.startswith("floor") else [str(args.tcbench), *case]
        times, cpus, answer = [], [], ""
        for _ in range(args.repeats):
            wall, cpu, done = once(argv)
            answer = checked(what, case, done)
            times.append(wall)
            cpus.append(cpu)
        rows.append({"what": what, "command": " ".join(case) if not what.startswith("floor") else what.split(": ")[1],
                     "median_s": statistics.median(times), "min_s": min(times), "max_s": max(times),
                     "median_cpu_s": statistics.median(cpus), "answer": answer, "times_s": times, "cpu_s": cpus})
        print(f"{rows[-1]['command']}: {rows[-1]['median_s']:.2f} s", file=sys.stderr, flush=True)
    load = (load_start, os.getloadavg()[0])
    libraries = versions("tcbench", "hydra-core", "omegaconf", "mlflow", "numpy", "gymnasium")
    print(f"## tcbench command line: --help and one-line errors, median of {args.repeats} fresh processes\n")
    print(f"Command: `{command_line()}` (script {args.tcbench})\n")
    print(f"Machine: {platform.platform()}, {os.cpu_count()} cores; "
          + ", ".join(f"{k} {v}" for k, v in libraries.items())
          + f"; 1-min load average {load[0]:.1f} at the start, {load[1]:.1f} at the end.\n")
    print("\n".join(table_head(["command", "kind", "median wall (s)", "min-max (s)", "median CPU (s)",
                                f"wall < {TARGET_S:g} s", "answer"], "llrrrll")))
    for r in rows:
        target = "" if r["what"].startswith("floor") else "met" if r["median_s"] < TARGET_S else "**not met**"
        print(table_row([f"`{r['command']}`", r["what"], f"{r['median_s']:.2f}", f"{r['min_s']:.2f}-{r['max_s']:.2f}",
                         f"{r['median_cpu_s']:.2f}", target, r["answer"][:90].replace("|", "\\|")]))
    write_json(args.json, {"benchmark": "cli_latency", "command": command_line(), "script": str(args.tcbench),
                           "repeats": args.repeats, "versions": libraries, "platform": platform.platform(),
                           "cpus": os.cpu_count(), "load_average": load, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
