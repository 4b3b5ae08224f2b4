"""What composing one job's config costs, with Hydra's ConfigStore copied at every compose and shared.

Hydra 1.3 deep-copies its config repository at every compose, and with it the ConfigStore its
structured source holds (every command schema tcbench registers, and Hydra's own); tcbench makes
a copy of the store the store itself (``tcbench/runner/schema.py``). Each row is a fresh process
that imports tcbench's app (registering the schemas), composes a job once to warm up, then times
``--composes`` composes of the same job (``tcbench.cli.app.compose_job``: Hydra's compose and
tcbench's checks) and reports the median time per compose over ``--repeats`` such blocks. The two
ways alternate, so both see the machine at the same moments. The composed configs must be equal.

Usage::

    python benchmarks/compose_speed.py --repeats 5 --composes 40
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
from pathlib import Path

from common import add_json, blas_threads, command_line, parser_for, table_head, table_row, versions, write_json

DEFAULT_JSON = Path(__file__).with_name("compose_speed.json")
JOB = ["task=msra_zerobias", "optimiser=ifa", "learner=bp"]
WAYS = ("copied", "shared")

CHILD = """
import hashlib, json, sys, time
from hydra import initialize_config_module
from hydra.core.config_store import ConfigStore
from tcbench.cli.app import compose_job
from tcbench.config_dir import CONFIG_MODULE
way, n, job = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
if way == "copied":  # Hydra's own behaviour: a deep copy of every schema at every compose
    del ConfigStore.__deepcopy__
with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
    cfg = compose_job(job)
    start = time.perf_counter()
    for _ in range(n):
        cfg = compose_job(job)
    ms = (time.perf_counter() - start) / n * 1e3
print(json.dumps({"ms": ms, "config": hashlib.sha256(repr(cfg).encode()).hexdigest()}))
"""


def _block(way: str, composes: int) -> dict[str, object]:
    """One fresh process composing the job ``composes`` times the given way."""
    out = subprocess.run([sys.executable, "-c", CHILD, way, str(composes), *JOB], check=True,
                         capture_output=True, text=True, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = parser_for(__doc__ or "")
    parser.add_argument("--repeats", type=int, default=5, help="fresh processes per way (default 5)")
    parser.add_argument("--composes", type=int, default=40, help="composes timed per process (default 40)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args()
    if args.repeats < 1 or args.composes < 1:
        parser.error("--repeats and --composes must be >= 1")
    blocks: dict[str, list[dict[str, object]]] = {way: [] for way in WAYS}
    for _ in range(args.repeats):
        for way in WAYS:
            blocks[way].append(_block(way, args.composes))
    configs = {str(b["config"]) for way in WAYS for b in blocks[way]}
    if len(configs) != 1:
        raise SystemExit("the two ways composed different configs")
    rows = []
    for way in WAYS:
        ms = [float(str(b["ms"])) for b in blocks[way]]
        rows.append({"way": way, "median_ms": statistics.median(ms), "min_ms": min(ms), "max_ms": max(ms)})
    ratio = rows[0]["median_ms"] / rows[1]["median_ms"]
    env = {"machine": f"{platform.system()} {platform.machine()}, {os.cpu_count()} cores",
           "python": platform.python_version(), "blas_threads": blas_threads(),
           "load_1min": round(os.getloadavg()[0], 1), **versions("hydra-core", "omegaconf", "tcbench")}
    print(f"# One job's compose ({' '.join(JOB)}), {args.composes} composes x {args.repeats} processes per way\n")
    for line in table_head(["ConfigStore at each compose", "median ms", "range ms"], "lrr"):
        print(line)
    for r in rows:
        print(table_row([r["way"], f"{r['median_ms']:.1f}", f"{r['min_ms']:.1f}-{r['max_ms']:.1f}"]))
    print(f"\ncopied / shared: {ratio:.2f}x (same configs: yes)\n")
    print("; ".join(f"{k} {v}" for k, v in env.items()))
    print(f"\nCommand: `{command_line()}`")
    write_json(args.json, {"rows": rows, "ratio_copied_over_shared": ratio, "environment": env,
                           "composes": args.composes, "repeats": args.repeats, "job": JOB})


if __name__ == "__main__":
    main()
