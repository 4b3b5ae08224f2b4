"""Benchmark tcbench's percentile bootstraps against ``scipy.stats.bootstrap``: same intervals? how fast?

tcbench has two hand-written bootstraps: :func:`tcbench.stats.bootstrap_median_ci` (the median
over seeds, a leaderboard's ``ci95``; failed runs are ``±inf`` values) and
:func:`tcbench.compensation.holdout.ratio_interval` (the ratio of two methods' held-out drifts
over resampled blocks, both methods on the same draws). Each is compared with the scipy call that
does the same thing, at equal work (same data, 2000 resamples, the same seed):

- median: ``scipy.stats.bootstrap((x,), np.median, method="percentile", n_resamples=2000,
  rng=np.random.default_rng(seed), vectorized=True)`` on the sorted, NaN-free values tcbench
  resamples;
- ratio: the same call with ``paired=True`` on ``(squares_a, squares_b, counts)`` and the ratio
  statistic written as tcbench writes it.

Identity is checked on ``--samples`` random samples shaped like a board's (2 to 60 values; normal,
log-normal, rounded and small-integer values, so ties; a third with failed runs as ``+inf`` or
``-inf``; some NaN) and ``--ratio-samples`` random block sums: (a) scipy's interval against
tcbench's, bit for bit; (b) tcbench's interval against tcbench's percentile rule applied to scipy's
``bootstrap_distribution``, which shows whether the resamples themselves are the same. Timing:
best of ``--repeats`` wall and CPU times of ``--calls`` calls, per call, at 5, 30 and 100 values.

Usage::

    python benchmarks/bootstrap_vs_scipy.py --samples 20000 --repeats 7
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import scipy
from common import add_json, blas_threads, command_line, parser_for, print_heading, table_head, table_row, versions, write_json
from scipy import stats

from tcbench.compensation.holdout import DRAWS, LEVEL, BlockSums, ratio_interval
from tcbench.stats import BOOTSTRAP_SEED, bootstrap_median_ci, percentiles

N_BOOT = 2000
DEFAULT_JSON = Path(__file__).with_name("bootstrap_vs_scipy.json")


def scipy_median(x: np.ndarray, seed: int = BOOTSTRAP_SEED) -> Any:
    """scipy's percentile bootstrap of the median on the values tcbench resamples."""
    x = np.sort(np.asarray(x, dtype=float))
    x = x[~np.isnan(x)]
    with warnings.catch_warnings():  # inf values: scipy warns (invalid values, degenerate interval)
        warnings.simplefilter("ignore")
        return stats.bootstrap((x,), np.median, method="percentile", n_resamples=N_BOOT,
                               rng=np.random.default_rng(seed), vectorized=True)


def _ratio(a: np.ndarray, b: np.ndarray, c: np.ndarray, axis: int = -1) -> np.ndarray:
    n = c.sum(axis=axis)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(a.sum(axis=axis) / n) / np.sqrt(b.sum(axis=axis) / n)


