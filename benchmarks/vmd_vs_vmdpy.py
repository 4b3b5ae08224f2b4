"""Benchmark tcbench's variational mode decomposition against ``vmdpy.VMD``.

One gyro-like rate signal (20 000 samples at 100 Hz by default, seed 0: a slow warm-up drift,
tones at 0.5, 3 and 12 Hz and white noise) is decomposed into K = 8 modes with alpha = 2000,
tau = 0, no DC mode, uniform initial centre frequencies (vmdpy ``init=1``) and tol = 1e-7, by
both libraries in this one process, each run to convergence by its own stopping rule:

* tcbench: eq. 7 of the seed paper, ``sum_k ||du_k||^2 / ||u_k||^2 < tol`` (relative);
* vmdpy: ``eps + sum_k ||du_k||^2 / T < tol`` (absolute, as Zosso's MATLAB code), at most
  499 iterations (its ``Niter = 500`` is fixed), returning the second-to-last iterate.

The two rules stop at different iterations, so an equal-work run is timed as well: tcbench
with ``tol=0`` and as many iterations as vmdpy ran. Its accuracy check runs tcbench to the
iterate vmdpy returns and reports the largest per-mode ``||u - u_vmdpy|| / ||u_vmdpy||`` and
the largest centre-frequency difference.

Wall times are medians of ``--repeats`` runs (``time.perf_counter``). Peak memory of one call of
each (tracemalloc, which sees numpy's buffers, so vmdpy's ``(500, 2n, K)`` iteration history
counts in full even though the OS maps its zero pages lazily) is measured in a separate pass,
since tracing slows the calls. BLAS threads are reported from ``threadpoolctl``.

Usage::

    python benchmarks/vmd_vs_vmdpy.py --samples 20000 --repeats 5
"""

from __future__ import annotations

import statistics
from collections.abc import Callable
from pathlib import Path

import numpy as np
from common import (
    add_json,
    blas_threads,
    command_line,
    environment,
    environment_line,
    parser_for,
    peak_mib,
    progress,
    table_head,
    table_row,
    wall_times_s,
    write_json,
)
from vmdpy import VMD

from tcbench.signal.vmd import vmd

FS_HZ = 100.0
K = 8
ALPHA = 2000.0
TOL = 1e-7
VMDPY_MAX_ITER = 499  # vmdpy's loop runs while n < Niter - 1 with Niter = 500 fixed
DRIFT_DEG_S = 0.3  # warm-up drift amplitude, deg/s, time constant DRIFT_TAU_S
DRIFT_TAU_S = 60.0
TONES = ((0.2, 0.5), (0.1, 3.0), (0.05, 12.0))  # (amplitude deg/s, Hz)
WHITE_SIGMA = 0.05  # deg/s per sample
DEFAULT_JSON = Path(__file__).with_name("vmd_vs_vmdpy.json")


def make_signal(n: int, seed: int = 0) -> np.ndarray:
    """Gyro-like rate (deg/s): exponential warm-up drift with a slow linear term, three tones and
    white noise, float64."""
    t = np.arange(n) / FS_HZ
    x = DRIFT_DEG_S * (1.0 - np.exp(-t / DRIFT_TAU_S)) + 1e-3 * t
    for amp, f_hz in TONES:
        x += amp * np.sin(2 * np.pi * f_hz * t)
    return x + WHITE_SIGMA * np.random.default_rng(seed).standard_normal(n)


