"""Benchmark tcbench's sample, fuzzy and permutation entropy against antropy and EntropyHub.

One signal, unit white noise plus a linear drift of 2 units over the record (20 000 samples by
default, seed 0), goes through, in this one process:

* sample entropy, m = 2, r = 0.2 std: ``tcbench.signal.entropy.sample_entropy`` vs
  ``antropy.sample_entropy(x, order=2, metric="chebyshev")`` (a KD-tree from N >= 5000, a
  numba loop below). antropy's numba functions are compiled when it is imported and it is
  called once untimed before timing, so no compile time is in its figures;
* fuzzy entropy, m = 2, r = 0.2 std, n = 2: ``fuzzy_entropy`` vs EntropyHub's
  ``FuzzEn(x, m=2, tau=1, r=(0.2 std, 2), Fx="default")`` (its value for m = 2), which holds
  two N x N float64 matrices and runs a Python loop over rows, so it gets ``--peer-repeats``
  (default 1) runs;
* permutation entropy, m = 3, delay 1, normalised: ``permutation_entropy`` vs
  ``antropy.perm_entropy(x, order=3, delay=1, normalize=True)``.

We report the median of the wall times (``time.perf_counter``), the ratio peer / tcbench, the
absolute difference of the values, the BLAS thread pools (threadpoolctl) and the versions.

Usage::

    python benchmarks/entropy_vs_peers.py --samples 20000 --repeats 5 --peer-repeats 1
"""

from __future__ import annotations

import statistics
from pathlib import Path

import antropy
import numpy as np
from common import (
    add_json,
    blas_threads,
    command_line,
    environment,
    environment_line,
    parser_for,
    progress,
    table_head,
    table_row,
    wall_times_s,
    write_json,
)
from EntropyHub import FuzzEn

from tcbench.signal.entropy import fuzzy_entropy, permutation_entropy, sample_entropy

DRIFT = 2.0  # linear drift over the record, in units of the white-noise sigma
DEFAULT_JSON = Path(__file__).with_name("entropy_vs_peers.json")


def make_signal(n: int, seed: int = 0) -> np.ndarray:
    """Unit white noise plus a linear drift from 0 to :data:`DRIFT`, float64."""
    rng = np.random.default_rng(seed)
    return rng.standard_normal(n) + np.linspace(0.0, DRIFT, n)


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--samples", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each call")
    parser.add_argument("--peer-repeats", type=int, default=1,
                        help="timed runs of EntropyHub's FuzzEn (slow at 20 000 samples)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args(argv)

    x = make_signal(args.samples)
    std = float(np.std(x))
    antropy.sample_entropy(x[:200], order=2, metric="chebyshev")  # warm-up, untimed
    antropy.perm_entropy(x[:200], order=3, normalize=True)
    cases = [
        ("sample entropy (m=2, r=0.2 std)", "antropy", args.repeats,
         lambda: sample_entropy(x, m=2, r=0.2),
         lambda: antropy.sample_entropy(x, order=2, metric="chebyshev")),
        ("fuzzy entropy (m=2, r=0.2 std, n=2)", "EntropyHub", args.peer_repeats,
         lambda: fuzzy_entropy(x, m=2, r=0.2, n=2),
         lambda: FuzzEn(x, m=2, tau=1, r=(0.2 * std, 2), Fx="default")[0][1]),
        ("permutation entropy (m=3, delay=1, normalised)", "antropy", args.repeats,
         lambda: permutation_entropy(x, m=3, delay=1, normalize=True),
         lambda: antropy.perm_entropy(x, order=3, delay=1, normalize=True)),
    ]
    rows = []
    for name, peer, peer_repeats, ours, theirs in cases:
        ours_all, v_ours = wall_times_s(ours, args.repeats)
        t_ours = statistics.median(ours_all)
        progress(f"{name}: tcbench {t_ours:.4f} s")
        peer_all, v_peer = wall_times_s(theirs, peer_repeats)
        t_peer = statistics.median(peer_all)
        progress(f"{name}: {peer} {t_peer:.4f} s")
        rows.append({
            "entropy": name, "peer": peer, "tcbench_s": t_ours, "peer_s": t_peer,
            "ratio_peer_over_tcbench": t_peer / t_ours, "tcbench_value": v_ours,
            "peer_value": v_peer, "abs_diff": abs(v_ours - v_peer), "tcbench_repeats":
            args.repeats, "peer_repeats": peer_repeats, "tcbench_times_s": ours_all,
            "peer_times_s": peer_all,
        })

    env = environment("antropy", "EntropyHub", "numba", "threadpoolctl")
    blas = blas_threads() or "none"
    command = command_line(argv)
    print(f"## Entropy vs antropy and EntropyHub ({args.samples} samples)\n")
    print(f"Command: `{command}`\n")
    print(
        f"Signal: unit white noise + linear drift 0 -> {DRIFT:g}, seed 0. Median of "
        f"{args.repeats} runs (EntropyHub's FuzzEn: {args.peer_repeats}). antropy's numba code "
        "is compiled at import and warmed up before timing: no compile time is included.\n"
    )
    print("\n".join(table_head(
        ["entropy", "peer", "tcbench (s)", "peer (s)", "peer / tcbench", "value", "|diff|"],
        "llrrrrr",
    )))
    for r in rows:
        print(table_row([
            r["entropy"], r["peer"], f"{r['tcbench_s']:.4f}", f"{r['peer_s']:.4f}",
            f"{r['ratio_peer_over_tcbench']:.1f}x", f"{r['tcbench_value']:.6f}",
            f"{r['abs_diff']:.1e}",
        ]))
    print(f"\nBLAS thread pools (threadpoolctl): {blas}. All three tcbench entropies are "
          "single-threaded numpy.\n")
    print(environment_line(env, f"antropy {env['antropy']} (numba {env['numba']}), "
                                f"EntropyHub {env['EntropyHub']}"))
    write_json(args.json, {
        "benchmark": "entropy_vs_peers", "samples": args.samples, "seed": 0, "drift": DRIFT,
        "repeats": args.repeats, "peer_repeats": args.peer_repeats, "command": command,
        "environment": env, "threadpools": blas, "rows": rows,
    })
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
