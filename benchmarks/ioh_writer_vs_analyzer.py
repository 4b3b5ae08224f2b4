"""Benchmark tcbench's IOHprofiler writer against ``ioh.logger.Analyzer``, side by side, same evaluations.

tcbench writes IOHprofiler's format itself (:mod:`tcbench.leaderboard.iohprofiler`,
``RunLogger``) from the batches its ask/tell loop evaluates. The alternative is to let every
evaluation pass through an ioh problem with ``ioh.logger.Analyzer`` attached. At equal work, the
same ``--evaluations`` points (batches of ``--batch``, a random search closing in on the optimum,
so that improvements of all sizes are logged) are evaluated and logged, files written at the end,
best of ``--repeats``:

- BBOB (``ioh.get_problem(f, instance, dim)``, the problem tcbench's BBOB task already calls on
  a whole batch): bare evaluation; with the Analyzer attached; bare evaluation plus
  ``RunLogger.record`` per batch and ``RunLogger.close``. Both logs are compared line by line.
- a tcbench function (Rastrigin, not an ioh problem): tcbench's vectorised function plus
  ``RunLogger``, against ``ioh.wrap_problem`` of the same function with the Analyzer attached,
  which calls the function once per point.

Then one short run with NaN values shows what each writes where the formats differ.

Usage::

    python benchmarks/ioh_writer_vs_analyzer.py --evaluations 100000 --repeats 5
"""

from __future__ import annotations

import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import ioh
import numpy as np
from common import add_json, blas_threads, command_line, parser_for, print_heading, table_head, table_row, versions, write_json

from tcbench.leaderboard.iohprofiler import ProblemMeta, RunLogger
from tcbench.tasks.functions import rastrigin

DEFAULT_JSON = Path(__file__).with_name("ioh_writer_vs_analyzer.json")


def points(evaluations: int, batch: int, dim: int, x_opt: np.ndarray, seed: int = 0) -> np.ndarray:
    """``(evaluations // batch, batch, dim)`` points closing in on ``x_opt`` within [-5, 5]."""
    g = np.random.default_rng(seed)
    n = evaluations // batch
    scale = 5.0 * 0.5 ** np.linspace(0.0, 30.0, n)[:, None, None]
    return np.clip(x_opt + scale * g.normal(size=(n, batch, dim)), -5.0, 5.0)


def best_s(fn: Callable[[Path], object], repeats: int) -> tuple[float, float]:
    """Best wall and CPU seconds of ``fn(folder)`` over ``repeats``, each in a fresh folder."""
    wall, cpu = np.inf, np.inf
    for _ in range(repeats):
        folder = Path(tempfile.mkdtemp(prefix="ioh-bench-"))
        try:
            w0, c0 = time.perf_counter(), time.process_time()
            fn(folder)
            wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    return wall, cpu


def bbob_runs(fid: int, dim: int, xs: np.ndarray) -> dict[str, Callable[[Path], object]]:
    """The three BBOB runs over the batches ``xs`` (each writing into the folder it is given)."""

    def problem() -> ioh.ProblemType:
        return ioh.get_problem(fid, 1, dim, ioh.ProblemClass.BBOB)

    def bare(_: Path) -> None:
        p = problem()
        for x in xs:
            p(x)

    def analyzer(folder: Path) -> None:
        p = problem()
        log = ioh.logger.Analyzer(root=str(folder), folder_name="ioh", algorithm_name="rs")
        p.attach_logger(log)
        for x in xs:
            p(x)
        p.reset()
        log.close()

    def tcbench(folder: Path) -> None:
        p = problem()
        f_opt = float(p.optimum.y)
        meta = ProblemMeta("BBOB", fid, str(p.meta_data.name), dim, 1)
        log = RunLogger(folder / "tcbench", meta, "rs", seed=0)
        for x in xs:
            log.record(x, np.asarray(p(x)) - f_opt)
        log.close()

    return {"bare": bare, "analyzer": analyzer, "tcbench": tcbench}


def function_runs(dim: int, xs: np.ndarray) -> dict[str, Callable[[Path], object]]:
    """tcbench's Rastrigin logged by tcbench, and through ``ioh.wrap_problem`` by the Analyzer."""

    def one(x: np.ndarray) -> float:
        return float(rastrigin(np.asarray(x)[None, :])[0])

    def bare(_: Path) -> None:
        for x in xs:
            rastrigin(x)

    def analyzer(folder: Path) -> None:
        p = ioh.wrap_problem(one, name="tcbench_rastrigin", dimension=dim, instance=1, lb=-5.12, ub=5.12)
        log = ioh.logger.Analyzer(root=str(folder), folder_name="ioh", algorithm_name="rs")
        p.attach_logger(log)
        for x in xs:
            p(x)
        p.reset()
        log.close()

    def tcbench(folder: Path) -> None:
        log = RunLogger(folder / "tcbench", ProblemMeta("tcbench", 102, "Rastrigin", dim, 1), "rs", seed=0)
        for x in xs:
            log.record(x, rastrigin(x))
        log.close()

    return {"bare": bare, "analyzer": analyzer, "tcbench": tcbench}