def run_vmdpy(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """vmdpy's modes and centre frequencies sorted by frequency, and its iteration count."""
    u, _, omega = VMD(x, ALPHA, 0.0, K, False, 1, TOL)
    order = np.argsort(omega[-1], kind="stable")
    return u[order], omega[-1][order], int(omega.shape[0])


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--samples", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5)
    add_json(parser, DEFAULT_JSON, help_text=None)
    args = parser.parse_args(argv)

    x = make_signal(args.samples)
    ours = vmd(x, K, ALPHA, init="uniform", tol=TOL)
    u_ref, omega_ref, vmdpy_iters = run_vmdpy(x)
    vmdpy_converged = vmdpy_iters < VMDPY_MAX_ITER
    # vmdpy returns iterate vmdpy_iters - 1; tcbench stopped there must give the same modes.
    same = vmd(x, K, ALPHA, init="uniform", tol=0.0, max_iter=vmdpy_iters - 1)
    rel = np.linalg.norm(same.modes - u_ref, axis=1) / np.linalg.norm(u_ref, axis=1)
    d_omega = np.abs(same.centre_freqs - omega_ref)
    rel_conv = np.linalg.norm(ours.modes - u_ref, axis=1) / np.linalg.norm(u_ref, axis=1)
    progress(f"tcbench {ours.iterations} iterations (converged {ours.converged}); vmdpy "
             f"{vmdpy_iters} (converged {vmdpy_converged}); equal-iterate max rel "
             f"{rel.max():.1e}")

    runs: dict[str, Callable[[], object]] = {
        "tcbench": lambda: vmd(x, K, ALPHA, init="uniform", tol=TOL),
        "tcbench, equal work": lambda: vmd(x, K, ALPHA, init="uniform", tol=0.0,
                                           max_iter=vmdpy_iters),
        "vmdpy": lambda: VMD(x, ALPHA, 0.0, K, False, 1, TOL),
    }
    seconds = {}
    for name, fn in runs.items():
        seconds[name] = statistics.median(wall_times_s(fn, args.repeats)[0])
        progress(f"{name}: median {seconds[name]:.3f} s")
    peaks = {}
    for name, fn in runs.items():  # memory in a separate pass: tracing slows the calls down
        peaks[name] = peak_mib(fn)
        progress(f"{name}: peak {peaks[name]:.1f} MiB")
    iterations = {"tcbench": ours.iterations, "tcbench, equal work": vmdpy_iters,
                  "vmdpy": vmdpy_iters}
    converged = {"tcbench": ours.converged, "tcbench, equal work": False,
                 "vmdpy": vmdpy_converged}

    threads = blas_threads()
    env = environment("vmdpy", "threadpoolctl", blas=threads)
    command = command_line()
    print(f"## VMD vs vmdpy ({args.samples} samples, K = {K})\n")
    print(f"Command: `{command}`\n")
    print(
        f"Signal: gyro-like rate at {FS_HZ:g} Hz, seed 0: warm-up drift "
        f"{DRIFT_DEG_S} (1 - exp(-t/{DRIFT_TAU_S:g} s)) + 0.001 t deg/s, tones "
        + ", ".join(f"{a} deg/s at {f:g} Hz" for a, f in TONES)
        + f", white noise {WHITE_SIGMA} deg/s. alpha {ALPHA:g}, tau 0, no DC mode, uniform "
        f"init (vmdpy init=1), tol {TOL:g}; median of {args.repeats} runs.\n"
    )
    print("\n".join(table_head(
        ["run", "iterations", "converged", "median wall time (s)", "vmdpy / this (time)",
         "peak traced memory (MiB)", "this / vmdpy (memory)"],
        "lrlrrrr",
    )))
    for name in runs:
        print(table_row([
            name, iterations[name], "yes" if converged[name] else "no",
            f"{seconds[name]:.3f}", f"{seconds['vmdpy'] / seconds[name]:.1f}x",
            f"{peaks[name]:.1f}", f"{peaks[name] / peaks['vmdpy']:.4f}",
        ]))
    print(
        f"\nStopping rules differ: tcbench uses eq. 7 (relative change), vmdpy an absolute "
        f"change (and returns its second-to-last iterate); the equal-work row runs tcbench for "
        f"vmdpy's {vmdpy_iters} iterations with tol = 0."
        + ("" if vmdpy_converged else f" vmdpy did not converge within its "
           f"{VMDPY_MAX_ITER}-iteration limit.")
    )
    print(
        f"\nAgreement at vmdpy's returned iterate ({vmdpy_iters - 1}): largest per-mode "
        f"||u - u_vmdpy|| / ||u_vmdpy|| = {rel.max():.1e}, largest centre-frequency difference "
        f"{d_omega.max():.1e} cycles/sample. Converged tcbench vs vmdpy: largest per-mode "
        f"relative difference {rel_conv.max():.1e}."
    )
    print("\nCentre frequencies (Hz, tcbench converged): "
          + ", ".join(f"{f * FS_HZ:.3f}" for f in ours.centre_freqs))
    print(f"\nBLAS: {threads}. " + environment_line(env, f"vmdpy {env['vmdpy']}"))
    write_json(args.json, {
        "benchmark": "vmd_vs_vmdpy",
        "samples": args.samples,
        "fs_hz": FS_HZ,
        "k": K,
        "alpha": ALPHA,
        "tau": 0.0,
        "init": "uniform",
        "tol": TOL,
        "repeats": args.repeats,
        "command": command,
        "environment": env,
        "runs": [
            {"run": name, "iterations": iterations[name], "converged": converged[name],
             "median_seconds": seconds[name],
             "time_ratio_vmdpy_over_this": seconds["vmdpy"] / seconds[name],
             "peak_mib": peaks[name], "memory_ratio_this_over_vmdpy": peaks[name] / peaks["vmdpy"]}
            for name in runs
        ],
        "equal_iterate_max_rel_diff": float(rel.max()),
        "equal_iterate_max_centre_freq_diff": float(d_omega.max()),
        "converged_max_rel_diff": float(rel_conv.max()),
        "centre_freqs_hz": [float(f * FS_HZ) for f in ours.centre_freqs],
    })
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
