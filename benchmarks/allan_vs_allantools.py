"""Benchmark tcbench's overlapping Allan deviation against ``allantools.oadev``.

One signal, white rate noise plus a rate random walk sampled at 100 Hz (10^6 samples by
default, seed 0), is analysed by both libraries in this one process on two tau sets: tcbench's
"octave" set (m = 1, 2, 4, ... <= (N - 1) // 2) and its "decade" set (about 10 log-spaced m per
decade). allantools gets the very same tau values in seconds
(``allantools.oadev(rate, rate=fs, data_type="freq", taus=tau_s)``), so both compute the same
statistic at the same m.

For each library and tau set we report the best of ``--repeats`` wall times
(``time.perf_counter``), the ratio allantools / tcbench (target >= 2x) and the largest relative
difference between the two deviation curves. Peak Python-heap memory of one call (tracemalloc,
which sees numpy's buffers) is measured in a separate pass, since tracing slows the calls.

Usage::

    python benchmarks/allan_vs_allantools.py --samples 1000000 --repeats 5
"""

from __future__ import annotations

from pathlib import Path

import allantools
import numpy as np
from common import (
    add_json,
    best_time_s,
    blas_threads,
    command_line,
    parser_for,
    peak_mib,
    print_heading,
    table_head,
    table_row,
    versions,
    write_json,
)

from tcbench.signal.allan import allan_deviation

FS_HZ = 100.0
WHITE_SIGMA = 0.05  # per-sample sigma of the white rate noise (rate unit)
RRW_K = 1e-3  # rate random walk, rate unit / sqrt(s)
DEFAULT_JSON = Path(__file__).with_name("allan_vs_allantools.json")


def make_signal(n: int, seed: int = 0) -> np.ndarray:
    """White noise plus a rate random walk with increments K sqrt(dt), float64."""
    rng = np.random.default_rng(seed)
    white = WHITE_SIGMA * rng.standard_normal(n)
    walk = np.cumsum(RRW_K * np.sqrt(1.0 / FS_HZ) * rng.standard_normal(n))
    return white + walk


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    add_json(parser, DEFAULT_JSON, help_text=None)
    args = parser.parse_args(argv)

    rate = make_signal(args.samples)
    rows = []
    for name in ("octave", "decade"):
        ours = allan_deviation(rate, FS_HZ, name)
        tau_s = np.array(ours.tau_s)

        def run_tcbench(tau_set: str = name) -> object:
            return allan_deviation(rate, FS_HZ, tau_set)

        def run_allantools(taus: np.ndarray = tau_s) -> object:
            return allantools.oadev(rate, rate=FS_HZ, data_type="freq", taus=taus)

        theirs_tau, theirs_adev, _, theirs_n = run_allantools()
        if not (np.array_equal(theirs_tau, ours.tau_s) and np.array_equal(theirs_n, ours.n_terms)):
            raise RuntimeError(f"{name}: allantools used other taus or term counts")
        rel = float(np.max(np.abs(ours.adev / theirs_adev - 1.0)))
        t_ours = best_time_s(run_tcbench, args.repeats)
        t_theirs = best_time_s(run_allantools, args.repeats)
        rows.append(
            {
                "taus": name,
                "n_taus": int(tau_s.size),
                "tcbench_s": t_ours,
                "allantools_s": t_theirs,
                "ratio": t_theirs / t_ours,
                "max_rel_diff": rel,
            }
        )
    for row in rows:  # memory in a separate pass: tracing slows the calls down
        tau_s = allan_deviation(rate, FS_HZ, row["taus"]).tau_s
        row["tcbench_peak_mib"] = peak_mib(lambda: allan_deviation(rate, FS_HZ, row["taus"]))
        row["allantools_peak_mib"] = peak_mib(
            lambda: allantools.oadev(rate, rate=FS_HZ, data_type="freq", taus=tau_s)
        )

    libraries = versions("numpy", "allantools", "tcbench")
    print_heading(f"Allan deviation vs allantools ({args.samples} samples)", command_line(),
                  libraries)
    print(
        f"Signal: white noise (sigma {WHITE_SIGMA}/sample) + rate random walk "
        f"(K = {RRW_K}/sqrt(s)) at {FS_HZ:g} Hz, seed 0; best of {args.repeats} runs.\n"
    )
    print(f"BLAS as the process starts (default thread settings, nothing forced): {blas_threads()}. "
          "Equal work: both compute the same statistic at the same m values.\n")
    print("\n".join(table_head(
        ["taus", "n taus", "tcbench (s)", "allantools (s)", "ratio allantools/tcbench",
         "max rel. diff", "tcbench peak (MiB)", "allantools peak (MiB)"],
        "lrrrrrrr",
    )))
    for r in rows:
        print(table_row([
            r["taus"], r["n_taus"], f"{r['tcbench_s']:.4f}", f"{r['allantools_s']:.4f}",
            f"{r['ratio']:.1f}x", f"{r['max_rel_diff']:.1e}", f"{r['tcbench_peak_mib']:.1f}",
            f"{r['allantools_peak_mib']:.1f}",
        ]))
    input_mib = rate.nbytes / 2**20
    print(f"\n(input array: {input_mib:.1f} MiB, not counted in the peaks)")
    write_json(
        args.json,
        {"samples": args.samples, "repeats": args.repeats, "versions": libraries, "rows": rows},
        final_newline=False,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