def same_dat(runs: dict[str, Callable[[Path], object]]) -> tuple[bool, int]:
    """Whether the Analyzer's and tcbench's ``.dat`` are identical, and their line count."""
    folder = Path(tempfile.mkdtemp(prefix="ioh-bench-"))
    try:
        runs["analyzer"](folder)
        runs["tcbench"](folder)
        theirs = next((folder / "ioh").rglob("*.dat")).read_text()
        ours = next((folder / "tcbench").rglob("*.dat")).read_text()
        return theirs == ours, ours.count("\n")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def nan_run() -> dict[str, str]:
    """Five points, NaN at the first, third and fifth, evaluated and logged by each writer."""
    xs = np.array([[0.9, 0.0], [0.2, 0.2], [0.9, 0.1], [0.1, 0.1], [0.8, 0.0]])

    def f(x: np.ndarray) -> float:
        return float("nan") if x[0] > 0.5 else float(np.sum(np.square(x)))

    folder = Path(tempfile.mkdtemp(prefix="ioh-bench-"))
    try:
        p = ioh.wrap_problem(f, name="nan_example", dimension=2, instance=1, lb=-1, ub=1)
        log = ioh.logger.Analyzer(root=str(folder), folder_name="ioh", algorithm_name="rs")
        p.attach_logger(log)
        p(xs)
        p.reset()
        log.close()
        ours = RunLogger(folder / "tcbench", ProblemMeta("tcbench", 101, "Example", 2, 1), "rs", seed=0)
        ours.record(xs, np.array([f(x) for x in xs]))
        ours.close()
        return {k: next((folder / k).rglob("*.dat")).read_text() for k in ("ioh", "tcbench")}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--evaluations", type=int, default=100_000)
    parser.add_argument("--batch", type=int, default=40, help="points per evaluated batch (a population)")
    parser.add_argument("--dim", type=int, default=5)
    parser.add_argument("--function", type=int, default=3, help="BBOB function id")
    parser.add_argument("--repeats", type=int, default=5)
    add_json(parser, DEFAULT_JSON, help_text=None)
    args = parser.parse_args(argv)

    print_heading("IOHprofiler logs: tcbench's writer against ioh.logger.Analyzer", command_line(argv),
                  versions("numpy", "ioh", "tcbench"))
    print(f"BLAS (default thread settings, nothing forced): {blas_threads()}.\n")
    x_opt = np.asarray(ioh.get_problem(args.function, 1, args.dim, ioh.ProblemClass.BBOB).optimum.x)
    cases = {
        f"BBOB f{args.function}, {args.dim}-D": bbob_runs(args.function, args.dim,
                                                          points(args.evaluations, args.batch, args.dim, x_opt)),
        f"tcbench Rastrigin, {args.dim}-D": function_runs(args.dim, points(args.evaluations, args.batch, args.dim,
                                                                           np.zeros(args.dim))),
    }
    rows = []
    for name, runs in cases.items():
        identical, lines = same_dat(runs)
        t = {k: best_s(fn, args.repeats) for k, fn in runs.items()}
        (b_w, b_c), (a_w, a_c), (o_w, o_c) = t["bare"], t["analyzer"], t["tcbench"]
        rows.append({"case": name, "evaluations": args.evaluations // args.batch * args.batch, "dat_lines": lines,
                     "dat_identical": identical, "bare_wall_s": b_w, "bare_cpu_s": b_c, "analyzer_wall_s": a_w,
                     "analyzer_cpu_s": a_c, "tcbench_wall_s": o_w, "tcbench_cpu_s": o_c,
                     "ratio_wall": a_w / o_w, "ratio_cpu": a_c / o_c,
                     "logging_ratio_cpu": (a_c - b_c) / max(o_c - b_c, 1e-9)})
    scale = 1e5 / rows[0]["evaluations"]
    print("\n".join(table_head(["evaluations of", "evaluation alone, s / 1e5 (CPU)", "ioh Analyzer, s / 1e5 (CPU)",
                                "tcbench RunLogger, s / 1e5 (CPU)", "Analyzer / tcbench, wall", "Analyzer / tcbench, CPU",
                                "logging alone, Analyzer / tcbench (CPU)", ".dat identical (lines)"], "lrrrrrrr")))
    for r in rows:
        print(table_row([r["case"], f"{scale * r['bare_wall_s']:.3f} ({scale * r['bare_cpu_s']:.3f})",
                         f"{scale * r['analyzer_wall_s']:.3f} ({scale * r['analyzer_cpu_s']:.3f})",
                         f"{scale * r['tcbench_wall_s']:.3f} ({scale * r['tcbench_cpu_s']:.3f})",
                         f"**{r['ratio_wall']:.2f}x**", f"{r['ratio_cpu']:.2f}x", f"{r['logging_ratio_cpu']:.2f}x",
                         f"{'yes' if r['dat_identical'] else 'no'} ({r['dat_lines']})"]))
    nan = nan_run()
    print("\nNaN at evaluations 1, 3 and 5 (values nan, 0.08, nan, 0.02, nan):\n")
    for k, text in nan.items():
        print(f"{k}:\n\n```\n{text}```\n")
    write_json(args.json, {"benchmark": "ioh_writer_vs_analyzer", "command": command_line(argv),
                           "versions": versions("numpy", "ioh", "tcbench"), "batch": args.batch, "dim": args.dim,
                           "repeats": args.repeats, "cases": rows, "nan_example": nan})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
