"""Pieces shared by the benchmark scripts: command line, versions and machine, markdown tables,
the JSON result, medians, timing and the ``--seeds``/``--json`` options.

The scripts run as files (``python benchmarks/<name>.py``), which puts this folder first on
``sys.path``, so they import this module as ``common``.

Only the standard library and numpy are imported here: ``simulate_gyro_24h.py`` measures the
resident memory of child processes after their imports, so this module must not pull in more
(``statistics`` is therefore imported inside the helpers that need it).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shlex
import sys
import time
import tracemalloc
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from dataclasses import asdict
from importlib.metadata import version
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np

MIN_SEEDS = 5
DEFAULT_CASES = ("rastrigin-10", "rastrigin-30", "sphere-10", "sphere-30")


class Run(Protocol):
    """What :func:`groups` and :func:`brief` read from a run (a frozen dataclass)."""

    @property
    def method(self) -> str: ...

    @property
    def seconds(self) -> float: ...


class BestRun(Run, Protocol):
    """A single-objective run: also its best value and evaluation count."""

    @property
    def best(self) -> float: ...

    @property
    def evaluations(self) -> int: ...


R = TypeVar("R", bound=Run)
B = TypeVar("B", bound=BestRun)
T = TypeVar("T")


# --- command line ---------------------------------------------------------------------------


def parser_for(doc: str) -> argparse.ArgumentParser:
    """An argument parser described by the first line of the script's docstring."""
    return argparse.ArgumentParser(description=doc.split("\n", 1)[0])


def add_seeds(parser: argparse.ArgumentParser) -> None:
    """``--seeds N``: seeds 0..N-1, at least :data:`MIN_SEEDS` (see :func:`check_seeds`)."""
    parser.add_argument("--seeds", type=int, default=MIN_SEEDS,
                        help=f"number of seeds (>= {MIN_SEEDS}), 0..N-1")


def add_json(parser: argparse.ArgumentParser, default: Path,
             help_text: str | None = "where to write results") -> None:
    """``--json PATH``: where the JSON result goes."""
    parser.add_argument("--json", type=Path, default=default, help=help_text)


def add_cases(parser: argparse.ArgumentParser) -> None:
    """``--cases``: function-dimension pairs (see :func:`parse_case`)."""
    parser.add_argument("--cases", nargs="+", default=list(DEFAULT_CASES),
                        help="function-dimension pairs, e.g. rastrigin-10 sphere-30")


def check_seeds(parser: argparse.ArgumentParser, seeds: int) -> None:
    """Stop with a usage error when fewer than :data:`MIN_SEEDS` seeds are asked for."""
    if seeds < MIN_SEEDS:
        parser.error(f"--seeds must be >= {MIN_SEEDS}")


def check_each(parser: argparse.ArgumentParser, values: Iterable[str],
               check: Callable[[str], object],
               errors: tuple[type[Exception], ...] = (ValueError,)) -> None:
    """Stop with a usage error on the first value that ``check`` rejects with ``errors``."""
    for value in values:
        try:
            check(value)
        except errors as err:
            parser.error(str(err))


def parse_case(case: str, known: Collection[str]) -> tuple[str, int]:
    """``"rastrigin-10"`` -> ``("rastrigin", 10)``; the name must be one of ``known``."""
    name, dim = case.rsplit("-", 1)
    if name not in known:
        raise ValueError(f"unknown function {name!r}; known: {', '.join(known)}")
    return name, int(dim)


def parse_case_args(doc: str, default_json: Path, known: Collection[str],
                    argv: Sequence[str] | None = None) -> argparse.Namespace:
    """``--seeds``, ``--cases`` and ``--json``, checked, for a single-objective benchmark."""
    parser = parser_for(doc)
    add_seeds(parser)
    add_cases(parser)
    add_json(parser, default_json)
    args = parser.parse_args(argv)
    check_seeds(parser, args.seeds)
    check_each(parser, args.cases, lambda case: parse_case(case, known))
    return args