def scipy_ratio(sums: BlockSums, seed: int = 0) -> Any:
    """scipy's paired percentile bootstrap of tcbench's drift ratio over blocks."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return stats.bootstrap((sums.squares["a"], sums.squares["b"], sums.counts), _ratio, paired=True,
                               method="percentile", n_resamples=DRAWS, confidence_level=LEVEL,
                               rng=np.random.default_rng(seed), vectorized=True)


def board_sample(g: np.random.Generator) -> np.ndarray:
    """Values like one method's over seeds: ties, failed runs (±inf) and NaN in some."""
    n = int(g.integers(2, 61))
    kind = int(g.integers(4))
    x = [g.normal(size=n), g.lognormal(size=n), np.round(g.lognormal(size=n), 1),
         g.integers(0, 4, n).astype(float)][kind]
    if g.random() < 1 / 3:
        x[g.choice(n, int(g.integers(1, n + 1)), replace=False)] = np.inf if g.random() < 0.5 else -np.inf
    if g.random() < 0.1:
        x[g.choice(n, int(g.integers(1, max(2, n // 4))), replace=False)] = np.nan
    return x


def block_sample(g: np.random.Generator) -> BlockSums:
    """Held-out block sums of two methods like :func:`tcbench.compensation.holdout.block_sums`'."""
    nb = int(g.integers(2, 61))
    counts = g.integers(50, 200, nb)
    return BlockSums({"a": g.chisquare(3, nb) * counts, "b": g.chisquare(3, nb) * counts * g.uniform(0.5, 4)},
                     counts, 10.0)


def same(p: tuple[float, float], q: tuple[float, float]) -> bool:
    """Bit-identical pairs (NaN equal to NaN)."""
    return bool(np.array_equal(np.asarray(p, float), np.asarray(q, float), equal_nan=True))


def check_median(samples: int) -> dict[str, float | int]:
    """Counts of identical and differing median intervals over ``samples`` board-like samples."""
    g = np.random.default_rng(0)
    out = {"samples": 0, "finite": 0, "scipy_interval_identical": 0, "scipy_interval_identical_finite": 0,
           "scipy_nan_where_tcbench_not": 0, "max_rel_diff_finite": 0.0, "distribution_identical": 0}
    tail = 100.0 * (1.0 - 0.95) / 2.0
    for _ in range(samples):
        x = board_sample(g)
        if np.count_nonzero(~np.isnan(x)) < 2:
            continue
        ours = bootstrap_median_ci(x)
        res = scipy_median(x)
        theirs = (float(res.confidence_interval.low), float(res.confidence_interval.high))
        from_dist = tuple(float(v) for v in percentiles(res.bootstrap_distribution, [tail, 100.0 - tail]))
        finite = bool(np.all(np.isfinite(ours)))
        out["samples"] += 1
        out["finite"] += finite
        out["scipy_interval_identical"] += same(ours, theirs)
        out["distribution_identical"] += same(ours, from_dist)
        out["scipy_nan_where_tcbench_not"] += bool(np.any(np.isnan(theirs) & ~np.isnan(ours)))
        if finite:
            out["scipy_interval_identical_finite"] += same(ours, theirs)
            rel = np.abs(np.subtract(theirs, ours)) / np.maximum(np.abs(ours), 1e-300)
            out["max_rel_diff_finite"] = max(out["max_rel_diff_finite"], float(np.max(rel)))
    return out


def check_ratio(samples: int) -> dict[str, float | int]:
    """The same counts for the drift-ratio interval over ``samples`` random block sums."""
    g = np.random.default_rng(1)
    out = {"samples": samples, "scipy_interval_identical": 0, "max_rel_diff": 0.0, "distribution_identical": 0}
    for _ in range(samples):
        sums = block_sample(g)
        _, lo, hi = ratio_interval(sums, "a", "b", seed=0)
        res = scipy_ratio(sums, seed=0)
        theirs = (float(res.confidence_interval.low), float(res.confidence_interval.high))
        from_dist = tuple(float(v) for v in np.nanquantile(res.bootstrap_distribution, [(1 - LEVEL) / 2, (1 + LEVEL) / 2]))
        out["scipy_interval_identical"] += same((lo, hi), theirs)
        out["distribution_identical"] += same((lo, hi), from_dist)
        out["max_rel_diff"] = max(out["max_rel_diff"], float(np.max(np.abs(np.subtract(theirs, (lo, hi))) / np.abs((lo, hi)))))
    return out


def per_call_s(fn: Callable[[], object], calls: int, repeats: int) -> tuple[float, float]:
    """Best of ``repeats`` wall and CPU times of ``calls`` calls of ``fn``, per call (s)."""
    wall, cpu = np.inf, np.inf
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        for _ in range(calls):
            fn()
        wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
    return wall / calls, cpu / calls


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--samples", type=int, default=20_000, help="random samples for the median check")
    parser.add_argument("--ratio-samples", type=int, default=2_000, help="random block sums for the ratio check")
    parser.add_argument("--calls", type=int, default=50)
    parser.add_argument("--repeats", type=int, default=7)
    add_json(parser, DEFAULT_JSON, help_text=None)
    args = parser.parse_args(argv)

    print_heading("Percentile bootstraps: tcbench against scipy.stats.bootstrap", command_line(argv),
                  versions("numpy", "scipy", "tcbench"))
    print(f"BLAS (default thread settings, nothing forced): {blas_threads()}.\n")
    median = check_median(args.samples)
    ratio = check_ratio(args.ratio_samples)
    print("\n".join(table_head(["interval", "samples", "scipy's interval bit-identical", "of which all finite",
                                "scipy NaN where tcbench is not", "largest relative difference (finite)",
                                "tcbench = its rule on scipy's resampled statistics"], "lrrrrrr")))
    print(table_row(["median (bootstrap_median_ci)", median["samples"], median["scipy_interval_identical"],
                     f"{median['scipy_interval_identical_finite']} of {median['finite']}",
                     median["scipy_nan_where_tcbench_not"], f"{median['max_rel_diff_finite']:.1e}",
                     median["distribution_identical"]]))
    print(table_row(["drift ratio (ratio_interval)", ratio["samples"], ratio["scipy_interval_identical"],
                     f"{ratio['scipy_interval_identical']} of {ratio['samples']}", "–",
                     f"{ratio['max_rel_diff']:.1e}", ratio["distribution_identical"]]))

    timings = []
    g = np.random.default_rng(2)
    for n in (5, 30, 100):
        x = g.lognormal(size=n)
        sums = BlockSums({"a": g.chisquare(3, n) * 100, "b": g.chisquare(3, n) * 200}, np.full(n, 100), 10.0)
        cases = {
            "median": (lambda x=x: bootstrap_median_ci(x), lambda x=x: scipy_median(x)),
            "drift ratio": (lambda s=sums: ratio_interval(s, "a", "b"), lambda s=sums: scipy_ratio(s)),
        }
        for name, (ours, theirs) in cases.items():
            ours(), theirs()  # warm-up
            (w_o, c_o), (w_s, c_s) = (per_call_s(f, args.calls, args.repeats) for f in (ours, theirs))
            timings.append({"interval": name, "n": n, "tcbench_wall_s": w_o, "tcbench_cpu_s": c_o,
                            "scipy_wall_s": w_s, "scipy_cpu_s": c_s, "ratio_wall": w_s / w_o, "ratio_cpu": c_s / c_o})
    print()
    print("\n".join(table_head(["interval", "values (blocks)", "tcbench ms / call, wall (CPU)",
                                "scipy ms / call, wall (CPU)", "scipy / tcbench, wall", "scipy / tcbench, CPU"],
                               "lrrrrr")))
    for t in timings:
        print(table_row([t["interval"], t["n"], f"{1e3 * t['tcbench_wall_s']:.2f} ({1e3 * t['tcbench_cpu_s']:.2f})",
                         f"{1e3 * t['scipy_wall_s']:.2f} ({1e3 * t['scipy_cpu_s']:.2f})",
                         f"**{t['ratio_wall']:.2f}x**", f"{t['ratio_cpu']:.2f}x"]))
    write_json(args.json, {"benchmark": "bootstrap_vs_scipy", "command": command_line(argv),
                           "versions": versions("numpy", "scipy", "tcbench"), "scipy": scipy.__version__,
                           "median": median, "ratio": ratio, "timings": timings})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