def command_line(argv: Sequence[str] | None = None) -> str:
    """The command for the report: ``python`` and ``sys.argv``, or ``argv`` when given."""
    return shlex.join(["python", *sys.argv]) if argv is None else shlex.join(argv)


# --- versions and machine -------------------------------------------------------------------


def versions(*distributions: str) -> dict[str, str]:
    """Python's version, then each installed distribution's."""
    return {"python": platform.python_version(), **{d: version(d) for d in distributions}}


def environment(*libraries: str, **extra: str) -> dict[str, str | int | None]:
    """Python, numpy, the peer ``libraries``, ``extra`` entries, tcbench, platform and CPUs."""
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        **{lib: version(lib) for lib in libraries},
        **extra,
        "tcbench": version("tcbench"),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
    }


def pymoo_environment() -> dict[str, str | int | None]:
    """:func:`environment` with pymoo and whether its compiled extensions are in use."""
    from pymoo.functions import is_compiled

    return environment("pymoo", pymoo_compiled=str(is_compiled()))


def pymoo_versions(env: dict[str, Any]) -> str:
    """The pymoo part of :func:`environment_line`."""
    return f"pymoo {env['pymoo']} (compiled extensions: {env['pymoo_compiled']})"


def environment_line(env: dict[str, Any], libraries: str) -> str:
    """One sentence of versions and machine; ``libraries`` names the peers' versions."""
    return (
        f"Python {env['python']}, numpy {env['numpy']}, {libraries}, tcbench {env['tcbench']}; "
        f"{env['platform']}, {env['cpus']} CPUs."
    )


def footer(env: dict[str, Any], libraries: str, command: str) -> list[str]:
    """The closing lines of an optimiser report: versions and machine, then the command."""
    return ["", environment_line(env, libraries), "", f"Command: `{command}`"]


def print_heading(title: str, command: str, versions: dict[str, str]) -> None:
    """Title, command and machine paragraph that open a signal-processing report."""
    print(f"## {title}\n")
    print(f"Command: `{command}`\n")
    print(
        f"Machine: {platform.system()} {platform.machine()}, {os.cpu_count()} cores; "
        + ", ".join(f"{k} {v}" for k, v in versions.items())
        + "\n"
    )


# --- markdown -------------------------------------------------------------------------------


def table_row(cells: Iterable[object]) -> str:
    """One markdown table row."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def table_head(columns: Sequence[str], align: str) -> list[str]:
    """Header and rule of a markdown table; ``align`` holds ``l`` or ``r`` for each column."""
    if len(align) != len(columns):
        raise ValueError(f"{len(columns)} columns but {len(align)} alignments")
    rule = "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"
    return [table_row(columns), rule]


def case_columns(method_title: str) -> list[str]:
    """The first columns of a single-objective table (see :func:`case_cells`)."""
    return ["problem", method_title, "median wall time (s)", "time / tcbench",
            "median final best", "best .. worst seed", "evaluations"]


def case_cells(row: dict[str, Any], labels: dict[str, str]) -> list[str]:
    """The first cells of a single-objective table row; ``labels`` titles the methods."""
    return [
        row["case"], labels[row["method"]], f"{row['median_seconds']:.3f}",
        f"{row['time_ratio_vs_tcbench']:.1f}x", f"{row['median_best']:.4g}",
        f"{row['min_best']:.3g} .. {row['max_best']:.3g}", f"{row['evaluations']:.0f}",
    ]


def objective_list(objective_s: dict[str, float]) -> str:
    """``case time ms, ...`` for the objective-alone sentence."""
    return ", ".join(f"{c} {1e3 * s:.1f} ms" for c, s in objective_s.items())


# --- results --------------------------------------------------------------------------------


def progress(text: str) -> None:
    """A progress line on stderr (stdout holds the report)."""
    print(text, file=sys.stderr, flush=True)


def brief(run: BestRun) -> str:
    """A run in a few words for a progress line."""
    return f"{run.method} {run.seconds:.3f}s f={run.best:.4g} ({run.evaluations} ev)"


def run_cases(cases: Iterable[str], seeds: int, run: Callable[[str, int], list[B]]) -> list[B]:
    """``run(case, seed)`` for every case and seed 0..seeds-1, one progress line each."""
    runs: list[B] = []
    for case in cases:
        for seed in range(seeds):
            batch = run(case, seed)
            runs += batch
            progress(f"{case} seed {seed}: " + " | ".join(brief(r) for r in batch))
    return runs


def groups(
    runs: Sequence[R], key: str, methods: Iterable[str]
) -> Iterator[tuple[str, str, list[R]]]:
    """``(value of key, method, runs)`` in first-seen order of ``key`` and ``methods``' order;
    combinations without runs are skipped."""
    methods = list(methods)
    for value in dict.fromkeys(getattr(r, key) for r in runs):
        for method in methods:
            mine = [r for r in runs if getattr(r, key) == value and r.method == method]
            if mine:
                yield value, method, mine


def median_of(runs: Iterable[object], field: str) -> float:
    """Median of one attribute over ``runs``."""
    import statistics

    return statistics.median(getattr(r, field) for r in runs)


def spread(values: Sequence[float], name: str) -> dict[str, float]:
    """``median_<name>``, ``min_<name>`` and ``max_<name>`` of ``values``."""
    import statistics

    return {f"median_{name}": statistics.median(values), f"min_{name}": min(values),
            f"max_{name}": max(values)}


def add_time_ratio(rows: list[dict[str, Any]], key: str = "case",
                   reference: str = "tcbench") -> list[dict[str, Any]]:
    """Add ``time_ratio_vs_tcbench``: each row's median time over the reference method's."""
    ref = {row[key]: row["median_seconds"] for row in rows if row["method"] == reference}
    for row in rows:
        row["time_ratio_vs_tcbench"] = row["median_seconds"] / ref[row[key]]
    return rows


def write_json(path: Path, data: object, final_newline: bool = True) -> None:
    """``data`` as indented JSON."""
    path.write_text(json.dumps(data, indent=2) + ("\n" if final_newline else ""))


def write_report(path: Path, benchmark: str, setup: dict[str, Any], seeds: int, command: str,
                 env: dict[str, Any], results: dict[str, Any], runs: Iterable[Any]) -> None:
    """The JSON result of an optimiser benchmark: name, ``setup``, seeds, command, environment,
    ``results`` and every run (dataclasses)."""
    write_json(path, {
        "benchmark": benchmark,
        **setup,
        "seeds": list(range(seeds)),
        "command": command,
        "environment": env,
        **results,
        "runs": [asdict(r) for r in runs],
    })


# --- timing and memory ----------------------------------------------------------------------


def best_time_s(fn: Callable[[], object], repeats: int) -> float:
    """Best of ``repeats`` wall times of ``fn()``."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def wall_times_s(fn: Callable[[], T], repeats: int) -> tuple[list[float], T]:
    """All ``repeats`` wall times of ``fn()`` (s) and its last return value."""
    times: list[float] = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return times, value


def blas_threads() -> str:
    """``library version (api) N threads`` for every thread pool loaded (threadpoolctl)."""
    from threadpoolctl import threadpool_info

    return "; ".join(
        f"{p['internal_api']} {p.get('version')} ({p['user_api']}) {p['num_threads']} threads"
        for p in threadpool_info()
    )


def objective_seconds(fn: Callable[[Any], object], x: Any, calls: int, repeats: int) -> float:
    """Best of ``repeats`` wall times of ``calls`` evaluations ``fn(x)`` in a bare loop."""

    def loop() -> None:
        for _ in range(calls):
            fn(x)

    return best_time_s(loop, repeats)


def peak_mib(fn: Callable[[], object]) -> float:
    """Peak traced allocation during one ``fn()`` call, MiB."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20
